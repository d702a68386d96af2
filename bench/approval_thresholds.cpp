#include "bench/approval_thresholds.hpp"

#include <filesystem>

#include "bench/io/imu_class_toml.hpp"

namespace calbench {

db::Thresholds approval_thresholds(const std::string& file, const std::string& model) {
  db::Thresholds t = file.empty() ? db::default_thresholds() : db::load_thresholds(file);
  for (const ImuClass& c : builtin_imu_classes()) {
    t.quality.allowances[normalized_model_name(c.name)] = c.allowance;
    for (const auto& a : c.aliases) t.quality.allowances[normalized_model_name(a)] = c.allowance;
    if (file.empty() && !model.empty() && imu_class_matches(c, model)) {
      const UnitSpread& s = c.spread;
      t.gyro.max_abs_bias = 5 * s.gyro_bias;
      t.gyro.max_abs_scale = 5 * s.gyro_scale;
      t.gyro.max_abs_skew = 10 * s.gyro_skew;
      t.accel.max_abs_bias = 5 * s.accel_bias;
      t.accel.max_abs_scale = 5 * s.accel_scale;
      t.accel.max_abs_skew = 10 * s.accel_skew;
      t.source = "built-in defaults of device class " + c.name + " (" +
                 std::filesystem::path(c.file).filename().string() + ")";
    }
  }
  return t;
}

}  // namespace calbench
