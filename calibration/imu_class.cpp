#include "calibration/imu_class.hpp"

#include <cctype>

namespace calbench {

std::string normalized_model_name(const std::string& model) {
  std::string s;
  for (const unsigned char c : model)
    if (!std::isspace(c)) s.push_back(static_cast<char>(std::tolower(c)));
  return s;
}

bool imu_class_matches(const ImuClass& c, const std::string& model) {
  const std::string m = normalized_model_name(model);
  if (m.empty()) return false;
  if (normalized_model_name(c.name) == m) return true;
  for (const std::string& a : c.aliases)
    if (normalized_model_name(a) == m) return true;
  return false;
}

}  // namespace calbench
