#include "calibration/diagnosis/drive_data.hpp"

#include <algorithm>
#include <cmath>

#include "calibration/ins/nav_math.hpp"

namespace calbench {

const char* motion_class_name(MotionClass c) {
  switch (c) {
    case MotionClass::stationary: return "stationary";
    case MotionClass::straight: return "straight";
    case MotionClass::turning: return "turning";
    case MotionClass::accelerating: return "accelerating";
  }
  return "?";
}

DriveDiagBuilder::DriveDiagBuilder(const Mat3& C_mb, const Vec3& lever, double parent_s, double window_s)
    : C_mb_(C_mb), lever_(lever), parent_s_(parent_s), window_s_(window_s) {}

void DriveDiagBuilder::add_part(const Vec3& dth, const Vec3& dv, double frac_dt, const DriveImuSample& s, double frac) {
  // Velocity increment in the frame at the start of the interval (rotation compensation), then
  // the attitude of the MEMS frame within the interval moves on by dθ.
  dv_acc_ += q_ * (dv + 0.5 * dth.cross(dv));
  q_ = q_ * ins::quat_from_rotvec(dth);
  q_.normalize();
  covered_ += frac_dt;
  if (frac > 0.5) ++n_;
  if (std::isfinite(s.temp_c)) {
    temp_sum_ += s.temp_c;
    ++temp_n_;
  }
}

void DriveDiagBuilder::imu(const DriveImuSample& s) {
  if (!(s.dt > 0)) return;
  const Vec3 w = s.has_rates ? s.w_raw : Vec3(s.dtheta / s.dt), f = s.has_rates ? s.f_raw : Vec3(s.dv / s.dt);
  if (have_prev_rate_) {
    for (int i = 0; i < 3; ++i) {
      dsum_[i] += 0.5 * std::pow(w(i) - prev_w_(i), 2);
      dsum_[3 + i] += 0.5 * std::pow(f(i) - prev_f_(i), 2);
    }
    ++dn_;
  }
  prev_w_ = w;
  prev_f_ = f;
  have_prev_rate_ = true;
  dt_sum_ += s.dt;
  ++dt_n_;
  if (have_pending_ && have_ref_) add_part(pending_.dtheta, pending_.dv, pending_.dt, pending_, 1.0);
  pending_ = s;
  have_pending_ = true;
}

void DriveDiagBuilder::reference(const DriveRefEpoch& r) {
  if (have_ref_ && !(r.t > last_ref_.t)) return;  // not increasing: ignore
  if (have_pending_ && pending_.t >= r.t - 1e-12 && pending_.t - pending_.dt < r.t) {
    const double a = std::clamp((r.t - (pending_.t - pending_.dt)) / pending_.dt, 0.0, 1.0);
    if (have_ref_ && a > 0) add_part(a * pending_.dtheta, a * pending_.dv, a * pending_.dt, pending_, a);
    if (have_ref_) close_interval(r);
    q_.setIdentity();
    dv_acc_.setZero();
    covered_ = temp_sum_ = 0;
    n_ = temp_n_ = 0;
    last_ref_ = r;
    have_ref_ = true;
    if (a < 1) add_part((1 - a) * pending_.dtheta, (1 - a) * pending_.dv, (1 - a) * pending_.dt, pending_, 1 - a);
    have_pending_ = false;
    return;
  }
  if (have_pending_ && pending_.t < r.t && have_ref_) {
    add_part(pending_.dtheta, pending_.dv, pending_.dt, pending_, 1.0);
    have_pending_ = false;
  }
  if (have_ref_) close_interval(r);
  q_.setIdentity();
  dv_acc_.setZero();
  covered_ = temp_sum_ = 0;
  n_ = temp_n_ = 0;
  last_ref_ = r;
  have_ref_ = true;
}

void DriveDiagBuilder::close_interval(const DriveRefEpoch& r) {
  const DriveRefEpoch& a = last_ref_;
  const double T = r.t - a.t;
  Raw x;
  x.t0 = a.t;
  x.t1 = r.t;
  if (!(T > 0) || covered_ < 0.9 * T || n_ < 1) {
    ++skipped_;
    return;
  }
  // Measured: exact composition of the increments.
  const Vec3 phi_m = ins::rotvec_from_dcm(q_.toRotationMatrix());
  x.gyro = phi_m / covered_;
  x.accel = (ins::quat_from_rotvec(-0.5 * phi_m) * dv_acc_) / covered_;
  x.n = n_;
  x.temp = temp_n_ ? temp_sum_ / temp_n_ : std::numeric_limits<double>::quiet_NaN();
  // Predicted from the reference (reference body axes).
  const Mat3 C0 = ins::dcm_from_rpy(a.rpy), C1 = ins::dcm_from_rpy(r.rpy);
  const Vec3 v_mid = 0.5 * (a.v_ned + r.v_ned);
  const ins::LocalEarth e = ins::local_earth(0.5 * (a.lat + r.lat), 0.5 * (a.h + r.h), v_mid);
  const Vec3 zeta = (e.w_ie + e.w_en) * T;
  const Mat3 R = C0.transpose() * ins::quat_from_rotvec(zeta).toRotationMatrix() * C1;
  const Vec3 phi_b = ins::rotvec_from_dcm(R);
  x.w_b = phi_b / T;
  const Vec3 f_n = (r.v_ned - a.v_ned) / T - e.g + (2 * e.w_ie + e.w_en).cross(v_mid);
  const Mat3 C_mid = C0 * ins::quat_from_rotvec(0.5 * phi_b).toRotationMatrix();
  x.f_b = C_mid.transpose() * f_n;
  x.speed = v_mid.norm();
  x.turn = (C_mid * x.w_b)(2) - (e.w_ie + e.w_en)(2);
  x.along = (r.v_ned.norm() - a.v_ned.norm()) / T;
  raw_.push_back(x);
}

DriveDiagData DriveDiagBuilder::finish() {
  DriveDiagData d;
  d.skipped_intervals = skipped_;
  d.imu_rate_hz = dt_n_ > 0 ? dt_n_ / dt_sum_ : 0;
  for (int i = 0; i < 6; ++i) d.sample_white_var[i] = dn_ > 0 ? dsum_[i] / dn_ : 0;
  const int N = static_cast<int>(raw_.size());
  if (N == 0) return d;
  const Mat3 C_bm = C_mb_.transpose();
  auto contiguous = [&](int j, int k) { return std::abs(raw_[j].t1 - raw_[k].t0) < 1e-6; };  // j before k
  auto tmid = [&](int j) { return 0.5 * (raw_[j].t0 + raw_[j].t1); };
  // Central differences over neighbouring intervals (one-sided at gaps and ends).
  auto deriv = [&](int j, auto get) -> Vec3 {
    const bool lo = j > 0 && contiguous(j - 1, j), hi = j + 1 < N && contiguous(j, j + 1);
    const int a = lo ? j - 1 : j, b = hi ? j + 1 : j;
    if (a == b) return Vec3::Zero();
    return (get(b) - get(a)) / (tmid(b) - tmid(a));
  };
  double dur = 0;
  d.subs.resize(N);
  d.sub_speed.resize(N);
  d.sub_w_body.resize(N);
  d.sub_f_body.resize(N);
  d.C_mb = C_mb_;
  for (int j = 0; j < N; ++j) {
    const Raw& x = raw_[j];
    SubBlock& s = d.subs[j];
    s.t_mid = tmid(j);
    s.duration = x.t1 - x.t0;
    s.n = x.n;
    s.gyro = x.gyro;
    s.accel = x.accel;
    const Vec3 wdot_b = deriv(j, [&](int k) { return raw_[k].w_b; });
    d.sub_w_body[j] = x.w_b;
    d.sub_f_body[j] = x.f_b + wdot_b.cross(lever_) + x.w_b.cross(x.w_b.cross(lever_));
    s.w = C_bm * d.sub_w_body[j];
    s.f = C_bm * d.sub_f_body[j];
    s.dw = deriv(j, [&](int k) { return raw_[k].gyro; });
    s.df = deriv(j, [&](int k) { return raw_[k].accel; });
    s.temp_c = x.temp;
    if (std::isfinite(x.temp)) d.has_temperature = true;
    d.sub_speed[j] = x.speed;
    dur += s.duration;
  }
  d.mean_sub_s = dur / N;
  // Parents: ~parent_s of contiguous intervals.
  int j = 0;
  while (j < N) {
    ParentBlock p;
    p.first = j;
    const double t0 = raw_[j].t0;
    int k = j;
    while (k + 1 < N && contiguous(k, k + 1) && raw_[k + 1].t1 - t0 <= parent_s_ + 0.5 * d.mean_sub_s) ++k;
    p.count = k - j + 1;
    DriveParentInfo info;
    double tw = 0;
    Vec3 wd = Vec3::Zero();
    for (int i = j; i <= k; ++i) {
      const SubBlock& s = d.subs[i];
      const double w = s.duration;
      tw += w;
      p.n += s.n;
      p.w += w * s.w;
      p.f += w * s.f;
      p.t_mid += w * s.t_mid;
      info.speed += w * raw_[i].speed;
      info.turn_rate += w * raw_[i].turn;
      info.along_accel += w * raw_[i].along;
      wd += w * deriv(i, [&](int m) { return raw_[m].w_b; });
    }
    p.duration = tw;
    p.w /= tw;
    p.f /= tw;
    p.t_mid /= tw;
    info.speed /= tw;
    info.turn_rate /= tw;
    info.along_accel /= tw;
    info.ang_accel = (wd / tw).norm();
    if (info.speed < 0.2) info.motion = MotionClass::stationary;
    else if (std::abs(info.turn_rate) > 0.035) info.motion = MotionClass::turning;
    else if (std::abs(info.along_accel) > 0.3) info.motion = MotionClass::accelerating;
    else info.motion = MotionClass::straight;
    p.step = static_cast<int>(std::floor(p.t_mid / window_s_));
    const int idx = static_cast<int>(d.parents.size());
    for (int i = j; i <= k; ++i) {
      d.subs[i].parent = idx;
      d.subs[i].step = p.step;
    }
    d.parents.push_back(p);
    d.info.push_back(info);
    j = k + 1;
  }
  return d;
}

void remount(DriveDiagData& d, const Mat3& C_mb) {
  const Mat3 C_bm = C_mb.transpose();
  for (std::size_t j = 0; j < d.subs.size(); ++j) {
    d.subs[j].w = C_bm * d.sub_w_body[j];
    d.subs[j].f = C_bm * d.sub_f_body[j];
  }
  for (ParentBlock& p : d.parents) {
    Vec3 w = Vec3::Zero(), f = Vec3::Zero();
    double tw = 0;
    for (int i = p.first; i < p.first + p.count; ++i) {
      const SubBlock& s = d.subs[i];
      w += s.duration * s.w;
      f += s.duration * s.f;
      tw += s.duration;
    }
    p.w = w / tw;
    p.f = f / tw;
  }
  d.C_mb = C_mb;
}

}  // namespace calbench
