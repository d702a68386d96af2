#include "bench/multipos/simulate_multipos.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "bench/io/coefficients_json.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "bench/io/message_text.hpp"
#include "bench/multipos/multipos_import.hpp"
#include "calibration/multipos/multipos_sim.hpp"
#include "common/input_error.hpp"
#include "common/json_fields.hpp"
#include "common/number_parse.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

// --still MIN,MAX: seconds, 0 < MIN <= MAX <= 3600.
std::pair<double, double> still_range(const std::string& v) {
  const std::size_t comma = v.find(',');
  double lo = 0, hi = 0;
  if (comma == std::string::npos || !parse_finite_number(std::string_view(v).substr(0, comma), lo) ||
      !parse_finite_number(std::string_view(v).substr(comma + 1), hi))
    throw InputError("--still", 0, "", "expected MIN,MAX in seconds (e.g. 1,3), got '" + field_text(v) + "'");
  if (!(lo > 0) || !(hi <= 3600))
    throw InputError("--still", 0, "", "each pose lasts more than 0 and at most 3600 s, got " + field_text(v));
  if (lo > hi)
    throw InputError("--still", 0, "", "MIN " + number_text(lo) + " s is above MAX " + number_text(hi) + " s");
  return {lo, hi};
}

nlohmann::json triad_noise_json(const TriadNoise& n, double rate_hz, const char* unit) {
  const std::string u(unit);
  return {{"white_density_" + u + "_sqrt_hz", n.white_density},
          {"white_sigma_per_sample_" + u, n.white_density * std::sqrt(rate_hz)},
          {"drift_sigma_" + u, n.drift_sigma},
          {"drift_tau_s", n.drift_tau_s}};
}

// The bias wander over the static poses' samples: its mean (the poses see b + this) and its RMS about it.
struct WanderStats {
  Vec3 sum_g = Vec3::Zero(), sum2_g = Vec3::Zero(), sum_a = Vec3::Zero(), sum2_a = Vec3::Zero();
  std::size_t n = 0;
  void add(const multipos::MultiposSimSample& s) {
    sum_g += s.gyro_wander;
    sum2_g += s.gyro_wander.cwiseAbs2();
    sum_a += s.accel_wander;
    sum2_a += s.accel_wander.cwiseAbs2();
    ++n;
  }
  nlohmann::json json() const {
    const double k = 1.0 / static_cast<double>(std::max<std::size_t>(n, 1));
    auto rms = [&](const Vec3& s1, const Vec3& s2) -> Vec3 { return (s2 * k - (s1 * k).cwiseAbs2()).cwiseMax(0.0).cwiseSqrt(); };
    return {{"samples", n},
            {"gyro_mean_rad_s", to_json(Vec3(sum_g * k))},
            {"gyro_rms_about_mean_rad_s", to_json(rms(sum_g, sum2_g))},
            {"accel_mean_m_s2", to_json(Vec3(sum_a * k))},
            {"accel_rms_about_mean_m_s2", to_json(rms(sum_a, sum2_a))},
            {"note", "the bias wander over the static poses' samples: they see the bias b + this mean"}};
  }
};

