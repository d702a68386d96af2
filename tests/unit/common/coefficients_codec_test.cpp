// The one coefficients.json codec (common/coefficients_codec.hpp): what it keeps, what it refuses
// and how it names the place of a refusal.
#include "common/coefficients_codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "common/input_error.hpp"

namespace calbench {
namespace {
using nlohmann::json;

json sample() {
  return json::parse(R"({
    "format": "calbench-coefficients/1",
    "device": {"model": "ADIS16488A", "serial": 4711},
    "gyro": {"bias": [1e-3, -2e-3, 3e-3], "M": [[1e-3, 2e-4, 0], [0, -1e-3, 0], [0, 0, 5e-4]],
             "sigma_bias": [1e-6, null, 2e-6], "temperature_bias": [1, 2, 3]},
    "accel": {"bias": [0.01, 0.02, -0.03], "M": [[0, 0, 0], [0, 0, 0], [0, 0, 0]],
              "sigma_M": [[1e-5, 1e-5, 1e-5], [1e-5, 1e-5, 1e-5], [1e-5, 1e-5, null]]},
    "g_sensitivity": {"value": [[0.1, 0, 0], [0, 0, 0], [0, 0, 0]]},
    "note": "kept"
  })");
}

// The refusal's field and message, or "" when the set was accepted.
std::string refusal(const json& j, std::string* field = nullptr) {
  try {
    (void)coefficients_from_json(j, "c.json");
    return "";
  } catch (const InputError& e) {
    if (field) *field = e.field();
    EXPECT_EQ(e.file(), "c.json");
    return e.what();
  }
}

TEST(CoefficientsCodec, ReadsTheSpecKeysAndMarksMissingSigmaUnknown) {
  const CoefficientSet c = coefficients_from_json(sample(), "c.json");
  EXPECT_EQ(c.device.model, "ADIS16488A");
  EXPECT_EQ(c.device.serial, "4711");  // an integer serial is read as its digits
  EXPECT_DOUBLE_EQ(c.errors.gyro.bias(1), -2e-3);
  EXPECT_DOUBLE_EQ(c.errors.gyro.M(0, 1), 2e-4);
  EXPECT_DOUBLE_EQ(c.errors.gyro.sigma_bias(0), 1e-6);
  EXPECT_TRUE(std::isinf(c.errors.gyro.sigma_bias(1)));        // null
  EXPECT_TRUE(std::isinf(c.errors.gyro.sigma_M(0, 0)));        // absent
  EXPECT_TRUE(std::isinf(c.errors.accel.sigma_M(2, 2)));
  EXPECT_DOUBLE_EQ(c.errors.accel.sigma_M(1, 1), 1e-5);
}

TEST(CoefficientsCodec, UnknownKeysPassThroughAReadAndWrite) {
  const json in = sample();
  const CoefficientSet c = coefficients_from_json(in, "c.json");
  EXPECT_EQ(c.extra.at("g_sensitivity"), in.at("g_sensitivity"));
  EXPECT_EQ(c.extra.at("gyro").at("temperature_bias"), in.at("gyro").at("temperature_bias"));
  EXPECT_FALSE(c.extra.contains("format"));
  EXPECT_FALSE(c.extra.contains("device"));
  const json out = coefficients_to_json(c);
  EXPECT_EQ(out.at("note"), "kept");
  EXPECT_EQ(out.at("g_sensitivity"), in.at("g_sensitivity"));
  EXPECT_EQ(out.at("gyro").at("temperature_bias"), in.at("gyro").at("temperature_bias"));
  EXPECT_TRUE(out.at("gyro").at("sigma_bias")[1].is_null());  // unknown σ written as null
  EXPECT_EQ(out.at("device").at("serial"), "4711");
  // A second pass changes nothing.
  EXPECT_EQ(coefficients_to_json(coefficients_from_json(out, "c.json")), out);
}

TEST(CoefficientsCodec, RefusalsNameTheKey) {
  std::string field;
  json j = sample();
  j["gyro"]["bias"][1] = "x";
  EXPECT_NE(refusal(j, &field).find("expected a number"), std::string::npos);
  EXPECT_EQ(field, "gyro.bias[1]");
  j = sample();
  j["accel"]["sigma_M"][2][0] = -1.0;
  EXPECT_NE(refusal(j, &field).find("cannot be negative"), std::string::npos);
  EXPECT_EQ(field, "accel.sigma_M[2][0]");
  j = sample();
  j["accel"].erase("M");
  EXPECT_NE(refusal(j, &field).find("missing key"), std::string::npos);
  EXPECT_EQ(field, "accel.M");
  j = sample();
  j["format"] = "calbench-coefficients/2";
  EXPECT_NE(refusal(j, &field).find("unsupported format"), std::string::npos);
  EXPECT_EQ(field, "format");
  j = sample();
  j["device"]["serial"] = json::array();
  EXPECT_NE(refusal(j, &field).find("expected a string"), std::string::npos);
  EXPECT_EQ(field, "device.serial");
  EXPECT_NE(refusal(json::array({1, 2})).find("expected a JSON object"), std::string::npos);
  EXPECT_EQ(refusal(sample()), "");
}

TEST(CoefficientsCodec, TheDeviceIsReadWithoutTheNumbers) {
  json j = sample();
  j.erase("gyro");  // coefficients_device does not look at the coefficients
  const DeviceId d = coefficients_device(j, "c.json");
  EXPECT_EQ(d.serial, "4711");
  EXPECT_THROW(coefficients_from_json(j, "c.json"), InputError);
}

TEST(CoefficientsCodec, TheIndexedCoefficientsAddressTheSet) {
  const CoefficientSet c = coefficients_from_json(sample(), "c.json");
  const auto& names = coefficient_names();
  ASSERT_EQ(names.size(), 24u);
  EXPECT_EQ(names.front(), "gyro.bias.x");
  EXPECT_EQ(names[12], "accel.bias.x");
  EXPECT_EQ(names.back(), "accel.M.zz");
  EXPECT_DOUBLE_EQ(coefficient_value(c.errors, "gyro.M.xy"), 2e-4);
  EXPECT_DOUBLE_EQ(coefficient_value(c.errors, "accel.bias.z"), -0.03);
  EXPECT_DOUBLE_EQ(coefficient_sigma(c.errors, "accel.M.yy"), 1e-5);
  EXPECT_TRUE(std::isinf(coefficient_sigma(c.errors, "gyro.bias.y")));
  EXPECT_THROW(coefficient_value(c.errors, "gyro.M.xw"), std::invalid_argument);
}

}  // namespace
}  // namespace calbench

