// The store's coefficients payloads go through the one codec (common/coefficients_codec.hpp) and
// add the store's rules on top: the device is checked before the numbers, extra keys are stored.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/coefficients_codec.hpp"
#include "common/input_error.hpp"
#include "db_test_util.hpp"
#include "db/store.hpp"

namespace calbench::db {
namespace {
using nlohmann::json;

TEST(DbCoefficientsPayload, TextRoundTripsThroughTheCodecWithExtraKeys) {
  const SensorErrors e = test::random_errors(11);
  const std::string text = coefficients_json_text({"ADIS16488A", "P7", ""}, e,
                                                   R"({"time_offset_s": 0.002, "device": {"serial": "OTHER"}})");
  const ParsedCoefficients p = parse_coefficients(text, "p.json", "P7");
  EXPECT_EQ(p.device.serial, "P7");  // the argument's device, not the extra key's
  EXPECT_TRUE(p.errors.gyro.bias.isApprox(e.gyro.bias, 0));
  EXPECT_TRUE(p.errors.accel.M.isApprox(e.accel.M, 0));
  EXPECT_EQ(json::parse(p.canonical_json).at("time_offset_s"), 0.002);
  // The bench's reading of the same text is the same set.
  const CoefficientSet c = coefficients_from_json(json::parse(text), "p.json");
  EXPECT_EQ(coefficients_to_json(c).dump(2), text);
}

TEST(DbCoefficientsPayload, TheDeviceIsCheckedBeforeTheNumbers) {
  const std::string wrong = R"({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A",
    "serial": "B9"}, "gyro": {"bias": [1, "x", 3]}, "accel": {}})";
  try {
    parse_coefficients(wrong, "p.json", "A3");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "device.serial");
    EXPECT_NE(std::string(e.what()).find("does not match the device 'A3'"), std::string::npos) << e.what();
  }
  const std::string no_model = R"({"format": "calbench-coefficients/1", "device": {"model": "", "serial": "A3"}})";
  try {
    parse_coefficients(no_model, "p.json", "");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "device.model");
  }
  // With the right device, the numbers are refused by the codec, naming the key.
  try {
    parse_coefficients(wrong, "p.json", "B9");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "gyro.bias[1]");
  }
}

}  // namespace
}  // namespace calbench::db
