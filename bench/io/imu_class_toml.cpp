#include "bench/io/imu_class_toml.hpp"

#include <toml++/toml.h>

#include "bench/io/imu_classes_embedded.hpp"
#include "bench/io/toml_read.hpp"
#include "bench/io/toml_text.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

constexpr double kBig = 1e12;

const toml::table& section(const TomlReader& r, const toml::table& root, const char* key) {
  const toml::node* n = root.get(key);
  if (!n) r.fail(root, key, "missing table [" + std::string(key) + "]");
  const toml::table* t = n->as_table();
  if (!t) r.fail(n, key, "expected a table [" + std::string(key) + "]");
  return *t;
}

ImuClass parse_table(const toml::table& root, const std::string& file) {
  using namespace units;
  const TomlReader r{file};
  r.check_keys(root, "", {"name", "aliases", "grade", "source", "gyro", "accel", "output", "spread", "priors", "allowance"});
  ImuClass c;
  c.file = file;
  c.name = r.str(root, "", "name", std::nullopt);
  if (normalized_model_name(c.name).empty()) r.fail(root.get("name"), "name", "must not be empty");
  if (const toml::node* n = root.get("aliases")) {
    const toml::array* a = n->as_array();
    if (!a) r.fail(n, "aliases", "expected an array of strings");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const auto s = (*a)[i].value<std::string>();
      const std::string key = "aliases[" + std::to_string(i + 1) + "]";
      if (!s) r.fail(&(*a)[i], key, "expected a string");
      if (normalized_model_name(*s).empty()) r.fail(&(*a)[i], key, "must not be empty");
      c.aliases.push_back(*s);
    }
  }
  c.grade = r.str(root, "", "grade", std::string());

  const toml::table& src = section(r, root, "source");
  r.check_keys(src, "source.", {"document", "url", "revision"});
  c.source = r.str(src, "source.", "document", std::nullopt);
  c.url = r.str(src, "source.", "url", std::string());
  c.revision = r.str(src, "source.", "revision", std::string());

  // Noise: the SI value is formed as common/noise_spec.hpp forms it (number × unit), so that a
  // file holding a data sheet's figures gives bit for bit the same NoiseSpec.
  const toml::table& g = section(r, root, "gyro");
  r.check_keys(g, "gyro.", {"arw_deg_sqrt_h", "bias_stability_deg_h", "bias_tau_s", "range_deg_s", "lsb_deg_s"});
  // White noise must be positive: no sensor is noiseless, and a zero level leaves the standstill
  // detection and every noise-weighted test without a scale (1e-6 °/√h, 1e-7 m/s/√h: far below any
  // navigation-grade part).
  c.noise.gyro.white_density = r.num(g, "gyro.", "arw_deg_sqrt_h", std::nullopt, 1e-6, kBig) * kDeg / kSqrtHour;
  c.noise.gyro.drift_sigma = r.num(g, "gyro.", "bias_stability_deg_h", std::nullopt, 0, kBig) * kDegPerHour;
  c.noise.gyro.drift_tau_s = r.num(g, "gyro.", "bias_tau_s", std::nullopt, 1e-3, kBig);
  c.noise.gyro.range = r.num(g, "gyro.", "range_deg_s", std::nullopt, 1e-6, kBig) * kDeg;
  c.noise.gyro.lsb = r.num(g, "gyro.", "lsb_deg_s", std::nullopt, 0, kBig) * kDeg;
  const toml::table& a = section(r, root, "accel");
  r.check_keys(a, "accel.", {"vrw_m_s_sqrt_h", "bias_stability_mg", "bias_tau_s", "range_g", "lsb_g"});
  c.noise.accel.white_density = r.num(a, "accel.", "vrw_m_s_sqrt_h", std::nullopt, 1e-7, kBig) / kSqrtHour;
  c.noise.accel.drift_sigma = r.num(a, "accel.", "bias_stability_mg", std::nullopt, 0, kBig) * kMilliG;
  c.noise.accel.drift_tau_s = r.num(a, "accel.", "bias_tau_s", std::nullopt, 1e-3, kBig);
  c.noise.accel.range = r.num(a, "accel.", "range_g", std::nullopt, 1e-6, kBig) * kG0;
  c.noise.accel.lsb = r.num(a, "accel.", "lsb_g", std::nullopt, 0, kBig) * kG0;
  const toml::table& o = section(r, root, "output");
  r.check_keys(o, "output.", {"rate_hz"});
  c.noise.output_rate_hz = r.num(o, "output.", "rate_hz", std::nullopt, 1e-3, 1e7);

  const toml::table& s = section(r, root, "spread");
  r.check_keys(s, "spread.", {"gyro_bias_deg_s", "accel_bias_mg", "gyro_scale", "gyro_skew", "accel_scale", "accel_skew"});
  c.spread.gyro_bias = r.num(s, "spread.", "gyro_bias_deg_s", std::nullopt, 0, kBig) * kDeg;
  c.spread.accel_bias = r.num(s, "spread.", "accel_bias_mg", std::nullopt, 0, kBig) * kMilliG;
  c.spread.gyro_scale = r.num(s, "spread.", "gyro_scale", std::nullopt, 0, 1);
  c.spread.gyro_skew = r.num(s, "spread.", "gyro_skew", std::nullopt, 0, 1);
  c.spread.accel_scale = r.num(s, "spread.", "accel_scale", std::nullopt, 0, 1);
  c.spread.accel_skew = r.num(s, "spread.", "accel_skew", std::nullopt, 0, 1);

  // Priors: a zero σ would pin a parameter, so each must be positive.
  const toml::table& p = section(r, root, "priors");
  r.check_keys(p, "priors.", {"gyro_bias_deg_s", "accel_bias_mg", "gyro_scale", "gyro_skew", "accel_scale", "accel_skew", "mount_deg"});
  c.priors.gyro_bias.setConstant(r.num(p, "priors.", "gyro_bias_deg_s", std::nullopt, 1e-12, kBig) * kDeg);
  c.priors.accel_bias.setConstant(r.num(p, "priors.", "accel_bias_mg", std::nullopt, 1e-12, kBig) * kMilliG);
  const double gs = r.num(p, "priors.", "gyro_scale", std::nullopt, 1e-12, 1), gk = r.num(p, "priors.", "gyro_skew", std::nullopt, 1e-12, 1);
  const double as = r.num(p, "priors.", "accel_scale", std::nullopt, 1e-12, 1), ak = r.num(p, "priors.", "accel_skew", std::nullopt, 1e-12, 1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      c.priors.gyro_M(i, j) = i == j ? gs : gk;
      c.priors.accel_M(i, j) = i == j ? as : ak;
    }
  c.priors.mount.setConstant(r.num(p, "priors.", "mount_deg", std::nullopt, 1e-12, 90) * kDeg);

  const toml::table& w = section(r, root, "allowance");
  r.check_keys(w, "allowance.", {"gyro_bias_deg_s", "accel_bias_mg", "gyro_scale_ppm", "gyro_skew_ppm", "accel_scale_ppm", "accel_skew_ppm",
                                 "mount_deg"});
  c.allowance.device_class = c.name;
  c.allowance.gyro_bias = r.num(w, "allowance.", "gyro_bias_deg_s", std::nullopt, 0, kBig) * kDeg;
  c.allowance.accel_bias = r.num(w, "allowance.", "accel_bias_mg", std::nullopt, 0, kBig) * kMilliG;
  c.allowance.gyro_scale = r.num(w, "allowance.", "gyro_scale_ppm", std::nullopt, 0, 1e6) * kPpm;
  c.allowance.gyro_skew = r.num(w, "allowance.", "gyro_skew_ppm", std::nullopt, 0, 1e6) * kPpm;
  c.allowance.accel_scale = r.num(w, "allowance.", "accel_scale_ppm", std::nullopt, 0, 1e6) * kPpm;
  c.allowance.accel_skew = r.num(w, "allowance.", "accel_skew_ppm", std::nullopt, 0, 1e6) * kPpm;
  c.allowance.mount = r.num(w, "allowance.", "mount_deg", std::nullopt, 0, 90) * kDeg;
  return c;
}

