// Strapdown INS on closed-form motions: rest at latitude φ, constant-rate turn, straight acceleration.
#include <gtest/gtest.h>

#include <functional>

#include "calibration/ins/strapdown.hpp"
#include "common/units.hpp"

using namespace calbench;
using namespace calbench::ins;

namespace {

struct BodyInputs {
  Vec3 w;  // rad/s, body w.r.t. inertial
  Vec3 f;  // m/s², specific force, body
};

// Increments over [t0, t1] by Simpson's rule with fine sub-steps (exact inputs to ~1e-12).
void increments(const std::function<BodyInputs(double)>& fn, double t0, double t1, Vec3& dth, Vec3& dv) {
  const int n = 8;
  const double h = (t1 - t0) / n;
  dth.setZero();
  dv.setZero();
  for (int i = 0; i <= n; ++i) {
    const double wgt = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    const BodyInputs b = fn(t0 + i * h);
    dth += wgt * b.w;
    dv += wgt * b.f;
  }
  dth *= h / 3.0;
  dv *= h / 3.0;
}

NavState start(double lat_deg, double h, const Vec3& rpy) {
  NavState s;
  s.lat = lat_deg * units::kDeg;
  s.lon = 0.5;
  s.h = h;
  s.q_nb = Quat(dcm_from_rpy(rpy));
  return s;
}

}  // namespace

TEST(InsStrapdown, RestAtLatitudeStaysAtRest) {
  for (double rate : {100.0, 2460.0}) {
    const NavState s0 = start(55.75, 150.0, Vec3(0.02, -0.01, 1.0));
    const LocalEarth e = local_earth(s0.lat, s0.h, Vec3::Zero());
    const Mat3 Cbn = s0.C_nb().transpose();
    const Vec3 w = Cbn * e.w_ie, f = -(Cbn * e.g);
    Strapdown ins(s0);
    const double dt = 1.0 / rate;
    const int n = static_cast<int>((rate > 1000 ? 120.0 : 600.0) * rate);  // 2 or 10 minutes
    for (int k = 0; k < n; ++k) ins.update(w * dt, f * dt, dt);
    const NavState& s = ins.state();
    const Vec3 dp = geodetic_diff_ned(s.lat, s.lon, s.h, s0.lat, s0.lon, s0.h);
    // Exact inputs: only round-off remains (the vertical channel is unstable, so allow mm).
    EXPECT_LT(dp.head<2>().norm(), 1e-3) << rate;
    EXPECT_LT(std::abs(dp(2)), 1e-2) << rate;
    EXPECT_LT(s.v.norm(), 1e-5) << rate;
    EXPECT_LT(rotvec_from_dcm(s.C_nb() * s0.C_nb().transpose()).norm(), 1e-9) << rate;
  }
}

TEST(InsStrapdown, RestWithNorthAccelBiasGivesSchulerBoundedError) {
  // Closed form: a level north accelerometer bias b gives a north position error
  // b/ωs²·(1 − cos ωs t) (Schuler loop), ωs² = g/R. Check at a quarter Schuler period.
  const NavState s0 = start(45.0, 0.0, Vec3::Zero());
  const LocalEarth e = local_earth(s0.lat, s0.h, Vec3::Zero());
  const Vec3 w = e.w_ie, f = -e.g + Vec3(1e-3, 0, 0);
  Strapdown ins(s0);
  const double dt = 0.01;
  const double R = std::sqrt(e.r.RM * e.r.RN);
  const double ws = std::sqrt(e.g.norm() / R);
  const double T = 0.25 * 2 * units::kPi / ws;
  const int n = static_cast<int>(T / dt);
  for (int k = 0; k < n; ++k) ins.update(w * dt, f * dt, dt);
  const Vec3 dp = geodetic_diff_ned(ins.state().lat, ins.state().lon, ins.state().h, s0.lat, s0.lon, s0.h);
  const double expected = 1e-3 / (ws * ws) * (1 - std::cos(ws * n * dt));
  // Earth-rate coupling (Foucault) perturbs the closed form by a few per cent at this horizon.
  EXPECT_NEAR(dp(0), expected, 0.05 * expected);
}

