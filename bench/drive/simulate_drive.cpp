#include "bench/drive/simulate_drive.hpp"

#include <optional>

#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/route_toml.hpp"
#include "bench/drive/sim_logger.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/recording.hpp"
#include "common/units.hpp"

namespace calbench {

namespace {
// --noise NOISE.json (see simulate_drive.hpp): the unit's drift levels, data-sheet default else.
NoiseSpec read_noise_file(const std::string& file, const NoiseSpec& base) {
  NoiseSpec n = base;
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

// One simulated unit: its truth (errors and true mounting) and what meta.json says of it.
struct SimUnit {
  std::string slot;
  CoefficientSet truth;
  Vec3 true_rpy_deg, nominal_rpy_deg, lever;
};

}  // namespace

SimulateDriveSummary simulate_drive_recording(const SimulateDriveArgs& a) {
  using units::kDeg;
  const RouteFile rf = load_route(a.route);
  if (a.units < 1 || a.units > 16) throw InputError("--units", 0, "", "1 to 16 units, not " + std::to_string(a.units));
  if (a.units > 1 && a.truth != "random")
    throw InputError("--units", 0, "", "several units need --truth random (each unit its own errors, drawn from --seed + k)");
  std::optional<ImuClassChoice> cls;
  if (!a.device_class.empty()) cls = choose_imu_class(a.device_class, "", "--device-class");
  std::vector<SimUnit> sim(static_cast<std::size_t>(a.units));
  for (int k = 0; k < a.units; ++k) {
    SimUnit& u = sim[static_cast<std::size_t>(k)];
    const std::uint64_t seed = a.seed + static_cast<std::uint64_t>(k);
    u.slot = std::to_string(k + 1);
    u.nominal_rpy_deg = rf.mounting_rpy_deg;
    u.lever = rf.lever_arm_m;
    if (a.units > 1) {  // on a plate round the route's lever arm, each turned 90° in yaw from the last
      const double ang = 2 * M_PI * k / a.units;
      u.nominal_rpy_deg(2) = std::remainder(rf.mounting_rpy_deg(2) + 90.0 * k, 360.0);
      u.lever += 0.15 * Vec3(std::cos(ang), std::sin(ang), 0.0);
    }
    u.true_rpy_deg = u.nominal_rpy_deg;
    if (a.truth == "random") {
      u.truth.errors = cls ? draw_random_unit(seed, cls->cls.spread) : draw_random_unit(seed);
      u.truth.device.serial = a.serial.empty() ? "SIM-" + std::to_string(seed) : (a.units > 1 ? a.serial + "-" + u.slot : a.serial);
      RouteFile r = rf;
      r.mounting_rpy_deg = u.nominal_rpy_deg;
      u.true_rpy_deg = draw_true_mounting_rpy_deg(r, seed);
      u.truth.extra["truth"] = {{"drawn_by", "calbench simulate drive --truth random"}, {"seed", seed}};
    } else {
      u.truth = read_coefficients(a.truth);
      if (!a.serial.empty()) u.truth.device.serial = a.serial;
      if (u.truth.extra.contains("mounting")) {
        const auto& m = u.truth.extra["mounting"];
        if (m.contains("rpy_deg")) u.true_rpy_deg = jvec3(m["rpy_deg"], a.truth, "mounting.rpy_deg");
        if (m.contains("lever_arm_m")) u.lever = jvec3(m["lever_arm_m"], a.truth, "mounting.lever_arm_m");
      }
    }
    if (cls) u.truth.device.model = cls->cls.name;  // the unit is of the simulated class
  }
  // Physics beyond the spec's model: the truth's own catalogue keys, an effects file, --inject (every unit).
  const EffectTerms effects = simulation_effects(sim.front().truth.extra, a.truth, a.effects, a.inject);
  {
    const std::string src = a.inject.empty() ? (a.effects.empty() ? a.truth : a.effects) : "--inject";
    for (const EffectSpec& x : effect_specs())
      if (x.drive_sim_refusal && effect_present(x, effects)) throw InputError(src, 0, x.key, x.drive_sim_refusal);
  }
  const NoiseSpec base = cls ? cls->cls.noise : adis16488a_noise();
  const NoiseSpec noise = a.noise.empty() ? base : read_noise_file(a.noise, base);
  for (SimUnit& u : sim) {
    if (effects.any()) replace_effect_keys(effects, u.truth.extra);
    // The true mounting (what the filter should find); meta.json carries the nominal one. A
    // catalogue lever_arm (IMU axes) is on top of mounting.lever_arm_m.
    u.truth.extra["mounting"] = {{"rpy_deg", to_json(u.true_rpy_deg)}, {"lever_arm_m", to_json(u.lever)}};
    if (!a.noise.empty())
      u.truth.extra["noise"] = {{"model", "first-order Gauss-Markov in-run drift (simulate drive --noise)"},
                                {"gyro", {{"drift_sigma_deg_h", noise.gyro.drift_sigma / units::kDegPerHour},
                                          {"drift_tau_s", noise.gyro.drift_tau_s}}},
                                {"accel", {{"drift_sigma_mg", noise.accel.drift_sigma / units::kMilliG},
                                           {"drift_tau_s", noise.accel.drift_tau_s}}}};
  }

  const fs::path out(a.out);
  const bool several = a.units > 1;
  if ((fs::exists(out / "meta.json") || fs::exists(out / "units.json")) && !a.force)
    throw InputError(a.out, 0, "", "already holds a recording (use --force to overwrite)");
  check_output_folder(out);
  fs::create_directories(out);
  if (several) fs::remove(out / "meta.json");  // not a one-unit recording any more (--force)

  drivesim::DriveSimConfig cfg;
  cfg.route = rf.route;
  cfg.imu_rate_hz = rf.imu_rate_hz;
  cfg.reference = rf.reference;
  cfg.gnss = rf.gnss;
  cfg.seed = a.seed;
  cfg.noise = noise;
  cfg.mems = sim.front().truth.errors;
  cfg.mounting_rpy = sim.front().true_rpy_deg * kDeg;
  cfg.lever_arm = sim.front().lever;
  cfg.effects = effects;
  for (std::size_t k = 1; k < sim.size(); ++k)
    cfg.more_units.push_back({sim[k].truth.errors, noise, sim[k].true_rpy_deg * kDeg, sim[k].lever, a.seed + k, effects});

  const bool with_gnss = rf.gnss.rate_hz > 0;
  std::vector<std::unique_ptr<RecordingWriter>> writers;
  for (const SimUnit& u : sim) {
    const fs::path dir = several ? out / u.slot : out;
    fs::create_directories(dir);
    write_coefficients(dir / "truth.json", u.truth);
    RecordingMeta meta;
    meta.kind = RecordingKind::drive;
    meta.device = u.truth.device;
    if (cls) meta.device.model = cls->cls.name;
    if (meta.device.model.empty()) meta.device.model = "ADIS16488A";
    meta.imu_rate_hz = rf.imu_rate_hz;
    meta.mounting = Mounting{u.nominal_rpy_deg, u.lever};
    meta.notes = "simulated by calbench: route '" + rf.route.name + "', seed " + std::to_string(a.seed) +
                 "; reference = FOG-grade INS/GNSS with white errors of the stated sigma";
    meta.extra["drive"] = {{"route", rf.route.name}, {"seed", a.seed}};
    if (several) meta.extra["drive"]["unit"] = {{"slot", u.slot}, {"of", a.units}};
    writers.push_back(std::make_unique<RecordingWriter>(dir, meta, ImuForm::rates, false, false, with_gnss));
  }
  RecordingWriter& w = *writers.front();  // the reference and GNSS go with the first unit's folder

  SimulateDriveSummary sum;
  drivesim::DriveSinks sinks;
  std::vector<PollingLogger> loggers;
  for (std::size_t k = 0; k < writers.size(); ++k)
    loggers.emplace_back(a.logger_read_hz, a.seed + k, [&, k](const ImuRecord& r) {
      writers[k]->imu(r);
      if (k == 0) {
        ++sum.imu_rows;
        sum.duration_s = r.t;
      }
    });
  DifferencingReceiver receiver(a.gnss_velocity_from_positions);
  sinks.imu = [&](const drivesim::SimImu& m) {
    ImuRecord r;
    r.t = m.t;
    r.gyro = m.gyro;
    r.accel = m.accel;
    loggers[static_cast<std::size_t>(m.unit)].sample(r);
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
    w.gnss(receiver.fix(g));
    ++sum.gnss_rows;
  };
  drivesim::simulate_drive(cfg, sinks, a.until_s);
  for (PollingLogger& l : loggers) l.finish(1.0 / rf.imu_rate_hz);
  w.finish();
  if (several) {
    // The drive's reference once: out/reference.csv (and gnss.csv), the same file in every unit's
    // folder, so that each folder is a whole recording of the interchange format. Each unit is
    // marked complete only after the check of what its folder finally holds, the shared files included.
    nlohmann::json units = nlohmann::json::array();
    for (const char* f : {"reference", "gnss"})
      if (fs::exists(out / sim.front().slot / (std::string(f) + ".csv")))
        link_or_copy(out / sim.front().slot / (std::string(f) + ".csv"), out / (std::string(f) + ".csv"));
    for (std::size_t k = 1; k < sim.size(); ++k) {
      writers[k]->share_table(w, "reference");
      if (with_gnss) writers[k]->share_table(w, "gnss");
      writers[k]->finish();
    }
    for (const SimUnit& u : sim) units.push_back({{"slot", u.slot}, {"dir", u.slot}, {"serial", u.truth.device.serial}});
    nlohmann::json uj = {{"format", "calbench-drive-units/1"}, {"reference", "reference.csv"}, {"units", units},
                         {"notes", "simulated by calbench simulate drive --units " + std::to_string(a.units) + ": route '" +
                                       rf.route.name + "', seed " + std::to_string(a.seed)}};
    if (with_gnss) uj["gnss"] = "gnss.csv";
    write_text_atomic(out / "units.json", uj.dump(2) + "\n");
  }
  return sum;
}

}  // namespace calbench
