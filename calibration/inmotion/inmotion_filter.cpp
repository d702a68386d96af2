#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/inmotion/obs_names.hpp"
#include "calibration/inmotion/gauge.hpp"

#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "common/units.hpp"

namespace calbench::inmotion {

using ins::skew;

namespace {
constexpr double kChi2_3_95 = 7.814727903;

// The measurement update shared by the observations of eqs (13)–(15) and the course update:
// dx += K·ν, P −= K·(PHᵀ)ᵀ (K = PHᵀS⁻¹ computed by the caller), P kept symmetric.
template <int M>
void apply_update(Eigen::MatrixXd& P, Eigen::VectorXd& dx, const Eigen::Matrix<double, Eigen::Dynamic, M>& K,
                  const Eigen::Matrix<double, Eigen::Dynamic, M>& PHt, const Eigen::Matrix<double, M, 1>& nu) {
  dx += K * nu;
  P -= K * PHt.transpose();
  P = 0.5 * (P + P.transpose()).eval();
}

// The same short-form update without the general matrix product's packing: P − K·PHtᵀ column by
// column (each entry's M terms summed in order, then subtracted, as the product does), then
// ½(P + Pᵀ): bit for bit apply_update's P.
template <int M>
void apply_update_fused(Eigen::MatrixXd& P, Eigen::VectorXd& dx, const Eigen::Matrix<double, Eigen::Dynamic, M>& K,
                        const Eigen::Matrix<double, Eigen::Dynamic, M>& PHt, const Eigen::Matrix<double, M, 1>& nu) {
  dx += K * nu;
  const int N = static_cast<int>(P.rows());
  const double* k = K.data();  // column-major: K(i,r) = k[r·N + i]
  for (int j = 0; j < N; ++j) {
    double pj[M];
    for (int r = 0; r < M; ++r) pj[r] = PHt(j, r);
    double* pc = P.data() + static_cast<std::ptrdiff_t>(j) * N;
    for (int i = 0; i < N; ++i) {
      double s = k[i] * pj[0];
      for (int r = 1; r < M; ++r) s += k[r * N + i] * pj[r];
      pc[i] -= s;
    }
  }
  P = 0.5 * (P + P.transpose()).eval();
}

// The columns an observation's H touches (a nonzero entry), in state order.
template <int M>
void touched_columns(const Eigen::Matrix<double, M, Eigen::Dynamic>& H, std::vector<int>& cols) {
  cols.clear();
  for (int k = 0; k < H.cols(); ++k)
    if (H.col(k).cwiseAbs().maxCoeff() > 0) cols.push_back(k);
}

// P·Hᵀ over the columns H touches: (P·Hᵀ)(i,r) = Σ_k P(i,k)·H(r,k) in the order of k, the zero
// terms of H skipped (bit for bit the matrix product, which sums them in that order too).
template <int M>
Eigen::Matrix<double, Eigen::Dynamic, M> p_times_ht(const Eigen::MatrixXd& P, const Eigen::Matrix<double, M, Eigen::Dynamic>& H,
                                                    std::vector<int>& cols) {
  touched_columns<M>(H, cols);
  Eigen::Matrix<double, Eigen::Dynamic, M> out = Eigen::Matrix<double, Eigen::Dynamic, M>::Zero(P.rows(), M);
  for (const int k : cols)
    for (int r = 0; r < M; ++r) {
      const double h = H(r, k);
      if (h != 0.0) out.col(r) += P.col(k) * h;
    }
  return out;
}

// Gᵀ = (Φ_M·P)ᵀ, N×m: Gᵀ(j,i) = Σ_k Φ_M(i,k)·P(k,j), each sum from zero over k in order, as a
// matrix product sums it (a product, then an add: no fused multiply-add, as the build has none);
// the terms with Φ_M(i,k) = 0 change no sum (x + 0·p = x) and are skipped where the R rows of a
// block all have them. P's rows are read as the columns of Pᵀ. R rows and 8 columns of Gᵀ at a
// time in registers (SSE2 pairs where the compiler has them).
// ks, as: work space (the q-th term kept: its k at ks[q], Φ_M(i0+r, k) at as[q·R + r]).
template <int R>
void phi_block_times_p(const Eigen::MatrixXd& PhiM, int i0, const Eigen::MatrixXd& Pt, Eigen::MatrixXd& Gt,
                       std::vector<int>& ks, std::vector<double>& as) {
  const int N = static_cast<int>(Pt.rows());
  ks.clear();
  as.clear();
  for (int k = 0; k < N; ++k) {
    bool any = false;
    for (int r = 0; r < R; ++r) any = any || PhiM(i0 + r, k) != 0.0;
    if (!any) continue;
    for (int r = 0; r < R; ++r) as.push_back(PhiM(i0 + r, k));
    ks.push_back(k);
  }
  const int nk = static_cast<int>(ks.size());
  int j0 = 0;
#if defined(__SSE2__)
  for (; j0 + 8 <= N; j0 += 8) {
    __m128d acc[R][4];
    for (int r = 0; r < R; ++r)
      for (int c = 0; c < 4; ++c) acc[r][c] = _mm_setzero_pd();
    for (int q = 0; q < nk; ++q) {
      const double* p = Pt.data() + static_cast<std::ptrdiff_t>(ks[q]) * N + j0;
      const __m128d p0 = _mm_loadu_pd(p), p1 = _mm_loadu_pd(p + 2), p2 = _mm_loadu_pd(p + 4), p3 = _mm_loadu_pd(p + 6);
      for (int r = 0; r < R; ++r) {
        const __m128d a = _mm_set1_pd(as[static_cast<std::size_t>(q) * R + r]);
        acc[r][0] = _mm_add_pd(acc[r][0], _mm_mul_pd(a, p0));
        acc[r][1] = _mm_add_pd(acc[r][1], _mm_mul_pd(a, p1));
        acc[r][2] = _mm_add_pd(acc[r][2], _mm_mul_pd(a, p2));
        acc[r][3] = _mm_add_pd(acc[r][3], _mm_mul_pd(a, p3));
      }
    }
    for (int r = 0; r < R; ++r) {
      double* g = Gt.data() + static_cast<std::ptrdiff_t>(i0 + r) * N + j0;
      for (int c = 0; c < 4; ++c) _mm_storeu_pd(g + 2 * c, acc[r][c]);
    }
  }
  for (; j0 + 2 <= N; j0 += 2) {
    __m128d acc[R];
    for (int r = 0; r < R; ++r) acc[r] = _mm_setzero_pd();
    for (int q = 0; q < nk; ++q) {
      const __m128d p0 = _mm_loadu_pd(Pt.data() + static_cast<std::ptrdiff_t>(ks[q]) * N + j0);
      for (int r = 0; r < R; ++r) acc[r] = _mm_add_pd(acc[r], _mm_mul_pd(_mm_set1_pd(as[static_cast<std::size_t>(q) * R + r]), p0));
    }
    for (int r = 0; r < R; ++r) _mm_storeu_pd(Gt.data() + static_cast<std::ptrdiff_t>(i0 + r) * N + j0, acc[r]);
  }
#endif
  for (; j0 < N; ++j0)
    for (int r = 0; r < R; ++r) {
      double acc = 0;
      for (int q = 0; q < nk; ++q) acc += as[static_cast<std::size_t>(q) * R + r] * Pt(j0, ks[q]);
      Gt(j0, i0 + r) = acc;
    }
}

DriftPrior prior_of(const std::optional<std::array<DriftPrior, 3>>& v, int i, const TriadNoise& n) {
  return v ? (*v)[static_cast<std::size_t>(i)] : DriftPrior{n.drift_sigma, n.drift_tau_s};
}

// A factor in a message: three significant digits ("x12.3", not std::to_string's "x12.345678").
std::string factor_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}
}  // namespace