TEST(InsStrapdown, ConstantRateTurnAtRest) {
  // Body spinning about the local vertical at 30 °/s while stationary at 40° N.
  const NavState s0 = start(40.0, 50.0, Vec3(0, 0, 0));
  const LocalEarth e = local_earth(s0.lat, s0.h, Vec3::Zero());
  const double r = 30.0 * units::kDeg;
  auto truth = [&](double t) {
    const Mat3 Cbn = dcm_from_rpy(Vec3(0, 0, r * t)).transpose();
    return BodyInputs{Vec3(0, 0, r) + Cbn * e.w_ie, -(Cbn * e.g)};
  };
  for (double rate : {100.0, 2460.0}) {
    Strapdown ins(s0);
    const double dt = 1.0 / rate;
    const int n = static_cast<int>(120.0 * rate);
    Vec3 dth, dv;
    for (int k = 0; k < n; ++k) {
      increments(truth, k * dt, (k + 1) * dt, dth, dv);
      ins.update(dth, dv, dt);
    }
    const double t = n * dt;
    const Mat3 C_true = dcm_from_rpy(Vec3(0, 0, r * t));
    EXPECT_LT(rotvec_from_dcm(ins.state().C_nb() * C_true.transpose()).norm(), 1e-8) << rate;
    EXPECT_LT(ins.state().v.norm(), 1e-5) << rate;
  }
}

TEST(InsStrapdown, StraightAcceleration) {
  // Level body heading north, accelerating at a = 1 m/s² for 20 s from rest at 30° N. The body
  // follows the local level (pitch rate −v/(R+h)); inputs include Coriolis and transport rate.
  const double a = 1.0, lat0 = 30.0 * units::kDeg, h0 = 10.0;
  const Radii R = wgs84_radii(lat0);
  auto truth = [&](double t) {
    const double v = a * t;
    const double lat = lat0 + 0.5 * a * t * t / (R.RM + h0);
    const Vec3 vn(v, 0, 0);
    const LocalEarth e = local_earth(lat, h0, vn);
    // Body = NED axes (level, north): C_bn = I.
    const Vec3 f = Vec3(a, 0, 0) + (2 * e.w_ie + e.w_en).cross(vn) - e.g;
    return BodyInputs{e.w_ie + e.w_en, f};
  };
  NavState s0 = start(30.0, h0, Vec3::Zero());
  s0.lon = 0;
  Strapdown ins(s0);
  const double dt = 1.0 / 200.0;
  const int n = 20 * 200;
  Vec3 dth, dv;
  for (int k = 0; k < n; ++k) {
    increments(truth, k * dt, (k + 1) * dt, dth, dv);
    ins.update(dth, dv, dt);
  }
  const NavState& s = ins.state();
  EXPECT_NEAR(s.v(0), 20.0, 1e-4);
  EXPECT_NEAR(s.v(1), 0.0, 1e-4);
  EXPECT_NEAR(s.v(2), 0.0, 1e-4);
  const Vec3 dp = geodetic_diff_ned(s.lat, s.lon, s.h, s0.lat, s0.lon, s0.h);
  EXPECT_NEAR(dp(0), 200.0, 2e-3);
  EXPECT_NEAR(dp(1), 0.0, 2e-3);
  EXPECT_NEAR(dp(2), 0.0, 2e-3);
}

TEST(InsStrapdown, RotationHelpersRoundTrip) {
  const Vec3 rpy(0.3, -0.2, 2.5);
  EXPECT_LT((rpy_from_dcm(dcm_from_rpy(rpy)) - rpy).norm(), 1e-12);
  const Vec3 phi(0.1, -0.2, 0.05);
  EXPECT_LT((rotvec_from_dcm(quat_from_rotvec(phi).toRotationMatrix()) - phi).norm(), 1e-12);
}
