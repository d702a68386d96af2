#include "bench/drive/qc_drive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/drive_stream.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/message_text.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/drive_result.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "calibration/qc/inertial_qc.hpp"
#include "common/units.hpp"

namespace calbench {

QcSet load_qc_set(const std::string& arg) {
  QcSet s;
  if (arg == "none") {
    s.name = "none";
    return s;
  }
  s.name = fs::path(arg).stem().string();
  const nlohmann::json j = read_json_file(arg);
  if (is_drive_result(j)) {  // an in-motion RESULT.json: its coefficients, mounting and fit window
    const DriveResult r = drive_result_from_json(j, arg);
    s.errors = r.coefficients.errors;
    s.device = r.coefficients.device;
    s.effects = effects_from_json(r.coefficients.extra, arg);
    if (r.mounting) s.mounting_rpy_deg = r.mounting->value_deg;
    s.fit_window_s = r.window_s;
  } else {
    const CoefficientSet cs = coefficients_from_json(j, arg);
    s.errors = cs.errors;
    s.device = cs.device;
    s.effects = effects_from_json(j, arg);
    // A simulator truth.json states the true mounting (key "mounting"); use it like a result's.
    if (j.is_object() && j.contains("mounting") && j["mounting"].is_object() && j["mounting"].contains("rpy_deg"))
      s.mounting_rpy_deg = jvec3(j["mounting"]["rpy_deg"], arg, "mounting.rpy_deg");
  }
  return s;
}

std::vector<std::vector<std::size_t>> time_offset_groups(const std::vector<QcSet>& sets) {
  std::vector<std::vector<std::size_t>> groups;  // by time offset, in order of appearance
  for (std::size_t i = 0; i < sets.size(); ++i) {
    bool placed = false;
    for (auto& g : groups)
      if (time_stamp_offset(sets[g[0]].effects) == time_stamp_offset(sets[i].effects)) {
        g.push_back(i);
        placed = true;
        break;
      }
    if (!placed) groups.push_back({i});
  }
  return groups;
}

std::vector<std::optional<ImuEffectCompensator>> qc_compensators(const std::vector<QcSet>& sets, const std::vector<std::size_t>& idx) {
  std::vector<std::optional<ImuEffectCompensator>> comp(idx.size());
  for (std::size_t i = 0; i < idx.size(); ++i)
    if (sets[idx[i]].effects.any_sensor_side()) comp[i].emplace(sets[idx[i]].effects, sets[idx[i]].errors);
  return comp;
}

void qc_imu(qc::InertialRun& run, std::optional<ImuEffectCompensator>& comp, const DriveStream::Event& e) {
  if (!comp) {
    run.imu(e.t, e.dtheta, e.dv, e.dt);
    return;
  }
  Vec3 dth = e.dtheta, dv = e.dv;
  comp->increments(dth, dv, e.dt, e.temp_c);
  run.imu(e.t, dth, dv, e.dt);
}

namespace {
// One pass over the recording for the sets `idx` (all with the same time offset).
void run_qc_group(const fs::path& dir, const std::vector<QcSet>& sets, const std::vector<std::size_t>& idx,
                  std::optional<double> from_s, double horizon_s, QcOutcome& q,
                  const std::shared_ptr<const SharedReference>& shared) {
  // The stream moves the time stamps; each set removes its own output terms.
  const EffectTerms shift = time_stamp_terms(sets[idx[0]].effects);
  DriveStream st(dir, std::nullopt, time_stamp_offset(shift) != 0 ? &shift : nullptr, Aiding::reference, shared);
  const Mat3 C_nom = st.nominal_mounting();
  const Vec3 lever = st.lever_arm();
  std::vector<std::unique_ptr<qc::InertialRun>> runs(idx.size());
  std::vector<std::optional<ImuEffectCompensator>> comp = qc_compensators(sets, idx);
  bool started = false;
  double t0 = 0;
  DriveStream::Event e;
  while (st.next(e)) {
    if (e.is_ref) {
      if (!started) {
        if (from_s && e.t < *from_s - 1e-9) continue;
        started = true;
        t0 = e.t;
        q.from_s = t0;
        for (std::size_t i = 0; i < idx.size(); ++i) {
          const QcSet& s = sets[idx[i]];
          const Mat3 C = s.mounting_rpy_deg ? ins::dcm_from_rpy(*s.mounting_rpy_deg * units::kDeg) : C_nom;
          runs[i] = std::make_unique<qc::InertialRun>(s.errors, C, lever, e.ref);
        }
        continue;
      }
      if (e.t - t0 > horizon_s + 1e-9) break;
      if (e.t > runs[0]->time() + 1e-6) continue;  // beyond the IMU data
      for (std::size_t i = 0; i < idx.size(); ++i) {
        q.curves[idx[i]].t.push_back(e.t - t0);
        q.curves[idx[i]].cpe.push_back(runs[i]->cpe(e.ref));
      }
    } else if (started) {
      for (std::size_t i = 0; i < idx.size(); ++i) qc_imu(*runs[i], comp[i], e);
    }
  }
  if (!started)
    throw InputError(dir.string(), 0, "",
                     "no reference epoch at or after the QC's start (" + (from_s ? number_text(*from_s) + " s" : std::string("the first epoch")) +
                         "): the reference or imu.csv ends before it; give an earlier start or check that the "
                         "recording's files are complete");
  // Started, but not one epoch after T0 with IMU data: nothing was navigated. Never a ΔS of 0 m
  // (issue 56: "final ΔS 0 m" read as perfect).
  if (q.curves[idx[0]].t.empty())
    throw InputError(dir.string(), 0, "",
                     "no data after the QC's start T0 = " + number_text(t0) +
                         " s: the reference or imu.csv ends there, so nothing was navigated and there is no ΔS to "
                         "report" + (from_s ? " (the start is the end of the sets' fit window: they were fitted up to the end "
                                              "of the recording; give --from T for an in-sample QC from an earlier T)"
                                            : std::string()));
  if (st.rows_with_temperature() > 0) q.has_temperature = true;
}
}  // namespace

QcOutcome run_qc(const fs::path& dir, const std::vector<QcSet>& sets, std::optional<double> from_s, double horizon_s,
                 std::shared_ptr<const SharedReference> shared) {
  QcOutcome q;
  q.horizon_s = horizon_s;
  for (const QcSet& s : sets) q.curves.push_back(QcCurve{s.name, {}, {}});
  for (const auto& g : time_offset_groups(sets)) run_qc_group(dir, sets, g, from_s, horizon_s, q, shared);
  if (!q.curves.empty() && !q.curves[0].t.empty()) q.horizon_s = std::min(horizon_s, q.curves[0].t.back());
  return q;
}

namespace {
// ΔS(t) for plotting: the first epoch at or after every multiple of the step (1 s, or longer so
// that no curve exceeds kMaxSeriesPoints), and always the last epoch; t to 1 ms, ΔS to 0.1 mm.
nlohmann::json cpe_series(const QcCurve& c) {
  constexpr double kMaxSeriesPoints = 3600;
  nlohmann::json t = nlohmann::json::array(), v = nlohmann::json::array();
  if (!c.t.empty()) {
    const double step = std::max(1.0, c.t.back() / kMaxSeriesPoints);
    double next = 0;
    for (std::size_t k = 0; k < c.t.size(); ++k) {
      if (c.t[k] < next - 1e-9 && k + 1 < c.t.size()) continue;
      t.push_back(std::round(c.t[k] * 1e3) / 1e3);
      v.push_back(std::round(c.cpe[k] * 1e4) / 1e4);
      next = (std::floor(c.t[k] / step + 1e-9) + 1) * step;
    }
  }
  return {{"t_s", t}, {"cpe_m", v}};
}
}  // namespace

nlohmann::json qc_json(const QcOutcome& q) {
  nlohmann::json j;
  j["from_s"] = q.from_s;
  j["horizon_s"] = q.horizon_s;
  j["sets"] = nlohmann::json::array();
  for (const QcCurve& c : q.curves) {
    nlohmann::json s;
    s["name"] = c.name;
    // No epoch navigated: no figure (null), never 0 m.
    double mx = 0;
    for (double v : c.cpe) mx = std::max(mx, v);
    s["final_cpe_m"] = c.cpe.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.cpe.back());
    s["max_cpe_m"] = c.cpe.empty() ? nlohmann::json(nullptr) : nlohmann::json(mx);
    nlohmann::json at = nlohmann::json::object();
    for (double mark : {10.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1200.0, 1800.0, 3600.0}) {
      if (c.t.empty() || mark > c.t.back() + 1e-6) continue;
      // ΔS at the first epoch at or after the mark.
      for (std::size_t k = 0; k < c.t.size(); ++k)
        if (c.t[k] >= mark - 1e-6) {
          char key[32];
          std::snprintf(key, sizeof key, "%g", mark);
          at[key] = c.cpe[k];
          break;
        }
    }
    s["cpe_m_at"] = at;
    s["cpe_series"] = cpe_series(c);
    j["sets"].push_back(s);
  }
  return j;
}