std::string class_line(const ImuClass& c) {
  std::string s = c.name;
  if (!c.aliases.empty()) {
    s += " (aliases:";
    for (std::size_t i = 0; i < c.aliases.size(); ++i) s += (i ? ", '" : " '") + c.aliases[i] + "'";
    s += ")";
  }
  return s;
}

}  // namespace

ImuClass parse_imu_class(const std::string& text, const std::string& file) { return parse_table(parse_toml_text(text, file), file); }

ImuClass load_imu_class(const std::filesystem::path& file) { return parse_table(parse_toml_file(file), file.string()); }

const std::vector<ImuClass>& builtin_imu_classes() {
  static const std::vector<ImuClass> all = [] {
    std::vector<ImuClass> v;
    for (const auto& [file, text] : generated::kImuClassFiles) v.push_back(parse_imu_class(text, file));
    return v;
  }();
  return all;
}

const ImuClass* find_builtin_imu_class(const std::string& model) {
  for (const ImuClass& c : builtin_imu_classes())
    if (imu_class_matches(c, model)) return &c;
  return nullptr;
}

const ImuClass& builtin_imu_class(const std::string& model) {
  if (const ImuClass* c = find_builtin_imu_class(model)) return *c;
  throw std::out_of_range("no built-in IMU class '" + model + "'");
}

