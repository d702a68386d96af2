#include <gtest/gtest.h>

#include "common/input_error.hpp"
#include "common/units.hpp"
#include "db/approval.hpp"
#include "db/signer.hpp"
#include "db/inmotion_import.hpp"
#include "db_test_util.hpp"

namespace calbench::db {
namespace {
using namespace calbench::units;

bool has_reason(const ApprovalCheck& c, const std::string& needle) {
  for (const auto& r : c.reasons)
    if (r.find(needle) != std::string::npos) return true;
  return false;
}

TEST(DbApproval, GoodSetIsApprovedAndAudited) {
  test::TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  Store q(t.db(), {}, test::qc_actor());  // the QC engineer who signs
  const auto id = s.store_bench({"ADIS16488A", "P1", ""}, test::bench_run(), test::payload("P1", test::random_errors(1))).set_id;
  const auto r = approve_checked(q, id, default_thresholds());
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(s.get_set(id).status, SetStatus::approved);
  // A second approval changes nothing and is not a refusal (nothing in the audit log).
  const auto audit = s.audit_of_device(s.get_set(id).device_id).size();
  const auto again = approve_checked(q, id, default_thresholds());
  EXPECT_TRUE(again.already);
  EXPECT_TRUE(again.reasons.empty());
  EXPECT_EQ(s.get_set(id).status, SetStatus::approved);
  EXPECT_EQ(s.audit_of_device(s.get_set(id).device_id).size(), audit);
}

TEST(DbApproval, CombinedSetWaitsForItsParent) {
  test::TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  Store q(t.db(), {}, test::qc_actor());  // the QC engineer who signs
  const auto parent = s.store_bench({"ADIS16488A", "P9", ""}, test::bench_run(), test::payload("P9", test::random_errors(9))).set_id;
  // The combined set refines its parent (the same figures here: no move, no σ growth to refuse).
  const SensorErrors e = test::random_errors(9);
  std::int64_t child = 0;
  s.connection().write_transaction([&] {
    child = s.insert_set_locked(s.get_set(parent).device_id, SetSource::combined, test::payload("P9", e), e, parent,
                                std::nullopt, std::nullopt, nullptr);
  });
  Thresholds th = default_thresholds();
  th.require_qc = false;  // this test is about the parent only
  const auto r = approve_checked(q, child, th);
  EXPECT_FALSE(r.ok);
  bool named = false;
  for (const auto& w : r.reasons) named = named || w.find("parent set " + std::to_string(parent) + " is draft") != std::string::npos;
  EXPECT_TRUE(named);
  // The report's verdict (check_standing) names the same reason, in the same words.
  const auto standing = check_standing(s, s.get_set(child), th);
  EXPECT_FALSE(standing.ok);
  EXPECT_TRUE(has_reason(standing, "parent set " + std::to_string(parent) + " is draft: approve the set it refines first"));
  EXPECT_TRUE(approve_checked(q, parent, default_thresholds()).ok);
  EXPECT_TRUE(check_standing(s, s.get_set(child), th).ok);
  EXPECT_TRUE(approve_checked(q, child, th).ok);
}

TEST(DbApproval, EachThresholdRefusesWithItsReason) {
  test::TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  Store q(t.db(), {}, test::qc_actor());  // the QC engineer who signs
  SensorErrors e = test::random_errors(2);
  e.gyro.bias(1) = 2.0 * kDeg;            // 7200 °/h > 3600
  e.accel.M(2, 2) = 0.05;                 // 50000 ppm scale > 25000
  e.gyro.M(0, 1) = 0.01;                  // skew 10000 ppm > 5000
  e.accel.sigma_bias(0) = 5 * kMilliG;    // σ 5 mg > 2
  e.gyro.sigma_M(2, 0) = kUnknownSigma;   // not estimated
  const auto id = s.store_bench({"ADIS16488A", "P2", ""}, test::bench_run(false), test::payload("P2", e)).set_id;
  const auto r = approve_checked(q, id, default_thresholds());
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(has_reason(r, "gyro bias y")) ;
  EXPECT_TRUE(has_reason(r, "accel M[zz]"));
  EXPECT_TRUE(has_reason(r, "gyro M[xy]"));
  EXPECT_TRUE(has_reason(r, "accel bias x: σ"));
  EXPECT_TRUE(has_reason(r, "gyro M[zx]: σ unknown"));
  EXPECT_TRUE(has_reason(r, "QC gyro.residual_rms"));
  EXPECT_EQ(r.reasons.size(), 6u);
  EXPECT_EQ(s.get_set(id).status, SetStatus::draft);
  bool refused = false;
  for (const auto& a : s.audit_of_device(s.get_set(id).device_id)) refused = refused || a.action == "approve-refused";
  EXPECT_TRUE(refused);
}

TEST(DbApproval, ConfigLoosensOrTightensAndRejectsTypos) {
  SensorErrors e = test::random_errors(3);
  e.gyro.sigma_M(2, 0) = kUnknownSigma;
  CoefficientSetRecord set;
  set.errors = e;
  const std::vector<QcResult> qc = {QcResult{"cpe_600s", 10, 100, true, "m", kOutOfSample, "|value| ≤ threshold"}};
  EXPECT_FALSE(check_approval(set, qc, default_thresholds()).ok);
  Thresholds loose = parse_thresholds(R"({"allow_unknown_sigma": true})", "t.json");
  EXPECT_TRUE(check_approval(set, qc, loose).ok);
  Thresholds tight = parse_thresholds(R"({"allow_unknown_sigma": true, "gyro": {"max_sigma_bias_dph": 0.01},
                                          "required_qc_metrics": ["cpe_600s", "nis_pos"]})", "t.json");
  const auto r = check_approval(set, qc, tight);
  EXPECT_TRUE(has_reason(r, "gyro bias x: σ"));
  EXPECT_TRUE(has_reason(r, "'nis_pos' missing"));
  EXPECT_FALSE(has_reason(r, "'cpe_600s' missing"));
  EXPECT_TRUE(check_approval(set, {}, loose).reasons.size() == 1);  // require_qc
  EXPECT_TRUE(check_approval(set, {}, parse_thresholds(R"({"allow_unknown_sigma": true, "require_qc": false})", "t")).ok);
  EXPECT_THROW(parse_thresholds(R"({"gyro": {"max_sigma_bias_degh": 1}})", "t.json"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"gyro": {"max_sigma_bias_dph": -1}})", "t.json"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"require_qc": "yes"})", "t.json"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"gyro": )", "t.json"), InputError);
}

