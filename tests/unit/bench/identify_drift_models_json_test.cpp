// drift_models (MODELS.json of `calbench identify`, mergeable into coefficients.json): round trip,
// survival through the coefficient reader/writer, and validation errors naming the key.
#include <gtest/gtest.h>

#include "bench/io/coefficients_json.hpp"
#include "bench/io/drift_models_json.hpp"
#include "common/input_error.hpp"

namespace calbench {
namespace {

namespace id = identification;
using nlohmann::json;

json models() {
  json j;
  j["format"] = "calbench-drift-models/1";
  j["drift_models"]["gx_rad_s"] = drift_model_json({id::DriftModelKind::exponential, 2.5e-5, 1.0 / 300, 0}, 1.0, "gyro", 0, "rad/s");
  j["drift_models"]["az_m_s2"] = drift_model_json({id::DriftModelKind::exp_cosine, 1e-3, 0.01, 0.02}, 1.0, "accel", 2, "m/s^2");
  return j;
}

TEST(IdentifyDriftModelsJson, RoundTrip) {
  const auto v = drift_models_from_json(models(), "models.json");
  ASSERT_EQ(v.size(), 2u);
  const auto g = find_drift_model(v, "gyro", 0);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->model.kind, id::DriftModelKind::exponential);
  EXPECT_DOUBLE_EQ(g->model.sigma, 2.5e-5);
  EXPECT_DOUBLE_EQ(g->model.alpha, 1.0 / 300);
  const auto a = find_drift_model(v, "accel", 2);
  ASSERT_TRUE(a.has_value());
  EXPECT_EQ(a->model.kind, id::DriftModelKind::exp_cosine);
  EXPECT_DOUBLE_EQ(a->model.beta, 0.02);
  EXPECT_FALSE(find_drift_model(v, "gyro", 1).has_value());
  // The written filter is the one shaping_filter() builds.
  const json m = models();
  const json& e = m["drift_models"]["az_m_s2"];
  EXPECT_EQ(e["n_states"], 2);
  EXPECT_EQ(e["H"], json::array({0.0, 1.0}));
  EXPECT_NEAR(e["P_inf"][1][1].get<double>(), 1e-6, 1e-18);
}

TEST(IdentifyDriftModelsJson, SurvivesMergeIntoCoefficients) {
  CoefficientSet c;
  c.device.model = "ADIS16488A";
  c.device.serial = "A00123";
  json cj = coefficients_to_json(c);
  cj["drift_models"] = models()["drift_models"];
  const CoefficientSet back = coefficients_from_json(cj, "coefficients.json");
  const json again = coefficients_to_json(back);
  const auto v = drift_models_from_json(again, "coefficients.json");
  EXPECT_EQ(v.size(), 2u);
}

TEST(IdentifyDriftModelsJson, ErrorsNameTheKey) {
  json j = models();
  j["drift_models"]["gx_rad_s"]["sigma"] = -1.0;
  try {
    drift_models_from_json(j, "m.json");
    FAIL() << "negative sigma accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "drift_models.gx_rad_s.sigma");
    EXPECT_EQ(e.file(), "m.json");
  }
  j = models();
  j["drift_models"]["az_m_s2"]["model"] = "cubic";
  EXPECT_THROW(drift_models_from_json(j, "m.json"), InputError);
  j = models();
  j["drift_models"]["az_m_s2"].erase("alpha");
  EXPECT_THROW(drift_models_from_json(j, "m.json"), InputError);
  EXPECT_THROW(drift_models_from_json(json::object(), "m.json"), InputError);
}

}  // namespace
}  // namespace calbench
