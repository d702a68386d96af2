#include <cmath>
#include <limits>

#include "bench/bench_recording.hpp"
#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/qc_drive.hpp"
#include "bench/drive/route_toml.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/plan_toml.hpp"
#include "calibration/bench_blocks.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/drive_result.hpp"
#include "common/imu_error_sim.hpp"
#include "calibration/ins/strapdown.hpp"
#include "common/units.hpp"
#include "common/input_error.hpp"

// The inputs of `calbench diagnose`: a bench or a drive recording read in one pass, or simulated in
// memory; a drive's --coeffs.

namespace calbench {

namespace {

// Parent blocks kept by the diagnosis (dense covariance per axis): longer parents beyond this.
constexpr int kMaxParents = 1000;

void feed(DiagDataBuilder& db, BenchBlockBuilder& bb, const DiagSample& s) {
  db.add(s);
  bb.add(s.t, s.dt, s.gyro, s.accel, s.w, s.f, s.step, s.temp_c);
}

void feed_imu(DriveDiagBuilder& b, ins::RateIntegrator& integ, bool rates, double t, double dt, const Vec3& g,
              const Vec3& a, double temp) {
  DriveImuSample s;
  s.t = t;
  s.dt = dt;
  s.temp_c = temp;
  if (rates) {
    integ(g, a, dt, s.dtheta, s.dv);
    s.has_rates = true;
    s.w_raw = g;
    s.f_raw = a;
  } else {
    s.dtheta = g;
    s.dv = a;
  }
  b.imu(s);
}

DriveRefEpoch to_epoch(const DriveRefRow& r) {
  DriveRefEpoch e;
  e.t = r.t;
  e.lat = r.lat_deg * units::kDeg;
  e.lon = r.lon_deg * units::kDeg;
  e.h = r.h_m;
  e.v_ned = r.v_ned;
  e.rpy = r.rpy_deg * units::kDeg;
  return e;
}

}  // namespace

DiagInput load_diag_input(const std::filesystem::path& dir, double parent_s) {
  DiagInput in;
  in.dir = dir;
  in.meta = read_meta(dir);
  if (in.meta.kind != RecordingKind::bench)
    throw InputError((dir / "meta.json").string(), 0, "kind",
                     "this is a drive recording; this command needs kind \"bench\"");
  ImuReader imu(dir / "imu.csv", in.meta.imu_rate_hz);
  BenchRefReader ref(dir / "reference.csv");
  DiagDataBuilder db(std::min(0.05, parent_s), parent_s, kMaxParents);
  BenchBlockBuilder bb(parent_s);
  BenchRefRow r0, r1;
  if (!ref.next(r0)) throw InputError((dir / "reference.csv").string(), 0, "", "no data rows");
  bool have_r1 = ref.next(r1);
  in.ref_rows = have_r1 ? 2 : 1;
  ImuRecord s;
  while (imu.next(s)) {
    ++in.imu_rows;
    const bool inc = imu.form() == ImuForm::increments;
    DiagSample x;
    x.t = inc ? s.t - 0.5 * s.dt : s.t;
    x.dt = s.dt;
    x.gyro = inc ? Vec3(s.gyro / s.dt) : s.gyro;
    x.accel = inc ? Vec3(s.accel / s.dt) : s.accel;
    x.temp_c = s.temp_c;
    while (have_r1 && r1.t < x.t) {
      r0 = r1;
      have_r1 = ref.next(r1);
      if (have_r1) ++in.ref_rows;
    }
    if (x.t == r0.t) {
      x.w = r0.w;
      x.f = r0.f;
      x.step = r0.step;
      x.angle_deg = r0.angle_deg;
    } else if (have_r1 && x.t > r0.t && x.t <= r1.t) {
      const double u = (x.t - r0.t) / (r1.t - r0.t);
      x.w = r0.w + u * (r1.w - r0.w);
      x.f = r0.f + u * (r1.f - r0.f);
      x.step = (r0.step == r1.step) ? r0.step : (x.t == r1.t ? r1.step : -1);
      if (std::isfinite(r0.angle_deg) && std::isfinite(r1.angle_deg))
        x.angle_deg = r0.angle_deg + u * std::remainder(r1.angle_deg - r0.angle_deg, 360.0);
    } else {
      continue;
    }
    if (x.step >= 0) ++in.used_rows;
    feed(db, bb, x);
  }
  while (have_r1 && ref.next(r1)) ++in.ref_rows;
  in.data = db.finish();
  in.blocks = bb.finish();
  if (in.data.parents.empty())
    throw InputError((dir / "reference.csv").string(), 0, "step", "no IMU sample falls inside a plan step (all steps are −1?)");
  return in;
}

DiagInput simulate_diag_input(const BenchPlan& plan, const SensorErrors& truth, const BenchSimOptions& opt) {
  DiagInput in;
  in.meta.kind = RecordingKind::bench;
  in.meta.site = plan.site;
  in.meta.imu_rate_hz = opt.noise.output_rate_hz;
  in.meta.extra["bench"] = {{"plan", plan.name}, {"table", table_spec_json(plan.table)}};
  DiagDataBuilder db(0.05, 1.0, kMaxParents);
  BenchBlockBuilder bb(1.0);
  const double dt = 1.0 / opt.noise.output_rate_hz;
  simulate_bench(plan, plan.site, truth, opt, [&](const BenchSample& s) {
    DiagSample x;
    x.t = s.t;
    x.dt = dt;
    x.gyro = s.gyro;
    x.accel = s.accel;
    x.w = s.w_ref;
    x.f = s.f_ref;
    x.step = s.step;
    x.temp_c = s.temp_c;
    x.angle_deg = s.angle_deg;
    feed(db, bb, x);
    ++in.imu_rows;
    ++in.ref_rows;
    if (x.step >= 0) ++in.used_rows;
  });
  in.data = db.finish();
  in.blocks = bb.finish();
  return in;
}

DriveCoeffs read_drive_coeffs(const std::string& file) {
  DriveCoeffs c;
  c.file = file;
  const QcSet q = load_qc_set(file);
  c.mounting_rpy_deg = q.mounting_rpy_deg;
  const nlohmann::json j = read_json_file(file);
  // A RESULT.json (through its codec, common/drive_result.hpp) or a coefficients.json.
  c.set = is_drive_result(j) ? drive_result_from_json(j, file).coefficients : coefficients_from_json(j, file);
  c.carried = effects_from_json(c.set.extra, file);
  return c;
}

DriveDiagInput load_drive_diag_input(const std::filesystem::path& dir, const std::optional<Vec3>& rpy_deg) {
  DriveDiagInput in;
  in.dir = dir;
  in.meta = read_meta(dir);
  const std::string mf = (dir / "meta.json").string();
  if (in.meta.kind != RecordingKind::drive) throw InputError(mf, 0, "kind", "expected a drive recording");
  if (!in.meta.mounting) throw InputError(mf, 0, "mounting", "a drive recording needs a mounting");
  if (!(in.meta.imu_rate_hz > 0)) throw InputError(mf, 0, "imu_rate_hz", "must be > 0");
  in.mounting_rpy_deg = rpy_deg ? *rpy_deg : in.meta.mounting->rpy_deg;
  in.mounting_source = rpy_deg ? "coefficients file" : "meta.json (nominal)";
  DriveDiagBuilder b(ins::dcm_from_rpy(in.mounting_rpy_deg * units::kDeg), in.meta.mounting->lever_arm_m);
  ImuReader imu(dir / "imu.csv", in.meta.imu_rate_hz);
  DriveRefReader ref(dir / "reference.csv");
  DriveRefRow rr;
  bool have_ref = ref.next(rr);
  if (!have_ref) throw InputError((dir / "reference.csv").string(), 0, "", "no data rows");
  ++in.ref_rows;
  ins::RateIntegrator integ;
  ImuRecord r;
  while (imu.next(r)) {
    ++in.imu_rows;
    feed_imu(b, integ, imu.form() == ImuForm::rates, r.t, r.dt, r.gyro, r.accel, r.temp_c);
    while (have_ref && rr.t <= r.t + 1e-9) {
      b.reference(to_epoch(rr));
      have_ref = ref.next(rr);
      if (have_ref) ++in.ref_rows;
    }
  }
  in.data = b.finish();
  if (in.data.parents.size() < 20)
    throw InputError(dir.string(), 0, "", "too little overlapping IMU and reference data for a diagnosis (< 20 s)");
  return in;
}

DriveCoeffs simulate_factory_coeffs(const std::string& plan_file, std::uint64_t seed, const EffectTerms& effects,
                                    std::uint64_t bench_seed) {
  const BenchPlan plan = load_plan(plan_file);
  BenchSimOptions so;
  so.seed = bench_seed;
  so.effects = effects;
  // The drive's installation (time offset, lever arm) and shifts since the calibration (an injected
  // scale_factor): the factory saw the unit without them.
  for (const EffectSpec& x : effect_specs())
    if (x.drive_installation) effect_clear(x, so.effects);
  BenchBlockBuilder bb(1.0);
  const double dt = 1.0 / so.noise.output_rate_hz;
  simulate_bench(plan, plan.site, draw_random_unit(seed), so, [&](const BenchSample& x) {
    bb.add(x.t, dt, x.gyro, x.accel, x.w_ref, x.f_ref, x.step, x.temp_c, x.saturated);
  });
  BenchFitOptions o;
  o.table = plan.table;
  DriveCoeffs c;
  c.set.errors = fit_bench(bb.finish(), o).estimate;
  c.file = plan_file + " (simulated, fitted)";
  return c;
}

DriveDiagInput simulate_drive_diag_input(const std::string& route_file, std::uint64_t seed, const EffectTerms& effects,
                                         double until_s) {
  const RouteFile rf = load_route(route_file);
  drivesim::DriveSimConfig cfg;
  cfg.route = rf.route;
  cfg.mems = draw_random_unit(seed);
  const Vec3 rpy = draw_true_mounting_rpy_deg(rf, seed);
  cfg.imu_rate_hz = rf.imu_rate_hz;
  cfg.mounting_rpy = rpy * units::kDeg;
  cfg.lever_arm = rf.lever_arm_m;
  cfg.reference = rf.reference;
  cfg.gnss = rf.gnss;
  cfg.gnss.rate_hz = 0;
  cfg.seed = seed;
  cfg.effects = effects;
  DriveDiagInput in;
  in.meta.kind = RecordingKind::drive;
  in.meta.imu_rate_hz = rf.imu_rate_hz;
  in.meta.mounting = Mounting{rf.mounting_rpy_deg, rf.lever_arm_m};
  in.meta.device.serial = "SIM-" + std::to_string(seed);
  in.mounting_rpy_deg = rf.mounting_rpy_deg;
  in.mounting_source = "route file (nominal)";
  DriveDiagBuilder b(ins::dcm_from_rpy(rf.mounting_rpy_deg * units::kDeg), rf.lever_arm_m);
  ins::RateIntegrator integ;
  const double dt = 1.0 / rf.imu_rate_hz;
  drivesim::DriveSinks sinks;
  sinks.imu = [&](const drivesim::SimImu& m) {
    ++in.imu_rows;
    feed_imu(b, integ, true, m.t, dt, m.gyro, m.accel, std::numeric_limits<double>::quiet_NaN());
  };
  sinks.reference = [&](const drivesim::SimRef& s) {
    ++in.ref_rows;
    DriveRefEpoch e;
    e.t = s.t;
    e.lat = s.lat;
    e.lon = s.lon;
    e.h = s.h;
    e.v_ned = s.v_ned;
    e.rpy = s.rpy;
    b.reference(e);
  };
  drivesim::simulate_drive(cfg, sinks, until_s);
  in.data = b.finish();
  return in;
}

}  // namespace calbench
