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

// One MEMS unit on the vehicle: its errors, noise and placement, and its output from the body's
// motion at one sample.
class MemsUnit {
 public:
  MemsUnit(const SensorErrors& mems, const NoiseSpec& spec, double rate_hz, const Vec3& mounting_rpy, const Vec3& lever,
           std::uint64_t seed, const EffectTerms& fx)
      : fx_(fx),
        sensor_fx_(fx.any_sensor_side()),
        gyro_inv_((Mat3::Identity() + mems.gyro.M).inverse()),
        accel_inv_((Mat3::Identity() + mems.accel.M).inverse()),
        mems_(mems, noise_for(spec, rate_hz, fx), seed),
        C_bm_(ins::dcm_from_rpy(mounting_rpy).transpose()),
        r_(lever) {}

  // The sample stamped t (body at t: b); its position lat, h for the motion at other times.
  ImuErrorSimulator::Output sample(const RouteProfile& prof, double t, double dt, const Body& b, double lat, double h) {
    // MEMS: lever-arm specific force, then into MEMS axes, then the device's errors.
    // A time offset τ: the sample stamped t saw the motion at t − τ (position change over τ is
    // negligible for gravity and Earth rate).
    const double t_seen = truth_time(fx_, t);
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
    const Vec3 f_m = bi.f + wdot.cross(r_) + bi.w_ib.cross(bi.w_ib.cross(r_));
    Vec3 w_in = C_bm_ * bi.w_ib, f_in = C_bm_ * f_m;
    if (sensor_fx_) {
      // Extra output d enters before noise and quantisation: (I+M)(x + (I+M)⁻¹d) + b = (I+M)x + b + d.
      EffectContext c;
      c.w = w_in;
      c.f = f_in;
      c.dw = C_bm_ * wdot;
      c.temp_c = fx_.t0_c;  // no temperature on a drive: temperature terms stay zero
      Vec3 dg, da;
      sensor_side_terms(fx_, c, dg, da);
      w_in += gyro_inv_ * dg;
      f_in += accel_inv_ * da;
    }
    return mems_.sample(t, w_in, f_in);
  }
  const ImuErrorSimulator& errors() const { return mems_; }

 private:
  static NoiseSpec noise_for(NoiseSpec n, double rate_hz, const EffectTerms& fx) {
    n.output_rate_hz = rate_hz;
    return noise_with_effects(n, fx);  // a correlated_drift term replaces the drift prior
  }
  const EffectTerms& fx_;
  bool sensor_fx_;
  Mat3 gyro_inv_, accel_inv_;
  ImuErrorSimulator mems_;
  Mat3 C_bm_;
  Vec3 r_;
};

}  // namespace

void simulate_drive(const DriveSimConfig& cfg, const DriveSinks& sinks, double until_s) {
  const RouteProfile prof(cfg.route);
  const double T = until_s > 0 ? std::min(until_s, prof.duration()) : prof.duration();
  std::vector<MemsUnit> units;
  units.reserve(1 + cfg.more_units.size());
  units.emplace_back(cfg.mems, cfg.noise, cfg.imu_rate_hz, cfg.mounting_rpy, cfg.lever_arm, cfg.seed, cfg.effects);
  for (const auto& u : cfg.more_units)
    units.emplace_back(u.mems, u.noise, cfg.imu_rate_hz, u.mounting_rpy, u.lever_arm, u.seed, u.effects);
  std::mt19937_64 rng(cfg.seed * 0x2545F4914F6CDD1DULL + 7);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto nvec = [&]() { return Vec3(n01(rng), n01(rng), n01(rng)); };

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
    for (std::size_t u = 0; u < units.size(); ++u) {
      const auto out = units[u].sample(prof, t, dt, b, lat, h);
      if (sinks.imu) sinks.imu(SimImu{t, out.gyro, out.accel, static_cast<int>(u)});
    }
    const ImuErrorSimulator& mems = units.front().errors();
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
