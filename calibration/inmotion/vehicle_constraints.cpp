// Vehicle constraints of the in-motion filter (InMotionConfig: obs_nhc, obs_zupt; docs/in-motion.md,
// "Vehicle constraints"): the standstill detection on the IMU stream, and the non-holonomic and
// zero-velocity/zero-rate updates (obs_nhc.cpp, obs_zupt.cpp) after a covariance propagation
// step, at most constraint_rate_hz times a second, gated and counted like the reference's
// observations.
#include <cmath>

#include "calibration/inmotion/inmotion_filter.hpp"

namespace calbench::inmotion {

namespace {
// 95 % points of χ² with 2 and 3 degrees of freedom.
double chi2_95(int dof) { return dof == 2 ? 5.991464547 : 7.814727903; }
}  // namespace

void InMotionFilter::constraint_sample(double t, const Vec3& dth_raw, const Vec3& dv_raw, double dt) {
  still_.add(t, dth_raw / dt, dv_raw / dt, dt);
  if (phase_ != Phase::levelling) {  // the zero-rate observation's mean raw rate
    c_dth_raw_ += dth_raw;
    c_T_ += dt;
  }
  if (t - last_still_eval_t_ < 1.0 / cfg_.constraint_rate_hz - 1e-9) return;
  last_still_eval_t_ = t;
  // Standstill: the IMU quiet, the INS and the last fix (within 2 s, where it has a velocity) slow.
  const bool quiet = still_.quiet(cfg_.noise, cfg_.standstill_factor);
  const bool ins_slow = phase_ == Phase::levelling || nav_.state().v.norm() < cfg_.standstill_max_speed;
  const bool fix_slow = !(fix_speed_t_ >= t - 2.0) || fix_speed_ < cfg_.standstill_max_speed;
  const bool still = quiet && ins_slow && fix_slow;
  if (still && !standing_) standstills_.push_back({still_.window_start(), t});
  if (still) standstills_.back().t1 = t;
  standing_ = still;
}

void InMotionFilter::constraint_note_fix(const RefObs& r) {
  if (!(cfg_.obs_nhc || cfg_.obs_zupt) || !r.has_vel) return;
  fix_speed_ = std::hypot(r.v_ned(0), r.v_ned(1));
  fix_speed_t_ = r.t;
}

std::vector<Standstill> InMotionFilter::standstills() const { return standstills_; }

template <int M>
bool InMotionFilter::constraint_update(Vec& dx, const ObservationM<M>& o, ConsistencyStats& st) {
  using VecM = Eigen::Matrix<double, M, 1>;
  const VecM nu = o.z - o.H * dx;
  const Eigen::Matrix<double, Eigen::Dynamic, M> PHt = pht<M>(o.H);
  const Eigen::LDLT<Eigen::Matrix<double, M, M>> Sl(o.H * PHt + o.R);
  const double nis = nu.dot(Sl.solve(nu));
  if (!(nis <= cfg_.gate_nis * M / 3.0)) {  // the reference's gate, per degree of freedom
    ++st.rejected;
    return false;
  }
  ++st.used;
  st.nis_sum += nis;
  if (nis <= chi2_95(M)) ++st.within95;
  const Eigen::Matrix<double, Eigen::Dynamic, M> K = Sl.solve(PHt.transpose()).transpose();
  update<M>(dx, o.H, o.R, PHt, K, nu);
  return true;
}

void InMotionFilter::constrain() {
  const double t = nav_.state().t;
  if (phase_ != Phase::aligned || t - last_constraint_t_ < 1.0 / cfg_.constraint_rate_hz - 1e-9 || !(c_T_ > 0)) return;
  last_constraint_t_ = t;
  const Vec3 y_mean = c_dth_raw_ / c_T_;
  const double T = c_T_;
  c_dth_raw_.setZero();
  c_T_ = 0;
  const ObsContext c = obs_context();
  Vec dx = Vec::Zero(N_);
  bool any = false;
  if (standing_) {
    if (!cfg_.obs_zupt) return;
    any = constraint_update<3>(dx, zupt_observation(c, cfg_.zupt_sigma), cstats_[kObsZupt - 3]) || any;
    if (cfg_.zupt_zero_rate) {
      const double sigma = standstill_mean_sigma(cfg_.noise.gyro, cfg_.standstill_factor, T);
      any = constraint_update<3>(dx, zero_rate_observation(c, n_, y_mean, sigma), cstats_[kObsZeroRate - 3]) || any;
    }
  } else {
    if (!cfg_.obs_nhc) return;
    const double speed = std::hypot(nav_.state().v(0), nav_.state().v(1));
    const double yaw_rate = std::abs((n_.C_mb * corr_.apply(kGyro, y_mean, 1.0))(2));
    if (speed < cfg_.nhc_min_speed || yaw_rate > cfg_.nhc_max_turn_rate || speed * yaw_rate > cfg_.nhc_max_lateral_accel) return;
    any = constraint_update<2>(dx, nhc_observation(c, cfg_.nhc_sigma), cstats_[kObsNhc - 3]);
  }
  if (!any) return;
  feedback(dx);
  if (cfg_.store_for_smoother) pending_dx_ += dx;
}

}  // namespace calbench::inmotion