// The report's verdict: every threshold of approval, whatever the status; the QC reason says why.
TEST(DbApproval, ThresholdCheckIgnoresStatusAndQcReasonSaysWhy) {
  CoefficientSetRecord set;
  set.id = 7;
  set.errors = test::random_errors(4);
  set.status = SetStatus::approved;
  const QcResult worse{"sets.in-motion.final_cpe_m", 250, 206.2, false, "m", kOutOfSample,
                       "never worse than the set the fit started from"};
  EXPECT_TRUE(check_thresholds(set, {QcResult{"x", 1, 2, true, "m", kInSample, "|value| ≤ threshold"}}, default_thresholds()).ok);
  EXPECT_FALSE(check_approval(set, {QcResult{"x", 1, 2, true, "m", kInSample, "|value| ≤ threshold"}}, default_thresholds()).ok);
  const auto r = check_thresholds(set, {worse}, default_thresholds());
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_TRUE(has_reason(r, "never worse than the set the fit started from"));
  EXPECT_TRUE(has_reason(r, "out-of-sample"));
  const auto lines = describe_thresholds(parse_thresholds(R"({"gyro": {"max_sigma_bias_dph": 7}, "required_qc_metrics": ["m1"]})", "t"));
  bool sigma = false, required = false;
  for (const auto& l : lines) {
    sigma = sigma || l.find("σ bias ≤ 7 °/h") != std::string::npos;
    required = required || l.find("m1") != std::string::npos;
  }
  EXPECT_TRUE(sigma && required);
}