bool needs_augmented_layout(const InMotionConfig& cfg) {
  for (int i = 0; i < 3; ++i)
    if ((cfg.gyro_drift && (*cfg.gyro_drift)[i].exp_cosine) || (cfg.accel_drift && (*cfg.accel_drift)[i].exp_cosine))
      return true;
  return false;
}

DriftModels drift_models(const InMotionConfig& cfg) {
  DriftModels d;
  for (int i = 0; i < 3; ++i) {
    const DriftPrior g = prior_of(cfg.gyro_drift, i, cfg.noise.gyro);
    const DriftPrior a = prior_of(cfg.accel_drift, i, cfg.noise.accel);
    d.alpha_g(i) = g.tau_s > 0 ? 1.0 / g.tau_s : 0.0;
    d.alpha_a(i) = a.tau_s > 0 ? 1.0 / a.tau_s : 0.0;
    d.sig_g(i) = g.sigma;
    d.sig_a(i) = a.sigma;
    const DriftPrior* pr[2] = {&g, &a};
    for (int s = 0; s < 2; ++s) {
      if (!pr[s]->exp_cosine) continue;
      identification::DriftModel m;
      m.kind = identification::DriftModelKind::exp_cosine;
      m.sigma = pr[s]->sigma;
      m.alpha = 1.0 / pr[s]->tau_s;
      m.beta = pr[s]->beta;
      d.sf[3 * s + i] = identification::shaping_filter(m);
      d.expcos[3 * s + i] = true;
    }
  }
  return d;
}

const identification::DiscreteShapingFilter& DriftModels::discrete(int k, double T) const {
  // The propagation step takes few distinct values (cov_dt plus whole IMU intervals, and the
  // remainders at reference epochs); recompute only when it changes.
  if (disc_[k].dt != T) disc_[k] = identification::discretise(sf[k], T);
  return disc_[k];
}

InMotionFilter::InMotionFilter(const InMotionConfig& cfg, const Mat3& C_mb, const Vec3& lever, const RefObs& first)
    : cfg_(cfg),
      layout_(make_layout(cfg_)),
      N_(layout_.size()),
      lever_(lever),
      still_(cfg_.standstill_window_s),
      lvl_still_(cfg_.align_level_s),
      adapt_(cfg.adaptive) {
  n_.nav = &nav_.state();
  n_.C_mb = C_mb;
  n_.x = Vec::Zero(N_);
  pending_dx_ = Vec::Zero(N_);
  drift_ = drift_models(cfg_);
  // Transfer the reference state to the MEMS IMU through the nominal mounting and lever arm.
  const Mat3 C_nb = ins::dcm_from_rpy(first.rpy);
  nav_.reset(mems_state_from_reference(first, n_.C_mb, lever_));

  acc_.resize(N_);
  acc_.track_jumps = cfg_.sample_time_sigma > 0;
  // Initial covariance: each block its own (state_blocks.cpp), in layout order.
  P_.setZero(N_, N_);
  const BlockInit in{cfg_, first, drift_, C_nb, first.sigma_pos > 0 ? first.sigma_pos : cfg_.ref_sigma_pos,
                     first.sigma_vel > 0 ? first.sigma_vel : cfg_.ref_sigma_vel,
                     first.sigma_att > 0 ? first.sigma_att : cfg_.ref_sigma_att};
  for (const BlockSpec* b : layout_.specs)
    if (b->init) b->init(in, layout_.L, layout_.L.offset(static_cast<int>(b->id)), P_);
  if (first.has_att) position_offset_blocks(C_nb, first.v_ned);  // ℓ̂ = 0, δt̂ = 0: the covariance only
  if (!first.has_att) {
    // A GNSS fix: no attitude. The MEMS is levelled from its own specific force over the first
    // align_level_s; the heading is re-initialised by the course over ground.
    nav_.state().v = first.has_vel ? first.v_ned : Vec3::Zero();
    nav_.state().q_nb = ins::Quat::Identity();
    phase_ = Phase::levelling;
    align_.mode = "gnss";
    align_.level_t0 = first.t;
  }
  refresh_correctors();
  rot_sigma_prior_ = inmotion::unobservable_rotation_sigma(P_, unobservable_rotation(layout_, n_));
}

void InMotionFilter::refresh_correctors() { corr_ = sensor_correction(layout_, n_); }

void InMotionFilter::scale_navigation(Mat& P, double d) const {
  for (const BlockSpec* b : layout_.specs)
    if (b->navigation) P.middleRows(off(b->id), b->size) *= d;
  for (const BlockSpec* b : layout_.specs)
    if (b->navigation) P.middleCols(off(b->id), b->size) *= d;
}

void InMotionFilter::imu(double t, const Vec3& dth_raw, const Vec3& dv_raw, double dt) {
  if (!(dt > 0) || t <= nav_.state().t) return;
  if (!bank_.f.empty()) {  // the hypotheses navigate; this filter only keeps the time
    for (auto& h : bank_.f) h->imu(t, dth_raw, dv_raw, dt);
    nav_.state().t = t;
    return;
  }
  const bool constraints = cfg_.obs_nhc || cfg_.obs_zupt;
  if (constraints) constraint_sample(t, dth_raw, dv_raw, dt);
  // The raw increments corrected by the sensor-error blocks (BlockSpec::compensate).
  const Vec3 dth = corr_.apply(kGyro, dth_raw, dt);
  const Vec3 dv = corr_.apply(kAccel, dv_raw, dt);
  if (phase_ == Phase::levelling) {  // standing: accumulate for the levelling, no navigation yet
    lvl_dth_ += dth;
    lvl_dv_ += dv;
    lvl_T_ += dt;
    lvl_f2_ += dv.squaredNorm() / dt;
    lvl_still_.add(t, dth_raw / dt, dv_raw / dt, dt);
    nav_.state().t = t;
    return;
  }
  const Mat3 C0 = nav_.state().C_nb();
  const Vec3 v0 = nav_.state().v;
  nav_.update(dth, dv, dt);
  w_last_ = dth / dt;
  a_last_ = (nav_.state().v - v0) / dt;
  motion_yaw_ += (C0 * dth)(2);  // for the epoch's mean turn rate (reporting only)
  motion_T_ += dt;
  if (cfg_.gnss_vel_latency_s != 0) vel_hist_.push(t, nav_.state().v - v0);
  acc_.add(layout_, C0, corr_, w_last_, dv / dt, dt);  // each block's part of the transition (BlockSpec::accumulate)
  nav_.state().t = t;
  if (acc_.T >= cfg_.cov_dt) {
    propagate();
    if (constraints) constrain();
  }
}

