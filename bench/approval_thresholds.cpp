#include "bench/approval_thresholds.hpp"

#include "bench/io/imu_class_toml.hpp"

namespace calbench {

db::Thresholds approval_thresholds(const std::string& file) {
  db::Thresholds t = file.empty() ? db::default_thresholds() : db::load_thresholds(file);
  for (const ImuClass& c : builtin_imu_classes()) {
    t.quality.allowances[normalized_model_name(c.name)] = c.allowance;
    for (const auto& a : c.aliases) t.quality.allowances[normalized_model_name(a)] = c.allowance;
  }
  return t;
}

}  // namespace calbench