TEST(DbApproval, OutageThresholdPerLengthOnTheResultSet) {
  CoefficientSetRecord set;
  set.id = 8;
  set.errors = test::random_errors(5);
  const Thresholds t = parse_thresholds(R"({"allow_unknown_sigma": true, "max_outage_median_m": {"15": 5, "60": 40}})", "t.json");
  ASSERT_EQ(t.max_outage_median_m.size(), 2u);
  EXPECT_DOUBLE_EQ(t.max_outage_median_m.at(15.0), 5.0);
  // Informative outage figures as db import-inmotion stores them (outage_metric names them).
  const auto metric = [](const std::string& set_name, double L, double v) {
    return QcResult{outage_metric(set_name, L, "median_max_m"), v, std::nullopt, true, "m", kInSample, ""};
  };
  EXPECT_EQ(outage_metric("in-motion", 15, "median_max_m"), "outages.in-motion.15s.median_max_m");
  // Within the limits; the raw data's large errors are not the set's.
  EXPECT_TRUE(check_thresholds(set, {metric("in-motion", 15, 4.9), metric("in-motion", 60, 39), metric("none", 15, 900)}, t).ok);
  const auto r = check_thresholds(set, {metric("in-motion", 15, 4.9), metric("in-motion", 60, 41)}, t);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_TRUE(has_reason(r, "outages.in-motion.60s.median_max_m = 41 m exceeds the outage threshold 40 m"));
  // A drive without outage QC (a reference drive) is not refused for it.
  EXPECT_TRUE(check_thresholds(set, {QcResult{"x", 1, 2, true, "m", kInSample, "|value| ≤ threshold"}}, t).ok);
  bool described = false;
  for (const auto& l : describe_thresholds(t)) described = described || l.find("60 s ≤ 40 m") != std::string::npos;
  EXPECT_TRUE(described);
  EXPECT_THROW(parse_thresholds(R"({"max_outage_median_m": {"abc": 5}})", "t.json"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"max_outage_median_m": {"15": -1}})", "t.json"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"max_outage_median_m": [5]})", "t.json"), InputError);
}

TEST(DbApproval, NeedsANamedOperatorOtherThanWhoStoredTheSet) {
  test::TempDir t;
  Store station(t.db(), test::create_opts(), Actor{"sam", "line-1", "CALBENCH_OPERATOR", "samos"});
  const auto id =
      station.store_bench({"ADIS16488A", "S1", ""}, test::bench_run(), test::payload("S1", test::random_errors(4))).set_id;
  EXPECT_EQ(station.get_set(id).created_by, "sam@line-1");
  // An OS user records who ran a command but does not sign.
  Store os(t.db(), {}, Actor{"root", "qc-desk", "OS user", "root"});
  auto r = approve_checked(os, id, default_thresholds());
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(has_reason(r, "approval needs a named operator"));
  // Four-eyes (the default): the operator who stored the set cannot approve it.
  r = approve_checked(station, id, default_thresholds());
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(has_reason(r, "four-eyes: set " + std::to_string(id) + " was stored by 'sam'"));
  EXPECT_EQ(station.get_set(id).status, SetStatus::draft);
  // A setting is changed only by a named operator, to a known value, and audited.
  EXPECT_THROW(os.set_setting(kFourEyes, "off"), DbError);
  EXPECT_THROW(station.set_setting(kFourEyes, "maybe"), InputError);
  EXPECT_THROW(station.set_setting("three_eyes", "on"), InputError);
  EXPECT_EQ(station.setting(kFourEyes), "on");
  station.set_setting(kFourEyes, "off");  // a one-person lab
  EXPECT_EQ(os.setting(kFourEyes), "off");
  const auto all = os.settings();
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].changed_by, "sam@line-1");
  EXPECT_FALSE(all[0].changed_at.empty());
  r = approve_checked(station, id, default_thresholds());
  EXPECT_TRUE(r.ok);
  // The approval names its signer in the audit log.
  bool signed_entry = false;
  for (const auto& a : os.audit_of_device(os.get_set(id).device_id))
    signed_entry = signed_entry || (a.action == "status" && a.user == "sam" &&
                                    a.detail.find("signed by sam (CALBENCH_OPERATOR; OS user samos, not authenticated (SQLite)), stored by sam (OS "
                                                  "user samos, not authenticated (SQLite)), four-eyes off") !=
                                        std::string::npos);
  EXPECT_TRUE(signed_entry);
}

