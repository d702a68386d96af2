#include "calibration/inmotion/inmotion_filter.hpp"

#include <cmath>
#include <stdexcept>

#include "calibration/units.hpp"

namespace calbench::inmotion {

using ins::skew;

namespace {
constexpr double kChi2_3_95 = 7.814727903;

template <int K, class M>
void set_diag(M& P, int off, double sigma) {
  for (int i = 0; i < K; ++i) P(off + i, off + i) = sigma * sigma;
}

DriftPrior prior_of(const std::optional<std::array<DriftPrior, 3>>& v, int i, const TriadNoise& n) {
  return v ? (*v)[static_cast<std::size_t>(i)] : DriftPrior{n.drift_sigma, n.drift_tau_s};
}
}  // namespace

bool needs_augmented_layout(const InMotionConfig& cfg) {
  for (int i = 0; i < 3; ++i)
    if ((cfg.gyro_drift && (*cfg.gyro_drift)[i].exp_cosine) || (cfg.accel_drift && (*cfg.accel_drift)[i].exp_cosine))
      return true;
  return false;
}

template <int N>
InMotionFilterT<N>::InMotionFilterT(const InMotionConfig& cfg, const Mat3& C_mb, const Vec3& lever, const RefObs& first)
    : cfg_(cfg), lever_(lever), C_mb_(C_mb) {
  for (int i = 0; i < 3; ++i) {
    const DriftPrior g = prior_of(cfg_.gyro_drift, i, cfg_.noise.gyro);
    const DriftPrior a = prior_of(cfg_.accel_drift, i, cfg_.noise.accel);
    alpha_g_(i) = g.tau_s > 0 ? 1.0 / g.tau_s : 0.0;
    alpha_a_(i) = a.tau_s > 0 ? 1.0 / a.tau_s : 0.0;
    sig_dg_(i) = g.sigma;
    sig_da_(i) = a.sigma;
    const DriftPrior* pr[2] = {&g, &a};
    for (int s = 0; s < 2; ++s) {
      if (!pr[s]->exp_cosine) continue;
      if constexpr (N == kStatesAug) {
        identification::DriftModel m;
        m.kind = identification::DriftModelKind::exp_cosine;
        m.sigma = pr[s]->sigma;
        m.alpha = 1.0 / pr[s]->tau_s;
        m.beta = pr[s]->beta;
        sf_[3 * s + i] = identification::shaping_filter(m);
        expcos_[3 * s + i] = true;
      } else {
        throw std::invalid_argument("InMotionFilter: an exponential-cosine drift model needs the augmented layout "
                                    "(InMotionFilterT<kStatesAug>)");
      }
    }
  }
  // Transfer the reference state to the MEMS IMU through the nominal mounting and lever arm.
  const Mat3 C_nb = ins::dcm_from_rpy(first.rpy);
  nav_.reset(mems_state_from_reference(first, C_mb_, lever_));

  P_.setZero();
  const double sp = first.sigma_pos > 0 ? first.sigma_pos : cfg_.ref_sigma_pos;
  const double sv = first.sigma_vel > 0 ? first.sigma_vel : cfg_.ref_sigma_vel;
  const double sa = first.sigma_att > 0 ? first.sigma_att : cfg_.ref_sigma_att;
  set_diag<3>(P_, kPos, std::hypot(sp, 0.05));
  set_diag<3>(P_, kVel, std::hypot(sv, cfg_.sigma_vel0));
  const ParameterPriors& pr = cfg_.prior;
  for (int i = 0; i < 3; ++i) {
    P_(kBg + i, kBg + i) = pr.gyro_bias(i) * pr.gyro_bias(i);
    P_(kBa + i, kBa + i) = pr.accel_bias(i) * pr.accel_bias(i);
    for (int j = 0; j < 3; ++j) {
      P_(kMg + 3 * i + j, kMg + 3 * i + j) = pr.gyro_M(i, j) * pr.gyro_M(i, j);
      P_(kMa + 3 * i + j, kMa + 3 * i + j) = pr.accel_M(i, j) * pr.accel_M(i, j);
    }
  }
  for (int i = 0; i < 3; ++i) {
    P_(kDg + i, kDg + i) = sig_dg_(i) * sig_dg_(i);
    P_(kDa + i, kDa + i) = sig_da_(i) * sig_da_(i);
  }
  if constexpr (N == kStatesAug) {
    // Exponential-cosine axes start from the stationary covariance P∞ of (x[0], x[1]).
    for (int k = 0; k < 6; ++k) {
      if (!expcos_[k]) continue;
      const int idx[2] = {k < 3 ? kDgAux + k : kDaAux + k - 3, k < 3 ? kDg + k : kDa + k - 3};
      for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 2; ++c) P_(idx[r], idx[c]) = sf_[k].P_inf(r, c);
    }
  }
  // The initial MEMS attitude error is the mounting error seen in NED plus the reference's own:
  // φ₀ = C_nb·δμ + ε_ref, so the two blocks start correlated.
  const Mat3 Pm = pr.mount.cwiseProduct(pr.mount).asDiagonal();
  P_.template block<3, 3>(kMount, kMount) = Pm;
  P_.template block<3, 3>(kAtt, kAtt) = C_nb * Pm * C_nb.transpose() + Mat3::Identity() * (sa * sa);
  P_.template block<3, 3>(kAtt, kMount) = C_nb * Pm;
  P_.template block<3, 3>(kMount, kAtt) = (C_nb * Pm).transpose();
  refresh_correctors();
}