void InMotionFilter::propagate() {
  const double T = acc_.T;
  if (!(T > 0)) return;
  // F and Q start at zero: all of them for the dense path; the structured path cleared, after its
  // last step, the rows that moved (every nonzero entry of F and Q is in them).
  if (F_.rows() != N_ || cfg_.covariance == InMotionConfig::Covariance::dense) {
    F_.setZero(N_, N_);
    Q_.setZero(N_, N_);
  }
  NavBlockInputs in;
  in.lat = nav_.state().lat;
  in.h = nav_.state().h;
  in.v_ned = nav_.state().v;
  in.f_n = acc_.f_n / T;
  in.earth = ins::local_earth(in.lat, in.h, in.v_ned);
  // Each block's F entries and process noise (state_blocks.cpp), in layout order.
  const BlockDynamics dyn{cfg_, acc_, in, T, drift_, adapt_.scale()};
  for (const BlockSpec* b : layout_.specs)
    if (b->dynamics) b->dynamics(dyn, layout_.L, layout_.L.offset(static_cast<int>(b->id)), F_, Q_);
  Mat Phi;  // the full transition, for the dense path and the smoother's store only
  Mat P_next;
  // The dense products: always for the dense path; for the structured one after something left P
  // not exactly symmetric (a re-alignment's rotation), where its blocks would not be the dense ones.
  const bool dense = cfg_.covariance == InMotionConfig::Covariance::dense || !p_symmetric_;
  if (dense) {
    const Mat FT = F_ * T;
    Phi = Mat::Identity(N_, N_) + FT + 0.5 * FT * FT;
    P_next = Phi * P_ * Phi.transpose() + Q_;
    P_next = 0.5 * (P_next + P_next.transpose()).eval();
    F_.setZero();  // the structured path's next step finds F and Q at zero
    Q_.setZero();
    p_symmetric_ = true;
  } else {
    // Rows that move: a nonzero entry in F or Q. Every other row of Φ = I + FT + ½(FT)² is a row of
    // the identity (F's rows there are zero, so are those of F²) and has no process noise. With M
    // the moving rows and C the rest: Φ_M = I_M + (FT)_M + ½(FT)_MM·(FT)_M, G = Φ_M·P, and
    //   P'_MM = G·Φ_Mᵀ + Q_MM,  P'_MC = G_C,  P'_CC = P_CC  (unchanged).
    moving_.clear();
    const Eigen::VectorXd rowmax = F_.cwiseAbs().rowwise().maxCoeff().cwiseMax(Q_.cwiseAbs().rowwise().maxCoeff());
    for (int i = 0; i < N_; ++i)
      if (rowmax(i) > 0) moving_.push_back(i);
    const int m = static_cast<int>(moving_.size());
    // The products are summed term by term in the order of the state (each sum starts at zero and
    // adds its products one after the other, as the dense path's matrix products do), skipping the
    // terms whose factor from Φ or F is zero (adding 0·x changes no sum): the moving rows come out
    // as the dense path computes them, in a fraction of the work.
    const Mat FM = F_(moving_, Eigen::all) * T;
    Mat FF = Mat::Zero(m, N_);  // ½·((FT)²)_M = ½·(FT)_MM·(FT)_M
    for (int j = 0; j < N_; ++j)
      for (int k = 0; k < m; ++k) {
        const double b = FM(k, j);
        if (b != 0.0) FF.col(j) += FM.col(moving_[k]) * b;
      }
    Mat PhiM = FM;  // I_M + (FT)_M + ½(FT)²_M, added in the dense path's order
    for (int k = 0; k < m; ++k) PhiM(k, moving_[k]) += 1.0;
    PhiM += 0.5 * FF;
    // G = Φ_M·P, kept as Gᵀ (N×m).
    // P's rows are its columns: P is exactly symmetric here.
    const Mat& Pt = P_;
    work_G_.resize(N_, m);
    {
      int i = 0;
      for (; i + 2 <= m; i += 2) phi_block_times_p<2>(PhiM, i, Pt, work_G_, work_k_, work_a_);
      for (; i < m; ++i) phi_block_times_p<1>(PhiM, i, Pt, work_G_, work_k_, work_a_);
    }
    // P'_MM = G·Φ_Mᵀ + Q_MM: column j is Σ_k G(:,k)·Φ(j,k), G(:,k) the row k of Gᵀ.
    Mat Pmm = Mat::Zero(m, m);
    const Mat Gk = work_G_.transpose();  // m×N
    for (int k = 0; k < N_; ++k)
      for (int j = 0; j < m; ++j) {
        const double a = PhiM(j, k);
        if (a != 0.0) Pmm.col(j) += Gk.col(k) * a;
      }
    Pmm += Q_(moving_, moving_);
    Pmm = 0.5 * (Pmm + Pmm.transpose()).eval();
    if (cfg_.store_for_smoother) {
      Phi = Mat::Identity(N_, N_);
      Phi(moving_, Eigen::all) = PhiM;
      P_next = P_;
    }
    Mat& Pn = cfg_.store_for_smoother ? P_next : P_;
    Pn(moving_, Eigen::all) = Gk;
    Pn(Eigen::all, moving_) = work_G_;
    Pn(moving_, moving_) = Pmm;
    F_(moving_, Eigen::all).setZero();
    Q_(moving_, moving_).setZero();
    // (P_next, assigned below with the smoother, is symmetric by construction too)
  }

  if (cfg_.store_for_smoother) {
    if (!store_.empty()) store_.back().dx_next = pending_dx_.template cast<float>();
    Stored s;
    s.t = nav_.state().t - T;
    s.P_post = P_.template cast<float>();
    s.Phi = Phi.template cast<float>();
    s.P_prior_next = P_next.template cast<float>();
    s.dx_next.setZero(N_);
    Vec x, sig;
    state_si(x, sig);
    s.x_post = x;
    store_.push_back(std::move(s));
    pending_dx_.setZero(N_);
  }
  if (dense || cfg_.store_for_smoother) P_ = P_next;
  propagate_drift_nominal(T);
  refresh_correctors();  // the drift estimates moved
  acc_.clear();
}

