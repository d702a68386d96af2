// Innovation statistics of the in-motion filter on a drive (docs/diagnosis.md, "Drives"): the
// second evidence source of `calbench diagnose` on a drive, next to the predicted-output
// comparison. Per observation type (position, velocity, attitude; eqs 13–15):
//   * NIS/dof: mean of νᵀS⁻¹ν / 3 over the epochs the filter used (1 for a consistent filter),
//     and the counts of rejected (gated) and forced epochs;
//   * whiteness: Ljung–Box (10 lags) of each normalised component ν_i/√S_ii over all epochs
//     (a consistent filter's innovations are white); the smallest p of the three is the verdict;
//   * where: the 20 s windows with the largest NIS/dof;
//   * under which conditions: the correlation, over the ~1 s blocks of the drive diagnosis, of the
//     block mean of √(NIS/3) (normalised innovation magnitude) with each drive condition and the
//     magnitude of the signed ones (|w_x|, …).
// Pure mathematics: the caller runs the filter and hands over its innovations.
#pragma once
#include <string>
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/diagnosis/drive_data.hpp"

namespace calbench {

struct InnovationSample {
  double t = 0;
  Vec3 nu = Vec3::Zero();
  Mat3 S = Mat3::Identity();
  double nis = 0;
  int status = 0;  // 0 used, 1 rejected, 2 forced (inmotion::InnovationRecord::Status)
};

struct InnovationWindow {
  double t0 = 0, t1 = 0;
  double nis_per_dof = 0;
  int epochs = 0;
};

struct InnovationStats {
  long epochs = 0, used = 0, rejected = 0, forced = 0;
  double nis_per_dof = 0;          // mean NIS/3 over used epochs
  double median_nis_per_dof = 0;   // over all epochs (robust to the gated ones)
  double fraction_within_95 = 0;   // used epochs with NIS ≤ χ²₃(0.95)
  double ljung_box_p[3] = {1, 1, 1};  // per component, normalised innovation
  double ljung_box_p_min = 1;
  double lag1_autocorr[3] = {0, 0, 0};
  std::vector<InnovationWindow> worst_windows;   // largest NIS/dof first
  std::vector<ConditionCorrelation> correlations;  // largest |r| first (n_correlations; < 0: all)
  int correlation_blocks = 0;                      // blocks with an epoch (n of the correlations)
};

// data: the drive diagnosis blocks (conditions); nullptr → no correlations.
InnovationStats innovation_stats(const std::vector<InnovationSample>& x, const DriveDiagData* data,
                                 double window_s = 20.0, int n_worst = 3, int n_correlations = -1);

}  // namespace calbench