template <int N>
void InMotionFilterT<N>::refresh_correctors() {
  Ag_ = (Mat3::Identity() + Mg_).inverse();
  Aa_ = (Mat3::Identity() + Ma_).inverse();
}

template <int N>
void InMotionFilterT<N>::imu(double t, const Vec3& dth_raw, const Vec3& dv_raw, double dt) {
  if (!(dt > 0) || t <= nav_.state().t) return;
  const Vec3 dth = Ag_ * (dth_raw - (bg_ + dg_) * dt);
  const Vec3 dv = Aa_ * (dv_raw - (ba_ + da_) * dt);
  const Mat3 C0 = nav_.state().C_nb();
  nav_.update(dth, dv, dt);
  w_last_ = dth / dt;
  acc_.add(C0, Ag_, Aa_, w_last_, dv / dt, dt);
  nav_.state().t = t;
  if (acc_.T >= cfg_.cov_dt) propagate();
}

template <int N>
void InMotionFilterT<N>::propagate() {
  const double T = acc_.T;
  if (!(T > 0)) return;
  Mat F = Mat::Zero();
  NavBlockInputs in;
  in.lat = nav_.state().lat;
  in.h = nav_.state().h;
  in.v_ned = nav_.state().v;
  in.f_n = acc_.f_n / T;
  in.earth = ins::local_earth(in.lat, in.h, in.v_ned);
  nav_block(in, F);
  gyro_blocks(acc_, F);
  accel_blocks(acc_, F);
  drift_blocks(alpha_g_, alpha_a_, F);
  if constexpr (N == kStatesAug)
    for (int k = 0; k < 6; ++k)
      if (expcos_[k]) expcos_drift_block(sf_[k], k < 3 ? kDgAux + k : kDaAux + k - 3, k < 3 ? kDg + k : kDa + k - 3, F);
  const Mat FT = F * T;
  const Mat Phi = Mat::Identity() + FT + 0.5 * FT * FT;

  Mat Q = Mat::Zero();
  const double qg = cfg_.noise.gyro.white_density, qa = cfg_.noise.accel.white_density;
  for (int i = 0; i < 3; ++i) {
    Q(kAtt + i, kAtt + i) = qg * qg * T;
    Q(kVel + i, kVel + i) = qa * qa * T;
    Q(kPos + i, kPos + i) = qa * qa * T * T * T / 3.0;
    Q(kDg + i, kDg + i) = sig_dg_(i) * sig_dg_(i) * (1.0 - std::exp(-2.0 * alpha_g_(i) * T));
    Q(kDa + i, kDa + i) = sig_da_(i) * sig_da_(i) * (1.0 - std::exp(-2.0 * alpha_a_(i) * T));
  }
  if constexpr (N == kStatesAug)
    for (int k = 0; k < 6; ++k)
      if (expcos_[k]) expcos_drift_noise(discrete(k, T), k < 3 ? kDgAux + k : kDaAux + k - 3, k < 3 ? kDg + k : kDa + k - 3, Q);
  Mat P_next = Phi * P_ * Phi.transpose() + Q;
  P_next = 0.5 * (P_next + P_next.transpose()).eval();

  if (cfg_.store_for_smoother) {
    if (!store_.empty()) store_.back().dx_next = pending_dx_.template cast<float>();
    Stored s;
    s.t = nav_.state().t - T;
    s.P_post = P_.template cast<float>();
    s.Phi = Phi.template cast<float>();
    s.P_prior_next = P_next.template cast<float>();
    s.dx_next.setZero();
    Vec x, sig;
    totals(x, sig);
    s.x_post = x;
    store_.push_back(std::move(s));
    pending_dx_.setZero();
  }
  P_ = P_next;
  propagate_drift_nominal(T);
  acc_.clear();
}

