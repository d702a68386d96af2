#include "calibration/gauss_markov_window.hpp"

#include <algorithm>
#include <cmath>

namespace calbench {
namespace {

// sinh(x)/x, accurate near 0.
double sinhc(double x) {
  if (std::abs(x) < 1e-4) return 1.0 + x * x / 6.0;
  return std::sinh(x) / x;
}

// 2(x − 1 + e^{−x})/x²: the variance factor of a mean over a window x correlation times long.
double same_window(double x) {
  if (x < 1e-3) return 1.0 - x / 3.0 + x * x / 12.0;
  return 2.0 * (x + std::expm1(-x)) / (x * x);
}

// τ²(e^{−|u|/τ} + |u|/τ − 1), the even second antiderivative of e^{−|u|/τ} with H(0) = 0.
double H(double u, double tau) {
  const double x = std::abs(u) / tau;
  return tau * tau * (std::expm1(-x) + x);
}

}  // namespace

double gm_window_correlation(double c1, double d1, double c2, double d2, double tau) {
  d1 = std::max(d1, 0.0);
  d2 = std::max(d2, 0.0);
  const double gap = std::abs(c1 - c2) - 0.5 * (d1 + d2);
  if (gap >= 0) return std::exp(-std::abs(c1 - c2) / tau) * sinhc(0.5 * d1 / tau) * sinhc(0.5 * d2 / tau);
  const double scale = 1e-9 * tau;
  if (std::abs(c1 - c2) <= scale && std::abs(d1 - d2) <= scale) return same_window(0.5 * (d1 + d2) / tau);
  // Overlapping windows. A (near) point inside a window: the mean of e^{−|t−c|/τ} over the window.
  if (std::min(d1, d2) <= scale) {
    const double c = d1 <= scale ? c1 : c2, cw = d1 <= scale ? c2 : c1, d = std::max(d1, d2);
    const double a = cw - 0.5 * d, b = cw + 0.5 * d;
    return tau / d * (-std::expm1(-(c - a) / tau) - std::expm1(-(b - c) / tau));
  }
  const double a1 = c1 - 0.5 * d1, b1 = c1 + 0.5 * d1, a2 = c2 - 0.5 * d2, b2 = c2 + 0.5 * d2;
  return (H(b2 - a1, tau) + H(a2 - b1, tau) - H(b2 - b1, tau) - H(a2 - a1, tau)) / (d1 * d2);
}

Eigen::VectorXd gm_window_smoothed(const std::vector<double>& centre, const std::vector<double>& duration,
                                   double sigma, double tau, const Eigen::VectorXd& v) {
  const int N = static_cast<int>(centre.size());
  Eigen::VectorXd drift(N);
  for (int k = 0; k < N; ++k) {
    double s = 0;
    for (int l = 0; l < N; ++l)
      s += sigma * sigma * gm_window_correlation(centre[k], duration[k], centre[l], duration[l], tau) * v(l);
    drift(k) = s;
  }
  return drift;
}

}  // namespace calbench
