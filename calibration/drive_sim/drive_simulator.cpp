#include "calibration/drive_sim/drive_simulator.hpp"

#include <cmath>

#include "calibration/effects/effect_registry.hpp"

namespace calbench::drivesim {
namespace {
using ins::skew;

struct Body {
  Vec3 v_n, w_ib, f;
  Mat3 C_nb;
};

Body body_at(const RouteProfile& prof, double t, double lat, double h) {
  const Motion m = prof.at(t);
  Body b;
  b.C_nb = ins::dcm_from_rpy(m.rpy);
  const double sr = std::sin(m.rpy(0)), cr = std::cos(m.rpy(0));
  const double sp = std::sin(m.rpy(1)), cp = std::cos(m.rpy(1));
  const Vec3& d = m.rpy_dot;
  const Vec3 w_nb(d(0) - d(2) * sp, d(1) * cr + d(2) * cp * sr, d(2) * cp * cr - d(1) * sr);
  const Vec3 u(m.v, 0, 0);
  b.v_n = b.C_nb * u;
  const Vec3 vdot_n = b.C_nb * (Vec3(m.v_dot, 0, 0) + w_nb.cross(u));
  const ins::LocalEarth e = ins::local_earth(lat, h, b.v_n);
  const Mat3 C_bn = b.C_nb.transpose();
  b.w_ib = w_nb + C_bn * (e.w_ie + e.w_en);
  b.f = C_bn * (vdot_n + (2 * e.w_ie + e.w_en).cross(b.v_n) - e.g);
  return b;
}
}  // namespace

void simulate_drive(const DriveSimConfig& cfg, const DriveSinks& sinks, double until_s) {
  const RouteProfile prof(cfg.route);
  const double T = until_s > 0 ? std::min(until_s, prof.duration()) : prof.duration();
  NoiseSpec noise = cfg.noise;
  noise.output_rate_hz = cfg.imu_rate_hz;
  const EffectTerms& fx = cfg.effects;
  noise = noise_with_effects(noise, fx);  // a correlated_drift term replaces the drift prior
  const bool sensor_fx = fx.any_sensor_side();
  const Mat3 gyro_inv = (Mat3::Identity() + cfg.mems.gyro.M).inverse();
  const Mat3 accel_inv = (Mat3::Identity() + cfg.mems.accel.M).inverse();
  ImuErrorSimulator mems(cfg.mems, noise, cfg.seed);
  std::mt19937_64 rng(cfg.seed * 0x2545F4914F6CDD1DULL + 7);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto nvec = [&]() { return Vec3(n01(rng), n01(rng), n01(rng)); };

  const Mat3 C_mb = ins::dcm_from_rpy(cfg.mounting_rpy);
  const Mat3 C_bm = C_mb.transpose();
  const Vec3& r = cfg.lever_arm;
  const double dt = 1.0 / cfg.imu_rate_hz;
  const long n = static_cast<long>(std::floor(T * cfg.imu_rate_hz + 1e-9));

  double lat = cfg.route.lat, lon = cfg.route.lon, h = cfg.route.h;
  double plat = lat, plon = lon, ph = h;  // previous sample's position
  Vec3 pv = Vec3::Zero();
  const double ref_dt = cfg.reference.rate_hz > 0 ? 1.0 / cfg.reference.rate_hz : 0;
  const double gnss_dt = cfg.gnss.rate_hz > 0 ? 1.0 / cfg.gnss.rate_hz : 0;
  long next_ref = 0, next_gnss = 0;

  for (long k = 0; k <= n; ++k) {
    const double t = k * dt;
    const Body b = body_at(prof, t, lat, h);
    if (k > 0) {
      // Trapezoidal position update from the previous sample's velocity to this one's.
      const Vec3 va = 0.5 * (pv + b.v_n);
      const ins::Radii R = ins::wgs84_radii(plat);
      h = ph - va(2) * dt;
      const double hm = 0.5 * (ph + h);
      lat = plat + va(0) / (R.RM + hm) * dt;
      lon = plon + va(1) / ((R.RN + hm) * std::cos(0.5 * (plat + lat))) * dt;
    }
    // MEMS: lever-arm specific force, then into MEMS axes, then the device's errors.
    // A time offset τ: the sample stamped t saw the motion at t − τ (position change over τ is
    // negligible for gravity and Earth rate).
    const double t_seen = truth_time(fx, t);
    const double ti = std::max(0.0, t_seen);
    const Body bi = t_seen != t ? body_at(prof, ti, lat, h) : b;
    // ω̇ as the mean over the sample interval centred on the sample: (ω(t+T/2) − ω(t−T/2))/T is
    // exactly the mean of ω̇ there, so ω̇×r is the interval mean of the tangential lever-arm
    // acceleration (what an IMU's band-limited sample shows; for smooth motion it differs from the
    // point derivative by ω⃛·T²/24). Finite for any motion: a step of the rate would give Δω×r/T on
    // one sample, not the Dirac pulse a point derivative (0.1 ms difference) makes of it.
    const double ta = ti + 0.5 * dt, tb = std::max(0.0, ti - 0.5 * dt);
    const Vec3 w_a = body_at(prof, ta, lat, h).w_ib, w_b = body_at(prof, tb, lat, h).w_ib;
    const Vec3 wdot = (w_a - w_b) / (ta - tb);
    const Vec3 f_m = bi.f + wdot.cross(r) + bi.w_ib.cross(bi.w_ib.cross(r));
    Vec3 w_in = C_bm * bi.w_ib, f_in = C_bm * f_m;
    if (sensor_fx) {
      // Extra output d enters before noise and quantisation: (I+M)(x + (I+M)⁻¹d) + b = (I+M)x + b + d.
      EffectContext c;
      c.w = w_in;
      c.f = f_in;
      c.dw = C_bm * wdot;
      c.temp_c = fx.t0_c;  // no temperature on a drive: temperature terms stay zero
      Vec3 dg, da;
      sensor_side_terms(fx, c, dg, da);
      w_in += gyro_inv * dg;
      f_in += accel_inv * da;
    }
    const auto out = mems.sample(t, w_in, f_in);
    if (sinks.imu) sinks.imu(SimImu{t, out.gyro, out.accel});
    if (sinks.truth) sinks.truth(SimTruth{t, lat, lon, h, b.v_n, b.C_nb, b.w_ib, b.f, mems.gyro_drift(), mems.accel_drift()});

    // Reference epochs and GNSS fixes in (t − dt, t]: position interpolated linearly.
    auto interp = [&](double te, double& la, double& lo, double& hh) {
      const double a = k > 0 ? (te - (t - dt)) / dt : 1.0;
      la = plat + a * (lat - plat);
      lo = plon + a * (lon - plon);
      hh = ph + a * (h - ph);
    };
    while (ref_dt > 0 && next_ref * ref_dt <= t + 1e-12) {
      const double te = next_ref * ref_dt;
      SimRef ref;
      ref.t = te;
      interp(te, ref.lat, ref.lon, ref.h);
      const Body be = body_at(prof, te, ref.lat, ref.h);
      const ReferenceErrors& re = cfg.reference;
      ins::geodetic_add_ned(ref.lat, ref.lon, ref.h, re.sigma_pos_m * nvec());
      ref.v_ned = be.v_n + re.sigma_vel_m_s * nvec();
      ref.rpy = ins::rpy_from_dcm(ins::quat_from_rotvec(re.sigma_att_rad * nvec()).toRotationMatrix() * be.C_nb);
      ref.sigma_pos = re.sigma_pos_m;
      ref.sigma_vel = re.sigma_vel_m_s;
      ref.sigma_att = re.sigma_att_rad;
      if (sinks.reference) sinks.reference(ref);
      ++next_ref;
    }
    while (gnss_dt > 0 && next_gnss * gnss_dt <= t + 1e-12) {
      const double te = next_gnss * gnss_dt;
      SimGnss g;
      g.t = te;
      interp(te, g.lat, g.lon, g.h);
      const Body be = body_at(prof, te, g.lat, g.h);
      const GnssErrors& ge = cfg.gnss;
      ins::geodetic_add_ned(g.lat, g.lon, g.h, Vec3(ge.sigma_h_m * n01(rng), ge.sigma_h_m * n01(rng), ge.sigma_v_m * n01(rng)));
      g.v_ned = be.v_n + ge.sigma_vel_m_s * nvec();
      g.sigma_h = ge.sigma_h_m;
      g.sigma_v = ge.sigma_v_m;
      g.sigma_vel = ge.sigma_vel_m_s;
      if (sinks.gnss) sinks.gnss(g);
      ++next_gnss;
    }
    plat = lat;
    plon = lon;
    ph = h;
    pv = b.v_n;
  }
}

}  // namespace calbench::drivesim