template <int N>
bool InMotionFilterT<N>::reference(const RefObs& r_in) {
  if (r_in.t < last_obs_t_ + 1.0 / cfg_.obs_rate_hz - 1e-6) return false;
  if (r_in.t > nav_.state().t + 1e-6) return false;  // not reached yet: caller's ordering error
  last_obs_t_ = r_in.t;
  propagate();

  // Bring the reference epoch to the INS time (at most one IMU interval): position with its
  // velocity, velocity with the INS's acceleration, attitude with the measured body rate.
  RefObs r = r_in;
  const double dt = nav_.state().t - r.t;
  if (dt > 0) {
    ins::geodetic_add_ned(r.lat, r.lon, r.h, r.v_ned * dt);
    const Mat3 C_ref = ins::dcm_from_rpy(r.rpy) * ins::quat_from_rotvec(C_mb_ * w_last_ * dt).toRotationMatrix();
    r.rpy = ins::rpy_from_dcm(C_ref);
  }
  if (!(r.sigma_pos > 0)) r.sigma_pos = cfg_.ref_sigma_pos;
  if (!(r.sigma_vel > 0)) r.sigma_vel = cfg_.ref_sigma_vel;
  if (!(r.sigma_att > 0)) r.sigma_att = cfg_.ref_sigma_att;

  ObsContext c;
  c.mems = &nav_.state();
  c.C_mb = C_mb_;
  c.lever = lever_;
  const Vec3 w_ie_b = predicted_body_attitude(c).transpose() * ins::earth_rate_ned_at(nav_.state().lat);
  c.w_eb_b = C_mb_ * w_last_ - w_ie_b;

  Vec dx = Vec::Zero();
  const bool use[3] = {cfg_.obs_pos, cfg_.obs_vel, cfg_.obs_att};
  for (int type = 0; type < 3; ++type) {
    if (!use[type]) continue;
    const Observation o = type == 0 ? position_observation(c, r) : type == 1 ? velocity_observation(c, r) : attitude_observation(c, r);
    Eigen::Matrix<double, 3, N> H;
    if constexpr (N == kStates) {
      H = o.H;
    } else {
      H.setZero();
      H.template leftCols<kStates>() = o.H;  // the augmented states are not observed directly
    }
    const Vec3 nu = o.z - H * dx;
    Eigen::Matrix<double, N, 3> PHt = P_ * H.transpose();
    Eigen::LDLT<Mat3> Sl(H * PHt + o.R);
    const double nis = nu.dot(Sl.solve(nu));
    ConsistencyStats& st = stats_[type];
    InnovationRecord& rec = innov_[type];
    rec.t = r.t;
    rec.nu = nu;
    rec.S = H * PHt + o.R;
    rec.nis = nis;
    rec.status = InnovationRecord::used;
    if (!(nis <= cfg_.gate_nis)) {
      if (st.rejected_since < 0) st.rejected_since = r.t;
      if (!std::isfinite(nis) || r.t - st.rejected_since < cfg_.gate_recover_s) {
        ++st.rejected;
        rec.status = InnovationRecord::rejected;
        continue;
      }
      rec.status = InnovationRecord::forced;
      // Lost track: widen the navigation block (D·P·D, D = √λ on position, velocity, attitude)
      // until this innovation is at the gate, then use it.
      ++st.forced;
      st.rejected_since = -1;
      double lo = 1, hi = nis / cfg_.gate_nis * 1e4;
      for (int it = 0; it < 40; ++it) {  // bisection on λ (NIS falls monotonically with it)
        const double lam = std::sqrt(lo * hi);
        Mat Pl = P_;
        const double d = std::sqrt(lam);
        Pl.template middleRows<9>(kPos) *= d;
        Pl.template middleCols<9>(kPos) *= d;
        const Eigen::LDLT<Mat3> Sx(H * Pl * H.transpose() + o.R);
        (nu.dot(Sx.solve(nu)) > cfg_.gate_nis ? lo : hi) = lam;
      }
      const double d = std::sqrt(hi);
      P_.template middleRows<9>(kPos) *= d;
      P_.template middleCols<9>(kPos) *= d;
      PHt = P_ * H.transpose();
      Sl.compute(H * PHt + o.R);
    } else {
      st.rejected_since = -1;
      ++st.used;
      st.nis_sum += nis;
      if (nis <= kChi2_3_95) ++st.within95;
    }
    const Eigen::Matrix<double, N, 3> K = Sl.solve(PHt.transpose()).transpose();
    dx += K * nu;
    P_ -= K * PHt.transpose();
    P_ = 0.5 * (P_ + P_.transpose()).eval();
  }
  feedback(dx);
  if (cfg_.store_for_smoother) pending_dx_ += dx;
  return true;
}

