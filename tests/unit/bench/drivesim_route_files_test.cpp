// The drive simulator on the shipped route files: the error-free MEMS output has no jumps beyond
// what the vehicle's motion allows over one sample interval, whatever the concealed time offset.
// (A lane change used to step the suspension's roll rate at both ends; a sample whose time,
// shifted by the offset, fell within 0.1 ms of such a step got a Dirac-like ω̇ and, through the
// 1 m lever arm, a 46 m/s² one-sample spike in the specific force — found by the drive-diagnosis
// sweep at a time offset of −1 ms on tests/data/drive_diag_route.toml.)
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bench/drive/route_toml.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "calibration/drive_sim/drive_simulator.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {
using drivesim::DriveSimConfig;
using drivesim::DriveSinks;
using drivesim::SimImu;
using units::kDeg;

struct Jumps {
  double dw = 0, df = 0;      // largest |Δω|, |Δf| between successive samples (rad/s, m/s²)
  double t_dw = 0, t_df = 0;  // where
  long samples = 0;
};

Jumps simulate_jumps(const RouteFile& rf, double time_offset_s, double until_s) {
  DriveSimConfig cfg;
  cfg.route = rf.route;
  cfg.noise = NoiseSpec{};  // no noise, no drift, no quantisation; the unit has no errors
  cfg.imu_rate_hz = rf.imu_rate_hz;
  cfg.mounting_rpy = rf.mounting_rpy_deg * kDeg;
  cfg.lever_arm = rf.lever_arm_m;
  cfg.reference.rate_hz = 0;
  cfg.gnss.rate_hz = 0;
  effect_vector<1>(cfg.effects, EffectId::time_offset)(0) = time_offset_s;
  Jumps j;
  bool first = true;
  SimImu prev;
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) {
    if (!first) {
      const double dw = (m.gyro - prev.gyro).norm(), df = (m.accel - prev.accel).norm();
      if (dw > j.dw) j.dw = dw, j.t_dw = m.t;
      if (df > j.df) j.df = df, j.t_df = m.t;
    }
    first = false;
    prev = m;
    ++j.samples;
  };
  drivesim::simulate_drive(cfg, sinks, until_s);
  return j;
}

// Physical bound on the change of the noise-free MEMS output over one sample interval dt.
// Angular rate: continuous, so |Δω| ≤ |ω̇|max·dt; these routes' largest angular acceleration is the
// yaw acceleration in a lane change or at a tight turn's ramp, below 1 rad/s² (the 3 s lane change
// at 40 km/h of the diagnosis route: 0.61 rad/s²; its 12 m turn at 25 km/h: v/R·π/(2·ramp) = 0.45).
// Specific force: continuous too, so its change is (a) the rate of change of the vehicle's specific
// force (jerk of speed changes and turn entries, gravity turning with roll and pitch rate, the
// centripetal term; below 10 m/s³ on these routes) times dt, plus (b) the lever-arm term ω̇×r where
// ω̇ has a corner step at a manoeuvre's end (the suspension's roll acceleration at a lane change's
// ends, k_r·v·ψ⃛ ≈ 0.21 rad/s² at most here; turn ramps and speed changes less): 0.25 rad/s²·|r|.
// For the diagnosis route (200 Hz, |r| = 1.06 m) 0.32 m/s², for the default route (2460 Hz,
// |r| = 1.31 m) 0.33 m/s²; a Dirac-like ω̇ (rate step over a 0.1 ms difference) gave 46 m/s².
double rate_bound(double dt) { return 1.0 * dt; }
double force_bound(double dt, const Vec3& r) { return 10.0 * dt + 0.25 * r.norm(); }

void check_route(const std::string& file, double until_s) {
  const RouteFile rf = load_route(std::string(CALBENCH_SOURCE_DIR) + "/" + file);
  const double span = until_s > 0 ? until_s : drivesim::RouteProfile(rf.route).duration();
  const double dt = 1.0 / rf.imu_rate_hz;
  for (double tau : {-1e-3, -0.5e-3, 1e-3}) {
    const Jumps j = simulate_jumps(rf, tau, until_s);
    SCOPED_TRACE(file + ", time offset " + std::to_string(tau * 1e3) + " ms");
    std::printf("%s tau %+.2f ms: |dw| max %.3g rad/s at %.4f s (bound %.3g); |df| max %.3g m/s^2 at %.4f s (bound %.3g)\n",
                file.c_str(), tau * 1e3, j.dw, j.t_dw, rate_bound(dt), j.df, j.t_df, force_bound(dt, rf.lever_arm_m));
    EXPECT_GT(j.samples, static_cast<long>(0.99 * span * rf.imu_rate_hz));
    EXPECT_LT(j.dw, rate_bound(dt)) << "at t = " << j.t_dw;
    EXPECT_LT(j.df, force_bound(dt, rf.lever_arm_m)) << "at t = " << j.t_df;
  }
}

}  // namespace

TEST(DrivesimRouteFiles, DiagRouteOutputHasNoJumpsWithTimeOffsets) { check_route("tests/data/drive_diag_route.toml", 0); }

// The first 260 s hold two lane changes (133–138 s at 40 km/h, 252–256 s at 60 km/h).
TEST(DrivesimRouteFiles, DefaultRouteOutputHasNoJumpsWithTimeOffsets) { check_route("bench/routes/default.toml", 260); }

}  // namespace calbench
