// The one RESULT.json codec (common/drive_result.hpp): a result in the form `fit drive` writes
// passes a read and a write unchanged, the typed parts hold what the readers use, the older forms
// the store has always taken are read, and malformed input is refused naming the file and the key.
#include "common/drive_result.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/input_error.hpp"
#include "common/json_parse.hpp"

namespace calbench {
namespace {
using nlohmann::json;

json triad(double b) {
  return {{"bias", {b, -b, 2 * b}},
          {"M", {{1e-4, 2e-5, 0.0}, {0.0, -1e-4, 0.0}, {0.0, 0.0, 3e-4}}},
          {"sigma_bias", {1e-6, 1e-6, 2e-6}},
          {"sigma_M", {{1e-5, 1e-5, 1e-5}, {1e-5, 1e-5, 1e-5}, {1e-5, 1e-5, 1e-5}}}};
}

json stage(const char* s, double share) {
  const double prior = 1e-3, post = prior * std::sqrt(1 - share);
  return {{"parent_sigma", nullptr}, {"prior_sigma", prior}, {"posterior_sigma", post},
          {"ratio", post / prior},   {"drive_share", share}, {"stage", s}};
}

// A result in the form fit drive writes (the keys it always writes, free-form sections abridged).
json sample() {
  json coeffs = {{"format", "calbench-coefficients/1"},
                 {"device", {{"model", "ADIS16488A"}, {"serial", "U7"}}},
                 {"gyro", triad(1e-5)},
                 {"accel", triad(2e-3)},
                 {"time_offset", {{"value", 0.002}, {"sigma", 1e-4}}}};
  json corr = coeffs;
  corr.erase("time_offset");
  json c = json::object(), m = json::object();
  for (const auto& n : coefficient_names()) c[n] = stage("drive", 0.9);
  c["accel.M.zz"] = stage("both", 0.5);
  for (const char* n : {"mount.x", "mount.y", "mount.z"}) m[n] = stage("prior", 0.0);
  return {{"format", "calbench-inmotion-result/1"},
          {"device", {{"model", "ADIS16488A"}, {"serial", "U7"}}},
          {"recording",
           {{"path", "/drives/d1"},
            {"sha256", std::string(64, 'a')},
            {"sha256_reference", nullptr},
            {"sha256_meta", std::string(64, 'c')},
            {"sha256_gnss", std::string(64, 'd')},
            {"device", {{"model", "ADIS16488A"}, {"serial", "U7"}}},
            {"uri", "file://station1/drives/d1"},
            {"digest_sha256", std::string(64, 'e')}}},
          {"reference_system", "GNSS fixes (gnss.csv)"},
          {"window_s", {0.5, 135.25}},
          {"observations", "pos,vel"},
          {"aiding", "gnss"},
          {"smoothed", false},
          {"covariance", "structured"},
          {"coefficients", coeffs},
          {"correction", corr},
          {"input_coefficients", nullptr},
          {"priors", {{"mode", "data-sheet"}, {"device_class", "ADIS16488A"}, {"input", nullptr}}},
          {"determined_by", {{"rule", "drive share"}, {"count", {{"bench", 0}, {"both", 1}, {"drive", 23}, {"prior", 0}}},
                             {"coefficients", c}, {"mounting", m}}},
          {"mounting_rpy_deg", {{"value", {0.1, -0.2, 90.3}}, {"sigma", {0.01, 0.02, 0.5}}, {"nominal", {0.0, 0.0, 90.0}},
                                {"lever_arm_m", {-1.0, 0.2, -0.3}}}},
          {"adaptive_noise", {{"enabled", true}, {"scale_max", 7.8e5}}},
          {"consistency", {{"position", {{"epochs", 120}, {"mean_nis", 3.4}}},
                           {"nhc", {{"equation", "obs_nhc.cpp"}, {"epochs", 900}, {"rejected", 4}, {"forced", 0},
                                    {"mean_nis", 1.9}, {"expected_nis", 2.0}, {"fraction_within_95pct", 0.96}}}}},
          {"qc", json::parse(R"J({"sample": "in-sample (outages inside the data the fit used)",
                  "outages": {"sample": "in-sample (outages inside the data the fit used)", "fix_sigma_h_m": 0.02,
                              "not_placed": [{"length_s": 60.0, "reason": "too short"}],
                              "sets": [{"name": "none", "per_length": [{"length_s": 15.0, "count": 2, "median_max_m": 3.5}]},
                                       {"name": "in-motion", "per_length": [{"length_s": 15.0, "median_max_m": 1.25}]}],
                              "outages": [{"start_s": 40.5, "length_s": 15.0, "fixes": 15,
                                           "max_m": {"none": 3.5, "in-motion": 1.25}, "end_m": {"none": 3.0}}]}})J")}};
}

TEST(DriveResultCodec, AResultAsFitDriveWritesItPassesAReadAndAWriteUnchanged) {
  const json in = sample();
  const DriveResult r = drive_result_from_json(in, "R.json");
  EXPECT_EQ(drive_result_to_json(r), in);
  EXPECT_EQ(drive_result_to_json(r).dump(2), in.dump(2));  // the bytes fit drive writes
}

TEST(DriveResultCodec, TheTypedPartsHoldWhatTheReadersUse) {
  const DriveResult r = drive_result_from_json(sample(), "R.json");
  EXPECT_EQ(r.format, kDriveResultFormat);
  EXPECT_EQ(r.device.serial, "U7");
  EXPECT_EQ(r.recording.path, "/drives/d1");
  EXPECT_FALSE(r.recording.sha256_reference);  // null: no reference.csv
  ASSERT_TRUE(r.recording.sha256_meta);
  EXPECT_EQ(*r.recording.sha256_meta, std::string(64, 'c'));
  ASSERT_TRUE(r.window_s);
  EXPECT_DOUBLE_EQ(r.window_s->second, 135.25);
  EXPECT_EQ(r.observations.value_or(""), "pos,vel");
  EXPECT_DOUBLE_EQ(r.coefficients.errors.accel.bias(2), 4e-3);
  EXPECT_TRUE(r.coefficients.extra.contains("time_offset"));  // catalogue keys stay with the set
  ASSERT_TRUE(r.correction);
  EXPECT_DOUBLE_EQ(r.correction->errors.gyro.M(0, 1), 2e-5);
  ASSERT_TRUE(r.mounting);
  EXPECT_DOUBLE_EQ(r.mounting->value_deg(2), 90.3);
  EXPECT_DOUBLE_EQ(r.mounting->sigma_deg(1), 0.02);
  ASSERT_TRUE(r.determined_by);
  EXPECT_EQ(r.determined_by->coefficients.size(), 24u);
  EXPECT_EQ(r.determined_by->coefficients.at("accel.M.zz").stage, "both");
  EXPECT_FALSE(r.determined_by->coefficients.at("gyro.bias.x").parent_sigma);
  EXPECT_EQ(r.determined_by->mounting.size(), 3u);
  EXPECT_EQ(r.priors_mode, "data-sheet");
  EXPECT_EQ(r.priors_device_class, "ADIS16488A");
  EXPECT_EQ(r.extra.at("adaptive_noise").at("scale_max"), 7.8e5);  // free-form sections kept
  EXPECT_FALSE(r.extra.contains("coefficients"));
  ASSERT_EQ(r.nis.size(), 2u);  // consistency, by observation
  EXPECT_EQ(r.nis.at("position").epochs.value_or(-1), 120);
  EXPECT_FALSE(r.nis.at("position").expected_nis);
  EXPECT_EQ(r.nis.at("nhc").equation.value_or(""), "obs_nhc.cpp");
  EXPECT_EQ(r.nis.at("nhc").rejected.value_or(-1), 4);
  EXPECT_DOUBLE_EQ(r.nis.at("nhc").fraction_within_95pct.value_or(0), 0.96);
  ASSERT_TRUE(r.outages);  // qc.outages
  EXPECT_DOUBLE_EQ(r.outages->fix_sigma_h_m.value_or(0), 0.02);
  ASSERT_EQ(r.outages->not_placed.size(), 1u);
  EXPECT_EQ(r.outages->not_placed[0], "too short");
  ASSERT_EQ(r.outages->sets.size(), 2u);
  EXPECT_EQ(r.outages->sets[1].name, "in-motion");
  EXPECT_DOUBLE_EQ(r.outages->sets[0].per_length.at(0).median_max_m.value_or(0), 3.5);
  EXPECT_FALSE(r.outages->sets[1].per_length.at(0).count);
  ASSERT_EQ(r.outages->outages.size(), 1u);
  EXPECT_DOUBLE_EQ(r.outages->outages[0].max_m.at("in-motion"), 1.25);
  EXPECT_EQ(r.outages->outages[0].end_m.count("in-motion"), 0u);
  EXPECT_TRUE(is_drive_result(sample()));
  EXPECT_FALSE(is_drive_result(sample()["coefficients"]));
}

std::string refused_field(const json& j);  // below

// qc of the ΔS QC (a drive with a reference): the sets with their marks and series, and the older
// "series" form; a null number (NaN when written) reads as NaN.
TEST(DriveResultCodec, TheDeltaSQcIsTyped) {
  json j = sample();
  j["qc"] = json::parse(R"J({"from_s": 100.0, "horizon_s": 60.0, "sample": "out-of-sample (after the fit window)",
    "sets": [{"name": "input", "final_cpe_m": 12.5, "max_cpe_m": 14.0, "cpe_m_at": {"10": 0.5, "30": null},
              "cpe_series": {"t_s": [0.0, 1.0, 2.0], "cpe_m": [0.0, 0.25, null]}},
             {"name": "in-motion", "final_cpe_m": 2.5}],
    "series": {"t_s": [0.0, 1.0], "input": [0.0, 0.5]}})J");
  const DriveResult r = drive_result_from_json(j, "R.json");
  EXPECT_EQ(drive_result_to_json(r), j);  // written as given
  EXPECT_DOUBLE_EQ(r.cpe.from_s.value_or(0), 100.0);
  EXPECT_DOUBLE_EQ(r.cpe.horizon_s.value_or(0), 60.0);
  EXPECT_EQ(r.cpe.sample.value_or(""), "out-of-sample (after the fit window)");
  ASSERT_EQ(r.cpe.sets.size(), 2u);
  EXPECT_EQ(r.cpe.sets[0].name.value_or(""), "input");
  EXPECT_DOUBLE_EQ(r.cpe.sets[0].cpe_m_at.at("10"), 0.5);
  EXPECT_TRUE(std::isnan(r.cpe.sets[0].cpe_m_at.at("30")));
  ASSERT_EQ(r.cpe.sets[0].series_cpe_m.size(), 3u);
  EXPECT_DOUBLE_EQ(r.cpe.sets[0].series_cpe_m[1], 0.25);
  EXPECT_TRUE(std::isnan(r.cpe.sets[0].series_cpe_m[2]));
  EXPECT_FALSE(r.cpe.sets[1].max_cpe_m);
  EXPECT_TRUE(r.cpe.sets[1].series_t_s.empty());
  ASSERT_TRUE(r.cpe.series_t_s);
  EXPECT_DOUBLE_EQ(r.cpe.series.at("input").at(1), 0.5);
  EXPECT_FALSE(r.outages);
  const auto refused = [&](auto edit) {
    json k = j;
    edit(k);
    return refused_field(k);
  };
  EXPECT_EQ(refused([](json& k) { k["qc"]["horizon_s"] = "60"; }), "qc.horizon_s");
  EXPECT_EQ(refused([](json& k) { k["qc"]["sets"] = {{"name", "input"}}; }), "qc.sets");
  EXPECT_EQ(refused([](json& k) { k["qc"]["sets"][1]["final_cpe_m"] = "2.5"; }), "qc.sets[1].final_cpe_m");
  EXPECT_EQ(refused([](json& k) { k["qc"]["sets"][0]["cpe_m_at"]["10"] = "x"; }), "qc.sets[0].cpe_m_at.10");
  EXPECT_EQ(refused([](json& k) { k["qc"]["sets"][0]["cpe_series"]["t_s"][1] = true; }), "qc.sets[0].cpe_series.t_s[1]");
  EXPECT_EQ(refused([](json& k) { k["qc"]["series"]["input"] = 3; }), "qc.series.input");
}

// The antenna blocks and the adaptive noise, read from the sections kept as written.
TEST(DriveResultCodec, TheEstimatesTheSummaryPrintsAreTyped) {
  json j = sample();
  j["lever_arm_m"] = {{"value", {-1.0, 0.25, -0.25}}, {"sigma", {0.05, 0.02, 0.1}}, {"prior", 0.1}, {"nominal", {-1.0, 0.2, -0.3}},
                      {"correction", {0.0, 0.05, 0.05}}, {"observable", {false, true, false}}, {"how", "text"}};
  j["time_offset_s"] = {{"value", 7e-5}, {"sigma", 3.5e-3}, {"prior", 0.02}, {"observable", true}};
  j["adaptive_noise"] = {{"enabled", true}, {"scale_max", 6.5e5}, {"scale_end", 3.5e5}, {"increases", 6}};
  const DriveResult r = drive_result_from_json(j, "R.json");
  EXPECT_EQ(drive_result_to_json(r), j);
  ASSERT_TRUE(r.lever_arm);
  EXPECT_DOUBLE_EQ(r.lever_arm->value(1), 0.25);
  EXPECT_DOUBLE_EQ(r.lever_arm->nominal(2), -0.3);
  EXPECT_TRUE(r.lever_arm->observable[1]);
  EXPECT_FALSE(r.lever_arm->observable[2]);
  ASSERT_TRUE(r.time_offset);
  EXPECT_DOUBLE_EQ(r.time_offset->sigma, 3.5e-3);
  ASSERT_TRUE(r.adaptive_noise);
  EXPECT_EQ(r.adaptive_noise->increases, 6);
  EXPECT_DOUBLE_EQ(r.adaptive_noise->scale_end, 3.5e5);
  EXPECT_FALSE(drive_result_from_json(sample(), "R.json").lever_arm);  // absent: not estimated
  const auto refused = [&](auto edit) {
    json k = j;
    edit(k);
    return refused_field(k);
  };
  EXPECT_EQ(refused([](json& k) { k["lever_arm_m"]["value"] = {1.0, 2.0}; }), "lever_arm_m.value");
  EXPECT_EQ(refused([](json& k) { k["lever_arm_m"]["observable"][2] = "no"; }), "lever_arm_m.observable[2]");
  EXPECT_EQ(refused([](json& k) { k["lever_arm_m"].erase("prior"); }), "lever_arm_m.prior");
  EXPECT_EQ(refused([](json& k) { k["time_offset_s"]["sigma"] = "3 ms"; }), "time_offset_s.sigma");
  EXPECT_EQ(refused([](json& k) { k["adaptive_noise"]["increases"] = -1; }), "adaptive_noise.increases");
  EXPECT_EQ(refused([](json& k) { k["adaptive_noise"]["scale_max"] = "big"; }), "adaptive_noise.scale_max");
}

TEST(DriveResultCodec, TheEffectsTheFitAppliedAreTyped) {
  json j = sample();
  j["effects"] = {{"source", "in memory"}, {"applied", {"lever_arm", "time_offset"}},
                  {"ignored", {{{"key", "misalignment"}, {"reason", "bench term"}}}}, {"time_offset_s", 0.004}};
  const DriveResult r = drive_result_from_json(j, "R.json");
  EXPECT_EQ(drive_result_to_json(r), j);
  ASSERT_TRUE(r.effects);
  EXPECT_EQ(r.effects->applied, (std::vector<std::string>{"lever_arm", "time_offset"}));
  ASSERT_EQ(r.effects->ignored.size(), 1u);
  EXPECT_EQ(r.effects->ignored[0].second, "bench term");
  EXPECT_DOUBLE_EQ(r.effects->time_offset_s.value_or(0), 0.004);
  json k = j;
  k["effects"]["applied"][1] = 3;
  EXPECT_EQ(refused_field(k), "effects.applied[1]");
  k = j;
  k["effects"]["ignored"][0].erase("reason");
  EXPECT_EQ(refused_field(k), "effects.ignored[0].reason");
}

TEST(DriveResultCodec, ReadsTheOlderFormsTheStoreHasAlwaysTaken) {
  json j = sample();
  j.erase("format");
  j["device"] = "U7";                          // the serial alone
  j["coefficients"].erase("device");
  j["correction"].erase("format");
  j["correction"].erase("device");
  j["mounting_rpy_deg"] = {1.0, 2.0, 3.0};
  j["mounting_rpy_sigma_deg"] = {0.1, nullptr, 0.3};
  j.erase("reference_system");
  j["reference"] = {{"name", "FOG INS"}};
  const DriveResult r = drive_result_from_json(j, "old.json");
  EXPECT_TRUE(is_drive_result(j));  // no format, but coefficients
  EXPECT_EQ(r.device.serial, "U7");
  EXPECT_TRUE(r.device.model.empty());
  EXPECT_EQ(r.coefficients.device.serial, "U7");
  EXPECT_DOUBLE_EQ(r.mounting->value_deg(1), 2.0);
  EXPECT_TRUE(std::isinf(r.mounting->sigma_deg(1)));
  EXPECT_DOUBLE_EQ(r.mounting->sigma_deg(2), 0.3);
  EXPECT_EQ(r.reference_system, R"({"name":"FOG INS"})");
}

// Issue 35 item 8: where the recording is (URI) and the digest of all its files, typed, required on
// write; a result written before them still reads, and is never written back without them.
TEST(DriveResultCodec, TheRecordingsUriAndDigestAreTypedRequiredOnWriteOptionalOnRead) {
  const DriveResult r = drive_result_from_json(sample(), "R.json");
  EXPECT_EQ(r.recording.uri.value_or(""), "file://station1/drives/d1");
  EXPECT_EQ(r.recording.digest.value_or(""), std::string(64, 'e'));
  EXPECT_TRUE(r.recording.extra.empty()) << r.recording.extra.dump();
  json old = sample();
  old["recording"].erase("uri");
  old["recording"].erase("digest_sha256");
  DriveResult o = drive_result_from_json(old, "old.json");
  EXPECT_FALSE(o.recording.uri);
  EXPECT_FALSE(o.recording.digest);
  try {
    (void)drive_result_to_json(o);
    ADD_FAILURE() << "a result without its recording's URI was written";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "recording.uri");
  }
  o.recording.uri = "file://h/x";
  try {
    (void)drive_result_to_json(o);
    ADD_FAILURE() << "a result without its recording's digest was written";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "recording.digest_sha256");
  }
}

