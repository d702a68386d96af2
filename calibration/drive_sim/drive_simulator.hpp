// The drive simulator: a route's exact kinematics → what the MEMS IMU outputs (at its rate, with
// the unit's deterministic errors, white noise and Gauss–Markov drift from ImuErrorSimulator),
// what a FOG-grade reference inertial-satellite system reports at its body origin (own rate,
// small white errors, with its σ), and GNSS fixes. The MEMS IMU sits at lever arm r (reference
// body axes) with rotation C_mb (MEMS → reference body); its specific force includes the
// lever-arm terms ω̇×r + ω×(ω×r), with ω̇ the mean angular acceleration over the sample interval
// centred on the sample.
//
// Truth quantities (reference body): v^n = C_nb·[v,0,0], ω_nb^b from the Euler-angle rates,
// ω_ib^b = ω_nb^b + C_bn(ω_ie + ω_en), f^b = C_bn(v̇^n + (2ω_ie + ω_en)×v^n − g). Position is
// integrated by the trapezoidal rule at the IMU rate.
#pragma once
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "calibration/drive_sim/route.hpp"
#include "calibration/effects/effect_terms.hpp"
#include "common/imu_error_sim.hpp"
#include "calibration/ins/nav_math.hpp"
#include "common/noise_spec.hpp"

namespace calbench::drivesim {

struct ReferenceErrors {
  double rate_hz = 100;
  double sigma_pos_m = 0.02;
  double sigma_vel_m_s = 0.005;
  double sigma_att_rad = 0.005 * units::kDeg;
};

struct GnssErrors {
  double rate_hz = 1;  // 0 = no GNSS
  double sigma_h_m = 1.0;
  double sigma_v_m = 2.0;
  double sigma_vel_m_s = 0.05;
};

struct DriveSimConfig {
  Route route;
  SensorErrors mems;               // the unit's deterministic errors (truth)
  NoiseSpec noise = adis16488a_noise();
  double imu_rate_hz = 2460;
  Vec3 mounting_rpy = Vec3::Zero();  // true MEMS → reference body rotation, rad
  Vec3 lever_arm = Vec3::Zero();     // true MEMS origin in reference body axes, m
  ReferenceErrors reference;
  GnssErrors gnss;
  std::uint64_t seed = 1;
  // Physics beyond the spec's model (docs/diagnosis.md, "Drives"), applied to the MEMS output only
  // (the reference stays nominal): sensor-side terms at the MEMS's true input; lever_arm = an
  // extra MEMS offset (IMU axes) beyond `lever_arm`; time_offset: the sample stamped t saw the
  // motion at t − τ; correlated_drift replaces the drift σ, τ of `noise`. Temperature terms need a
  // temperature and the table terms a bench: not used here.
  EffectTerms effects;
  // More MEMS units on the same vehicle (issue 21): the route, the reference and the GNSS are the
  // drive's, once; each unit here has its own errors, noise, seed, mounting and lever arm. The unit
  // above is unit 0 and its output is unchanged by them.
  struct Unit {
    SensorErrors mems;
    NoiseSpec noise = adis16488a_noise();
    Vec3 mounting_rpy = Vec3::Zero();
    Vec3 lever_arm = Vec3::Zero();
    std::uint64_t seed = 1;
    EffectTerms effects;
  };
  std::vector<Unit> more_units;
};

struct SimImu {
  double t = 0;
  Vec3 gyro, accel;  // rad/s, m/s², MEMS axes (device output)
  int unit = 0;      // 0, or 1 + index into DriveSimConfig::more_units
};
struct SimRef {
  double t = 0;
  double lat = 0, lon = 0, h = 0;  // rad, rad, m
  Vec3 v_ned, rpy;                 // m/s, rad
  double sigma_pos = 0, sigma_vel = 0, sigma_att = 0;
};
struct SimGnss {
  double t = 0;
  double lat = 0, lon = 0, h = 0;
  Vec3 v_ned;
  double sigma_h = 0, sigma_v = 0, sigma_vel = 0;
};
// Truth of the reference body at a time (for tests).
struct SimTruth {
  double t = 0;
  double lat = 0, lon = 0, h = 0;
  Vec3 v_ned;
  Mat3 C_nb;
  Vec3 w_ib_b, f_b;  // reference body
  Vec3 gyro_drift = Vec3::Zero(), accel_drift = Vec3::Zero();  // the MEMS unit's in-run drift now
};

struct DriveSinks {
  std::function<void(const SimImu&)> imu;
  std::function<void(const SimRef&)> reference;  // emitted after the IMU sample that closes its interval
  std::function<void(const SimGnss&)> gnss;
  std::function<void(const SimTruth&)> truth;    // at every IMU sample (optional)
};

// Runs the whole route (or up to `until_s` if > 0).
void simulate_drive(const DriveSimConfig& cfg, const DriveSinks& sinks, double until_s = 0);

}  // namespace calbench::drivesim
