#include "bench/drive/simulate_drive.hpp"

#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/route_toml.hpp"
#include "bench/io/coefficients_json.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/recording.hpp"
#include "common/units.hpp"

namespace calbench {

namespace {
// --noise NOISE.json (see simulate_drive.hpp): the unit's drift levels, data-sheet default else.
NoiseSpec read_noise_file(const std::string& file) {
  NoiseSpec n = adis16488a_noise();
  const nlohmann::json j = read_json_file(file);
  if (!j.is_object()) throw InputError(file, 0, "", "not a JSON object");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const bool gyro = it.key() == "gyro";
    if (!gyro && it.key() != "accel") throw InputError(file, 0, it.key(), "unknown key (gyro, accel)");
    if (!it.value().is_object()) throw InputError(file, 0, it.key(), "must be an object");
    TriadNoise& t = gyro ? n.gyro : n.accel;
    const std::string sk = gyro ? "drift_sigma_deg_h" : "drift_sigma_mg";
    for (auto k = it.value().begin(); k != it.value().end(); ++k) {
      const std::string key = it.key() + "." + k.key();
      const double v = jnum(k.value(), file, key);
      if (k.key() == sk) {
        if (!(v >= 0)) throw InputError(file, 0, key, "must not be negative");
        t.drift_sigma = v * (gyro ? units::kDegPerHour : units::kMilliG);
      } else if (k.key() == "drift_tau_s") {
        if (!(v > 0)) throw InputError(file, 0, key, "must be positive");
        t.drift_tau_s = v;
      } else {
        throw InputError(file, 0, key, "unknown key (" + sk + ", drift_tau_s)");
      }
    }
  }
  return n;
}
}  // namespace

SimulateDriveSummary simulate_drive_recording(const SimulateDriveArgs& a) {
  using units::kDeg;
  const RouteFile rf = load_route(a.route);
  CoefficientSet truth;
  Vec3 true_rpy_deg = rf.mounting_rpy_deg;
  Vec3 lever = rf.lever_arm_m;
  if (a.truth == "random") {
    truth.errors = draw_random_unit(a.seed);
    truth.device.serial = a.serial.empty() ? "SIM-" + std::to_string(a.seed) : a.serial;
    true_rpy_deg = draw_true_mounting_rpy_deg(rf, a.seed);
    truth.extra["truth"] = {{"drawn_by", "calbench simulate drive --truth random"}, {"seed", a.seed}};
  } else {
    truth = read_coefficients(a.truth);
    if (!a.serial.empty()) truth.device.serial = a.serial;
    if (truth.extra.contains("mounting")) {
      const auto& m = truth.extra["mounting"];
      if (m.contains("rpy_deg")) true_rpy_deg = jvec3(m["rpy_deg"], a.truth, "mounting.rpy_deg");
      if (m.contains("lever_arm_m")) lever = jvec3(m["lever_arm_m"], a.truth, "mounting.lever_arm_m");
    }
  }
  // Physics beyond the spec's model: the truth's own catalogue keys, an effects file, --inject.
  const EffectTerms effects = simulation_effects(truth.extra, a.truth, a.effects, a.inject);
  {
    const std::string src = a.inject.empty() ? (a.effects.empty() ? a.truth : a.effects) : "--inject";
    for (const EffectSpec& x : effect_specs())
      if (x.drive_sim_refusal && effect_present(x, effects)) throw InputError(src, 0, x.key, x.drive_sim_refusal);
  }
  if (effects.any()) replace_effect_keys(effects, truth.extra);
  // The true mounting (what the filter should find); meta.json carries the nominal one. A
  // catalogue lever_arm (IMU axes) is on top of mounting.lever_arm_m.
  truth.extra["mounting"] = {{"rpy_deg", to_json(true_rpy_deg)}, {"lever_arm_m", to_json(lever)}};
  const NoiseSpec noise = a.noise.empty() ? adis16488a_noise() : read_noise_file(a.noise);
  if (!a.noise.empty())
    truth.extra["noise"] = {{"model", "first-order Gauss-Markov in-run drift (simulate drive --noise)"},
                            {"gyro", {{"drift_sigma_deg_h", noise.gyro.drift_sigma / units::kDegPerHour},
                                      {"drift_tau_s", noise.gyro.drift_tau_s}}},
                            {"accel", {{"drift_sigma_mg", noise.accel.drift_sigma / units::kMilliG},
                                       {"drift_tau_s", noise.accel.drift_tau_s}}}};

  const fs::path out(a.out);
  if (fs::exists(out / "meta.json") && !a.force)
    throw InputError(a.out, 0, "", "already holds a recording (use --force to overwrite)");
  check_output_folder(out);
  fs::create_directories(out);
  write_coefficients(out / "truth.json", truth);

  RecordingMeta meta;
  meta.kind = RecordingKind::drive;
  meta.device = truth.device;
  if (meta.device.model.empty()) meta.device.model = "ADIS16488A";
  meta.imu_rate_hz = rf.imu_rate_hz;
  meta.mounting = Mounting{rf.mounting_rpy_deg, rf.lever_arm_m};
  meta.notes = "simulated by calbench: route '" + rf.route.name + "', seed " + std::to_string(a.seed) +
               "; reference = FOG-grade INS/GNSS with white errors of the stated sigma";
  meta.extra["drive"] = {{"route", rf.route.name}, {"seed", a.seed}};

  drivesim::DriveSimConfig cfg;
  cfg.route = rf.route;
  cfg.mems = truth.errors;
  cfg.imu_rate_hz = rf.imu_rate_hz;
  cfg.mounting_rpy = true_rpy_deg * kDeg;
  cfg.lever_arm = lever;
  cfg.reference = rf.reference;
  cfg.gnss = rf.gnss;
  cfg.seed = a.seed;
  cfg.effects = effects;
  cfg.noise = noise;

  SimulateDriveSummary sum;
  RecordingWriter w(out, meta, ImuForm::rates, false, false, rf.gnss.rate_hz > 0);
  drivesim::DriveSinks sinks;
  sinks.imu = [&](const drivesim::SimImu& m) {
    ImuRecord r;
    r.t = m.t;
    r.gyro = m.gyro;
    r.accel = m.accel;
    w.imu(r);
    ++sum.imu_rows;
    sum.duration_s = m.t;
  };
  sinks.reference = [&](const drivesim::SimRef& s) {
    DriveRefRow r;
    r.t = s.t;
    r.lat_deg = units::deg(s.lat);
    r.lon_deg = units::deg(s.lon);
    r.h_m = s.h;
    r.v_ned = s.v_ned;
    r.rpy_deg = s.rpy / kDeg;
    r.sigma_pos_m = s.sigma_pos;
    r.sigma_vel_m_s = s.sigma_vel;
    r.sigma_att_deg = units::deg(s.sigma_att);
    w.drive_ref(r);
    ++sum.ref_rows;
  };
  sinks.gnss = [&](const drivesim::SimGnss& s) {
    GnssRow g;
    g.t = s.t;
    g.lat_deg = units::deg(s.lat);
    g.lon_deg = units::deg(s.lon);
    g.h_m = s.h;
    g.v_ned = s.v_ned;
    g.sigma_h_m = s.sigma_h;
    g.sigma_v_m = s.sigma_v;
    g.sigma_vel_m_s = s.sigma_vel;
    w.gnss(g);
    ++sum.gnss_rows;
  };
  drivesim::simulate_drive(cfg, sinks, a.until_s);
  w.finish();
  return sum;
}

}  // namespace calbench