template <int M>
Eigen::Matrix<double, Eigen::Dynamic, M> InMotionFilter::pht(const Eigen::Matrix<double, M, Eigen::Dynamic>& H) {
  if (cfg_.covariance == InMotionConfig::Covariance::dense) return P_ * H.transpose();
  return p_times_ht<M>(P_, H, work_k_);
}

template <int M>
void InMotionFilter::update(Vec& dx, const Eigen::Matrix<double, M, Eigen::Dynamic>& H, const Eigen::Matrix<double, M, M>& R,
                            const Eigen::Matrix<double, Eigen::Dynamic, M>& PHt, const Eigen::Matrix<double, Eigen::Dynamic, M>& K,
                            const Eigen::Matrix<double, M, 1>& nu) {
  p_symmetric_ = true;  // every form ends with ½(P + Pᵀ)
  if (cfg_.covariance == InMotionConfig::Covariance::dense) {
    apply_update<M>(P_, dx, K, PHt, nu);
    return;
  }
  if (cfg_.covariance == InMotionConfig::Covariance::structured) {
    apply_update_fused<M>(P_, dx, K, PHt, nu);
    return;
  }
  dx += K * nu;
  // Joseph form P' = (I − KH)·P·(I − KH)ᵀ + K·R·Kᵀ, without forming I − KH (N×N): with HP = PHtᵀ,
  //   X = P − K·PHtᵀ = (I − KH)·P,   P' = X − (X·Hᵀ)·Kᵀ + K·R·Kᵀ,
  // where X·Hᵀ uses only the columns H touches. O(N²·M) instead of O(N³); positive semi-definite
  // for any K (the short form P − K·HP is so only for the exact optimal gain, and loses digits when
  // an observation shrinks a variance by orders of magnitude).
  std::vector<int>& J = work_k_;
  touched_columns<M>(H, J);
  P_.noalias() -= K * PHt.transpose();
  const Eigen::Matrix<double, Eigen::Dynamic, M> XHt = P_(Eigen::all, J) * H(Eigen::all, J).transpose();
  P_.noalias() -= XHt * K.transpose();
  P_.noalias() += K * (R * K.transpose());
  P_ = 0.5 * (P_ + P_.transpose()).eval();
}

// The update template and P·Hᵀ for the vehicle constraints' sizes (vehicle_constraints.cpp).
template void InMotionFilter::update<2>(Vec&, const Eigen::Matrix<double, 2, Eigen::Dynamic>&, const Eigen::Matrix<double, 2, 2>&,
                                        const Eigen::Matrix<double, Eigen::Dynamic, 2>&, const Eigen::Matrix<double, Eigen::Dynamic, 2>&,
                                        const Eigen::Matrix<double, 2, 1>&);
template void InMotionFilter::update<3>(Vec&, const Eigen::Matrix<double, 3, Eigen::Dynamic>&, const Eigen::Matrix<double, 3, 3>&,
                                        const Eigen::Matrix<double, Eigen::Dynamic, 3>&, const Eigen::Matrix<double, Eigen::Dynamic, 3>&,
                                        const Eigen::Matrix<double, 3, 1>&);
template Eigen::Matrix<double, Eigen::Dynamic, 2> InMotionFilter::pht<2>(const Eigen::Matrix<double, 2, Eigen::Dynamic>&);
template Eigen::Matrix<double, Eigen::Dynamic, 3> InMotionFilter::pht<3>(const Eigen::Matrix<double, 3, Eigen::Dynamic>&);

ObsContext InMotionFilter::obs_context() const {
  ObsContext c;
  c.mems = &nav_.state();
  c.C_mb = n_.C_mb;
  c.lever = lever_;
  c.set_layout(layout_);
  set_body_rate(c, layout_, corr_, w_last_);
  c.a_ned = a_last_;
  return c;
}

