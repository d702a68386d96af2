// Error-state layout of the in-motion calibration filter (paper section IV, eq 11): named offsets
// into the state vector, as production filters (e.g. KF-GINS) keep them. Every error is
// "estimate minus truth".
//   δr   position error, NED metres                                   [kPos, +3)
//   δv   velocity error, NED m/s                                      [kVel, +3)
//   φ    attitude error, NED rad: Ĉ_nb = (I − φ×)·C_nb               [kAtt, +3)
//   δb_g gyro drift (turn-on constant part), rad/s                    [kBg, +3)
//   δb_a accelerometer bias (constant part), m/s²                     [kBa, +3)
//   δM_g gyro M, row-major (scale on the diagonal, skews off it)      [kMg, +9)
//   δM_a accelerometer M, row-major                                   [kMa, +9)
//   δμ   mounting misalignment, reference body axes, rad:
//        Ĉ_mb = (I − δμ×)·C_mb (C_mb: MEMS → reference body)          [kMount, +3)
//   δd_g gyro in-run drift, first-order shaping filter (eq 22)        [kDg, +3)
//   δd_a accelerometer in-run drift, shaping filter (eq 22)           [kDa, +3)
// Augmented layout (only when some axis carries an exponential-cosine drift model, eqs 35–36):
//   δx0_g first state Δμ of the gyro exp-cosine shaping filter         [kDgAux, +3)
//   δx0_a first state of the accelerometer exp-cosine shaping filter   [kDaAux, +3)
//   The drift itself is the filter's second state, H = [0 1] (shaping_filter.hpp), and sits in
//   kDg / kDa as in the default layout; an axis with a first-order model leaves its aux unused.
#pragma once
#include <Eigen/Dense>

#include "calibration/inmotion/state_blocks.hpp"
#include <array>
#include <string>

namespace calbench::inmotion {

// Offsets of the full layout (every built-in block active), computed from the block declarations
// (state_blocks.hpp). The navigation blocks lead every layout, so kPos, kVel and kAtt are the
// filter's offsets too; for the other blocks the filter asks its run-time layout.
inline constexpr int kPos = offset_of(Block::pos);
inline constexpr int kVel = offset_of(Block::vel);
inline constexpr int kAtt = offset_of(Block::att);
inline constexpr int kBg = offset_of(Block::bg);
inline constexpr int kBa = offset_of(Block::ba);
inline constexpr int kMg = offset_of(Block::Mg);
inline constexpr int kMa = offset_of(Block::Ma);
inline constexpr int kMount = offset_of(Block::mount);
inline constexpr int kDg = offset_of(Block::dg);
inline constexpr int kDa = offset_of(Block::da);
inline constexpr int kStates = offset_of(Block::dg_aux);  // the default layout: every block before the aux ones
inline constexpr int kDgAux = offset_of(Block::dg_aux);
inline constexpr int kDaAux = offset_of(Block::da_aux);
inline constexpr int kStatesAug = offset_of(Block::count);
static_assert(kStates == 42 && kStatesAug == 48, "the paper's layout: 42 states, 48 with the exp-cosine aux states");

// Column names of the --series file, one per state (totals, not errors), in state order.
const std::array<std::string, kStates>& state_names();
// Names of the augmented states [kDgAux, kStatesAug): gyro_drift_aux_x_dph_s …, accel_drift_aux_x_mg_s ….
const std::array<std::string, kStatesAug - kStates>& aux_state_names();
// Names of the total drift columns (constant part + in-run shaping-filter state, per axis):
// gyro_total_x_dph, …, accel_total_x_mg, … — the process `calbench identify` identifies.
const std::array<std::string, 6>& total_drift_names();

}  // namespace calbench::inmotion
