#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "common/input_error.hpp"
#include "db/inmotion_import.hpp"
#include "db_test_util.hpp"

namespace calbench::db {
namespace {

// The QC metric of that name among the imported ones (a test failure when it is missing).
QcResult find(const std::vector<QcResult>& qc, const std::string& m) {
  for (const auto& q : qc)
    if (q.metric == m) return q;
  ADD_FAILURE() << "no metric " << m;
  return QcResult{};
}
using nlohmann::json;

json block(const std::string& serial, const SensorErrors& e) { return json::parse(test::payload(serial, e)); }

json result(const std::string& serial, const SensorErrors& total, const SensorErrors& correction) {
  json r;
  r["device"] = {{"model", "ADIS16488A"}, {"serial", serial}};
  r["recording"] = {{"path", "/drives/d1"}, {"sha256", std::string(64, 'b')}};
  r["coefficients"] = block(serial, total);
  json c = block(serial, correction);
  c.erase("format");
  c.erase("device");
  r["correction"] = c;
  r["mounting_rpy_deg"] = {{"value", {0.1, -0.2, 0.3}}, {"sigma", {0.01, 0.01, 0.05}}};
  r["consistency"] = {{"pos", {{"nis_mean", 1.02}}}};
  r["qc"] = {{"sets", json::array({{{"name", "bench"}, {"final_cpe_m", 850.0}}, {{"name", "bench+in-motion"}, {"final_cpe_m", 40.0}}})},
             {"cpe_ratio", {{"value", 21.2}, {"threshold", 10.0}, {"pass", true}}}};
  return r;
}

struct ImportFixture : ::testing::Test {
  test::TempDir t;
  Store s{t.db(), test::create_opts(), test::test_actor()};
  SensorErrors bench = test::random_errors(21), corr = test::random_errors(22);
  std::int64_t bench_id = 0;
  void SetUp() override {
    bench_id = s.store_bench({"ADIS16488A", "M1", ""}, test::bench_run(), test::payload("M1", bench)).set_id;
  }
  std::size_t written() { return static_cast<std::size_t>(s.count("inmotion_runs") + s.count("coefficient_sets") + s.count("qc_results")); }
};

TEST_F(ImportFixture, CombinedSetFindsItsBenchParentByComposition) {
  const SensorErrors total = compose(bench, corr);
  const auto r = parse_inmotion_result(result("M1", total, corr).dump(), "RESULT.json");
  EXPECT_EQ(r.qc.size(), 3u);  // two informative CPE figures + the ratio with its threshold
  const auto o = import_inmotion(s, r, "RESULT.json");
  EXPECT_EQ(o.source, SetSource::combined);
  ASSERT_TRUE(o.parent_id);
  EXPECT_EQ(*o.parent_id, bench_id);
  EXPECT_EQ(o.version, 2);
  const auto set = s.get_set(o.set_id);
  EXPECT_LT(max_difference(set.errors, total), 1e-15);
  const auto run = s.inmotion_run(*set.inmotion_run_id);
  EXPECT_DOUBLE_EQ(run->mounting_rpy_deg[2], 0.3);
  EXPECT_DOUBLE_EQ(run->mounting_sigma_deg[2], 0.05);
  EXPECT_EQ(s.qc_of_set(set).size(), 3u);
  // The same result again is refused (it would store a second, identical set) and stores nothing.
  const auto before = s.sets_of(set.device_id).size();
  EXPECT_THROW(import_inmotion(s, r, "RESULT.json", bench_id), std::runtime_error);
  EXPECT_EQ(s.sets_of(set.device_id).size(), before);
  // An explicit parent gives the same answer (a result of another recording, same coefficients).
  json other = result("M1", total, corr);
  other["recording"]["path"] = "/drives/another";
  const auto o2 = import_inmotion(s, parse_inmotion_result(other.dump(), "R2"), "R2", bench_id);
  EXPECT_EQ(*o2.parent_id, bench_id);
}

TEST_F(ImportFixture, ResultOnRawDataIsAnInMotionSetWithoutParent) {
  const SensorErrors raw = test::random_errors(30);
  const auto o = import_inmotion(s, parse_inmotion_result(result("M1", raw, raw).dump(), "R"), "R");
  EXPECT_EQ(o.source, SetSource::in_motion);
  EXPECT_FALSE(o.parent_id);
}

TEST_F(ImportFixture, WrongParentIsRefusedAndNothingWritten) {
  const SensorErrors total = compose(bench, corr);
  const auto other = s.store_set({"ADIS16488A", "M1", ""}, SetSource::bench, test::payload("M1", test::random_errors(40))).set_id;
  const auto before = written();
  EXPECT_THROW(import_inmotion(s, parse_inmotion_result(result("M1", total, corr).dump(), "R"), "R", other), InputError);
  EXPECT_EQ(written(), before);
}

TEST_F(ImportFixture, UnknownDeviceMismatchedSerialsAndMalformedFilesAreRefused) {
  const SensorErrors total = compose(bench, corr);
  const auto before = written();
  const auto expect_error = [&](const json& j, const std::string& needle) {
    try {
      import_inmotion(s, parse_inmotion_result(j.dump(), "RESULT.json"), "RESULT.json");
      ADD_FAILURE() << "accepted " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("RESULT.json"), std::string::npos) << e.what();
    }
  };
  expect_error(result("NOPE", total, corr), "unknown device");
  json mism = result("M1", total, corr);
  mism["coefficients"]["device"]["serial"] = "M2";
  expect_error(mism, "does not match");
  json wrong_type = result("M1", total, corr);
  wrong_type["coefficients"]["gyro"]["bias"][0] = "0.1";
  expect_error(wrong_type, "coefficients.gyro.bias[0]");
  json bad_sha = result("M1", total, corr);
  bad_sha["recording"]["sha256"] = "abc";
  expect_error(bad_sha, "recording.sha256");
  json no_dev = result("M1", total, corr);
  no_dev.erase("device");
  expect_error(no_dev, "device");
  json bad_qc = result("M1", total, corr);
  bad_qc["qc"]["cpe_ratio"]["value"] = "high";
  expect_error(bad_qc, "qc.cpe_ratio.value");
  json bad_mount = result("M1", total, corr);
  bad_mount["mounting_rpy_deg"] = {1, 2};
  expect_error(bad_mount, "mounting_rpy_deg");
  const std::string text = result("M1", total, corr).dump();
  EXPECT_THROW(parse_inmotion_result(text.substr(0, text.size() - 20), "R"), InputError);
  std::string nan = text;
  nan.replace(nan.find("1.02"), 4, "NaN");
  EXPECT_THROW(parse_inmotion_result(nan, "R"), InputError);
  EXPECT_EQ(written(), before);
}

// The qc block of `fit drive` (sets "input" and "in-motion"): the figures carry qc.sample; the
// result's final ΔS is checked against the input set's, everything else is informative; from_s and
// horizon_s are context, not metrics.
TEST_F(ImportFixture, FitDriveQcChecksTheResultAgainstTheSetItStartedFrom) {
  const SensorErrors total = compose(bench, corr);
  const auto qc_of = [&](double input_m, double result_m, const char* sample) {
    json r = result("M1", total, corr);
    r["qc"] = {{"from_s", 200.0}, {"horizon_s", 81.2}, {"sample", sample},
               {"sets", json::array({{{"name", "input"}, {"final_cpe_m", input_m}, {"max_cpe_m", input_m}},
                                     {{"name", "in-motion"}, {"final_cpe_m", result_m}, {"max_cpe_m", result_m}}})}};
    return parse_inmotion_result(r.dump(), "RESULT.json").qc;
  };
  const auto better = qc_of(206.2, 10.1, "out-of-sample (after the fit window)");
  ASSERT_EQ(better.size(), 4u);  // final and largest ΔS of both sets
  const QcResult res = find(better, "sets.in-motion.final_cpe_m");
  ASSERT_TRUE(res.threshold);
  EXPECT_DOUBLE_EQ(*res.threshold, 206.2);
  EXPECT_TRUE(res.pass);
  EXPECT_FALSE(res.informative());
  EXPECT_NE(res.criterion.find("'input'"), std::string::npos) << res.criterion;
  for (const auto& q : better) {
    EXPECT_EQ(q.sample, kOutOfSample) << q.metric;
    EXPECT_EQ(q.unit, "m") << q.metric;
    if (q.metric != "sets.in-motion.final_cpe_m") {
      EXPECT_TRUE(q.informative()) << q.metric;
    }
  }
  const auto worse = qc_of(206.2, 250.0, "in-sample (no data after the fit window)");
  EXPECT_FALSE(find(worse, "sets.in-motion.final_cpe_m").pass);
  EXPECT_EQ(find(worse, "sets.in-motion.final_cpe_m").sample, kInSample);
  // Stored and read back with sample and criterion.
  json r = result("M1", total, corr);
  r["qc"] = {{"sample", "out-of-sample (after the fit window)"},
             {"sets", json::array({{{"name", "none"}, {"final_cpe_m", 900.0}}, {{"name", "in-motion"}, {"final_cpe_m", 40.0}}})}};
  const auto o = import_inmotion(s, parse_inmotion_result(r.dump(), "R"), "R");
  const auto stored = s.qc_of_set(s.get_set(o.set_id));
  const QcResult back = find(stored, "sets.in-motion.final_cpe_m");
  EXPECT_EQ(back.sample, kOutOfSample);
  EXPECT_DOUBLE_EQ(back.threshold.value_or(0), 900.0);
  EXPECT_NE(back.criterion.find("'none'"), std::string::npos) << back.criterion;
}

// qc.outages of a GNSS-only drive: per set and length the figures, informative except the result's
// median largest error, checked against the input set's plus 3σ of the fixes.
TEST_F(ImportFixture, OutageQcFiguresAndTheNeverWorseCheck) {
  const SensorErrors total = compose(bench, corr);
  const auto with = [&](double input_60, double result_60, const json& fix_sigma) {
    json r = result("M1", total, corr);
    const auto per = [](double m15, double m60) {
      return json::array({{{"length_s", 15}, {"count", 3}, {"median_max_m", m15}, {"max_max_m", m15 + 1}, {"median_end_m", m15},
                           {"max_end_m", m15 + 1}},
                          {{"length_s", 60}, {"count", 1}, {"median_max_m", m60}, {"max_max_m", m60}, {"median_end_m", m60},
                           {"max_end_m", m60}}});
    };
    r["qc"] = {{"sample", "in-sample (outages inside the data the fit used)"},
               {"outages", {{"sample", "out-of-sample (outages after the fit window)"}, {"fix_sigma_h_m", fix_sigma},
                            {"sets", json::array({{{"name", "none"}, {"per_length", per(30, 1800)}},
                                                  {{"name", "input"}, {"per_length", per(2.8, input_60)}},
                                                  {{"name", "in-motion"}, {"per_length", per(2.7, result_60)}}})}}}};
    return parse_inmotion_result(r.dump(), "RESULT.json").qc;
  };
  const auto qc = with(19.4, 20.0, 1.0);
  EXPECT_EQ(qc.size(), 3u * 2u * 4u);  // 3 sets x 2 lengths x 4 figures
  const QcResult r60 = find(qc, "outages.in-motion.60s.median_max_m");
  ASSERT_TRUE(r60.threshold);
  EXPECT_DOUBLE_EQ(*r60.threshold, 19.4 + 3.0);  // the input's, plus 3σ of the fixes
  EXPECT_TRUE(r60.pass);
  EXPECT_EQ(r60.sample, kOutOfSample);
  EXPECT_EQ(r60.unit, "m");
  EXPECT_NE(r60.criterion.find("'input'"), std::string::npos) << r60.criterion;
  EXPECT_TRUE(find(qc, "outages.none.60s.median_max_m").informative());
  EXPECT_TRUE(find(qc, "outages.in-motion.60s.max_max_m").informative());
  EXPECT_FALSE(find(with(19.4, 23.0, 1.0), "outages.in-motion.60s.median_max_m").pass);
  EXPECT_FALSE(find(with(19.4, 19.5, nullptr), "outages.in-motion.60s.median_max_m").pass);  // no σ stated: no allowance
  // Malformed: named by key.
  json bad = result("M1", total, corr);
  bad["qc"] = {{"outages", {{"sets", json::array({{{"name", "none"}, {"per_length", json::array({{{"length_s", "x"}}})}}})}}}};
  try {
    parse_inmotion_result(bad.dump(), "R.json");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "qc.outages.sets[0].per_length[0].length_s");
  }
}