bool InMotionFilter::reference(const RefObs& r_in) {
  if (!bank_.f.empty()) return bank_reference(r_in);
  constraint_note_fix(r_in);
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
    const Mat3 C_ref = ins::dcm_from_rpy(r.rpy) * ins::quat_from_rotvec(n_.C_mb * w_last_ * dt).toRotationMatrix();
    r.rpy = ins::rpy_from_dcm(C_ref);
  }
  // A GNSS velocity describing the motion gnss_vel_latency_s before its stamp (velocity_latency.hpp).
  if (cfg_.gnss_vel_latency_s != 0 && !r.has_att && r.has_vel)
    r.v_ned += vel_hist_.change(r_in.t - cfg_.gnss_vel_latency_s, nav_.state().t);
  if (!(r.sigma_pos > 0)) r.sigma_pos = cfg_.ref_sigma_pos;
  if (!(r.sigma_vel > 0)) r.sigma_vel = cfg_.ref_sigma_vel;
  if (!(r.sigma_att > 0)) r.sigma_att = cfg_.ref_sigma_att;

  // Heading from the course over ground: the fixes of the last align_window_s with the INS yaw.
  if (!cfg_.obs_att && cfg_.realign_heading) {
    const double yaw = phase_ == Phase::levelling ? std::numeric_limits<double>::quiet_NaN() : ins::rpy_from_dcm(nav_.state().C_nb() * n_.C_mb.transpose())(2);
    fixes_.push_back(Fix{r.t, r.lat, r.lon, r.h, yaw, r.v_ned, r.has_vel && cfg_.obs_vel, r.sigma_pos, r.sigma_vel});
    while (!fixes_.empty() && fixes_.front().t < r.t - cfg_.align_window_s) fixes_.pop_front();
  }
  if (phase_ == Phase::levelling) {
    if (lvl_T_ < cfg_.align_level_s) return false;
    finish_levelling(r);
  }
  if (phase_ == Phase::heading_unknown || (phase_ == Phase::aligned && !cfg_.obs_att && cfg_.realign_heading && !in_bank_)) {
    double cog = 0, sc = 0;
    std::string how;
    const bool mv = moving();
    if (phase_ == Phase::heading_unknown) {
      if (!mv) moving_since_ = -1;
      if (mv) {
        if (moving_since_ < 0) moving_since_ = r.t;
        if (!course(cog, sc, how)) {  // moving without a heading: skip until the course or the hypotheses give one
          ++align_.skipped_unaligned;
          if (cfg_.align_hypotheses > 1 && r.t - moving_since_ >= cfg_.align_bank_wait_s) start_bank(r);
          return false;
        }
        realign(r, cog, sc, "start of motion without a heading (GNSS-only start)", how);
        align_.heading_t = r.t;
        phase_ = Phase::aligned;
      }
    } else {
      if (!mv) motion_check_ = true;  // standing: the next start of motion checks the heading
      if (mv && course(cog, sc, how)) {
        const double sp = std::sqrt(std::max(0.0, P_(off(Block::att) + 2, off(Block::att) + 2)));
        double lost = 0;  // longest current run of gate rejections
        for (const ConsistencyStats& st : stats_)
          if (st.rejected_since >= 0) lost = std::max(lost, r.t - st.rejected_since);
        if (lost >= cfg_.gate_recover_s && r.t - last_realign_t_ > 3 * cfg_.gate_recover_s)
          realign(r, cog, sc, "lost track: observations rejected by the gate for " + std::to_string(static_cast<int>(lost)) + " s", how);
        else if (motion_check_ && sp > cfg_.align_heading_sigma && sc < 0.5 * sp)
          realign(r, cog, sc, "start of motion with a heading sigma of " + std::to_string(static_cast<int>(std::lround(sp / units::kDeg))) +
                                  " deg (beyond the linear range)", how);
        motion_check_ = false;
      }
    }
  }

  const ObsContext c = obs_context();
  // The motion since the previous epoch (reporting only: where innovations grow): mean turn rate
  // about the vertical and mean horizontal acceleration over the interval, not one IMU step's (a
  // handheld unit's step would sort by its vibration), and the speed now.
  const Vec3& v_nav = nav_.state().v;
  const double speed = std::hypot(v_nav(0), v_nav(1));
  double turn = (nav_.state().C_nb() * w_last_)(2), accel_h = std::hypot(a_last_(0), a_last_(1));
  if (motion_T_ > 0 && motion_have_v0_) {
    turn = motion_yaw_ / motion_T_;
    accel_h = std::hypot(v_nav(0) - motion_v0_(0), v_nav(1) - motion_v0_(1)) / motion_T_;
  }
  motion_yaw_ = motion_T_ = 0;
  motion_v0_ = v_nav;
  motion_have_v0_ = true;

  Vec dx = Vec::Zero(N_);
  const bool use[3] = {cfg_.obs_pos, cfg_.obs_vel, cfg_.obs_att};
  for (int type = 0; type < 3; ++type) {
    if (!use[type] || (type == 1 && !r.has_vel) || (type == 2 && !r.has_att)) continue;
    const Observation o = type == 0 ? position_observation(c, r) : type == 1 ? velocity_observation(c, r) : attitude_observation(c, r);
    Eigen::Matrix<double, 3, Eigen::Dynamic> H = o.H;
    Vec3 z = o.z;
    // Blocks with an observation part of their own (declared outside eqs 13–15).
    observe_blocks(layout_, BlockObsInput{c, r}, n_, type, H, z);
    const Vec3 nu = z - H * dx;
    Eigen::Matrix<double, Eigen::Dynamic, 3> PHt = pht<3>(H);
    const Mat3 HPHt = H * PHt;
    Eigen::LDLT<Mat3> Sl(HPHt + o.R);
    const double nis = nu.dot(Sl.solve(nu));
    ConsistencyStats& st = stats_[type];
    InnovationRecord& rec = innov_[type];
    rec.t = r.t;
    rec.nu = nu;
    rec.S = HPHt + o.R;
    rec.nis = nis;
    rec.status = InnovationRecord::used;
    rec.speed = speed;
    rec.turn_rate = turn;
    rec.accel = accel_h;
    if (in_bank_) {  // a heading hypothesis: its innovations' log-likelihood, and no adaptive noise
      // (a wrong heading would buy itself noise to explain its misfit)
      const double term = -0.5 * (nis + std::log(rec.S.determinant()));
      loglik_ += term;
      if (!(nis <= cfg_.gate_nis)) bank_rejected_[type] = term;
    } else if (phase_ == Phase::aligned) {
      // The adaptive process noise sees every innovation once the heading is known, a rejected one
      // capped at the gate. Not before: standing with a placeholder heading, the first metres of
      // motion are seen in the wrong direction, a misfit of the heading, not of the noise (as in the bank).
      const double cap = nis > cfg_.gate_nis ? cfg_.gate_nis / nis : 1.0;
      // (the trace of the product expression, Eigen's diagonal-only sums, as measured: HPHt.trace()
      // sums in another order and moves the walk's results at the last digit)
      adapt_.add(type, AdaptiveSample{r.t, nis * cap, 3, nu.squaredNorm() * cap, o.R.trace(), (H * PHt).trace(), speed, turn, accel_h});
    }
    if (!(nis <= cfg_.gate_nis)) {
      if (st.rejected_since < 0) st.rejected_since = r.t;
      if (!std::isfinite(nis) || r.t - st.rejected_since < cfg_.gate_recover_s || in_bank_) {
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
        scale_navigation(Pl, std::sqrt(lam));
        const Eigen::LDLT<Mat3> Sx(H * Pl * H.transpose() + o.R);
        (nu.dot(Sx.solve(nu)) > cfg_.gate_nis ? lo : hi) = lam;
      }
      p_symmetric_ = false;
      const Mat Nrot = cfg_.hold_unobservable_rotation ? unobservable_rotation(layout_, n_) : Mat();
      Eigen::Matrix3d S_rot;
      const bool hold = unobservable_rotation_covariance(P_, Nrot, S_rot);
      scale_navigation(P_, std::sqrt(hi));
      // The widening is no information: the unobservable rotation keeps its covariance (gauge.hpp).
      if (hold) restore_unobservable_rotation(P_, Nrot, S_rot);
      recoveries_.push_back({r.t, std::string("lost track: ") + obs_type_name(type) + " rejected by the gate for " +
                                      std::to_string(static_cast<int>(cfg_.gate_recover_s)) + " s",
                             "navigation covariance widened x" + factor_text(hi) + " until NIS = gate, epoch used"});
      PHt = pht<3>(H);
      Sl.compute(H * PHt + o.R);
    } else {
      st.rejected_since = -1;
      ++st.used;
      st.nis_sum += nis;
      if (nis <= kChi2_3_95) ++st.within95;
    }
    const Eigen::Matrix<double, Eigen::Dynamic, 3> K = Sl.solve(PHt.transpose()).transpose();
    update<3>(dx, H, o.R, PHt, K, nu);
  }
  // The course over ground as a heading observation while the heading is poorly known.
  if (phase_ == Phase::aligned && !cfg_.obs_att && cfg_.realign_heading && !in_bank_ && cfg_.course_update_s > 0 &&
      r.t - last_course_t_ >= cfg_.course_update_s &&
      P_(off(Block::att) + 2, off(Block::att) + 2) > cfg_.course_update_sigma * cfg_.course_update_sigma &&
      moving()) {
    double cog = 0, sc = 0;
    std::string how;
    if (course(cog, sc, how)) {
      last_course_t_ = r.t;
      // Heading of the reference body: z = ψ_course − ψ̂ = e_Dᵀ(φ − C_nb·δμ) (the down row of eq 15).
      const Mat3 C_nb = predicted_body_attitude(c);
      Eigen::Matrix<double, 1, Eigen::Dynamic> H = Eigen::Matrix<double, 1, Eigen::Dynamic>::Zero(N_);
      H(off(Block::att) + 2) = 1;
      if (off(Block::mount) >= 0) H.template segment<3>(off(Block::mount)) = -C_nb.row(2);
      const double z = std::remainder(cog - ins::rpy_from_dcm(C_nb)(2), 2 * units::kPi);
      const double nu = z - (H * dx)(0);
      const Vec PHt = pht<1>(H);
      const double S = (H * PHt)(0) + sc * sc;
      if (nu * nu / S <= cfg_.gate_nis / 3) {  // the gate per degree of freedom
        update<1>(dx, H, Eigen::Matrix<double, 1, 1>(sc * sc), PHt, Eigen::Matrix<double, Eigen::Dynamic, 1>(PHt / S),
                  Eigen::Matrix<double, 1, 1>(nu));
        ++align_.course_updates;
      } else {
        ++align_.course_rejected;
      }
    }
  }
  feedback(dx);
  if (cfg_.store_for_smoother) pending_dx_ += dx;
  return true;
}

