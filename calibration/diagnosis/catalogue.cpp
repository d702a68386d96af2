#include "calibration/diagnosis/catalogue.hpp"

#include <cmath>
#include <iterator>

namespace calbench {

namespace {
constexpr const char* kNames[] = {"temperature_bias", "temperature_scale", "g_sensitivity", "scale_nonlinearity",
                                  "scale_asymmetry",  "time_offset",       "lever_arm",     "misalignment",
                                  "table_wobble",     "correlated_drift",  "temperature_rate", "scale_factor"};
TriadEffectTerms& triad(EffectTerms& e, int sensor) { return sensor == 0 ? e.gyro : e.accel; }
const TriadEffectTerms& triad(const EffectTerms& e, int sensor) { return sensor == 0 ? e.gyro : e.accel; }
}  // namespace

static_assert(std::size(kNames) == static_cast<std::size_t>(EffectId::scale_factor) + 1, "a name per EffectId");

const char* effect_name(EffectId e) { return kNames[static_cast<int>(e)]; }
int effect_count() { return static_cast<int>(std::size(kNames)); }

bool effect_from_name(const std::string& s, EffectId& e) {
  for (int k = 0; k < effect_count(); ++k)
    if (s == kNames[k]) {
      e = static_cast<EffectId>(k);
      return true;
    }
  return false;
}

int Term::nparams() const {
  switch (effect) {
    case EffectId::g_sensitivity: return 3;
    case EffectId::lever_arm: return 3;
    case EffectId::misalignment: return 2;
    case EffectId::table_wobble: return 2;
    case EffectId::correlated_drift: return 0;
    default: return 1;
  }
}

bool Term::touches(int s, int a) const {
  switch (effect) {
    case EffectId::time_offset:
    case EffectId::table_wobble: return true;
    case EffectId::lever_arm:
    case EffectId::misalignment: return s == 1;
    case EffectId::correlated_drift: return false;
    default: return s == sensor && a == axis;
  }
}

std::string Term::label() const {
  std::string l = effect_name(effect);
  l += sensor == 0 ? " gyro" : sensor == 1 ? " accel" : " reference";
  if (axis >= 0) l += std::string(" ") + "xyz"[axis];
  return l;
}

void Term::add_param(EffectTerms& e, int p, double v) const {
  switch (effect) {
    case EffectId::temperature_bias: triad(e, sensor).temp_bias(axis) += v; break;
    case EffectId::temperature_scale: triad(e, sensor).temp_scale(axis) += v; break;
    case EffectId::temperature_rate: triad(e, sensor).temp_rate(axis) += v; break;
    case EffectId::scale_nonlinearity: triad(e, sensor).nonlinearity(axis) += v; break;
    case EffectId::scale_asymmetry: triad(e, sensor).asymmetry(axis) += v; break;
    case EffectId::scale_factor: triad(e, sensor).scale(axis) += v; break;
    case EffectId::g_sensitivity: e.g_sensitivity(axis, p) += v; break;
    case EffectId::time_offset: e.time_offset_s += v; break;
    case EffectId::lever_arm: e.lever_arm_m(p) += v; break;
    case EffectId::misalignment: e.table_tilt_rad(p) += v; break;
    case EffectId::table_wobble: e.wobble_rad(p) += v; break;
    case EffectId::correlated_drift: break;
  }
}

double Term::get_param(const EffectTerms& e, int p) const {
  switch (effect) {
    case EffectId::temperature_bias: return triad(e, sensor).temp_bias(axis);
    case EffectId::temperature_scale: return triad(e, sensor).temp_scale(axis);
    case EffectId::temperature_rate: return triad(e, sensor).temp_rate(axis);
    case EffectId::scale_nonlinearity: return triad(e, sensor).nonlinearity(axis);
    case EffectId::scale_asymmetry: return triad(e, sensor).asymmetry(axis);
    case EffectId::scale_factor: return triad(e, sensor).scale(axis);
    case EffectId::g_sensitivity: return e.g_sensitivity(axis, p);
    case EffectId::time_offset: return e.time_offset_s;
    case EffectId::lever_arm: return e.lever_arm_m(p);
    case EffectId::misalignment: return e.table_tilt_rad(p);
    case EffectId::table_wobble: return e.wobble_rad(p);
    case EffectId::correlated_drift: return 0;
  }
  return 0;
}

std::vector<Term> candidate_terms() {
  std::vector<Term> out;
  for (int s = 0; s < 2; ++s)
    for (int a = 0; a < 3; ++a)
      for (EffectId e : {EffectId::temperature_bias, EffectId::temperature_scale, EffectId::temperature_rate, EffectId::scale_nonlinearity,
                         EffectId::scale_asymmetry, EffectId::scale_factor})
        out.push_back({e, s, a});
  for (int a = 0; a < 3; ++a) out.push_back({EffectId::g_sensitivity, 0, a});
  out.push_back({EffectId::time_offset, 2, -1});
  out.push_back({EffectId::lever_arm, 1, -1});
  out.push_back({EffectId::misalignment, 2, -1});
  out.push_back({EffectId::table_wobble, 2, -1});
  return out;
}

bool static_attitude(const Vec3& w, const Vec3& f, Mat3& C) {
  if (w.norm() > 1e-3 || f.norm() < 1.0) return false;  // rotating, or no gravity reference
  const Vec3 d = -f.normalized();                        // down, IMU axes
  Vec3 n = w - w.dot(d) * d;                             // Earth rate: its horizontal part points north
  if (n.norm() < 1e-6) return false;
  n.normalize();
  const Vec3 e = d.cross(n);
  // C_b_l: rows are the level axes (N, E, D) in IMU coordinates.
  C.row(0) = n.transpose();
  C.row(1) = e.transpose();
  C.row(2) = d.transpose();
  return true;
}

bool bench_attitude(const Vec3& w, const Vec3& f, Mat3& C) {
  if (w.norm() <= 1e-3) return static_attitude(w, f, C);
  if (f.norm() < 1.0) return false;
  int m = 0;
  w.cwiseAbs().maxCoeff(&m);
  const Vec3 k = Vec3::Unit(m);
  const Vec3 w_perp = w - w(m) * k;             // Earth rate only when the table spins about IMU axis m
  if (w_perp.norm() > 1e-3) return false;
  const Vec3 d = -f.normalized();
  const Vec3 c = k.cross(d);
  Vec3 n;
  if (c.norm() > 1e-3) {
    n = c.normalized();                          // north ⟂ k and ⟂ down
    if (w.dot(n) < 0) n = -n;                    // the horizontal Earth rate points north
  } else {
    if (w_perp.norm() < 1e-7) return false;      // at a pole, or no Earth rate in the reference
    n = (w_perp - w_perp.dot(d) * d).normalized();
  }
  const Vec3 e = d.cross(n);
  C.row(0) = n.transpose();
  C.row(1) = e.transpose();
  C.row(2) = d.transpose();
  return true;
}

void predict_extra(const EffectTerms& e, const SubBlock& s, Vec3& dg, Vec3& da) {
  EffectTerms sensor_only = e;
  EffectContext c;
  c.w = s.w;
  c.f = s.f;
  c.dw = s.dw;
  c.df = s.df;
  c.temp_c = std::isfinite(s.temp_c) ? s.temp_c : e.t0_c;
  c.dtemp_k_s = std::isfinite(s.temp_c) ? s.dtemp : 0.0;
  sensor_side_terms(sensor_only, c, dg, da);
  // Reference-side terms: the true input differs from the reference by Δ; the output by ≈ Δ.
  if (e.time_offset_s != 0) {
    dg -= e.time_offset_s * s.dw;
    da -= e.time_offset_s * s.df;
  }
  if (!e.wobble_rad.isZero(0) && std::isfinite(s.angle)) {
    if (std::abs(s.angle_rate) > 0.0174533) {
      // True angle θ + δ(θ): rate scaled by 1 + δ'(θ), attitude advanced by δ about the rate axis.
      const Vec3 w_table = s.w;  // Earth rate is negligible beside the table rate
      dg += wobble_slope(e.wobble_rad, s.angle) * w_table;
      da += wobble_angle(e.wobble_rad, s.angle) * s.df / s.angle_rate;
    } else if (!s.inner_axis.isZero(0)) {
      // Static position: the table stands at θ + δ(θ). Everything fixed in the level frame —
      // gravity and the Earth rate — turns in IMU axes by −δ about the axis u of the angle column
      // (the same f × u = ∂f/∂θ as in a rotating step): Δf = δ·(f × u), Δω = δ·(ω × u).
      const double d = wobble_angle(e.wobble_rad, s.angle);
      dg += d * s.w.cross(s.inner_axis);
      da += d * s.f.cross(s.inner_axis);
    }
  }
  if (!e.table_tilt_rad.isZero(0)) {
    // The tilted base turns the level frame seen by the IMU: gravity and the Earth rate, both
    // fixed in the level frame, reach the IMU through C_bLᵀ(I − [ψ×]) (the table's own rate is
    // unaffected). Static and rotating steps alike.
    Mat3 C;
    if (bench_attitude(s.w, s.f, C)) {
      da += table_tilt_force(e.table_tilt_rad, C, s.f);
      // Earth-rate part (≤ Ω·|ψ|, 2e-8 rad/s at 60″): its vertical component is known from the
      // reference only when the table is still or spins about a horizontal axis.
      const Vec3 wl = C * s.w;
      if (s.w.norm() <= 1e-3 || std::abs(C.row(2).dot(s.w.normalized())) < 1e-6)
        dg += table_tilt_force(e.table_tilt_rad, C, C.transpose() * Vec3(wl(0), 0.0, wl(2)));
    }
  }
}

std::string term_unit(const Term& t) {
  const bool g = t.sensor == 0;
  switch (t.effect) {
    case EffectId::temperature_bias: return g ? "rad/s/K" : "m/s^2/K";
    case EffectId::temperature_scale: return "1/K";
    case EffectId::temperature_rate: return g ? "rad/s/(K/s)" : "m/s^2/(K/s)";
    case EffectId::g_sensitivity: return "rad/s/(m/s^2)";
    case EffectId::scale_nonlinearity: return g ? "1/(rad/s)" : "1/(m/s^2)";
    case EffectId::scale_asymmetry: return "1";
    case EffectId::scale_factor: return "1";
    case EffectId::time_offset: return "s";
    case EffectId::lever_arm: return "m";
    case EffectId::misalignment: return "rad";
    case EffectId::table_wobble: return "rad";
    case EffectId::correlated_drift: return g ? "rad/s" : "m/s^2";
  }
  return "";
}

}  // namespace calbench
