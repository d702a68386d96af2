#include "common/fit_quality.hpp"

#include <cmath>

namespace calbench {

std::vector<LargestResidual> largest_residuals(const BenchFitQuality& q, bool gyro) {
  std::vector<LargestResidual> out;
  for (const char* kind : {kStepStatic, kStepRate}) {
    LargestResidual L;
    L.kind = kind;
    for (const auto& s : q.steps) {
      if (s.kind != kind) continue;
      ++L.steps;
      const Vec3& r = gyro ? s.gyro : s.accel;
      for (int i = 0; i < 3; ++i)
        if (std::abs(r(i)) > L.value || L.step < 0) {
          L.value = std::abs(r(i));
          L.step = s.step;
          L.axis = i;
        }
    }
    if (L.steps > 0) out.push_back(L);
  }
  return out;
}

}  // namespace calbench