namespace {
std::string fmt1(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}
}  // namespace

void InMotionFilter::finish_levelling(const RefObs& r) {
  // Mean specific force over the standstill in MEMS axes → roll and pitch of the MEMS frame
  // (f = C_mn·(0, 0, −g)); the yaw is a placeholder until the course over ground.
  const Vec3 f = lvl_dv_ / lvl_T_;
  const double roll = std::atan2(-f(1), -f(2)), pitch = std::atan2(f(0), std::hypot(f(1), f(2)));
  const Mat3 C_nm = ins::dcm_from_rpy(Vec3(roll, pitch, 0.0));
  ins::NavState& s = nav_.state();
  const Mat N_placeholder = cfg_.hold_unobservable_rotation ? unobservable_rotation(layout_, n_) : Mat();
  s.q_nb = ins::Quat(C_nm);
  carry_rotation(N_placeholder);
  s.lat = r.lat;
  s.lon = r.lon;
  s.h = r.h;
  ins::geodetic_add_ned(s.lat, s.lon, s.h, C_nm * n_.C_mb.transpose() * lever_);
  s.v = r.has_vel ? r.v_ned : Vec3::Zero();
  align_.level_t1 = r.t;
  align_.level_rpy = Vec3(roll, pitch, 0.0);
  align_.level_accel_std = std::sqrt(std::max(0.0, lvl_f2_ / lvl_T_ - f.squaredNorm()));
  align_.level_gyro_mean = (lvl_dth_ / lvl_T_).norm();
  align_.level_quiet = lvl_still_.quiet(cfg_.noise, cfg_.standstill_factor);
  lvl_still_ = StandstillDetector(cfg_.align_level_s);  // its samples are no longer needed
  if (cfg_.level_gyro_bias && align_.level_quiet && off(Block::bg) >= 0) {
    // The gyro bias from the standstill, the heading unknown (InMotionConfig::level_gyro_bias).
    const Vec3 y_mean = (Mat3::Identity() + n_.mat3(off(Block::Mg))) * (lvl_dth_ / lvl_T_) + n_.vec3(off(Block::bg)) + n_.vec3(off(Block::dg));
    const Observation o =
        zero_rate_observation(obs_context(), n_, y_mean, standstill_mean_sigma(cfg_.noise.gyro, cfg_.standstill_factor, lvl_T_), false);
    const Eigen::Matrix<double, Eigen::Dynamic, 3> PHt = pht<3>(o.H);
    const Eigen::LDLT<Mat3> Sl(o.H * PHt + o.R);
    const Eigen::Matrix<double, Eigen::Dynamic, 3> K = Sl.solve(PHt.transpose()).transpose();
    Vec dx = Vec::Zero(N_);
    update<3>(dx, o.H, o.R, PHt, K, o.z);
    feedback(dx);
    align_.level_gyro_bias = true;
  }
  lvl_snap_ = Snapshot{P_, n_, s.q_nb};
  phase_ = Phase::heading_unknown;
}

Vec3 InMotionFilter::position_offset_blocks(const Mat3& C_nb, const Vec3& v) {
  Vec3 d = Vec3::Zero();
  Mat G;
  for (const BlockSpec* b : layout_.specs) {
    if (!b->position_offset) continue;
    const int o = layout_.L.offset(static_cast<int>(b->id));
    Mat A;
    b->position_offset(n_, C_nb, v, o, A);
    if (G.size() == 0) G = Mat::Zero(3, N_);
    G.middleCols(o, b->size) = A;
    d += A * n_.x.segment(o, b->size);
  }
  if (G.size() == 0) return d;
  // r = r₀ + G·x: Cov(r, x) = G·P(·, x) (P(blocks, r) = 0 before), Cov(r, r) = P₀ + G·P·Gᵀ.
  const int pos = off(Block::pos);
  const Mat3 Prr = P_.block<3, 3>(pos, pos) + G * P_ * G.transpose();
  const Mat rows = G * P_;
  P_.middleRows<3>(pos) += rows;
  P_.middleCols<3>(pos) = P_.middleRows<3>(pos).transpose().eval();  // they overlap at (pos, pos): no aliasing
  P_.block<3, 3>(pos, pos) = Prr;
  p_symmetric_ = false;
  return d;
}

bool InMotionFilter::moving() const {
  if (fixes_.empty()) return false;
  const Fix& n = fixes_.back();
  if (n.has_vel && std::hypot(n.v(0), n.v(1)) >= 1.0) return true;
  if (phase_ == Phase::heading_unknown) {
    // Without a heading a fix is used only while the unit stands: walking pace and slower counts as
    // motion here (speed beyond 4σ of the fix velocity; displacement over 5 s beyond 4·√2·σ).
    if (n.has_vel) return std::hypot(n.v(0), n.v(1)) >= std::max(0.1, 4.0 * n.sigma_vel);
    for (const Fix& f : fixes_) {
      if (f.t < n.t - 5.0) continue;
      const Vec3 d = ins::geodetic_diff_ned(n.lat, n.lon, n.h, f.lat, f.lon, f.h);
      return std::hypot(d(0), d(1)) >= std::max(0.5, 4.0 * std::sqrt(2.0) * n.sigma_h);
    }
    return false;
  }
  // The INS speed once it has a heading (before, its velocity is only held by the fixes).
  if (phase_ == Phase::aligned && std::hypot(nav_.state().v(0), nav_.state().v(1)) >= 1.0) return true;
  // The fixes alone: displacement over the last 5 s beyond what their noise makes.
  for (const Fix& f : fixes_) {
    if (f.t < n.t - 5.0) continue;
    const Vec3 d = ins::geodetic_diff_ned(n.lat, n.lon, n.h, f.lat, f.lon, f.h);
    return std::hypot(d(0), d(1)) >= std::max(5.0, 4.0 * std::sqrt(2.0) * n.sigma_h);
  }
  return false;
}