template <int N>
void InMotionFilterT<N>::feedback(const Vec& dx) {
  ins::NavState& s = nav_.state();
  ins::geodetic_add_ned(s.lat, s.lon, s.h, -dx.template segment<3>(kPos));
  s.v -= dx.template segment<3>(kVel);
  s.q_nb = ins::quat_from_rotvec(dx.template segment<3>(kAtt)) * s.q_nb;
  s.q_nb.normalize();
  bg_ -= dx.template segment<3>(kBg);
  ba_ -= dx.template segment<3>(kBa);
  dg_ -= dx.template segment<3>(kDg);
  da_ -= dx.template segment<3>(kDa);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Mg_(i, j) -= dx(kMg + 3 * i + j);
      Ma_(i, j) -= dx(kMa + 3 * i + j);
    }
  if constexpr (N == kStatesAug) {
    xg0_ -= dx.template segment<3>(kDgAux);
    xa0_ -= dx.template segment<3>(kDaAux);
  }
  C_mb_ = ins::quat_from_rotvec(dx.template segment<3>(kMount)).toRotationMatrix() * C_mb_;
  refresh_correctors();
}

template <int N>
const identification::DiscreteShapingFilter& InMotionFilterT<N>::discrete(int k, double T) {
  // The propagation step takes few distinct values (cov_dt plus whole IMU intervals, and the
  // remainders at reference epochs); recompute only when it changes.
  if (disc_[k].dt != T) disc_[k] = identification::discretise(sf_[k], T);
  return disc_[k];
}

template <int N>
void InMotionFilterT<N>::propagate_drift_nominal(double T) {
  // x̂ ← Φ·x̂ (the prediction of the shaping filters). First-order axes only on request.
  for (int k = 0; k < 6; ++k) {
    double& d = k < 3 ? dg_(k) : da_(k - 3);
    if (expcos_[k]) {
      double& x0 = k < 3 ? xg0_(k) : xa0_(k - 3);
      const Eigen::Vector2d x = discrete(k, T).Phi * Eigen::Vector2d(x0, d);
      x0 = x(0);
      d = x(1);
    } else if (cfg_.propagate_drift) {
      d *= std::exp(-(k < 3 ? alpha_g_(k) : alpha_a_(k - 3)) * T);
    }
  }
}

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
  Vec sd = P_.diagonal().cwiseMax(0.0).cwiseSqrt();
  sig = sd;
  sig.template segment<3>(kAtt) = sd.template segment<3>(kAtt) / kDeg;
  sig.template segment<3>(kBg) = sd.template segment<3>(kBg) / kDegPerHour;
  sig.template segment<3>(kDg) = sd.template segment<3>(kDg) / kDegPerHour;
  sig.template segment<3>(kBa) = sd.template segment<3>(kBa) / kMilliG;
  sig.template segment<3>(kDa) = sd.template segment<3>(kDa) / kMilliG;
  sig.template segment<9>(kMg) = sd.template segment<9>(kMg) / kPpm;
  sig.template segment<9>(kMa) = sd.template segment<9>(kMa) / kPpm;
  sig.template segment<3>(kMount) = ms / kDeg;
  if constexpr (N == kStatesAug) {
    sig.template segment<3>(kDgAux) = sd.template segment<3>(kDgAux) / kDegPerHour;
    sig.template segment<3>(kDaAux) = sd.template segment<3>(kDaAux) / kMilliG;
  }
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
  unit.template segment<3>(kBg).setConstant(1.0 / units::kDegPerHour);
  unit.template segment<3>(kDg).setConstant(1.0 / units::kDegPerHour);
  unit.template segment<3>(kBa).setConstant(1.0 / units::kMilliG);
  unit.template segment<3>(kDa).setConstant(1.0 / units::kMilliG);
  unit.template segment<9>(kMg).setConstant(1.0 / units::kPpm);
  unit.template segment<9>(kMa).setConstant(1.0 / units::kPpm);
  if constexpr (N == kStatesAug) {
    unit.template segment<3>(kDgAux).setConstant(1.0 / units::kDegPerHour);
    unit.template segment<3>(kDaAux).setConstant(1.0 / units::kMilliG);
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
    for (int i = kBg; i < N; ++i)
      if (i < kMount || i >= kDg) e.x(i) += s(i) * unit(i);
    total_drift_of(e.x, Ps, e.total, e.total_sigma);
    out[static_cast<std::size_t>(k)] = e;
  }
  return out;
}

template class InMotionFilterT<kStates>;
template class InMotionFilterT<kStatesAug>;

}  // namespace calbench::inmotion
