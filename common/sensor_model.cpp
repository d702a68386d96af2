#include "common/sensor_model.hpp"

#include <cmath>

namespace calbench {

TriadErrors compose(const TriadErrors& a, const TriadErrors& b) {
  TriadErrors out;
  const Mat3 I = Mat3::Identity();
  out.M = (I + a.M) * (I + b.M) - I;
  out.bias = a.bias + (I + a.M) * b.bias;
  // First-order σ: M_ij = a_ij + b_ij + Σ_k a_ik b_kj; the product terms are second order, so
  // σ(M_ij)² ≈ σa_ij² + Σ_k ((δ_ik + a_ik)·σb_kj)²; σ(b_i)² ≈ σa_i² + Σ_k ((δ_ik + a_ik)·σb_k)² + Σ_k (b_k·σa_ik)².
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double v = a.sigma_M(i, j) * a.sigma_M(i, j);
      for (int k = 0; k < 3; ++k) {
        const double g = (I + a.M)(i, k) * b.sigma_M(k, j);
        v += g * g;
      }
      out.sigma_M(i, j) = std::sqrt(v);
    }
    double v = a.sigma_bias(i) * a.sigma_bias(i);
    for (int k = 0; k < 3; ++k) {
      const double g = (I + a.M)(i, k) * b.sigma_bias(k);
      const double h = b.bias(k) * a.sigma_M(i, k);
      v += g * g + h * h;
    }
    out.sigma_bias(i) = std::sqrt(v);
  }
  return out;
}

SensorErrors compose(const SensorErrors& first, const SensorErrors& second) {
  return {compose(first.gyro, second.gyro), compose(first.accel, second.accel)};
}

TriadErrors compose_fused(const TriadErrors& a, const TriadErrors& b) {
  TriadErrors out = compose(a, b);
  const Mat3 A = Mat3::Identity() + a.M;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double v = 0;
      for (int k = 0; k < 3; ++k) v += std::pow(A(i, k) * b.sigma_M(k, j), 2);
      out.sigma_M(i, j) = std::sqrt(v);
    }
    double v = 0;
    for (int k = 0; k < 3; ++k) v += std::pow(A(i, k) * b.sigma_bias(k), 2);
    out.sigma_bias(i) = std::sqrt(v);
  }
  return out;
}

SensorErrors compose_fused(const SensorErrors& first, const SensorErrors& second) {
  return {compose_fused(first.gyro, second.gyro), compose_fused(first.accel, second.accel)};
}

}  // namespace calbench
