// Where the innovations of a GNSS-aided filter grow, by motion condition (issue 53 item 5,
// docs/diagnosis.md "GNSS-only drives"). A model error shows where the motion excites it: a
// sample-timing error of the logger and a scale factor with turn rate and acceleration, a lever arm
// with turn rate, a lagging fix velocity or a time offset with acceleration, a wrong noise model at
// standstill, a heading error at the start of motion. The breakdown bins one observation type's
// epochs by each condition and compares the mean NIS/dof of the bins:
//   * motion state: standstill (speed below standstill_speed, until it passes moving_speed), start of
//     motion (the first start_of_motion_s after a standstill of at least min_standstill_s), moving;
//   * speed, turn rate |ψ̇|, horizontal acceleration: terciles of the moving epochs (equal counts,
//     the drive's own range) — the top tercile against the bottom one.
// The motion state compares moving against standstill, standstill against moving and start of
// motion against moving. A condition "grows" when the compared bin's NIS/dof is ≥ kGrowRatio times the reference bin's and
// the difference is ≥ kGrowZ standard errors. The standard error counts the innovations' serial
// correlation: n_eff = n·(1 − ρ)/(1 + ρ), ρ the lag-1 autocorrelation of the binned epochs' NIS in
// time order, each less its bin's mean. Of several comparisons (the motion state's) the one reported
// is the most significant that grows, else the most significant.
// Gated epochs are left out (their NIS is not the filter's fit); the used and forced ones count.
// Pure mathematics over the samples the caller's filter run produced.
#pragma once
#include <string>
#include <vector>

#include "calibration/diagnosis/drive_innovations.hpp"

namespace calbench {

struct ConditionBin {
  std::string label;       // "standstill", "start of motion", "moving", "low", "mid", "high"
  double lo = 0, hi = 0;   // the bin's range of the condition (SI; unused for the motion state)
  long epochs = 0;
  double nis_per_dof = 0;  // mean NIS/3
  double var = 0;          // sample variance of NIS/3 within the bin
};

struct ConditionBreakdown {
  std::string condition;   // "motion", "speed", "turn rate", "acceleration"
  std::vector<ConditionBin> bins;
  // The growth: bin `grown` against bin `reference` (indices into bins; −1 when either is empty).
  int reference = -1, grown = -1;
  double ratio = 1, z = 0;
  bool grows = false;
};

struct ConditionOptions {
  // Standstill below standstill_speed, moving from moving_speed on (between them the state holds).
  double standstill_speed = 0.2, moving_speed = 0.5;  // m/s
  double min_standstill_s = 2;    // a start of motion needs a standstill at least this long before
  double start_of_motion_s = 5;
  double grow_ratio = 1.5;
  double grow_z = 3;
  int min_bin_epochs = 10;
};

// One breakdown per condition (motion state first; then speed, turn rate, acceleration).
std::vector<ConditionBreakdown> innovation_conditions(const std::vector<InnovationSample>& x, const ConditionOptions& opt = {});

// The conditions that grow, in one line: "turn rate x2.1 (NIS/dof 2.3 high turn rate against 1.1 low
// turn rate, z 5.3); …", with ": the reference is far below 1" where its NIS/dof is under 0.5 (the
// growth is then the reference's quiet, not the compared bin's misfit); empty when none grows.
std::string growing_conditions_text(const std::vector<ConditionBreakdown>& b);

}  // namespace calbench