namespace calbench {
namespace {
// "fit_quality" of a bench fit: read strictly into its type, written back with the derived
// largest_systematic (per kind and triad), and a bad value refused naming its key.
TEST(CoefficientsCodec, FitQualityIsTypedAndChecked) {
  json j = sample();
  j["fit_quality"] = json::parse(R"({
    "chi2_per_dof": {"gyro": [1.0, 0.9, 1.1], "accel": [1.0, 4.0, 1.0]},
    "steps": [{"step": 0, "kind": "static", "gyro_mean_rad_s": [1e-5, -3e-4, 0], "accel_mean_m_s2": [0, 0, 1e-3]},
              {"step": 4, "kind": "rate", "gyro_mean_rad_s": [2e-4, 0, 0], "accel_mean_m_s2": [0, -5e-3, 0]}]})");
  const CoefficientSet c = coefficients_from_json(j, "c.json");
  ASSERT_TRUE(c.fit_quality);
  EXPECT_FALSE(c.extra.contains("fit_quality"));
  EXPECT_DOUBLE_EQ(c.fit_quality->accel_chi2_dof(1), 4.0);
  ASSERT_EQ(c.fit_quality->steps.size(), 2u);
  EXPECT_EQ(c.fit_quality->steps[1].kind, "rate");
  const json out = coefficients_to_json(c);
  const json& L = out["fit_quality"]["largest_systematic"];
  EXPECT_DOUBLE_EQ(L["static"]["gyro_rad_s"]["value"].get<double>(), 3e-4);
  EXPECT_EQ(L["static"]["gyro_rad_s"]["axis"], "y");
  EXPECT_EQ(L["rate"]["accel_m_s2"]["step"], 4);
  EXPECT_DOUBLE_EQ(L["rate"]["accel_m_s2"]["value"].get<double>(), 5e-3);
  // Read back: the same figures (largest_systematic is derived, not read).
  const CoefficientSet again = coefficients_from_json(out, "again.json");
  EXPECT_EQ(coefficients_to_json(again), out);
  // No fit_quality: none written.
  EXPECT_FALSE(coefficients_to_json(coefficients_from_json(sample(), "s.json")).contains("fit_quality"));
  std::string field;
  json bad = j;
  bad["fit_quality"]["steps"][1]["kind"] = "spin";
  EXPECT_NE(refusal(bad, &field), "");
  EXPECT_EQ(field, "fit_quality.steps[1].kind");
  bad = j;
  bad["fit_quality"]["chi2_per_dof"]["gyro"][2] = -1;
  EXPECT_NE(refusal(bad, &field), "");
  EXPECT_EQ(field, "fit_quality.chi2_per_dof.gyro");
  bad = j;
  bad["fit_quality"]["residuals"] = 1;
  EXPECT_NE(refusal(bad, &field), "");
  EXPECT_EQ(field, "fit_quality.residuals");
  bad = j;
  bad["fit_quality"]["steps"][0].erase("accel_mean_m_s2");
  EXPECT_NE(refusal(bad, &field), "");
  EXPECT_EQ(field, "fit_quality.steps[0].accel_mean_m_s2");
}
}  // namespace
}  // namespace calbench
