#include "bench/bench_recording.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <sstream>

#include "calibration/qc/bench_fit_quality.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "common/units.hpp"

namespace calbench {

void write_bench_sample(RecordingWriter& w, const BenchSample& s) {
  ImuRecord r;
  r.t = s.t;
  r.gyro = s.gyro;
  r.accel = s.accel;
  r.temp_c = s.temp_c;
  w.imu(r);
  w.bench_ref({s.t, s.w_ref, s.f_ref, s.step, s.angle_deg});
}

BenchRecordingData load_bench_blocks(const std::filesystem::path& dir, double block_s) {
  BenchRecordingData d;
  d.meta = read_meta(dir);
  if (d.meta.kind != RecordingKind::bench)
    throw InputError((dir / "meta.json").string(), 0, "kind",
                     std::string("this is a ") + kind_name(d.meta.kind) + " recording; `fit bench` needs kind \"bench\"" +
                         (d.meta.kind == RecordingKind::multipos ? " (a multipos recording: `fit multipos`)"
                                                                 : " (a drive: `fit drive`)"));
  ImuReader imu(dir / "imu.csv", d.meta.imu_rate_hz);
  BenchRefReader ref(dir / "reference.csv");
  d.form = imu.form();
  BenchBlockBuilder bb(block_s);
  BenchRefRow r0, r1;
  if (!ref.next(r0)) return d;
  bool have_r1 = ref.next(r1);
  d.ref_rows = have_r1 ? 2 : 1;
  ImuRecord s;
  while (imu.next(s)) {
    ++d.imu_rows;
    // Increments describe the interval (t − dt, t]: their mean rate belongs to its middle.
    const bool inc = d.form == ImuForm::increments;
    const double tq = inc ? s.t - 0.5 * s.dt : s.t;
    const Vec3 g = inc ? Vec3(s.gyro / s.dt) : s.gyro;
    const Vec3 a = inc ? Vec3(s.accel / s.dt) : s.accel;
    while (have_r1 && r1.t < tq) {
      r0 = r1;
      have_r1 = ref.next(r1);
      if (have_r1) ++d.ref_rows;
    }
    Vec3 w, f;
    int step;
    if (tq == r0.t) {
      w = r0.w;
      f = r0.f;
      step = r0.step;
    } else if (have_r1 && tq > r0.t && tq <= r1.t) {
      const double u = (tq - r0.t) / (r1.t - r0.t);
      w = r0.w + u * (r1.w - r0.w);
      f = r0.f + u * (r1.f - r0.f);
      step = (r0.step == r1.step) ? r0.step : (tq == r1.t ? r1.step : -1);
    } else {
      continue;  // outside the reference's time span
    }
    if (step >= 0) ++d.used_rows;
    bb.add(tq, s.dt, g, a, w, f, step, s.temp_c);
  }
  while (have_r1 && ref.next(r1)) ++d.ref_rows;
  d.blocks = bb.finish();
  return d;
}

TableSpec recording_table_spec(const RecordingMeta& meta) {
  using namespace units;
  TableSpec t;  // defaults as in a plan without these keys
  t.rate_accuracy_rel = 1.0 * kPpm;
  t.position_accuracy = 2.0 * kDeg / 3600;
  t.axis_wobble = 1.0 * kDeg / 3600;
  if (meta.extra.contains("bench") && meta.extra["bench"].contains("table")) {
    const auto& j = meta.extra["bench"]["table"];
    const std::string f = "meta.json";
    if (j.contains("rate_accuracy_ppm")) t.rate_accuracy_rel = jnum(j["rate_accuracy_ppm"], f, "bench.table.rate_accuracy_ppm") * kPpm;
    if (j.contains("position_accuracy_arcsec"))
      t.position_accuracy = jnum(j["position_accuracy_arcsec"], f, "bench.table.position_accuracy_arcsec") * kDeg / 3600;
    if (j.contains("axis_wobble_arcsec"))
      t.axis_wobble = jnum(j["axis_wobble_arcsec"], f, "bench.table.axis_wobble_arcsec") * kDeg / 3600;
  }
  return t;
}

nlohmann::json table_spec_json(const TableSpec& t) {
  using namespace units;
  return {{"rate_accuracy_ppm", t.rate_accuracy_rel / kPpm},
          {"position_accuracy_arcsec", t.position_accuracy / kDeg * 3600},
          {"axis_wobble_arcsec", t.axis_wobble / kDeg * 3600}};
}

namespace {
std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}
nlohmann::json v3(const Vec3& v) { return to_json(v); }
}  // namespace