// The refusal's field, checking that it names the file; "" when the input was accepted.
std::string refused_field(const json& j) {
  try {
    (void)drive_result_from_json(j, "R.json");
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "R.json") << e.what();
    EXPECT_NE(std::string(e.what()).find("R.json"), std::string::npos);
    return e.field().empty() ? "(no field)" : e.field();
  }
  return "";
}

TEST(DriveResultCodec, MalformedInputIsRefusedNamingTheFileAndTheKey) {
  const auto with = [](auto edit) {
    json j = sample();
    edit(j);
    return j;
  };
  EXPECT_EQ(refused_field(with([](json& j) { j.erase("device"); })), "device");
  EXPECT_EQ(refused_field(with([](json& j) { j["device"] = 7; })), "device");
  EXPECT_EQ(refused_field(with([](json& j) { j["format"] = "calbench-inmotion-result/2"; })), "format");
  EXPECT_EQ(refused_field(with([](json& j) { j.erase("recording"); })), "recording");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["sha256"] = "abc"; })), "recording.sha256");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["path"] = 1; })), "recording.path");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["uri"] = "/drives/d1"; })), "recording.uri");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["uri"] = 1; })), "recording.uri");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["digest_sha256"] = "abc"; })), "recording.digest_sha256");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["sha256_meta"] = 1; })), "recording.sha256_meta");
  EXPECT_EQ(refused_field(with([](json& j) { j["recording"]["device"]["serial"] = "U8"; })), "recording.device.serial");
  EXPECT_EQ(refused_field(with([](json& j) { j.erase("coefficients"); })), "coefficients");
  EXPECT_EQ(refused_field(with([](json& j) { j["coefficients"]["gyro"]["bias"][0] = "0.1"; })), "coefficients.gyro.bias[0]");
  EXPECT_EQ(refused_field(with([](json& j) { j["coefficients"]["accel"].erase("M"); })), "coefficients.accel.M");
  EXPECT_EQ(refused_field(with([](json& j) { j["correction"]["device"]["serial"] = "U8"; })), "correction.device.serial");
  EXPECT_EQ(refused_field(with([](json& j) { j["mounting_rpy_deg"] = {1, 2}; })), "mounting_rpy_deg");
  EXPECT_EQ(refused_field(with([](json& j) { j["mounting_rpy_deg"]["sigma"][0] = -1.0; })), "mounting_rpy_deg.sigma[0]");
  EXPECT_EQ(refused_field(with([](json& j) { j["window_s"] = {1.0}; })), "window_s");
  EXPECT_EQ(refused_field(with([](json& j) { j["window_s"][1] = "end"; })), "window_s[1]");
  EXPECT_EQ(refused_field(with([](json& j) { j["smoothed"] = "yes"; })), "smoothed");
  EXPECT_EQ(refused_field(with([](json& j) { j["observations"] = 3; })), "observations");
  EXPECT_EQ(refused_field(with([](json& j) { j["priors"] = "data-sheet"; })), "priors");
  EXPECT_EQ(refused_field(with([](json& j) { j["consistency"] = 3; })), "consistency");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"] = "fine"; })), "qc");
  EXPECT_EQ(refused_field(with([](json& j) { j["consistency"]["nhc"] = 2; })), "consistency.nhc");
  EXPECT_EQ(refused_field(with([](json& j) { j["consistency"]["nhc"]["mean_nis"] = "1.9"; })), "consistency.nhc.mean_nis");
  EXPECT_EQ(refused_field(with([](json& j) { j["consistency"]["nhc"]["epochs"] = 9.5; })), "consistency.nhc.epochs");
  EXPECT_EQ(refused_field(with([](json& j) { j["consistency"]["nhc"]["equation"] = 13; })), "consistency.nhc.equation");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"] = {1, 2}; })), "qc.outages");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["sample"] = 1; })), "qc.outages.sample");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["fix_sigma_h_m"] = "2 cm"; })), "qc.outages.fix_sigma_h_m");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["sets"][1].erase("name"); })), "qc.outages.sets[1].name");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["sets"][0]["per_length"] = 3; })),
            "qc.outages.sets[0].per_length");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["sets"][0]["per_length"][0]["median_max_m"] = true; })),
            "qc.outages.sets[0].per_length[0].median_max_m");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["outages"][0]["max_m"]["none"] = "far"; })),
            "qc.outages.outages[0].max_m.none");
  EXPECT_EQ(refused_field(with([](json& j) { j["qc"]["outages"]["not_placed"] = "none"; })), "qc.outages.not_placed");
  EXPECT_EQ(refused_field(with([](json& j) { j["determined_by"] = "bench"; })), "determined_by");
  EXPECT_EQ(refused_field(with([](json& j) { j["determined_by"]["coefficients"]["gyro.bias.x"]["stage"] = "factory"; })),
            "determined_by.coefficients.gyro.bias.x.stage");
  EXPECT_EQ(refused_field(with([](json& j) { j["determined_by"]["coefficients"]["gyro.bias.w"] = stage("drive", 0.9); })),
            "determined_by.coefficients.gyro.bias.w");
  EXPECT_EQ(refused_field(with([](json& j) { j["determined_by"]["mounting"]["mount.x"]["ratio"] = "x"; })),
            "determined_by.mounting.mount.x.ratio");
  EXPECT_EQ(refused_field(json::array()), "(no field)");
  EXPECT_EQ(refused_field(sample()), "");  // the sample itself is accepted
  // A truncated file: the parser names the file and the line, the codec never sees it.
  const std::string text = sample().dump(2);
  try {
    (void)drive_result_from_json(parse_json_text(text.substr(0, text.size() / 2), "R.json"), "R.json");
    ADD_FAILURE() << "a truncated RESULT.json was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "R.json");
    EXPECT_GT(e.line(), 1u);
  }
}

}  // namespace
}  // namespace calbench