// truth.json: a coefficients file (the unit's b and M, SI, spec convention) with what else the
// simulation knows: the noise used, and every pose and turn (docs/multipos.md "Simulated recordings").
CoefficientSet truth_set(const SimulateMultiposArgs& a, const ImuClassChoice& cls, const multipos::MultiposSimConfig& c,
                         const multipos::HandTurnPlan& p, const WanderStats& wander, const DeviceId& dev) {
  CoefficientSet t;
  t.device = dev;
  t.errors = c.truth;
  t.extra["truth"] = {{"drawn_by", "calbench simulate multipos"}, {"seed", a.seed}, {"device_class", cls.cls.name},
                      {"class_chosen_by", cls.chosen_by}, {"spread", "the class's unit spread (1 sigma), imu_error_sim.hpp"}};
  t.extra["noise"] = {{"model", "white noise (factor x the class's densities) and a first-order Gauss-Markov bias "
                                "wander (the class's sigma and tau, started in its stationary distribution) on top of b; "
                                "no output quantisation"},
                      {"factor", a.noise_factor},
                      {"gyro", triad_noise_json(c.noise.gyro, c.rate_hz, "rad_s")},
                      {"accel", triad_noise_json(c.noise.accel, c.rate_hz, "m_s2")},
                      {"wander_over_poses", wander.json()}};
  nlohmann::json poses = nlohmann::json::array(), turns = nlohmann::json::array();
  for (std::size_t k = 0; k < p.poses.size(); ++k)
    poses.push_back({{"pose", k}, {"t0_s", p.poses[k].t0}, {"t1_s", p.poses[k].t1}, {"up_body", to_json(p.poses[k].up_body)}});
  for (std::size_t k = 0; k < p.turns.size(); ++k)
    turns.push_back({{"turn", k}, {"from_pose", k}, {"to_pose", k + 1}, {"t0_s", p.turns[k].t0}, {"t1_s", p.turns[k].t1},
                     {"axis_body", to_json(p.turns[k].axis)}, {"angle_rad", p.turns[k].angle}});
  nlohmann::json sim = {{"rate_hz", c.rate_hz},
                        {"samples", p.samples},
                        {"duration_s", p.duration_s()},
                        {"gravity_m_s2", multipos::hand_turn_gravity(c.site)},
                        {"earth_rate", c.site.has_value()},
                        {"still_s", {c.hand.still_min_s, c.hand.still_max_s}},
                        {"opening_still_s", c.hand.opening_still_s},
                        {"turn_s", {c.hand.turn_min_s, c.hand.turn_max_s}},
                        {"turn_angle_rad", {c.hand.angle_min, c.hand.angle_max}},
                        {"frame", "body = the sensor's axes; up_body: unit vector up (the reaction to gravity, what an "
                                  "error-free accelerometer measures / g); pose [t0_s, t1_s]: its first and last sample"},
                        {"poses", poses},
                        {"turns", turns}};
  if (c.site) sim["site"] = {{"lat_deg", c.site->lat_deg}, {"h_m", c.site->h_m}};
  t.extra["multipos_sim"] = sim;
  return t;
}

}  // namespace

SimulateMultiposSummary simulate_multipos_recording(const SimulateMultiposArgs& a) {
  // Every option first: nothing is written on bad input.
  if (a.poses < 2 || a.poses > 1000) throw InputError("--poses", 0, "", "2 to 1000 poses, not " + std::to_string(a.poses));
  const auto [still_lo, still_hi] = still_range(a.still);
  const ImuClassChoice cls = a.device_class.empty()
                                 ? ImuClassChoice{builtin_imu_class("ICM-42688-P"), "the default (a consumer MEMS part)"}
                                 : choose_imu_class(a.device_class, "", "--device-class");
  multipos::MultiposSimConfig c;
  c.hand.poses = a.poses;
  c.hand.still_min_s = still_lo;
  c.hand.still_max_s = still_hi;
  c.hand.opening_still_s = a.opening_still_s;
  c.rate_hz = a.rate_hz;
  c.seed = a.seed;
  if (a.site_lat_deg) c.site = Site{*a.site_lat_deg, 0.0, 0.0};
  c.truth = draw_random_unit(a.seed, cls.cls.spread);
  c.noise = multipos::hand_turn_noise(cls.cls.noise, a.noise_factor, a.rate_hz);

  MultiposTarget target;
  target.out = a.out;
  target.model = a.model.empty() ? cls.cls.name : a.model;
  target.serial = a.serial.empty() ? "SIM-" + std::to_string(a.seed) : a.serial;
  target.rate_hz = a.rate_hz;
  target.lat_deg = a.site_lat_deg;
  target.force = a.force;
  const std::filesystem::path out = check_multipos_target(target);  // refuses an existing recording without --force
  RecordingMeta meta = multipos_meta(target, a.rate_hz);
  meta.notes = "simulated by calbench simulate multipos: one " + cls.cls.name + " unit (the class's spread and noise) turned by hand through " +
               std::to_string(a.poses) + " static poses, seed " + std::to_string(a.seed) + "; truth in truth.json";

  SimulateMultiposSummary sum;
  multipos::HandTurnPlan plan;
  WanderStats wander;
  write_multipos(
      out, meta, ImuForm::rates,
      [&](RecordingWriter& w) {
        plan = multipos::simulate_multipos(c, [&](const multipos::MultiposSimSample& s) {
          ImuRecord r;
          r.t = s.t;
          r.gyro = s.gyro;
          r.accel = s.accel;
          w.imu(r);
          ++sum.samples;
          if (s.pose >= 0) wander.add(s);
        });
      },
      [&](const std::filesystem::path& file) { write_coefficients(file, truth_set(a, cls, c, plan, wander, meta.device)); });
  sum.poses = static_cast<int>(plan.poses.size());
  sum.duration_s = plan.duration_s();
  sum.rate_hz = a.rate_hz;
  sum.gravity_m_s2 = multipos::hand_turn_gravity(c.site);
  sum.device_class = cls.cls.name;
  sum.model = meta.device.model;
  sum.out = out.string();
  sum.truth = (out / "truth.json").string();
  return sum;
}

}  // namespace calbench
