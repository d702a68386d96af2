// Deterministic sensor error model of one triad and of a whole IMU, in the spec's convention
// (../shared/spec/recording-format.md):  measured = (I + M) · true + b + noise.
// M[i][j] (i != j) is the skew δ_ij of axis i towards axis j; diag(M) are scale-factor errors.
#pragma once
#include <Eigen/Dense>
#include <limits>
#include <string>

namespace calbench {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

inline constexpr double kUnknownSigma = std::numeric_limits<double>::infinity();

struct TriadErrors {
  Vec3 bias = Vec3::Zero();
  Mat3 M = Mat3::Zero();
  // 1-σ of each coefficient; +inf marks a coefficient that is unknown (not estimated / unobservable).
  Vec3 sigma_bias = Vec3::Zero();
  Mat3 sigma_M = Mat3::Zero();

  // What the sensor outputs for a true input (no noise).
  Vec3 measure(const Vec3& truth) const { return (Mat3::Identity() + M) * truth + bias; }
  // The true input recovered from a measurement: (I + M)⁻¹ (measured − b).
  Vec3 correct(const Vec3& measured) const {
    return (Mat3::Identity() + M).partialPivLu().solve(measured - bias);
  }
};

// A triad corrector with the factorisation done once, for hot loops.
class TriadCorrector {
 public:
  TriadCorrector() = default;
  explicit TriadCorrector(const TriadErrors& e)
      : bias_(e.bias), inv_((Mat3::Identity() + e.M).inverse()) {}  // 3×3, well conditioned (|M| ≪ 1)
  Vec3 operator()(const Vec3& measured) const { return inv_ * (measured - bias_); }
  // For increments over dt: the bias integrates to b·dt.
  Vec3 increment(const Vec3& measured_inc, double dt) const { return inv_ * (measured_inc - bias_ * dt); }

 private:
  Vec3 bias_ = Vec3::Zero();
  Mat3 inv_ = Mat3::Identity();
};

struct DeviceId {
  std::string model = "ADIS16488A";
  std::string serial;
};

struct SensorErrors {
  TriadErrors gyro;
  TriadErrors accel;
};

// Composition of two successive corrections. If `first` describes the raw sensor and `second` was
// estimated on data already corrected with `first`, then
//   raw = (I+M1)·((I+M2)·true + b2) + b1  ⇒  M = (I+M1)(I+M2) − I,  b = b1 + (I+M1)·b2.
// σ are propagated to first order, treating the two sets as independent.
TriadErrors compose(const TriadErrors& first, const TriadErrors& second);
SensorErrors compose(const SensorErrors& first, const SensorErrors& second);

// The same composition for a `second` estimated with priors that already hold `first`'s
// uncertainty (the in-motion filter with priors from the set, calibration/inmotion/priors.hpp):
// the result is the fused estimate, and its σ are `second`'s posterior σ carried through (I + M1)
// — `first`'s σ are in them already and are not added again:
//   σ(M_ij)² = Σ_k ((δ_ik + a_ik)·σb_kj)²,  σ(b_i)² = Σ_k ((δ_ik + a_ik)·σb_k)².
// Values are those of compose().
TriadErrors compose_fused(const TriadErrors& first, const TriadErrors& second);
SensorErrors compose_fused(const SensorErrors& first, const SensorErrors& second);

}  // namespace calbench
