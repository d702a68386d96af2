// coefficients.json payloads inside the store: the store's checks on top of the one codec.
#include <nlohmann/json.hpp>

#include "common/coefficients_codec.hpp"
#include "common/input_error.hpp"
#include "common/json_parse.hpp"
#include "db/store.hpp"

namespace calbench::db {

// The schema is read by the one codec (common/coefficients_codec.hpp); the store adds its own
// rules: a set names its device (model and serial not empty), and the device it is stored for.
ParsedCoefficients parse_coefficients(const std::string& text, const std::string& f, const std::string& expect_serial) {
  const nlohmann::json j = parse_json_text(text, f);
  // The device first: a payload for another device is refused as such, whatever its numbers.
  const DeviceId dev = coefficients_device(j, f);
  if (dev.model.empty()) throw InputError(f, 0, "device.model", "expected a non-empty string");
  if (dev.serial.empty()) throw InputError(f, 0, "device.serial", "empty serial number");
  if (!expect_serial.empty() && dev.serial != expect_serial)
    throw InputError(f, 0, "device.serial",
                     "serial '" + dev.serial + "' does not match the device '" + expect_serial + "'");
  ParsedCoefficients p;
  p.device.model = dev.model;
  p.device.serial = dev.serial;
  p.errors = coefficients_from_json(j, f).errors;
  p.canonical_json = j.dump(2);  // as given (extra keys and number forms kept): what is stored
  return p;
}

std::string coefficients_json_text(const DeviceInfo& device, const SensorErrors& errors, const std::string& extra_json) {
  CoefficientSet c;
  c.device = DeviceId{device.model, device.serial};
  c.errors = errors;
  if (!extra_json.empty()) {
    nlohmann::json x = nlohmann::json::parse(extra_json);
    if (x.is_object()) c.extra = std::move(x);
  }
  // The arguments name the device and the format, whatever the extra keys say.
  c.extra.erase("format");
  c.extra.erase("device");
  return coefficients_to_json(c).dump(2);
}

}  // namespace calbench::db
