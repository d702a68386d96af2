// Strapdown inertial navigation: quaternion mechanization in the local NED frame on the WGS-84
// ellipsoid, driven by angle and velocity increments (Δθ, Δv) at any IMU rate (100–2460 Hz).
//   attitude: q_nb(k) = q(−ζ) ⊗ q_nb(k−1) ⊗ q(φ_k), φ_k = Δθ_k + Δθ_{k−1}×Δθ_k/12 (two-sample coning),
//             ζ = (ω_ie + ω_en)·Δt, the rotation of the NED frame over the step;
//   velocity: v(k) = v(k−1) + (I − ζ×/2)·C_nb(k−1)·Δv_f + (g − (2ω_ie + ω_en)×v)·Δt, where
//             Δv_f = Δv_k + Δθ_k×Δv_k/2 + (Δθ_{k−1}×Δv_k + Δv_{k−1}×Δθ_k)/12 (rotation + sculling);
//   position: trapezoidal in latitude, longitude and height.
// Earth quantities (radii, rates, GeographicLib normal gravity) are taken at the extrapolated
// midpoint of the step.
#pragma once
#include "calibration/ins/nav_math.hpp"

namespace calbench::ins {

struct NavState {
  double t = 0;                      // s
  double lat = 0, lon = 0, h = 0;    // rad, rad, m (WGS-84 geodetic)
  Vec3 v = Vec3::Zero();             // m/s, NED
  Quat q_nb = Quat::Identity();      // body → NED
  Mat3 C_nb() const { return q_nb.toRotationMatrix(); }
};

class Strapdown {
 public:
  explicit Strapdown(const NavState& s = {}) { reset(s); }
  // Start from a state; forgets the previous increments (coning/sculling memory).
  void reset(const NavState& s);
  // Advance by one IMU interval of length dt with body increments Δθ (rad) and Δv (m/s).
  void update(const Vec3& dtheta, const Vec3& dv, double dt);

  const NavState& state() const { return s_; }
  NavState& state() { return s_; }  // for error feedback
  const LocalEarth& earth() const { return earth_; }
  // Specific force in NED over the last step (m/s²), and the body rate (rad/s, w.r.t. inertial).
  const Vec3& f_ned() const { return f_ned_; }
  const Vec3& f_body() const { return f_body_; }
  const Vec3& w_body() const { return w_body_; }

 private:
  NavState s_;
  LocalEarth earth_;
  Vec3 prev_dth_ = Vec3::Zero(), prev_dv_ = Vec3::Zero();
  bool have_prev_ = false;
  Vec3 dv_n_last_ = Vec3::Zero();  // velocity change of the previous step (midpoint extrapolation)
  double dlat_last_ = 0, dh_last_ = 0;
  double cache_lat_ = 0, cache_h_ = 0, tan_lat_ = 0;
  Vec3 f_ned_ = Vec3::Zero(), f_body_ = Vec3::Zero(), w_body_ = Vec3::Zero();
};

// Turns rate samples (rad/s, m/s² at the end of each interval) into increments over the interval
// by the trapezoidal rule; the first sample is taken as constant over its interval.
class RateIntegrator {
 public:
  void operator()(const Vec3& w, const Vec3& f, double dt, Vec3& dtheta, Vec3& dv) {
    if (!have_) {
      dtheta = w * dt;
      dv = f * dt;
    } else {
      dtheta = 0.5 * (w + w_) * dt;
      dv = 0.5 * (f + f_) * dt;
    }
    w_ = w;
    f_ = f;
    have_ = true;
  }
  void reset() { have_ = false; }

 private:
  Vec3 w_ = Vec3::Zero(), f_ = Vec3::Zero();
  bool have_ = false;
};

}  // namespace calbench::ins