std::string known_imu_classes_text() {
  std::string s;
  for (const ImuClass& c : builtin_imu_classes()) s += (s.empty() ? "" : "; ") + class_line(c);
  return s;
}

ImuClassChoice choose_imu_class(const std::string& option, const std::string& model, const std::string& meta_file) {
  if (!option.empty()) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(option, ec)) return {load_imu_class(option), "--device-class " + option};
    for (const ImuClass& c : builtin_imu_classes())
      if (imu_class_matches(c, option)) return {c, "--device-class " + option};
    if (option.find('/') != std::string::npos || option.ends_with(".toml"))  // meant as a file
      throw InputError(option, 0, "--device-class",
                       "no such class file; known classes by name: " + known_imu_classes_text());
    throw InputError("--device-class", 0, "",
                     "'" + option + "' is neither a class file nor a known class; known classes: " + known_imu_classes_text());
  }
  if (const ImuClass* c = find_builtin_imu_class(model)) return {*c, "meta.json device.model '" + model + "'"};
  throw InputError(meta_file, 0, "device.model",
                   "unknown IMU model '" + model + "': no device class has this name or alias. Known classes: " +
                       known_imu_classes_text() +
                       ". Give the class with --device-class FILE (bench/imu_classes/<name>.toml or your own; "
                       "docs/in-motion.md, \"Device classes\")");
}

nlohmann::json imu_class_json(const ImuClassChoice& ch) {
  using namespace units;
  const ImuClass& c = ch.cls;
  return {{"name", c.name},
          {"grade", c.grade},
          {"file", c.file},
          {"chosen_by", ch.chosen_by},
          {"source", {{"document", c.source}, {"url", c.url}, {"revision", c.revision}}},
          {"gyro", {{"arw_deg_sqrt_h", c.noise.gyro.white_density * kSqrtHour / kDeg},
                    {"bias_stability_deg_h", c.noise.gyro.drift_sigma / kDegPerHour},
                    {"bias_tau_s", c.noise.gyro.drift_tau_s}}},
          {"accel", {{"vrw_m_s_sqrt_h", c.noise.accel.white_density * kSqrtHour},
                     {"bias_stability_mg", c.noise.accel.drift_sigma / kMilliG},
                     {"bias_tau_s", c.noise.accel.drift_tau_s}}}};
}

}  // namespace calbench
