#include "calibration/diagnosis/catalogue.hpp"

#include <cmath>

namespace calbench {

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

}  // namespace calbench