TEST_F(ImportFixture, DeterminedByIsReadAndValidated) {
  const SensorErrors total = compose(bench, corr);
  json r = result("M1", total, corr);
  EXPECT_FALSE(parse_inmotion_result(r.dump(), "R").determined_by);  // older results have none
  json c = json::object();
  for (const auto& n : coefficient_names())
    c[n] = {{"parent_sigma", 1.7e-5}, {"prior_sigma", 4.9e-4}, {"posterior_sigma", 2.8e-5}, {"ratio", 0.057},
            {"drive_share", 0.997}, {"stage", "drive"}};
  c["gyro.M.xy"] = {{"parent_sigma", nullptr}, {"prior_sigma", 5e-5}, {"posterior_sigma", 4.9e-5}, {"ratio", 0.98},
                    {"drive_share", 1 - 0.98 * 0.98}, {"stage", "bench"}};
  r["determined_by"] = {{"rule", "drive share"}, {"coefficients", c}};
  const auto d = parse_inmotion_result(r.dump(), "R").determined_by;
  ASSERT_TRUE(d);
  EXPECT_EQ(d->coefficients.size(), 24u);
  EXPECT_EQ(d->coefficients.at("gyro.M.xy").stage, "bench");
  EXPECT_FALSE(d->coefficients.at("gyro.M.xy").parent_sigma);
  EXPECT_DOUBLE_EQ(*d->coefficients.at("gyro.bias.x").posterior_sigma, 2.8e-5);
  // The report reads it back from the stored result.
  const auto o = import_inmotion(s, parse_inmotion_result(r.dump(), "R"), "R");
  const auto run = s.inmotion_run(*s.get_set(o.set_id).inmotion_run_id);
  EXPECT_EQ(parse_determined_by(run->result_json, "run")->coefficients.at("accel.M.zz").stage, "drive");
  const auto before = written();
  const auto expect_error = [&](json bad, const std::string& needle) {
    try {
      parse_inmotion_result(bad.dump(), "RESULT.json");
      ADD_FAILURE() << "accepted " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  json bad = r;
  bad["determined_by"]["coefficients"]["gyro.bias.x"]["stage"] = "factory";
  expect_error(bad, "determined_by.coefficients.gyro.bias.x.stage");
  bad = r;
  bad["determined_by"]["coefficients"]["gyro.bias.w"] = c["gyro.bias.x"];
  expect_error(bad, "determined_by.coefficients.gyro.bias.w");
  bad = r;
  bad["determined_by"]["coefficients"]["accel.M.zz"]["posterior_sigma"] = -1.0;
  expect_error(bad, "determined_by.coefficients.accel.M.zz.posterior_sigma");
  bad = r;
  bad["determined_by"] = "bench";
  expect_error(bad, "determined_by");
  EXPECT_EQ(written(), before);
}

}  // namespace
}  // namespace calbench::db
