#include "common/imu_error_sim.hpp"

#include <cmath>

#include "common/units.hpp"

namespace calbench {
namespace {
double quantise(double v, double lsb) { return lsb > 0 ? std::round(v / lsb) * lsb : v; }
}  // namespace

ImuErrorSimulator::ImuErrorSimulator(const SensorErrors& truth, const NoiseSpec& noise, std::uint64_t seed)
    : truth_(truth), noise_(noise), rng_(seed) {
  // Start the drifts in their stationary distribution.
  for (int i = 0; i < 3; ++i) {
    gyro_drift_(i) = noise_.gyro.drift_sigma * n01_(rng_);
    accel_drift_(i) = noise_.accel.drift_sigma * n01_(rng_);
  }
}

void ImuErrorSimulator::advance_drift(double dt) {
  auto step = [&](Vec3& d, const TriadNoise& n) {
    if (n.drift_sigma <= 0 || n.drift_tau_s <= 0) return;
    const double phi = std::exp(-dt / n.drift_tau_s);
    const double q = n.drift_sigma * std::sqrt(1.0 - phi * phi);
    for (int i = 0; i < 3; ++i) d(i) = phi * d(i) + q * n01_(rng_);
  };
  step(gyro_drift_, noise_.gyro);
  step(accel_drift_, noise_.accel);
}

ImuErrorSimulator::Output ImuErrorSimulator::sample(double t, const Vec3& w_true, const Vec3& f_true) {
  if (started_ && t > t_last_) advance_drift(t - t_last_);
  started_ = true;
  t_last_ = t;
  const double rate = noise_.output_rate_hz;
  const double sg = noise_.gyro.white_density * std::sqrt(rate);   // per-sample σ of white noise
  const double sa = noise_.accel.white_density * std::sqrt(rate);
  Output o;
  o.gyro = truth_.gyro.measure(w_true) + gyro_drift_;
  o.accel = truth_.accel.measure(f_true) + accel_drift_;
  for (int i = 0; i < 3; ++i) {
    o.gyro(i) += sg * n01_(rng_);
    o.accel(i) += sa * n01_(rng_);
    if (noise_.gyro.range > 0 && std::abs(o.gyro(i)) > noise_.gyro.range) {
      o.gyro(i) = std::copysign(noise_.gyro.range, o.gyro(i));
      o.saturated = true;
    }
    if (noise_.accel.range > 0 && std::abs(o.accel(i)) > noise_.accel.range) {
      o.accel(i) = std::copysign(noise_.accel.range, o.accel(i));
      o.saturated = true;
    }
    o.gyro(i) = quantise(o.gyro(i), noise_.gyro.lsb);
    o.accel(i) = quantise(o.accel(i), noise_.accel.lsb);
  }
  return o;
}

SensorErrors draw_random_unit(std::uint64_t seed, const UnitSpread& sp) {
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> n(0.0, 1.0);
  SensorErrors e;
  for (int i = 0; i < 3; ++i) {
    e.gyro.bias(i) = sp.gyro_bias * n(rng);
    e.accel.bias(i) = sp.accel_bias * n(rng);
    for (int j = 0; j < 3; ++j) {
      e.gyro.M(i, j) = (i == j ? sp.gyro_scale : sp.gyro_skew) * n(rng);
      e.accel.M(i, j) = (i == j ? sp.accel_scale : sp.accel_skew) * n(rng);
    }
  }
  return e;
}

SensorErrors draw_random_unit(std::uint64_t seed) {
  using namespace units;
  // Turn-on bias, data-sheet class ±0.2 °/s and ±16 mg; scale 0.5 %, skew 0.05 %.
  return draw_random_unit(seed, UnitSpread{0.2 * kDeg, 16.0 * kMilliG, 5e-3, 5e-4, 5e-3, 5e-4});
}

}  // namespace calbench