bool InMotionFilter::course(double& cog, double& sigma, std::string& how) const {
  if (fixes_.empty()) return false;
  const Fix& n = fixes_.back();
  if (n.has_vel) {
    const double sp = std::hypot(n.v(0), n.v(1));
    if (sp < cfg_.align_min_speed) return false;
    cog = std::atan2(n.v(1), n.v(0));
    sigma = std::hypot(n.sigma_vel / sp, cfg_.align_sideslip);
    how = "fix velocity, " + fmt1(sp) + " m/s";
    return true;
  }
  // The chord from the oldest fix of a straight stretch to this one; its direction is the heading
  // at the middle of the stretch, moved to now by half the INS heading change along it.
  const double min_chord =
      std::clamp(std::sqrt(2.0) * n.sigma_h / cfg_.align_sideslip, cfg_.align_min_chord_m, std::max(cfg_.align_min_chord_m, cfg_.align_min_baseline_m));
  for (const Fix& f : fixes_) {
    const double turn = std::remainder(n.yaw_ins - f.yaw_ins, 2 * units::kPi);
    if (!(std::abs(turn) <= cfg_.align_max_turn)) continue;
    const Vec3 d = ins::geodetic_diff_ned(n.lat, n.lon, n.h, f.lat, f.lon, f.h);
    const double L = std::hypot(d(0), d(1));
    if (L < min_chord) break;  // later fixes give shorter chords
    cog = std::atan2(d(1), d(0)) + 0.5 * turn;
    sigma = std::hypot(std::hypot(std::sqrt(2.0) * n.sigma_h / L, cfg_.align_sideslip), 0.1 * turn);
    how = "fix positions, " + fmt1(L) + " m chord over " + fmt1(n.t - f.t) + " s";
    return true;
  }
  return false;
}

void InMotionFilter::rebind() {
  n_.nav = &nav_.state();
  layout_ = make_layout(cfg_);  // its extra blocks' specs are those of this filter's configuration
}

void InMotionFilter::start_bank(const RefObs& r) {
  const int K = cfg_.align_hypotheses;
  const double psi0 = ins::rpy_from_dcm(nav_.state().C_nb() * n_.C_mb.transpose())(2);
  const double spacing = 2 * units::kPi / K;
  for (int k = 0; k < K; ++k) {
    auto h = std::make_unique<InMotionFilter>(*this);
    h->rebind();
    h->in_bank_ = true;
    h->loglik_ = 0;
    // Each hypothesis: its heading and a σ that covers its share of the circle (uniform over the
    // spacing: spacing/√12), in the linear range of the error model.
    h->realign(r, psi0 + k * spacing, spacing / std::sqrt(12.0), "", "hypothesis");
    h->recoveries_.pop_back();
    h->phase_ = Phase::aligned;
    bank_.f.push_back(std::move(h));
  }
  bank_.t0 = r.t;
}

bool InMotionFilter::bank_reference(const RefObs& r) {
  for (auto& h : bank_.f) {
    std::fill(std::begin(h->bank_rejected_), std::end(h->bank_rejected_), std::numeric_limits<double>::quiet_NaN());
    h->reference(r);
  }
  // An innovation type every hypothesis rejected at the gate (a gross outlier: a fix 100 m off) says
  // nothing about which heading is right, and its term, large in all of them, would decide between
  // them by how near each happened to pass: it leaves every likelihood (the contaminated-normal
  // model's reading of an outlier: a constant, whatever the state). Otherwise the terms stay.
  for (int type = 0; type < 3; ++type) {
    bool all = !bank_.f.empty();
    for (const auto& h : bank_.f) all = all && std::isfinite(h->bank_rejected_[type]);
    if (all)
      for (auto& h : bank_.f) h->loglik_ -= h->bank_rejected_[type];
  }
  const double T = r.t - bank_.t0;
  if (T < cfg_.align_bank_min_s) return false;
  std::vector<std::size_t> order(bank_.f.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return bank_.f[a]->loglik_ > bank_.f[b]->loglik_; });
  // The lead over the most likely copy of another heading: copies that converged to the same heading
  // (within half the spacing of their starts) are one answer, not an ambiguity; when all did, the
  // lead is over the least likely.
  const auto heading = [](const InMotionFilter& h) { return ins::rpy_from_dcm(h.nav_.state().C_nb() * h.n_.C_mb.transpose())(2); };
  const double psi_best = heading(*bank_.f[order[0]]);
  double lead = bank_.f[order[0]]->loglik_ - bank_.f[order.back()]->loglik_;
  for (std::size_t k = 1; k < order.size(); ++k)
    if (std::abs(std::remainder(heading(*bank_.f[order[k]]) - psi_best, 2 * units::kPi)) >= units::kPi / static_cast<double>(order.size())) {
      lead = bank_.f[order[0]]->loglik_ - bank_.f[order[k]]->loglik_;
      break;
    }
  if (!(lead >= cfg_.align_bank_select) && T < cfg_.align_bank_max_s) return false;
  // The most likely hypothesis becomes the filter (its statistics include its bank epochs).
  std::unique_ptr<InMotionFilter> best = std::move(bank_.f[order[0]]);
  const int K = static_cast<int>(bank_.f.size());
  const Vec3 rpy = ins::rpy_from_dcm(best->nav_.state().C_nb() * best->n_.C_mb.transpose());
  const double sig = std::sqrt(std::max(0.0, best->P_(best->off(Block::att) + 2, best->off(Block::att) + 2)));
  std::vector<Recovery> rec = std::move(recoveries_);
  AlignmentReport al = align_;
  *this = std::move(*best);
  rebind();
  in_bank_ = false;
  loglik_ = 0;
  bank_.f.clear();
  al.heading_t = r.t;
  al.heading_hypotheses = K;
  al.heading_lead = lead;
  align_ = al;
  rec.push_back({r.t, "motion without a course over ground (GNSS-only start)",
                 "heading chosen among " + std::to_string(K) + " hypotheses by the fixes' likelihood over " + fmt1(T) +
                     " s (lead " + fmt1(lead) + (lead >= cfg_.align_bank_select ? "" : ", below the selection margin: the bank's time ran out") +
                     "): " + fmt1(rpy(2) / units::kDeg) + " deg, sigma " + fmt1(sig / units::kDeg) + " deg"});
  recoveries_ = std::move(rec);
  last_realign_t_ = r.t;
  phase_ = Phase::aligned;
  return true;
}

