#include "calibration/drive_sim/route.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/units.hpp"

namespace calbench::drivesim {
namespace {
constexpr double kPi = units::kPi;

// Smooth speed change v0 → v1 over T: v = v0 + Δv·(x − sin 2πx / 2π), x = τ/T.
void speed_change(double v0, double v1, double T, double tau, double& v, double& vd, double& vdd) {
  const double x = std::clamp(tau / T, 0.0, 1.0);
  const double dv = v1 - v0;
  v = v0 + dv * (x - std::sin(2 * kPi * x) / (2 * kPi));
  vd = dv / T * (1 - std::cos(2 * kPi * x));
  vdd = (tau < 0 || tau > T) ? 0.0 : dv / T * (2 * kPi / T) * std::sin(2 * kPi * x);
}

// Raised-cosine plateau of height 1 on [0, T] with ramps of length r: value, integral, derivative.
void plateau(double T, double r, double tau, double& val, double& integral, double& deriv) {
  tau = std::clamp(tau, 0.0, T);
  auto rise_int = [&](double s) { return s / 2 - r / (2 * kPi) * std::sin(kPi * s / r); };
  if (tau < r) {
    val = 0.5 * (1 - std::cos(kPi * tau / r));
    deriv = 0.5 * kPi / r * std::sin(kPi * tau / r);
    integral = rise_int(tau);
  } else if (tau <= T - r) {
    val = 1;
    deriv = 0;
    integral = r / 2 + (tau - r);
  } else {
    const double s = T - tau;
    val = 0.5 * (1 - std::cos(kPi * s / r));
    deriv = -0.5 * kPi / r * std::sin(kPi * s / r);
    integral = (T - r) - rise_int(s);
  }
}
}  // namespace

const char* segment_name(SegmentKind k) {
  switch (k) {
    case SegmentKind::accelerate: return "accelerate";
    case SegmentKind::cruise: return "cruise";
    case SegmentKind::turn: return "turn";
    case SegmentKind::stop: return "stop";
    case SegmentKind::climb: return "climb";
    case SegmentKind::lane_change: return "lane_change";
  }
  return "?";
}

RouteProfile::RouteProfile(const Route& r) : route_(r) {
  double t = 0, v = 0, psi = r.heading;
  auto bad = [](const Segment& s, const std::string& m) {
    throw std::invalid_argument("segment at line " + std::to_string(s.line) + " (" + segment_name(s.kind) + "): " + m);
  };
  for (const Segment& s : r.segments) {
    Laid l;
    l.s = s;
    l.t0 = t;
    l.v0 = v;
    l.v1 = v;
    l.psi0 = psi;
    switch (s.kind) {
      case SegmentKind::accelerate: {
        if (s.to_speed < 0) bad(s, "to_kmh must be >= 0");
        l.v1 = s.to_speed;
        const double dv = std::abs(l.v1 - v);
        // Given duration, or a default mean acceleration of 1.5 m/s².
        l.T = s.duration_s > 0 ? s.duration_s : std::max(dv / 1.5, 1.0);
        break;
      }
      case SegmentKind::cruise:
      case SegmentKind::climb:
        if (!(s.duration_s > 0)) bad(s, "duration_s must be > 0");
        l.T = s.duration_s;
        if (s.kind == SegmentKind::climb) {
          if (v <= 0) bad(s, "climb needs the vehicle moving");
          l.ramp = s.ramp_s > 0 ? s.ramp_s : 5.0;
          if (l.T < 2 * l.ramp) bad(s, "duration_s must be at least twice ramp_s");
        }
        break;
      case SegmentKind::stop:
        if (s.duration_s < 0) bad(s, "duration_s must be >= 0");
        l.brake_T = v > 0 ? std::max(v / 2.0, 1.0) : 0.0;  // braking at ~2 m/s² mean
        l.T = l.brake_T + s.duration_s;
        l.v1 = 0;
        if (!(l.T > 0)) bad(s, "empty stop");
        break;
      case SegmentKind::turn: {
        if (v <= 0) bad(s, "turn needs the vehicle moving");
        if (!(s.radius > 0)) bad(s, "radius_m must be > 0");
        if (s.angle == 0) bad(s, "angle_deg must be non-zero");
        l.rate = std::copysign(v / s.radius, s.angle);
        const double core = std::abs(s.angle / l.rate);
        l.ramp = std::min(s.ramp_s > 0 ? s.ramp_s : 2.0, core);
        l.T = core + l.ramp;
        psi += s.angle;
        break;
      }
      case SegmentKind::lane_change: {
        if (v <= 0) bad(s, "lane change needs the vehicle moving");
        l.T = s.duration_s > 0 ? s.duration_s : 4.0;
        // Heading deviation a·x³(1−x)³, x = τ/T: the lateral offset v·∫δψ dτ = v·T·a/140 = width
        // (small angles); yaw rate and yaw acceleration are 0 at both ends (see at()).
        l.rate = 140 * s.width / (v * l.T);
        break;
      }
    }
    t += l.T;
    v = l.v1;
    laid_.push_back(l);
  }
  total_ = t;
}

Motion RouteProfile::at(double t) const {
  Motion m;
  if (laid_.empty()) {
    m.rpy(2) = route_.heading;
    return m;
  }
  // Segment containing t (binary search on start times).
  auto it = std::upper_bound(laid_.begin(), laid_.end(), t, [](double x, const Laid& l) { return x < l.t0; });
  const Laid& l = it == laid_.begin() ? laid_.front() : *(it - 1);
  double tau = t - l.t0;
  const bool after = tau > l.T;
  if (after) tau = l.T;
  double vdd = 0, psi_dot = 0, psi_ddot = 0, pitch = 0, pitch_dot = 0;
  double psi = l.psi0;
  m.v = l.v0;
  switch (l.s.kind) {
    case SegmentKind::accelerate:
      speed_change(l.v0, l.v1, l.T, tau, m.v, m.v_dot, vdd);
      break;
    case SegmentKind::stop:
      if (tau < l.brake_T) speed_change(l.v0, 0.0, l.brake_T, tau, m.v, m.v_dot, vdd);
      else m.v = 0;
      break;
    case SegmentKind::cruise:
      break;
    case SegmentKind::climb: {
      double val, integ, der;
      plateau(l.T, l.ramp, tau, val, integ, der);
      pitch = l.s.grade * val;
      pitch_dot = after ? 0.0 : l.s.grade * der;
      break;
    }
    case SegmentKind::turn: {
      double val, integ, der;
      plateau(l.T, l.ramp, tau, val, integ, der);
      psi = l.psi0 + l.rate * integ;
      psi_dot = after ? 0.0 : l.rate * val;
      psi_ddot = after ? 0.0 : l.rate * der;
      break;
    }
    case SegmentKind::lane_change: {
      // δψ = a·u³ with u = x(1−x), x = τ/T (the lateral position is the 7th-order smoothstep).
      // ψ̈ starts and ends at 0, so the roll rate −k_r(v̇ψ̇ + vψ̈) and with it ω are continuous —
      // a sine period of yaw rate (ψ̈ = ±rate·w at the ends) made the roll rate step by k_r·v·rate·w
      // at both ends, i.e. a Dirac pulse of ω̇ and of the lever-arm force ω̇×r.
      const double x = tau / l.T, u = x * (1 - x), s = 1 - 2 * x;
      psi = l.psi0 + l.rate * u * u * u;
      psi_dot = after ? 0.0 : l.rate / l.T * 3 * u * u * s;
      psi_ddot = after ? 0.0 : l.rate / (l.T * l.T) * 6 * u * (s * s - u);
      break;
    }
  }
  if (after) {
    m.v_dot = 0;
    vdd = 0;
  }
  // Suspension: roll outwards in turns (lateral acceleration v·ψ̇ to the right → roll left),
  // pitch nose-up under acceleration.
  const double kr = route_.roll_per_lat_accel, kp = route_.pitch_per_long_accel;
  m.rpy(0) = -kr * m.v * psi_dot;
  m.rpy_dot(0) = -kr * (m.v_dot * psi_dot + m.v * psi_ddot);
  m.rpy(1) = pitch + kp * m.v_dot;
  m.rpy_dot(1) = pitch_dot + kp * vdd;
  m.rpy(2) = psi;
  m.rpy_dot(2) = psi_dot;
  return m;
}

}  // namespace calbench::drivesim
