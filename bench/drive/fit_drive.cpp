#include "bench/drive/fit_drive.hpp"

#include <cmath>
#include <sstream>

#include "bench/drive/drive_stream.hpp"
#include "bench/drive/qc_drive.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/csv.hpp"
#include "bench/io/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/units.hpp"

namespace calbench {
namespace {

std::pair<double, double> parse_window(const std::string& w) {
  double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
  if (w.empty()) return {t0, t1};
  const auto c = w.find(':');
  if (c == std::string::npos) throw InputError("--window", 0, "", "expected T0:T1 (seconds; either may be empty)");
  try {
    if (c > 0) t0 = std::stod(w.substr(0, c));
    if (c + 1 < w.size()) t1 = std::stod(w.substr(c + 1));
  } catch (const std::exception&) {
    throw InputError("--window", 0, "", "expected T0:T1 (seconds)");
  }
  if (!(t1 > t0)) throw InputError("--window", 0, "", "T1 must be after T0");
  return {t0, t1};
}

nlohmann::json set_json(const DeviceId& d, const SensorErrors& e) {
  CoefficientSet c;
  c.device = d;
  c.errors = e;
  return coefficients_to_json(c);
}

}  // namespace

nlohmann::json fit_drive(const FitDriveArgs& a) {
  using namespace units;
  const auto [t0, t1] = parse_window(a.window);
  std::optional<CoefficientSet> bench;
  if (!a.coeffs.empty()) bench = read_coefficients(a.coeffs);
  inmotion::InMotionConfig cfg;
  cfg.obs_pos = cfg.obs_vel = cfg.obs_att = false;
  {
    std::stringstream ss(a.obs);
    std::string tok;
    while (std::getline(ss, tok, ',')) {
      if (tok == "pos") cfg.obs_pos = true;
      else if (tok == "vel") cfg.obs_vel = true;
      else if (tok == "att") cfg.obs_att = true;
      else throw InputError("--obs", 0, "", "unknown observation '" + tok + "' (pos, vel, att)");
    }
    if (!cfg.obs_pos && !cfg.obs_vel && !cfg.obs_att) throw InputError("--obs", 0, "", "no observation selected");
  }
  cfg.obs_rate_hz = a.obs_rate_hz;
  cfg.cov_dt = a.cov_dt;
  cfg.store_for_smoother = a.smooth;

  DriveStream st(a.dir, bench ? std::optional<SensorErrors>(bench->errors) : std::nullopt);
  std::unique_ptr<inmotion::InMotionFilter> f;
  std::unique_ptr<CsvWriter> series;
  std::vector<std::string> cols;
  if (!a.series.empty() && !a.smooth) {
    cols.push_back("t_s");
    for (const auto& n : inmotion::state_names()) cols.push_back(n);
    for (const auto& n : inmotion::state_names()) cols.push_back("sigma_" + n);
    series = std::make_unique<CsvWriter>(a.series, cols, "in-motion filter estimates (forward pass), totals and 1-sigma");
  }
  auto override_sigma = [&](inmotion::RefObs& r) {
    if (a.sigma_pos > 0) r.sigma_pos = a.sigma_pos;
    if (a.sigma_vel > 0) r.sigma_vel = a.sigma_vel;
    if (a.sigma_att_deg > 0) r.sigma_att = a.sigma_att_deg * kDeg;
  };
  double t_first = 0, t_last = 0, t_data_end = 0;
  long n_imu = 0;
  DriveStream::Event e;
  std::vector<double> row(cols.size());
  while (st.next(e)) {
    t_data_end = std::max(t_data_end, e.t);
    if (e.t < t0 - 1e-9) continue;
    if (e.t > t1 + 1e-9) continue;  // keep reading to learn where the data end
    if (e.is_ref) {
      override_sigma(e.ref);
      if (!f) {
        f = std::make_unique<inmotion::InMotionFilter>(cfg, st.nominal_mounting(), st.lever_arm(), e.ref);
        t_first = e.t;
        continue;
      }
      if (f->reference(e.ref) && series) {
        inmotion::StateVec x, s;
        f->totals(x, s);
        row[0] = e.t;
        for (int i = 0; i < inmotion::kStates; ++i) {
          row[1 + i] = x(i);
          row[1 + inmotion::kStates + i] = s(i);
        }
        series->row(row.data(), row.size());
      }
    } else if (f) {
      double dt = e.dt;
      Vec3 dth = e.dtheta, dv = e.dv;
      if (e.t - dt < f->time()) {  // the first interval straddles the start epoch
        const double part = e.t - f->time();
        if (part <= 0) continue;
        dth *= part / dt;
        dv *= part / dt;
        dt = part;
      }
      f->imu(e.t, dth, dv, dt);
      ++n_imu;
      t_last = e.t;
    }
  }
  if (!f) throw InputError(a.dir, 0, "reference.csv", "no reference epoch inside the fit window");
  if (n_imu < 10) throw InputError(a.dir, 0, "imu.csv", "too few IMU samples inside the fit window");
  if (series) series->close();
  if (a.smooth) {
    const auto sm = f->smooth();
    if (!a.series.empty()) {
      cols.assign(1, "t_s");
      for (const auto& n : inmotion::state_names()) cols.push_back(n);
      for (const auto& n : inmotion::state_names()) cols.push_back("sigma_" + n);
      CsvWriter w(a.series, cols, "in-motion estimates after the RTS smoother (sensor states smoothed; navigation states from the forward pass)");
      row.resize(cols.size());
      for (const auto& ep : sm) {
        row[0] = ep.t;
        for (int i = 0; i < inmotion::kStates; ++i) {
          row[1 + i] = ep.x(i);
          row[1 + inmotion::kStates + i] = ep.sigma(i);
        }
        w.row(row.data(), row.size());
      }
      w.close();
    }
  }

  const SensorErrors corr = f->estimate();
  const SensorErrors total = bench ? compose(bench->errors, corr) : corr;
  const RecordingMeta& meta = st.meta();
  DeviceId dev = bench ? bench->device : meta.device;
  if (dev.serial.empty()) dev.serial = meta.device.serial;

  nlohmann::json j;
  j["format"] = "calbench-inmotion-result/1";
  j["device"] = {{"model", dev.model}, {"serial", dev.serial}};
  const fs::path dir(a.dir);
  j["recording"] = {{"path", fs::absolute(dir).lexically_normal().string()},
                    {"sha256", sha256_file(dir / "imu.csv")},
                    {"sha256_reference", sha256_file(dir / "reference.csv")},
                    {"sha256_meta", sha256_file(dir / "meta.json")}};
  j["window_s"] = {t_first, t_last};
  j["observations"] = a.obs;
  j["smoothed"] = a.smooth;
  j["coefficients"] = set_json(dev, total);
  j["correction"] = set_json(dev, corr);
  j["input_coefficients"] = a.coeffs.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.coeffs);
  Vec3 mr, ms;
  f->mounting_rpy(mr, ms);
  j["mounting_rpy_deg"] = {{"value", to_json(Vec3(mr / kDeg))}, {"sigma", to_json(Vec3(ms / kDeg))},
                           {"nominal", to_json(meta.mounting->rpy_deg)}, {"lever_arm_m", to_json(meta.mounting->lever_arm_m)}};
  // The in-run drift at the end of the window (shaping-filter states), and the σ of the total
  // gyro drift (constant + in-run), which is what the drive determines best.
  j["in_run_drift_end"] = {{"gyro_rad_s", to_json(f->gyro_drift())}, {"accel_m_s2", to_json(f->accel_drift())},
                           {"gyro_total_sigma_rad_s", to_json(f->gyro_total_drift_sigma())}};
  nlohmann::json cons;
  const char* names[3] = {"position", "velocity", "attitude"};
  const char* eqs[3] = {"13", "14", "15"};
  const bool used[3] = {cfg.obs_pos, cfg.obs_vel, cfg.obs_att};
  for (int i = 0; i < 3; ++i) {
    if (!used[i]) continue;
    const auto& c = f->consistency(i);
    cons[names[i]] = {{"equation", eqs[i]}, {"epochs", c.used}, {"rejected", c.rejected}, {"mean_nis", c.mean_nis()},
                      {"expected_nis", 3.0},
                      {"fraction_within_95pct", c.used ? static_cast<double>(c.within95) / static_cast<double>(c.used) : 0.0}};
  }
  j["consistency"] = cons;

  // QC: out-of-sample inertial-only navigation after the window, with the input set and with
  // the result, when the recording continues; otherwise in-sample from the window start.
  nlohmann::json qj;
  if (a.qc) {
    const bool oos = t_data_end > t_last + 10.0;
    const double from = oos ? t_last : t_first;
    QcSet before{bench ? "input" : "none", bench ? bench->errors : SensorErrors{}, std::nullopt, std::nullopt};
    QcSet after{"in-motion", total, Vec3(mr / kDeg), std::nullopt};
    const QcOutcome q = run_qc(a.dir, {before, after}, from, a.qc_horizon_s);
    qj = qc_json(q);
    qj["sample"] = oos ? "out-of-sample (after the fit window)" : "in-sample (no data after the fit window)";
  } else {
    qj = {{"sample", "not run"}};
  }
  j["qc"] = qj;
  write_text_atomic(a.out, j.dump(2) + "\n");
  return j;
}

}  // namespace calbench
