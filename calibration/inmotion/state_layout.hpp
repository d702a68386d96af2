// Error state of the in-motion calibration filter (paper section IV, eq 11), by block (declared in
// state_blocks.cpp, offsets from the run-time layout, StateLayout). Every error is "estimate minus
// truth".
//   pos    δr   position error, NED metres                                     3
//   vel    δv   velocity error, NED m/s                                        3
//   att    φ    attitude error, NED rad: Ĉ_nb = (I − φ×)·C_nb                 3
//   bg     δb_g gyro drift (turn-on constant part), rad/s                      3
//   ba     δb_a accelerometer bias (constant part), m/s²                       3
//   Mg     δM_g gyro M, row-major (scale on the diagonal, skews off it)        9
//   Ma     δM_a accelerometer M, row-major                                     9
//   mount  δμ   mounting misalignment, reference body axes, rad:
//               Ĉ_mb = (I − δμ×)·C_mb (C_mb: MEMS → reference body)            3
//   dg     δd_g gyro in-run drift, first-order shaping filter (eq 22)          3
//   da     δd_a accelerometer in-run drift, shaping filter (eq 22)             3
// The paper's 42 states. Augmented layout (only when some axis carries an exponential-cosine drift
// model, eqs 35–36), 48 states:
//   dg_aux δx0_g first state Δμ of the gyro exp-cosine shaping filter          3
//   da_aux δx0_a first state of the accelerometer exp-cosine shaping filter    3
//   The drift itself is the filter's second state, H = [0 1] (shaping_filter.hpp), and sits in
//   dg / da as in the default layout; an axis with a first-order model leaves its aux unused.
#pragma once
#include <Eigen/Dense>

#include "calibration/inmotion/state_blocks.hpp"
#include <array>
#include <string>

namespace calbench::inmotion {

// Names of the total drift columns (constant part + in-run shaping-filter state, per axis):
// gyro_total_x_dph, …, accel_total_x_mg, … — the process `calbench identify` identifies.
const std::array<std::string, 6>& total_drift_names();

}  // namespace calbench::inmotion
