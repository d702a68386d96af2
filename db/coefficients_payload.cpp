// coefficients.json payloads inside the store: the store's checks on top of the one codec, and the
// 24 indexed coefficients (names, values, σ) the store keeps in coefficient_values.
#include <algorithm>
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

namespace {
const char* const kAxes = "xyz";
}  // namespace

const std::vector<std::string>& coefficient_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const char* s : {"gyro", "accel"}) {
      for (int i = 0; i < 3; ++i) n.push_back(std::string(s) + ".bias." + kAxes[i]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) n.push_back(std::string(s) + ".M." + kAxes[i] + kAxes[j]);
    }
    return n;
  }();
  return names;
}

namespace {
// name → (triad, is_bias, i, j); throws std::invalid_argument on an unknown name.
struct Where {
  bool gyro, bias;
  int i, j;
};
Where locate(const std::string& name) {
  const auto& n = coefficient_names();
  const auto it = std::find(n.begin(), n.end(), name);
  if (it == n.end()) throw std::invalid_argument("unknown coefficient name '" + name + "'");
  int k = static_cast<int>(it - n.begin());
  Where w{k < 12, false, 0, 0};
  k %= 12;
  if (k < 3) {
    w.bias = true;
    w.i = k;
  } else {
    w.i = (k - 3) / 3;
    w.j = (k - 3) % 3;
  }
  return w;
}
}  // namespace

double coefficient_value(const SensorErrors& e, const std::string& name) {
  const Where w = locate(name);
  const TriadErrors& t = w.gyro ? e.gyro : e.accel;
  return w.bias ? t.bias(w.i) : t.M(w.i, w.j);
}
double coefficient_sigma(const SensorErrors& e, const std::string& name) {
  const Where w = locate(name);
  const TriadErrors& t = w.gyro ? e.gyro : e.accel;
  return w.bias ? t.sigma_bias(w.i) : t.sigma_M(w.i, w.j);
}

}  // namespace calbench::db
