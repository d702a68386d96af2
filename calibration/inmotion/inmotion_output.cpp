// The in-motion filter's output side: the estimate with σ, the totals of every state in the
// series' display units (each block's factor from its declaration, state_blocks.hpp) and the RTS
// smoother. Apart from inmotion_filter.cpp so that the propagation and update code stays free of
// display units.
#include <array>
#include <cmath>

#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"

namespace calbench::inmotion {

template <int N>
SensorErrors InMotionFilterT<N>::estimate() const {
  SensorErrors e;
  e.gyro.bias = bg_;
  e.accel.bias = ba_;
  e.gyro.M = Mg_;
  e.accel.M = Ma_;
  for (int i = 0; i < 3; ++i) {
    e.gyro.sigma_bias(i) = std::sqrt(P_(kBg + i, kBg + i));
    e.accel.sigma_bias(i) = std::sqrt(P_(kBa + i, kBa + i));
    for (int j = 0; j < 3; ++j) {
      e.gyro.sigma_M(i, j) = std::sqrt(P_(kMg + 3 * i + j, kMg + 3 * i + j));
      e.accel.sigma_M(i, j) = std::sqrt(P_(kMa + 3 * i + j, kMa + 3 * i + j));
    }
  }
  return e;
}

template <int N>
Vec3 InMotionFilterT<N>::gyro_total_drift_sigma() const {
  Vec3 s;
  for (int i = 0; i < 3; ++i)
    s(i) = std::sqrt(std::max(0.0, P_(kBg + i, kBg + i) + P_(kDg + i, kDg + i) + 2 * P_(kBg + i, kDg + i)));
  return s;
}

template <int N>
void InMotionFilterT<N>::mounting_rpy(Vec3& rpy, Vec3& sigma) const {
  rpy = ins::rpy_from_dcm(C_mb_);
  const Mat3 J = ins::rpy_jacobian_left(C_mb_);  // ∂rpy/∂δμ for C_mb ← (I + δμ×)C_mb
  const Mat3 S = J * P_.template block<3, 3>(kMount, kMount) * J.transpose();
  sigma = S.diagonal().cwiseMax(0.0).cwiseSqrt();
}

template <int N>
void InMotionFilterT<N>::totals(Vec& x, Vec& sig) const {
  using namespace units;
  const ins::NavState& s = nav_.state();
  x(kPos) = deg(s.lat);
  x(kPos + 1) = deg(s.lon);
  x(kPos + 2) = s.h;
  x.template segment<3>(kVel) = s.v;
  const Vec3 rpy = ins::rpy_from_dcm(s.C_nb());
  for (int i = 0; i < 3; ++i) x(kAtt + i) = deg(rpy(i));
  x.template segment<3>(kBg) = bg_ / kDegPerHour;
  x.template segment<3>(kBa) = ba_ / kMilliG;
  x.template segment<3>(kDg) = dg_ / kDegPerHour;
  x.template segment<3>(kDa) = da_ / kMilliG;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      x(kMg + 3 * i + j) = Mg_(i, j) / kPpm;
      x(kMa + 3 * i + j) = Ma_(i, j) / kPpm;
    }
  Vec3 mr, ms;
  mounting_rpy(mr, ms);
  for (int i = 0; i < 3; ++i) x(kMount + i) = deg(mr(i));
  if constexpr (N == kStatesAug) {
    x.template segment<3>(kDgAux) = xg0_ / kDegPerHour;
    x.template segment<3>(kDaAux) = xa0_ / kMilliG;
  }
  // σ in display units, each block by its declared factor; the mounting σ is of its Euler angles.
  const Vec sd = P_.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (const BlockSpec& b : block_specs())
    if (offset_of(b.id) + b.size <= N) sig.segment(offset_of(b.id), b.size) = sd.segment(offset_of(b.id), b.size) / b.si_per_display;
  sig.template segment<3>(kMount) = ms / kDeg;
}

