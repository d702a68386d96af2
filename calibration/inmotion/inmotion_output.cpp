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
  e.gyro.bias = n_.bg;
  e.accel.bias = n_.ba;
  e.gyro.M = n_.Mg;
  e.accel.M = n_.Ma;
  const int bg = off(Block::bg), ba = off(Block::ba), mg = off(Block::Mg), ma = off(Block::Ma);
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

void InMotionFilter::totals(Vec& x, Vec& sig) const {
  x.resize(N_);
  sig.resize(N_);
  // σ in display units, each block by its declared factor; the mounting σ is of its Euler angles.
  const Vec sd = P_.diagonal().cwiseMax(0.0).cwiseSqrt();
  double v[16];
  for (const BlockSpec* b : layout_.specs) {
    const int o = layout_.L.offset(static_cast<int>(b->id));
    if (b->total) b->total(n_, o, v);
    for (int i = 0; i < b->size; ++i) {
      x(o + i) = b->total ? v[i] / (b->total_per_display ? b->total_per_display[i] : b->si_per_display) : 0.0;
      sig(o + i) = sd(o + i) / b->si_per_display;
    }
  }
  if (off(Block::mount) >= 0) {
    Vec3 mr, ms;
    mounting_rpy(mr, ms);
    sig.segment<3>(off(Block::mount)) = ms / units::kDeg;
  }
}

namespace {
// Total drift b + d per axis in series units and its 1σ from a covariance (any layout).
template <class M, class V>
void total_drift_of(const V& x_series, const M& P, int bg, int ba, int dg, int da, Eigen::Matrix<double, 6, 1>& x,
                    Eigen::Matrix<double, 6, 1>& s) {
  for (int k = 0; k < 6; ++k) {
    const int b = k < 3 ? bg + k : ba + k - 3, d = k < 3 ? dg + k : da + k - 3;
    const double unit = k < 3 ? units::kDegPerHour : units::kMilliG;
    x(k) = x_series(b) + x_series(d);
    s(k) = std::sqrt(std::max(0.0, static_cast<double>(P(b, b) + P(d, d) + 2 * P(b, d)))) / unit;
  }
}
}  // namespace

void InMotionFilter::total_drift(Vec6& x, Vec6& sigma) const {
  Vec xs, ss;
  totals(xs, ss);
  total_drift_of(xs, P_, off(Block::bg), off(Block::ba), off(Block::dg), off(Block::da), x, sigma);
}

std::vector<InMotionFilter::SmoothedEpoch> InMotionFilter::smooth() {
  std::vector<SmoothedEpoch> out;
  if (store_.empty()) return out;
  store_.back().dx_next = pending_dx_.cast<float>();
  // Scale of each state between series units and SI (for the sensor blocks).
  Vec unit = Vec::Ones(N_);
  std::vector<bool> sensor(static_cast<std::size_t>(N_), false);  // the smoother corrects the sensor blocks' series values only
  for (const BlockSpec* b : layout_.specs) {
    const int o = layout_.L.offset(static_cast<int>(b->id));
    if (!b->sensor) continue;
    unit.segment(o, b->size).setConstant(1.0 / b->si_per_display);
    for (int i = 0; i < b->size; ++i) sensor[static_cast<std::size_t>(o + i)] = true;
  }
  Vec s = Vec::Zero(N_);  // smoothed minus filtered totals (SI) at epoch k+1
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
    e.sigma = Ps.diagonal().cwiseMax(0.0).cwiseSqrt().cwiseProduct(unit);
    for (int i = 0; i < N_; ++i)
      if (sensor[static_cast<std::size_t>(i)]) e.x(i) += s(i) * unit(i);
    total_drift_of(e.x, Ps, off(Block::bg), off(Block::ba), off(Block::dg), off(Block::da), e.total, e.total_sigma);
    out[static_cast<std::size_t>(k)] = e;
  }
  return out;
}

}  // namespace calbench::inmotion
