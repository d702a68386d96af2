// A unit turned by hand through static poses, simulated with known truth (`calbench simulate
// multipos`, docs/multipos.md "Simulated recordings"): the mathematics only, no I/O.
//
// The hand: between two static poses a smooth turn about a body axis by 60–150° (either sign) over
// 1–3 s with the rate profile θ/T·(1 − cos 2πτ/T), integrated exactly per sample (the angle of each
// sample interval is the profile's integral, as bench/multipos/hand_turn.py and the fit's unit test
// make it). Each next pose is the one, of a few random turns, whose gravity direction lies farthest
// from the poses before it, so that the poses spread over the sphere: every axis up and down, tilted
// poses between. The physics: gravity and (with a site) the Earth rate in a level frame (NED). The
// sensor: common/imu_error_sim.hpp (measured = (I + M)·true + b, white noise, first-order
// Gauss–Markov bias wander), with the device class's noise.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "calibration/bench_plan.hpp"
#include "common/imu_error_sim.hpp"
#include "common/noise_spec.hpp"
#include "common/sensor_model.hpp"

namespace calbench::multipos {

// What the hand does (SI: seconds, radians).
struct HandTurnConfig {
  int poses = 24;                  // static poses, the opening one included
  double still_min_s = 1.0, still_max_s = 3.0;
  double opening_still_s = 0;      // > 0: the first pose lasts this long (an opening static interval)
  double turn_min_s = 1.0, turn_max_s = 3.0;
  double angle_min = 60.0 * 3.14159265358979323846 / 180, angle_max = 150.0 * 3.14159265358979323846 / 180;
  int candidates = 24;             // random turns tried for each next pose (the farthest is kept)
};

// One static pose: samples [i0, i1) are still, at times [t0, t1] (first and last sample).
struct SimPose {
  std::size_t i0 = 0, i1 = 0;
  double t0 = 0, t1 = 0;
  Vec3 up_body;  // unit vector "up" in the body frame: what an error-free accelerometer sees, / g
};

// One turn from pose k to pose k + 1: samples [i0, i1), about the body axis `axis` by `angle`.
struct SimTurn {
  std::size_t i0 = 0, i1 = 0;
  double t0 = 0, t1 = 0;  // first and last sample of the turn
  Vec3 axis;              // unit, body frame
  double angle = 0;       // rad, signed
};

// The whole sequence, drawn before any sample is made.
struct HandTurnPlan {
  double rate_hz = 100;
  Mat3 C0 = Mat3::Identity();  // body → level (NED) at the start
  std::vector<SimPose> poses;
  std::vector<SimTurn> turns;  // turns[k] leads from poses[k] to poses[k + 1]
  std::size_t samples = 0;
  double duration_s() const { return samples ? static_cast<double>(samples - 1) / rate_hz : 0.0; }
};

// Draws the poses and turns (durations rounded to whole samples). The unit starts lying flat
// (body z up) at a random heading.
HandTurnPlan plan_hand_turns(const HandTurnConfig& c, double rate_hz, std::uint64_t seed);

// One sample of the turn's profile: the rate about the axis at the sample (rad/s) and the exact
// angle turned since the previous sample (rad). Over the turn's n samples the angles sum to `angle`.
struct TurnStep {
  double rate = 0, dangle = 0;
};
TurnStep turn_step(double angle, std::size_t n, std::size_t k, double rate_hz);  // k = 1 … n

// The simulated unit's noise: the class's white noise densities × factor at `rate_hz`, its drift
// (σ, τ) and ranges unchanged, no output quantisation (the class's LSB is not applied: a consumer
// part's 16-bit gyro LSB is above its white noise at 100 Hz, and the recording stands for a logger
// of SI values).
NoiseSpec hand_turn_noise(const NoiseSpec& cls, double factor, double rate_hz);

struct MultiposSimConfig {
  HandTurnConfig hand;
  double rate_hz = 100;
  std::optional<Site> site;   // gravity (WGS-84 normal) and Earth rate; none: 9.80665 m/s², no Earth rate
  SensorErrors truth;         // the unit's b and M, spec convention
  NoiseSpec noise;            // hand_turn_noise(...)
  std::uint64_t seed = 1;     // the plan and the noise
};

struct MultiposSimSample {
  double t = 0;
  Vec3 gyro, accel;    // the unit's output (rad/s, m/s²)
  Vec3 w_true, f_true; // what it really experienced
  Vec3 gyro_wander, accel_wander;  // the bias wander in the output (truth side: b + wander is the bias now)
  int pose = -1;       // the static pose the sample belongs to, −1 while turning
};

// Gravity magnitude used (m/s²): normal gravity at the site, else standard gravity.
double hand_turn_gravity(const std::optional<Site>& site);

// Simulates the whole recording; `sink` receives every sample in time order. Returns the plan.
HandTurnPlan simulate_multipos(const MultiposSimConfig& c, const std::function<void(const MultiposSimSample&)>& sink);

}  // namespace calbench::multipos
