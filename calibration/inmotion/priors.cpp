#include "calibration/inmotion/priors.hpp"

#include <cmath>
#include <limits>

#include "calibration/ins/nav_math.hpp"
#include "common/units.hpp"

namespace calbench::inmotion {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

ParameterPriors sigma_of(const SensorErrors& e, const Vec3& mount_sigma) {
  ParameterPriors p;
  p.gyro_bias = e.gyro.sigma_bias;
  p.accel_bias = e.accel.sigma_bias;
  p.gyro_M = e.gyro.sigma_M;
  p.accel_M = e.accel.sigma_M;
  p.mount = mount_sigma;
  return p;
}

ParameterPriors datasheet_priors() {
  using namespace units;
  ParameterPriors p;
  p.gyro_bias.setConstant(0.5 * kDeg);
  p.accel_bias.setConstant(30 * kMilliG);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p.gyro_M(i, j) = p.accel_M(i, j) = i == j ? 1e-2 : 2e-3;
  p.mount.setConstant(1.0 * kDeg);
  return p;
}

const std::vector<std::string>& prior_parameter_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    const char* ax = "xyz";
    for (const char* s : {"gyro", "accel"}) {
      for (int i = 0; i < 3; ++i) n.push_back(std::string(s) + ".bias." + ax[i]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) n.push_back(std::string(s) + ".M." + ax[i] + ax[j]);
    }
    for (int i = 0; i < 3; ++i) n.push_back(std::string("mount.") + ax[i]);
    return n;
  }();
  return names;
}

namespace {
// k → (block, i, j): block 0 gyro bias, 1 gyro M, 2 accel bias, 3 accel M, 4 mount.
template <class P, class F>
auto visit(P& p, std::size_t k, F f) {
  if (k >= 24) return f(p.mount(static_cast<int>(k - 24)));
  auto& bias = k < 12 ? p.gyro_bias : p.accel_bias;
  auto& M = k < 12 ? p.gyro_M : p.accel_M;
  const int r = static_cast<int>(k % 12);
  return r < 3 ? f(bias(r)) : f(M((r - 3) / 3, (r - 3) % 3));
}
}  // namespace

double prior_value(const ParameterPriors& p, std::size_t k) {
  return visit(p, k, [](double v) { return v; });
}

void set_prior_value(ParameterPriors& p, std::size_t k, double sigma) {
  visit(p, k, [sigma](double& v) { v = sigma; });
}

Vec3 mounting_sigma_from_rpy(const Vec3& rpy, const Vec3& sigma_rpy) {
  const Mat3 Ji = ins::rpy_jacobian_left(ins::dcm_from_rpy(rpy)).inverse();
  const Mat3 S = Ji * sigma_rpy.cwiseProduct(sigma_rpy).asDiagonal() * Ji.transpose();
  return S.diagonal().cwiseMax(0.0).cwiseSqrt();
}

PriorReport priors_datasheet(const ParameterPriors& datasheet) {
  const std::size_t n = prior_parameter_names().size();
  PriorReport r;
  r.sigma = r.sigma_raw = datasheet;
  r.source.assign(n, PriorSource::datasheet);
  r.set_sigma.assign(n, kNaN);
  r.allowance.assign(n, kNaN);
  return r;
}

PriorReport priors_from_set(const SensorErrors& set, const StabilityAllowance& a, const Vec3& mount_sigma,
                            const ParameterPriors& datasheet) {
  PriorReport r = priors_datasheet(datasheet);
  const ParameterPriors given = sigma_of(set, mount_sigma);
  ParameterPriors allow;
  allow.gyro_bias.setConstant(a.gyro_bias);
  allow.accel_bias.setConstant(a.accel_bias);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      allow.gyro_M(i, j) = i == j ? a.gyro_scale : a.gyro_skew;
      allow.accel_M(i, j) = i == j ? a.accel_scale : a.accel_skew;
    }
  allow.mount.setConstant(a.mount);
  for (std::size_t k = 0; k < r.source.size(); ++k) {
    const double s = prior_value(given, k), al = prior_value(allow, k);
    if (!std::isfinite(s) || s < 0) continue;  // unknown (or no mounting given): data-sheet class
    const double raw = std::hypot(s, al);
    set_prior_value(r.sigma_raw, k, raw);
    // Into the frame of the corrected data: b = b_set + (I + M_set)·δb, M = (I + M_set)(I + δM) − I,
    // whose diagonal of I + M_set scales row i (the off-diagonal part, ≤ 0.1 %, mixes rows at 1e-6).
    double scale = 1;
    if (k < 24) {
      const std::size_t r12 = k % 12;
      const int row = static_cast<int>(r12 < 3 ? r12 : (r12 - 3) / 3);
      scale = 1.0 + (k < 12 ? set.gyro.M(row, row) : set.accel.M(row, row));
    }
    set_prior_value(r.sigma, k, raw / std::abs(scale));
    r.source[k] = PriorSource::set_and_allowance;
    r.set_sigma[k] = s;
    r.allowance[k] = al;
  }
  return r;
}

}  // namespace calbench::inmotion