// Issue 35: on SQLite (no authentication) four-eyes compares the typed names ignoring case and
// runs of whitespace, and the OS user is recorded beside each signature.
TEST(DbApproval, FourEyesIgnoresCaseAndSpacingOfNamesOnSqlite) {
  EXPECT_EQ(normalized_name("  Tess \t  TUCK "), "tess tuck");
  EXPECT_TRUE(same_person("Tess Tuck", "tess   tuck"));
  EXPECT_FALSE(same_person("Tess Tuck", "Tess Tucker"));
  test::TempDir t;
  Actor tess{"Tess  Tuck", "line-1", "--operator", "tessos"};
  Store station(t.db(), test::create_opts(), tess);
  const auto id =
      station.store_bench({"ADIS16488A", "S1", ""}, test::bench_run(), test::payload("S1", test::random_errors(4))).set_id;
  EXPECT_EQ(station.get_set(id).created_by_login, "tessos");
  for (const char* variant : {"tess tuck", "TESS TUCK", "Tess\tTuck"}) {
    Store s(t.db(), {}, Actor{variant, "qc-desk", "--operator", "other"});
    const auto r = approve_checked(s, id, default_thresholds());
    EXPECT_FALSE(r.ok) << variant;
    EXPECT_TRUE(has_reason(r, "four-eyes: set " + std::to_string(id) + " was stored by 'Tess  Tuck'")) << variant;
  }
  EXPECT_EQ(station.get_set(id).status, SetStatus::draft);
  Store quinn(t.db(), {}, Actor{"Quinn", "qc-desk", "--operator", "quinnos"});
  ASSERT_TRUE(approve_checked(quinn, id, default_thresholds()).ok);
  bool signed_entry = false;
  for (const auto& a : quinn.audit_of_device(quinn.get_set(id).device_id))
    signed_entry = signed_entry || (a.action == "status" && a.login == "quinnos" &&
                                    a.detail.find("signed by Quinn (--operator; OS user quinnos, not authenticated "
                                                  "(SQLite)), stored by Tess  Tuck (OS user tessos, not authenticated "
                                                  "(SQLite))") != std::string::npos);
  EXPECT_TRUE(signed_entry);
}

TEST(DbApproval, OperatorNamesAreChecked) {
  EXPECT_NO_THROW(check_operator_name("Anna Müller", "--operator"));
  for (const std::string& bad : std::vector<std::string>{"", " anna", "anna ", "a@b", "a\nb", std::string(65, 'x')})
    EXPECT_THROW(check_operator_name(bad, "--operator"), InputError) << bad;
}

