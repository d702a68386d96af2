#include "calibration/multipos/multipos_sim.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "calibration/earth.hpp"
#include "common/units.hpp"

namespace calbench::multipos {
namespace {

using units::kPi;

// Samples of an interval of `s` seconds at `rate_hz`, at least one.
std::size_t samples_of(double s, double rate_hz) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(s * rate_hz)));
}

// Up in the level frame (NED: z down).
const Vec3 kUpLevel(0.0, 0.0, -1.0);

// The smallest angle between `u` and any of `ups` (π when there are none).
double nearest_angle(const Vec3& u, const std::vector<Vec3>& ups) {
  double best = kPi;
  for (const Vec3& v : ups) best = std::min(best, std::acos(std::clamp(u.dot(v), -1.0, 1.0)));
  return best;
}

}  // namespace

TurnStep turn_step(double angle, std::size_t n, std::size_t k, double rate_hz) {
  const double T = static_cast<double>(n) / rate_hz;
  const double tau = static_cast<double>(k) / rate_hz, tau0 = static_cast<double>(k - 1) / rate_hz;
  // The angle turned by time τ: θ·(τ/T − sin(2πτ/T)/2π), the integral of θ/T·(1 − cos 2πτ/T).
  auto turned = [&](double s) { return angle * (s / T - std::sin(2 * kPi * s / T) / (2 * kPi)); };
  TurnStep st;
  st.rate = angle / T * (1 - std::cos(2 * kPi * tau / T));
  st.dangle = k == n ? angle - turned(tau0) : turned(tau) - turned(tau0);  // the last one closes the turn exactly
  return st;
}

HandTurnPlan plan_hand_turns(const HandTurnConfig& c, double rate_hz, std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x6a09e667f3bcc909ULL);  // not the noise's stream (ImuErrorSimulator(seed))
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * u01(rng); };
  HandTurnPlan p;
  p.rate_hz = rate_hz;
  // Lying flat, body z up, at a random heading: body → NED is a turn about down after z flipped.
  p.C0 = Eigen::AngleAxisd(uniform(0, 2 * kPi), Vec3::UnitZ()).toRotationMatrix() * Vec3(1, -1, -1).asDiagonal();
  Mat3 C = p.C0;
  std::vector<Vec3> ups;
  std::size_t i = 0;
  for (int k = 0; k < c.poses; ++k) {
    if (k > 0) {
      // A few random turns; the one whose end pose is farthest from every pose so far is made.
      SimTurn best;
      double best_score = -1;
      for (int m = 0; m < std::max(1, c.candidates); ++m) {
        Vec3 axis(n01(rng), n01(rng), n01(rng));
        if (axis.norm() < 1e-9) axis = Vec3::UnitX();
        axis.normalize();
        const double angle = uniform(c.angle_min, c.angle_max) * (u01(rng) < 0.5 ? -1.0 : 1.0);
        const Mat3 C1 = C * Eigen::AngleAxisd(angle, axis).toRotationMatrix();
        const double score = nearest_angle(C1.transpose() * kUpLevel, ups);
        if (score > best_score) {
          best_score = score;
          best.axis = axis;
          best.angle = angle;
        }
      }
      best.i0 = i;
      i += samples_of(uniform(c.turn_min_s, c.turn_max_s), rate_hz);
      best.i1 = i;
      best.t0 = static_cast<double>(best.i0) / rate_hz;
      best.t1 = static_cast<double>(best.i1 - 1) / rate_hz;
      C = C * Eigen::AngleAxisd(best.angle, best.axis).toRotationMatrix();
      p.turns.push_back(best);
    }
    SimPose s;
    s.i0 = i;
    const bool opening = k == 0 && c.opening_still_s > 0;
    i += samples_of(opening ? c.opening_still_s : uniform(c.still_min_s, c.still_max_s), rate_hz);
    s.i1 = i;
    s.t0 = static_cast<double>(s.i0) / rate_hz;
    s.t1 = static_cast<double>(s.i1 - 1) / rate_hz;
    s.up_body = C.transpose() * kUpLevel;
    ups.push_back(s.up_body);
    p.poses.push_back(s);
  }
  p.samples = i;
  return p;
}

NoiseSpec hand_turn_noise(const NoiseSpec& cls, double factor, double rate_hz) {
  NoiseSpec n = cls;
  n.gyro.white_density *= factor;
  n.accel.white_density *= factor;
  n.gyro.lsb = n.accel.lsb = 0;
  n.output_rate_hz = rate_hz;
  return n;
}

double hand_turn_gravity(const std::optional<Site>& site) {
  return site ? SiteEarth(*site).g_ned.norm() : units::kG0;
}

HandTurnPlan simulate_multipos(const MultiposSimConfig& c, const std::function<void(const MultiposSimSample&)>& sink) {
  HandTurnPlan p = plan_hand_turns(c.hand, c.rate_hz, c.seed);
  const std::optional<SiteEarth> earth = c.site ? std::optional<SiteEarth>(std::in_place, *c.site) : std::nullopt;
  const Vec3 g_ned = earth ? earth->g_ned : Vec3(0.0, 0.0, units::kG0);
  const Vec3 w_ie = earth ? earth->w_ie_ned : Vec3::Zero();
  NoiseSpec noise = c.noise;
  noise.output_rate_hz = c.rate_hz;
  ImuErrorSimulator imu(c.truth, noise, c.seed);
  Mat3 C = p.C0;  // body → level, integrated sample by sample
  MultiposSimSample s;
  auto emit = [&](std::size_t i, const Vec3& w_turn, int pose) {
    s.t = static_cast<double>(i) / c.rate_hz;
    s.w_true = w_turn + C.transpose() * w_ie;
    s.f_true = -(C.transpose() * g_ned);  // a unit at rest in the level frame: the reaction to gravity
    s.pose = pose;
    const ImuErrorSimulator::Output o = imu.sample(s.t, s.w_true, s.f_true);
    s.gyro = o.gyro;
    s.accel = o.accel;
    s.gyro_wander = imu.gyro_drift();
    s.accel_wander = imu.accel_drift();
    sink(s);
  };
  for (std::size_t k = 0; k < p.poses.size(); ++k) {
    SimPose& pose = p.poses[k];
    pose.up_body = -(C.transpose() * g_ned).normalized();  // the attitude the samples reached
    for (std::size_t i = pose.i0; i < pose.i1; ++i) emit(i, Vec3::Zero(), static_cast<int>(k));
    if (k >= p.turns.size()) continue;
    const SimTurn& tr = p.turns[k];
    const std::size_t n = tr.i1 - tr.i0;
    for (std::size_t j = 1; j <= n; ++j) {
      const TurnStep st = turn_step(tr.angle, n, j, c.rate_hz);
      C = C * Eigen::AngleAxisd(st.dangle, tr.axis).toRotationMatrix();  // exact over the interval (fixed axis)
      emit(tr.i0 + j - 1, st.rate * tr.axis, -1);
    }
  }
  return p;
}

}  // namespace calbench::multipos
