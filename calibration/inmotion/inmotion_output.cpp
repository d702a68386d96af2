// The in-motion filter's output side: the estimate with σ, the totals of every state in the
// series' display units (each block's value and factor from its declaration, state_blocks.cpp)
// and the RTS smoother. Apart from inmotion_filter.cpp so that the propagation and update code
// stays free of display units.
#include <cmath>
#include <vector>

#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"

namespace calbench::inmotion {

SensorErrors InMotionFilter::estimate() const {
  SensorErrors e;
  const int bg = off(Block::bg), ba = off(Block::ba), mg = off(Block::Mg), ma = off(Block::Ma);
  e.gyro.bias = n_.vec3(bg);
  e.accel.bias = n_.vec3(ba);
  e.gyro.M = n_.mat3(mg);
  e.accel.M = n_.mat3(ma);
  for (int i = 0; i < 3; ++i) {
    e.gyro.sigma_bias(i) = std::sqrt(P_(bg + i, bg + i));
    e.accel.sigma_bias(i) = std::sqrt(P_(ba + i, ba + i));
    for (int j = 0; j < 3; ++j) {
      e.gyro.sigma_M(i, j) = std::sqrt(P_(mg + 3 * i + j, mg + 3 * i + j));
      e.accel.sigma_M(i, j) = std::sqrt(P_(ma + 3 * i + j, ma + 3 * i + j));
    }
  }
  return e;
}

Vec3 InMotionFilter::gyro_total_drift_sigma() const {
  const int bg = off(Block::bg), dg = off(Block::dg);
  Vec3 s;
  for (int i = 0; i < 3; ++i)
    s(i) = std::sqrt(std::max(0.0, P_(bg + i, bg + i) + P_(dg + i, dg + i) + 2 * P_(bg + i, dg + i)));
  return s;
}

void InMotionFilter::mounting_rpy(Vec3& rpy, Vec3& sigma) const {
  rpy = ins::rpy_from_dcm(n_.C_mb);
  sigma.setZero();
  const int mo = off(Block::mount);
  if (mo < 0) return;  // not estimated: the nominal mounting, taken as exact
  const Mat3 J = ins::rpy_jacobian_left(n_.C_mb);  // ∂rpy/∂δμ for C_mb ← (I + δμ×)C_mb
  const Mat3 S = J * P_.block<3, 3>(mo, mo) * J.transpose();
  sigma = S.diagonal().cwiseMax(0.0).cwiseSqrt();
}

std::vector<std::string> InMotionFilter::column_names() const { return inmotion::column_names(layout_); }

void InMotionFilter::state_si(Vec& x, Vec& sig) const {
  x.resize(N_);
  sig.resize(N_);
  sig = P_.diagonal().cwiseMax(0.0).cwiseSqrt();
  double v[16];
  for (const BlockSpec* b : layout_.specs) {
    const int o = layout_.L.offset(static_cast<int>(b->id));
    if (b->total) b->total(n_, o, v);
    for (int i = 0; i < b->size; ++i) x(o + i) = b->total ? v[i] : 0.0;
  }
  if (off(Block::mount) >= 0) {  // the mounting σ is of its Euler angles
    Vec3 mr, ms;
    mounting_rpy(mr, ms);
    sig.segment<3>(off(Block::mount)) = ms;
  }
}

namespace {
// 1σ of b + d per axis (SI) from a covariance, with the b–d correlation.
template <class M>
Eigen::Matrix<double, 6, 1> total_drift_sigma(const M& P, int bg, int ba, int dg, int da) {
  Eigen::Matrix<double, 6, 1> s;
  for (int k = 0; k < 6; ++k) {
    const int b = k < 3 ? bg + k : ba + k - 3, d = k < 3 ? dg + k : da + k - 3;
    s(k) = std::sqrt(std::max(0.0, static_cast<double>(P(b, b) + P(d, d) + 2 * P(b, d))));
  }
  return s;
}
}  // namespace

void InMotionFilter::total_drift_si(Vec6& x, Vec6& sigma) const {
  x << n_.vec3(off(Block::bg)) + n_.vec3(off(Block::dg)), n_.vec3(off(Block::ba)) + n_.vec3(off(Block::da));
  sigma = total_drift_sigma(P_, off(Block::bg), off(Block::ba), off(Block::dg), off(Block::da));
}

std::vector<InMotionFilter::SmoothedEpoch> InMotionFilter::smooth() {
  std::vector<SmoothedEpoch> out;
  if (store_.empty()) return out;
  store_.back().dx_next = pending_dx_.cast<float>();
  // The smoother corrects the sensor blocks' values only (navigation and mounting: forward pass).
  std::vector<bool> sensor(static_cast<std::size_t>(N_), false);
  for (const BlockSpec* b : layout_.specs) {
    const int o = layout_.L.offset(static_cast<int>(b->id));
    if (!b->sensor) continue;
    for (int i = 0; i < b->size; ++i) sensor[static_cast<std::size_t>(o + i)] = true;
  }
  Vec s = Vec::Zero(N_);  // smoothed minus filtered values (SI) at epoch k+1
  Mat Ps = P_;            // smoothed covariance at the final epoch
  out.resize(store_.size());
  for (long k = static_cast<long>(store_.size()) - 1; k >= 0; --k) {
    const Stored& st = store_[static_cast<std::size_t>(k)];
    const Mat Pk = st.P_post.cast<double>(), Pn = st.P_prior_next.cast<double>(), Phi = st.Phi.cast<double>();
    const Mat A = Pn.ldlt().solve(Phi * Pk).transpose();
    s = A * (s - st.dx_next.cast<double>());
    Ps = Pk + A * (Ps - Pn) * A.transpose();
    SmoothedEpoch e;
    e.t = st.t;
    e.x = st.x_post;
    e.sigma = Ps.diagonal().cwiseMax(0.0).cwiseSqrt();
    for (int i = 0; i < N_; ++i)
      if (sensor[static_cast<std::size_t>(i)]) e.x(i) += s(i);
    e.total_sigma = total_drift_sigma(Ps, off(Block::bg), off(Block::ba), off(Block::dg), off(Block::da));
    out[static_cast<std::size_t>(k)] = e;
  }
  return out;
}

}  // namespace calbench::inmotion