// Issue 35 tryout: names that look like another's and differ only in invisible characters, Unicode
// spaces or a letter from another script must not pass four-eyes as a second person.
TEST(DbApproval, LookAlikeOperatorNamesAreRefusedOrSamePerson) {
  auto problem = [](const std::string& name) { return operator_name_problem(name); };
  // One script per name, non-ASCII included: valid.
  for (const std::string& ok : {"J\u00fcrgen Wei\u00df", "\u0141ukasz", "\u0410\u043d\u043d\u0430 \u041f\u0435\u0442\u0440\u043e\u0432\u0430",
                                 "\u0391\u03bd\u03bd\u03b1", "Anna \u0410\u043d\u043d\u0430"})
    EXPECT_EQ(problem(ok), "") << ok;
  // Invisible and format characters: refused naming the code point.
  const std::vector<std::pair<std::string, std::string>> invisible = {
      {"Tess\u200b Tuck", "U+200B"}, {"Tess Tuck\u200b", "U+200B"}, {"Tess\u00adTuck", "U+00AD"},
      {"Tess\u202eTuck", "U+202E"},  {"Tess\u2060Tuck", "U+2060"},  {"\ufeffTess Tuck", "U+FEFF"},
      {"Tess\u200dTuck", "U+200D"}};
  for (const auto& [name, cp] : invisible) {
    const std::string p = problem(name);
    EXPECT_NE(p.find("invisible or format character " + cp), std::string::npos) << p;
  }
  // Invalid UTF-8 (a lone continuation byte, a truncated sequence, an overlong '/').
  for (const std::string& bad : {std::string("Tess\x80Tuck"), std::string("Tess \xc3"), std::string("Tess\xc0\xafTuck")})
    EXPECT_NE(problem(bad).find("not valid UTF-8"), std::string::npos) << problem(bad);
  // A Cyrillic е (U+0435) or Greek ο (U+03BF) among Latin letters of one word.
  EXPECT_NE(problem("T\u0435ss Tuck").find("mixes Latin and Cyrillic letters in the word 'T\u0435ss' (U+0435)"), std::string::npos)
      << problem("T\u0435ss Tuck");
  EXPECT_NE(problem("Tess T\u03bfck").find("mixes Latin and Greek letters"), std::string::npos);
  // Unicode spaces are spaces: the same person as with an ASCII space; at an edge, refused as a space.
  for (const std::string& sp : {"\u00a0", "\u1680", "\u2002", "\u2009", "\u200a", "\u202f", "\u205f", "\u3000"}) {
    EXPECT_EQ(problem("Tess" + sp + "Tuck"), "") << sp;
    EXPECT_TRUE(same_person("Tess" + sp + "Tuck", "tess tuck")) << sp;
    EXPECT_NE(problem("Tess Tuck" + sp).find("start or end with a space"), std::string::npos) << sp;
  }
  EXPECT_EQ(normalized_name("  J\u00dcRGEN\u00a0\u00a0 Wei\u00df "), "j\u00dcrgen wei\u00df");
  EXPECT_FALSE(same_person("J\u00fcrgen", "Jurgen"));
}

// Four-eyes on SQLite with the tryout's look-alike names: each is refused as input before anything
// is approved, or (a Unicode space) taken for the same person.
TEST(DbApproval, FourEyesHoldsAgainstLookAlikeNames) {
  test::TempDir t;
  Store tess(t.db(), test::create_opts(), Actor{"Tess Tuck", "line-7", "--operator", "tessos"});
  const auto id =
      tess.store_bench({"ADIS16488A", "S1", ""}, test::bench_run(), test::payload("S1", test::random_errors(4))).set_id;
  for (const std::string& look_alike : {"Tess\u200b Tuck", "Tess Tuck\u200b", "T\u0435ss Tuck"})
    EXPECT_THROW(check_operator_name(look_alike, "--operator"), InputError) << look_alike;
  Store nbsp(t.db(), {}, Actor{"Tess\u00a0Tuck", "qc-desk", "--operator", "otheros"});
  const ApprovalCheck r = approve_checked(nbsp, id, default_thresholds());
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(has_reason(r, "four-eyes: set " + std::to_string(id) + " was stored by 'Tess Tuck'"));
  EXPECT_EQ(nbsp.get_set(id).status, SetStatus::draft);
}

}  // namespace
}  // namespace calbench::db
