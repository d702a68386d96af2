#include "calibration/inmotion/state_layout.hpp"

namespace calbench::inmotion {

namespace {
// Column names of the blocks with offsets in [from, to), from their declarations.
template <std::size_t K>
std::array<std::string, K> columns_of_range(int from, int to) {
  std::array<std::string, K> n;
  for (const BlockSpec& b : block_specs()) {
    const int o = offset_of(b.id);
    if (o < from || o >= to) continue;
    for (int i = 0; i < b.size; ++i) n[static_cast<std::size_t>(o - from + i)] = b.columns[i];
  }
  return n;
}
}  // namespace

const std::array<std::string, kStates>& state_names() {
  static const std::array<std::string, kStates> names = columns_of_range<kStates>(0, kStates);
  return names;
}

const std::array<std::string, kStatesAug - kStates>& aux_state_names() {
  static const std::array<std::string, kStatesAug - kStates> names = columns_of_range<kStatesAug - kStates>(kStates, kStatesAug);
  return names;
}

const std::array<std::string, 6>& total_drift_names() {
  static const std::array<std::string, 6> names = {"gyro_total_x_dph",  "gyro_total_y_dph",  "gyro_total_z_dph",
                                                   "accel_total_x_mg", "accel_total_y_mg", "accel_total_z_mg"};
  return names;
}

}  // namespace calbench::inmotion
