#include "calibration/qc/bench_fit_quality.hpp"

namespace calbench::qc {

BenchFitQuality bench_fit_quality(const BenchFitResult& r) {
  BenchFitQuality q;
  q.gyro_chi2_dof = r.gyro_chi2_dof;
  q.accel_chi2_dof = r.accel_chi2_dof;
  for (const auto& s : r.steps) q.steps.push_back({s.step, s.rotating ? kStepRate : kStepStatic, s.gyro_mean, s.accel_mean});
  return q;
}

}  // namespace calbench::qc