void InMotionFilter::realign(const RefObs& r, double cog, double sigma, const std::string& reason, const std::string& how) {
  ins::NavState& s = nav_.state();
  if (phase_ == Phase::heading_unknown && cfg_.restart_at_heading) {
    // Keep the attitude (the standstill's tilt), forget the sensor-error states' standstill.
    P_ = lvl_snap_.P;
    ins::NavState* nav = n_.nav;
    n_ = lvl_snap_.n;
    refresh_correctors();
    // P is the levelling's, the attitude is now's: the rotation's direction then, carried to now.
    Mat N_then;
    if (cfg_.hold_unobservable_rotation) {
      ins::NavState then = s;
      then.q_nb = lvl_snap_.q_nb;
      n_.nav = &then;
      N_then = unobservable_rotation(layout_, n_);
    }
    n_.nav = nav;
    carry_rotation(N_then);
  }
  p_symmetric_ = false;  // the rotation of the NED blocks need not keep P exactly symmetric
  const Mat3 C_nm = s.C_nb();
  const double dpsi = std::remainder(cog - ins::rpy_from_dcm(C_nm * n_.C_mb.transpose())(2), 2 * units::kPi);
  Mat3 R;
  R << std::cos(dpsi), -std::sin(dpsi), 0, std::sin(dpsi), std::cos(dpsi), 0, 0, 0, 1;
  s.q_nb = ins::Quat(R * C_nm);
  s.q_nb.normalize();
  const Mat3 C_nb = R * C_nm * n_.C_mb.transpose();
  if (phase_ == Phase::heading_unknown && !cfg_.restart_at_heading) {
    // Standing with a placeholder heading, the INS took the Earth rate off the gyros in the wrong
    // axes, and the fixes made the gyro drift estimate take up the difference (the tilt stayed put):
    // b̂ − b = (C_nm − Ĉ_nm)ᵀ·ω_ie. With the heading known, that part is given back.
    const Vec3 w_ie = ins::earth_rate_ned_at(s.lat);
    n_.x.segment<3>(off(Block::bg)) -= ((R * C_nm).transpose() - C_nm.transpose()) * w_ie;
    refresh_correctors();
  }
  const bool fix_vel = !fixes_.empty() && fixes_.back().has_vel;
  s.v = fix_vel ? r.v_ned : Vec3(R * s.v);
  s.lat = r.lat;
  s.lon = r.lon;
  s.h = r.h;
  ins::geodetic_add_ned(s.lat, s.lon, s.h, C_nb * lever_);
  // The NED error blocks turn with the heading (the filter's world was rotated by the heading error).
  for (const BlockSpec* b : layout_.specs)
    if (b->navigation) P_.template middleRows<3>(off(b->id)) = R * P_.template middleRows<3>(off(b->id));
  for (const BlockSpec* b : layout_.specs)
    if (b->navigation) P_.template middleCols<3>(off(b->id)) = P_.template middleCols<3>(off(b->id)) * R.transpose();
  // Heading error of the MEMS = course error ⊕ mounting error seen about down: φ_D = ε + c·δμ,
  // c = e_Dᵀ·C_nb, so it correlates with the mounting and with what the mounting correlates with.
  const Eigen::Matrix<double, 1, 3> c = C_nb.row(2);
  const int mo = off(Block::mount);  // without the mounting block the course error alone
  const Eigen::Matrix<double, 1, Eigen::Dynamic> row =
      mo >= 0 ? Eigen::Matrix<double, 1, Eigen::Dynamic>(c * P_.middleRows<3>(mo)) : Eigen::Matrix<double, 1, Eigen::Dynamic>::Zero(N_);
  const double var = sigma * sigma + (mo >= 0 ? (c * P_.block<3, 3>(mo, mo) * c.transpose())(0, 0) : 0.0);
  const int yaw = off(Block::att) + 2;
  P_.row(yaw) = row;
  P_.col(yaw) = row.transpose();
  P_(yaw, yaw) = var;
  // Position reset to the fix; velocity to the fix's, or rotated with a σ for the heading it had.
  const double sp = std::hypot(s.v(0), s.v(1));
  const double sv = fix_vel ? r.sigma_vel : std::hypot(0.5, sp * sigma);
  const Vec3 sd(r.sigma_pos, r.sigma_pos, r.sigma_pos_v > 0 ? r.sigma_pos_v : r.sigma_pos);
  const int pos = off(Block::pos), vel = off(Block::vel);
  for (int i = 0; i < 3; ++i) {
    P_.row(pos + i).setZero();
    P_.col(pos + i).setZero();
    P_(pos + i, pos + i) = sd(i) * sd(i);
    P_.row(vel + i).setZero();
    P_.col(vel + i).setZero();
    P_(vel + i, vel + i) = i < 2 ? sv * sv : (fix_vel ? sv * sv : 0.3 * 0.3);
  }
  ins::geodetic_add_ned(s.lat, s.lon, s.h, position_offset_blocks(C_nb, s.v));
  for (ConsistencyStats& st : stats_) st.rejected_since = -1;
  last_realign_t_ = r.t;
  recoveries_.push_back({r.t, reason,
                         "heading re-aligned from the course over ground (" + how + "): " + fmt1(dpsi / units::kDeg) +
                             " deg, sigma " + fmt1(std::sqrt(var) / units::kDeg) + " deg; position reset to the fix, velocity " +
                             (fix_vel ? "the fix's" : "turned with the heading")});
}

void InMotionFilter::carry_rotation(const Mat& N_before) {
  if (N_before.size() == 0) return;
  const Mat N_after = unobservable_rotation(layout_, n_);
  if (N_after == N_before) return;  // nothing it depends on moved (attitude, the two M, mounting)
  if (carry_unobservable_rotation(P_, N_before, N_after).any()) p_symmetric_ = true;
}

void InMotionFilter::feedback(const Vec& dx) {
  // The unobservable rotation's direction before the feedback (gauge.hpp).
  const Mat N_before = cfg_.hold_unobservable_rotation ? unobservable_rotation(layout_, n_) : Mat();
  // Each block feeds its own estimate back (state_blocks.cpp).
  for (const BlockSpec* b : layout_.specs)
    if (b->feedback) b->feedback(n_, layout_.L.offset(static_cast<int>(b->id)), dx);
  refresh_correctors();
  // Its conditional covariance moves with it: no information on it from moving the linearisation point.
  carry_rotation(N_before);
}

Vec3 InMotionFilter::unobservable_rotation_sigma() const {
  return inmotion::unobservable_rotation_sigma(P_, unobservable_rotation(layout_, n_));
}

void InMotionFilter::propagate_drift_nominal(double T) { propagate_drift(drift_, layout_, n_, T); }

void propagate_drift(const DriftModels& drift, const StateLayout& s, Nominal& n, double T) {
  // Between updates the drift estimates move with their shaping filters: x̂ ← Φ·x̂, the filter's
  // prediction (for a first-order axis d̂ ← e^{−αT}·d̂), each block its own (BlockSpec::predict).
  // The error state's F (δḋ = −α·δd, error_model.hpp) assumes the estimate decays with the drift;
  // held constant instead, the real error d̂ − d would have the extra term α·d̂ the covariance does
  // not carry, and the filter would be overconfident about the drift (before 2026-11-23 the
  // estimates were held: with a reference INS always, GNSS-only until 3f38af4; docs/in-motion.md,
  // "GNSS-only drives").
  for (const BlockSpec* b : s.specs)
    if (b->predict) b->predict(drift, s.L, s.L.offset(static_cast<int>(b->id)), n, T);
}


}  // namespace calbench::inmotion
