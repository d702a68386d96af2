// MODELS.json → the in-motion filter's six sensor axes (fit drive --drift-models): sensor and axis
// from the entry or its key, units converted to SI, and errors naming the key for what cannot be
// placed.
#include <gtest/gtest.h>

#include "bench/io/drift_models_json.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using nlohmann::json;

json entry(const char* model, double sigma, double alpha) { return {{"model", model}, {"sigma", sigma}, {"alpha", alpha}}; }

TEST(InmotionDriftModelsAssign, KeysUnitsAndExplicitFields) {
  json j;
  j["drift_models"]["gyro_total_y_dph"] = entry("exponential", 20.0, 1.0 / 60);  // identify's old "signal": from the key
  j["drift_models"]["gyro_total_y_dph"]["unit"] = "signal";
  j["drift_models"]["az_m_s2"] = entry("exponential", 2e-3, 0.01);
  j["drift_models"]["mine"] = entry("exp_cosine", 0.5, 0.02);
  j["drift_models"]["mine"].update({{"sensor", "accel"}, {"axis", 0}, {"unit", "mg"}, {"beta", 0.05}});
  const AxisDriftModels m = assign_drift_models(drift_models_from_json(j, "m.json"), "m.json");
  ASSERT_TRUE(m.gyro[1]);
  EXPECT_NEAR(m.gyro[1]->model.sigma, 20.0 * units::kDegPerHour, 1e-18);
  EXPECT_EQ(m.gyro[1]->unit, "rad/s");
  ASSERT_TRUE(m.accel[2]);
  EXPECT_DOUBLE_EQ(m.accel[2]->model.sigma, 2e-3);
  ASSERT_TRUE(m.accel[0]);
  EXPECT_NEAR(m.accel[0]->model.sigma, 0.5 * units::kMilliG, 1e-15);
  EXPECT_EQ(m.accel[0]->model.kind, identification::DriftModelKind::exp_cosine);
  EXPECT_DOUBLE_EQ(m.accel[0]->model.beta, 0.05);
  EXPECT_FALSE(m.gyro[0]);
  EXPECT_FALSE(m.gyro[2]);
  EXPECT_FALSE(m.accel[1]);
}

TEST(InmotionDriftModelsAssign, ColumnNames) {
  for (const char* n : {"gx_rad_s", "gyro_total_x_dph", "gyro_bias_x_dph", "gyro_drift_x_dph"}) {
    const auto c = column_sensor(n);
    ASSERT_TRUE(c) << n;
    EXPECT_EQ(c->sensor, "gyro");
    EXPECT_EQ(c->axis, 0);
  }
  const auto a = column_sensor("accel_total_z_mg");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->axis, 2);
  EXPECT_DOUBLE_EQ(a->si_per_unit, units::kMilliG);
  EXPECT_FALSE(column_sensor("lat_deg"));
  EXPECT_FALSE(column_sensor("gyro_M_xx_ppm"));
}

void expect_error(const json& j, const std::string& field_part) {
  try {
    assign_drift_models(drift_models_from_json(j, "m.json"), "m.json");
    FAIL() << "no error for " << j.dump();
  } catch (const InputError& e) {
    EXPECT_NE(e.field().find(field_part), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "m.json");
  }
}

TEST(InmotionDriftModelsAssign, ErrorsNameTheKey) {
  json unknown;
  unknown["drift_models"]["temperature"] = entry("exponential", 1, 0.1);
  expect_error(unknown, "drift_models.temperature");
  json wrong_unit;
  wrong_unit["drift_models"]["gx_rad_s"] = entry("exponential", 1, 0.1);
  wrong_unit["drift_models"]["gx_rad_s"]["unit"] = "mg";
  expect_error(wrong_unit, "drift_models.gx_rad_s.unit");
  json no_unit;
  no_unit["drift_models"]["g"] = entry("exponential", 1, 0.1);
  no_unit["drift_models"]["g"].update({{"sensor", "gyro"}, {"axis", 2}});
  expect_error(no_unit, "drift_models.g.unit");
  json twice;
  twice["drift_models"]["gx_rad_s"] = entry("exponential", 1e-5, 0.1);
  twice["drift_models"]["gyro_total_x_dph"] = entry("exponential", 2, 0.1);
  expect_error(twice, "drift_models.");
}

}  // namespace
}  // namespace calbench