namespace {
// Total drift b + d per axis in series units and its 1σ from a covariance (any layout).
template <class M, class V>
void total_drift_of(const V& x_series, const M& P, Eigen::Matrix<double, 6, 1>& x, Eigen::Matrix<double, 6, 1>& s) {
  for (int k = 0; k < 6; ++k) {
    const int b = k < 3 ? kBg + k : kBa + k - 3, d = k < 3 ? kDg + k : kDa + k - 3;
    const double unit = k < 3 ? units::kDegPerHour : units::kMilliG;
    x(k) = x_series(b) + x_series(d);
    s(k) = std::sqrt(std::max(0.0, static_cast<double>(P(b, b) + P(d, d) + 2 * P(b, d)))) / unit;
  }
}
}  // namespace

template <int N>
void InMotionFilterT<N>::total_drift(Vec6& x, Vec6& sigma) const {
  Vec xs, ss;
  totals(xs, ss);
  total_drift_of(xs, P_, x, sigma);
}

template <int N>
std::vector<typename InMotionFilterT<N>::SmoothedEpoch> InMotionFilterT<N>::smooth() {
  std::vector<SmoothedEpoch> out;
  if (store_.empty()) return out;
  store_.back().dx_next = pending_dx_.template cast<float>();
  // Scale of each state between series units and SI (for the sensor blocks).
  Vec unit = Vec::Ones();
  std::array<bool, N> sensor{};  // the smoother corrects the sensor blocks' series values only
  for (const BlockSpec& b : block_specs()) {
    const int o = offset_of(b.id);
    if (o + b.size > N || !b.sensor) continue;
    unit.segment(o, b.size).setConstant(1.0 / b.si_per_display);
    for (int i = 0; i < b.size; ++i) sensor[static_cast<std::size_t>(o + i)] = true;
  }
  Vec s = Vec::Zero();  // smoothed minus filtered totals (SI) at epoch k+1
  Mat Ps = P_;                // smoothed covariance at the final epoch
  out.resize(store_.size());
  for (long k = static_cast<long>(store_.size()) - 1; k >= 0; --k) {
    const Stored& st = store_[static_cast<std::size_t>(k)];
    const Mat Pk = st.P_post.template cast<double>(), Pn = st.P_prior_next.template cast<double>(), Phi = st.Phi.template cast<double>();
    const Mat A = Pn.ldlt().solve(Phi * Pk).transpose();
    s = A * (s - st.dx_next.template cast<double>());
    Ps = Pk + A * (Ps - Pn) * A.transpose();
    SmoothedEpoch e;
    e.t = st.t;
    e.x = st.x_post;
    e.sigma = Ps.diagonal().cwiseMax(0.0).cwiseSqrt().cwiseProduct(unit);
    for (int i = 0; i < N; ++i)
      if (sensor[static_cast<std::size_t>(i)]) e.x(i) += s(i) * unit(i);
    total_drift_of(e.x, Ps, e.total, e.total_sigma);
    out[static_cast<std::size_t>(k)] = e;
  }
  return out;
}

// The members defined here, for both layouts (the class itself is instantiated in inmotion_filter.cpp).
#define CALBENCH_INMOTION_OUTPUT(N)                                                        \
  template SensorErrors InMotionFilterT<N>::estimate() const;                              \
  template Vec3 InMotionFilterT<N>::gyro_total_drift_sigma() const;                        \
  template void InMotionFilterT<N>::mounting_rpy(Vec3&, Vec3&) const;                      \
  template void InMotionFilterT<N>::totals(InMotionFilterT<N>::Vec&, InMotionFilterT<N>::Vec&) const; \
  template void InMotionFilterT<N>::total_drift(InMotionFilterT<N>::Vec6&, InMotionFilterT<N>::Vec6&) const; \
  template std::vector<InMotionFilterT<N>::SmoothedEpoch> InMotionFilterT<N>::smooth();
CALBENCH_INMOTION_OUTPUT(kStates)
CALBENCH_INMOTION_OUTPUT(kStatesAug)
#undef CALBENCH_INMOTION_OUTPUT

}  // namespace calbench::inmotion
