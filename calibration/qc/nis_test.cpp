#include "calibration/qc/nis_test.hpp"

#include <algorithm>
#include <cmath>

namespace calbench::qc {

double chi2_quantile(double nu, double z) {
  const double a = 2.0 / (9.0 * nu);
  const double c = std::max(1.0 - a + z * std::sqrt(a), 1e-3);
  return nu * c * c * c;
}

double two_sided_z(double level) {
  // Solve P(|Z| > z) = erfc(z/√2) = 1 − level by bisection (erfc is monotone).
  const double alpha = 1.0 - level;
  double lo = 0, hi = 10;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double normal_quantile(double p) {
  double lo = -40, hi = 40;  // Φ(z) = erfc(−z/√2)/2 increases with z
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

NisTest nis_test(long epochs, int dof, double mean_nis, double fraction_within_95, double level) {
  NisTest t;
  t.level = level;
  if (epochs <= 0 || dof <= 0) return t;
  const double z = two_sided_z(level), n = static_cast<double>(epochs), nu = n * dof;
  t.mean_lo = chi2_quantile(nu, -z) / n;
  t.mean_hi = chi2_quantile(nu, z) / n;
  t.mean = mean_nis > t.mean_hi ? NisVerdict::too_large : mean_nis < t.mean_lo ? NisVerdict::too_small : NisVerdict::consistent;
  const double sd = std::sqrt(0.95 * 0.05 / n);
  t.frac_lo = std::max(0.0, 0.95 - z * sd);
  t.frac_hi = std::min(1.0, 0.95 + z * sd);
  t.fraction = fraction_within_95 < t.frac_lo   ? NisVerdict::too_large
               : fraction_within_95 > t.frac_hi ? NisVerdict::too_small
                                                : NisVerdict::consistent;
  return t;
}

}  // namespace calbench::qc