CoefficientSet bench_result_to_coefficients(const BenchFitResult& r, const BenchFitOptions& opt,
                                            const RecordingMeta& meta, const std::string& recording_path) {
  CoefficientSet c;
  c.device = meta.device;
  c.errors = r.estimate;
  c.fit_quality = qc::bench_fit_quality(r);
  nlohmann::json un = nlohmann::json::array();
  for (const auto& u : r.unobservable) un.push_back({{"triad", u.triad}, {"param", u.param}, {"reason", u.reason}});
  c.extra["calibration"] = {
      {"source", "bench"},
      {"method", opt.method == BenchMethod::lsq ? "lsq" : "ekf"},
      {"model", opt.model == BenchModel::full ? "full" : "paper"},
      {"recording", recording_path},
      {"created_utc", utc_now()},
      {"not_determined", un},
      {"not_estimated", r.not_estimated},
      {"bias_sigma_includes", "in-run drift (first-order Gauss-Markov, data-sheet sigma and tau) and bench errors"},
  };
  return c;
}

nlohmann::json bench_result_json(const BenchFitResult& r, const CoefficientSet& c) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& s : r.steps)
    steps.push_back({{"step", s.step},
                     {"rotating", s.rotating},
                     {"samples", s.samples},
                     {"duration_s", s.duration_s},
                     {"rate_norm_rad_s", s.rate_norm},
                     {"f_mean_m_s2", v3(s.f_mean)},
                     {"gyro_resid_mean_rad_s", v3(s.gyro_mean)},
                     {"gyro_resid_rms_rad_s", v3(s.gyro_rms)},
                     {"accel_resid_mean_m_s2", v3(s.accel_mean)},
                     {"accel_resid_rms_m_s2", v3(s.accel_rms)}});
  nlohmann::json un = nlohmann::json::array();
  for (const auto& u : r.unobservable) un.push_back({{"triad", u.triad}, {"param", u.param}, {"reason", u.reason}});
  return {{"coefficients", coefficients_to_json(c)},
          {"not_determined", un},
          {"not_estimated", r.not_estimated},
          {"blocks", r.blocks},
          {"data_s", r.data_s},
          {"white_noise", {{"gyro_rad_s_per_sqrt_hz", v3(r.gyro_white_density)},
                           {"accel_m_s2_per_sqrt_hz", v3(r.accel_white_density)}}},
          {"chi2_per_dof", {{"gyro", v3(r.gyro_chi2_dof)}, {"accel", v3(r.accel_chi2_dof)}}},
          {"steps", steps}};
}

std::string bench_result_text(const BenchFitResult& r) {
  using namespace units;
  std::ostringstream o;
  o.setf(std::ios::fixed);
  auto val = [&](double v, double s, double unit, int prec) {
    std::ostringstream x;
    x.setf(std::ios::fixed);
    x.precision(prec);
    if (!std::isfinite(s)) x << "   (not determined)  ";
    else x << std::setw(10) << v / unit << " ± " << std::setw(7) << s / unit;
    return x.str();
  };
  const char* ax = "xyz";
  o << "gyro drift (°/h):\n";
  for (int i = 0; i < 3; ++i) o << "  " << ax[i] << ": " << val(r.estimate.gyro.bias(i), r.estimate.gyro.sigma_bias(i), kDegPerHour, 2) << "\n";
  o << "gyro M = scale (diagonal) and skews (ppm):\n";
  for (int i = 0; i < 3; ++i) {
    o << "  ";
    for (int j = 0; j < 3; ++j) o << val(r.estimate.gyro.M(i, j), r.estimate.gyro.sigma_M(i, j), kPpm, 1) << "  ";
    o << "\n";
  }
  o << "accelerometer bias (mg):\n";
  for (int i = 0; i < 3; ++i) o << "  " << ax[i] << ": " << val(r.estimate.accel.bias(i), r.estimate.accel.sigma_bias(i), kMilliG, 4) << "\n";
  o << "accelerometer M (ppm):\n";
  for (int i = 0; i < 3; ++i) {
    o << "  ";
    for (int j = 0; j < 3; ++j) o << val(r.estimate.accel.M(i, j), r.estimate.accel.sigma_M(i, j), kPpm, 1) << "  ";
    o << "\n";
  }
  o.precision(3);
  o << "white noise: gyro " << r.gyro_white_density.maxCoeff() / kDeg * kSqrtHour << " °/√h (ARW, worst axis), accel "
    << r.accel_white_density.maxCoeff() * kSqrtHour << " m/s/√h (VRW)\n";
  o << "data: " << r.blocks << " blocks, " << r.data_s << " s in " << r.steps.size() << " plan steps\n";
  for (const auto& n : r.not_estimated) o << "not estimated (model choice): " << n << "\n";
  for (const auto& u : r.unobservable) o << "NOT DETERMINED " << u.triad << "." << u.param << ": " << u.reason << "\n";
  return o.str();
}

}  // namespace calbench