std::string metres_or_no_data(const nlohmann::json& v) {
  if (!v.is_number()) return "no data";
  std::ostringstream os;
  os.precision(4);
  os << v.get<double>() << " m";
  return os.str();
}

void qc_plot(const QcOutcome& q, const fs::path& png, const std::string& title) {
  const fs::path tmp = fs::temp_directory_path() / ("calbench-qc-" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  std::ofstream gp(tmp / "plot.gp");
  gp << "set terminal pngcairo size 1000,600\nset output '" << png.string() << "'\n"
     << "set title \"" << title << "\"\nset xlabel 'time since T0 = " << q.from_s << " s [s]'\n"
     << "set ylabel 'circular position error {/Symbol D}S [m] (eq 39)'\nset grid\nset key top left\nplot ";
  for (std::size_t i = 0; i < q.curves.size(); ++i) {
    const fs::path dat = tmp / ("set" + std::to_string(i) + ".dat");
    std::ofstream d(dat);
    for (std::size_t k = 0; k < q.curves[i].t.size(); ++k) d << q.curves[i].t[k] << ' ' << q.curves[i].cpe[k] << '\n';
    gp << (i ? ", " : "") << "'" << dat.string() << "' using 1:2 with lines lw 2 title '" << q.curves[i].name << "'";
  }
  gp << "\n";
  gp.close();
  const std::string cmd = "gnuplot '" + (tmp / "plot.gp").string() + "' 2>&1";
  const int rc = std::system(cmd.c_str());
  fs::remove_all(tmp);
  if (rc != 0) throw std::runtime_error("gnuplot failed (is gnuplot installed?) writing " + png.string());
}

}  // namespace calbench
