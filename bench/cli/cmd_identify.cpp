// calbench identify INPUT [--column NAME ...] [--max-lag S] [--json] [--plot OUT.png] [--out MODELS.json]
// Identification of sensor-drift models (paper section IV, eqs 16–38; issue 6): correlation
// function, the paper's log-linear estimates, NLS fits with evidence-based structure choice,
// shaping filters, Allan deviation and noise terms. See docs/identification.md.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <sstream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/csv.hpp"
#include "bench/io/drift_models_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/recording.hpp"
#include "bench/report/gnuplot.hpp"
#include "calibration/identification/allan.hpp"
#include "calibration/identification/correlation_fit.hpp"
#include "calibration/identification/shaping_filter.hpp"
#include "common/units.hpp"

namespace calbench::cli {
namespace {

namespace fs = std::filesystem;
namespace id = calbench::identification;
using nlohmann::json;

struct IdentifyArgs {
  std::string input, plot, out;
  std::vector<std::string> columns;
  double max_lag_s = 0;
  double from_s = -1e300;  // CSV rows before this time are skipped
  std::size_t decimate = 1;
  bool json_out = false;
  bool no_allan = false;
};

enum class Quantity { gyro, accel, other };

struct Series {
  std::string name;
  Quantity q = Quantity::other;
  int axis = -1;  // 0,1,2 for recording columns and in-motion series drift columns
  double si_per_unit = 1;  // column value × si_per_unit = SI (in-motion series: °/h, mg)
  std::string column_unit;  // the column's own unit when it was converted
  std::vector<double> x;   // SI
};

struct Loaded {
  bool inmotion_series = false;  // a fit drive --series file
  std::string file;  // the file the rows came from (for messages)
  double dt = 0;
  std::vector<Series> series;
};

constexpr std::size_t kMinSamples = 50;

Quantity quantity_of(const std::string& name) {
  auto ends = [&](const char* s) {
    const std::string e(s);
    return name.size() >= e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
  };
  if (ends("_rad_s")) return Quantity::gyro;
  if (ends("_m_s2")) return Quantity::accel;
  return Quantity::other;
}

// Check one time step against the nominal step; a gap or a jump is an InputError at that line.
void check_step(const std::string& file, std::size_t line, double t_prev, double t, double dt_nom,
                double tol) {
  const double d = t - t_prev;
  if (std::abs(d - dt_nom) > tol * dt_nom) {
    std::ostringstream m;
    m.precision(9);
    m << "time step " << d << " s where the series has " << dt_nom << " s ("
      << (d > dt_nom ? "gap: missing samples?" : "irregular sampling")
      << "); identify needs a constant step";
    throw InputError(file, line, "t_s", m.str());
  }
}

// The in-motion series of `fit drive --series` (columns gyro_bias_x_dph …): by default its total
// drift columns gyro_total_{x,y,z}_dph and accel_total_{x,y,z}_mg (constant part + in-run state per
// axis, the process the paper identifies, eq 25 on the estimated drift), converted to SI. A series
// written before those columns existed has them made as gyro_bias_* + gyro_drift_*.
const char* kAxes = "xyz";
std::string total_part(const std::string& total, const char* part) {
  std::string n = total;
  n.replace(n.find("_total_"), 7, std::string("_") + part + "_");
  return n;
}
bool is_inmotion_series(const std::vector<std::string>& header) {
  auto has = [&](const std::string& n) { return std::find(header.begin(), header.end(), n) != header.end(); };
  return has("gyro_total_x_dph") || (has("gyro_bias_x_dph") && has("gyro_drift_x_dph"));
}

Loaded load_csv(const IdentifyArgs& a) {
  Loaded L;
  L.file = a.input;
  CsvReader r(a.input);
  L.inmotion_series = is_inmotion_series(r.header());
  const int t = r.require("t_s");
  r.set_time_slot(t);
  std::vector<std::string> names = a.columns;
  const std::vector<std::string>& header = r.header();
  auto in_header = [&](const std::string& n) { return std::find(header.begin(), header.end(), n) != header.end(); };
  if (names.empty()) {
    if (is_inmotion_series(header)) {
      for (const char* s : {"gyro", "accel"})
        for (int i = 0; i < 3; ++i)
          names.push_back(std::string(s) + "_total_" + kAxes[i] + (s[0] == 'g' ? "_dph" : "_mg"));
    } else {
      for (const auto& h : header)
        if (h != "t_s") names.push_back(h);
    }
  }
  if (names.empty()) throw InputError(a.input, 1, "", "no value column besides t_s");
  // Each series is the sum of one or two columns (a total made from its parts).
  std::vector<std::vector<int>> slots;
  for (const auto& n : names) {
    std::vector<int> sl;
    if (!in_header(n) && n.find("_total_") != std::string::npos && column_sensor(n) &&
        in_header(total_part(n, "bias")) && in_header(total_part(n, "drift"))) {
      sl.push_back(r.require(total_part(n, "bias")));
      sl.push_back(r.require(total_part(n, "drift")));
    } else {
      sl.push_back(r.require(n));
    }
    slots.push_back(sl);
    Series s;
    s.name = n;
    s.q = quantity_of(n);
    if (const auto cs = column_sensor(n)) {
      s.q = cs->sensor == "gyro" ? Quantity::gyro : Quantity::accel;
      s.axis = cs->axis;
      s.si_per_unit = cs->si_per_unit;
      if (cs->si_per_unit != 1.0) s.column_unit = cs->unit;
    }
    L.series.push_back(std::move(s));
  }
  double t0 = 0, t_prev = 0, dt_nom = 0;
  std::size_t rows = 0;
  while (r.next()) {
    const double tv = r.value(t);
    if (tv < a.from_s) continue;
    if (rows == 0) t0 = tv;
    if (rows == 1) dt_nom = tv - t0;
    if (rows >= 2) check_step(a.input, r.line(), t_prev, tv, dt_nom, 1e-3);
    t_prev = tv;
    for (std::size_t k = 0; k < slots.size(); ++k) {
      double v = 0;
      for (int sl : slots[k]) v += r.value(sl);
      L.series[k].x.push_back(v * L.series[k].si_per_unit);
    }
    ++rows;
  }
  if (rows < kMinSamples)
    throw InputError(a.input, 0, "", "too short: " + std::to_string(rows) + " rows, need at least " +
                                         std::to_string(kMinSamples));
  L.dt = (t_prev - t0) / static_cast<double>(rows - 1);
  return L;
}

Loaded load_recording(const IdentifyArgs& a) {
  Loaded L;
  const fs::path dir(a.input);
  const RecordingMeta meta = read_meta(dir);
  const fs::path imu = dir / "imu.csv";
  ImuReader r(imu, meta.imu_rate_hz);  // imu.csv, or the imu dataset of recording.h5
  L.file = r.path();
  const char* names[6] = {"gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"};
  std::vector<int> pick;
  if (a.columns.empty()) {
    for (int k = 0; k < 6; ++k) pick.push_back(k);
  } else {
    for (const auto& c : a.columns) {
      auto it = std::find_if(std::begin(names), std::end(names), [&](const char* n) { return c == n; });
      if (it == std::end(names))
        throw InputError("--column", 0, c,
                         "unknown column for a recording (use gx_rad_s … az_m_s2; increments are "
                         "converted to these rates)");
      pick.push_back(static_cast<int>(it - std::begin(names)));
    }
  }
  for (int k : pick) {
    Series s;
    s.name = names[k];
    s.q = k < 3 ? Quantity::gyro : Quantity::accel;
    s.axis = k % 3;
    L.series.push_back(std::move(s));
  }
  const double dt_nom = 1.0 / meta.imu_rate_hz;
  ImuRecord rec;
  double t0 = 0, t_prev = 0;
  std::size_t rows = 0;
  while (r.next(rec)) {
    if (rows == 0) t0 = rec.t;
    // Logger clocks jitter: ±10 % of the nominal step is accepted, a missing sample is not.
    if (rows >= 1) check_step(L.file, r.line(), t_prev, rec.t, dt_nom, 0.1);
    t_prev = rec.t;
    const double inv = r.form() == ImuForm::increments ? 1.0 / rec.dt : 1.0;
    for (std::size_t j = 0; j < pick.size(); ++j) {
      const int k = pick[j];
      L.series[j].x.push_back((k < 3 ? rec.gyro(k) : rec.accel(k - 3)) * inv);
    }
    ++rows;
  }
  if (rows < kMinSamples)
    throw InputError(L.file, 0, "", "too short: " + std::to_string(rows) + " rows, need at least " +
                                        std::to_string(kMinSamples));
  L.dt = (t_prev - t0) / static_cast<double>(rows - 1);
  return L;
}

// Display units of the Allan terms (SI inside; the conventional unit beside it).
struct TermUnit {
  const char* si;
  const char* unit;
  double per_si;  // unit value = SI value × per_si
};
struct Units {
  const char* signal;
  TermUnit Q, N, B, K, R;
};
Units units_for(Quantity q) {
  using namespace calbench::units;
  const double deg = 1.0 / kDeg;
  switch (q) {
    case Quantity::gyro:
      return {"rad/s",
              {"rad", "arcsec", deg * 3600.0},
              {"rad/s^0.5", "deg/h^0.5", deg * kSqrtHour},
              {"rad/s", "deg/h", deg * 3600.0},
              {"rad/s^1.5", "deg/h/h^0.5", deg * 3600.0 * kSqrtHour},
              {"rad/s^2", "deg/h^2", deg * 3600.0 * 3600.0}};
    case Quantity::accel:
      return {"m/s^2",
              {"m/s", "m/s", 1.0},
              {"m/s^1.5", "m/s/h^0.5", kSqrtHour},
              {"m/s^2", "mg", 1.0 / kMilliG},
              {"m/s^2.5", "mg/h^0.5", kSqrtHour / kMilliG},
              {"m/s^3", "mg/h", 3600.0 / kMilliG}};
    default:
      return {"signal",
              {"signal*s", "signal*s", 1.0},
              {"signal*s^0.5", "signal*s^0.5", 1.0},
              {"signal", "signal", 1.0},
              {"signal/s^0.5", "signal/s^0.5", 1.0},
              {"signal/s", "signal/s", 1.0}};
  }
}

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json term_json(const id::AllanTerm& t, const TermUnit& u, const char* definition) {
  return {{"present", t.present}, {"si", num(t.value)}, {"se_si", num(t.se)}, {"si_unit", u.si},
          {"value", num(t.value * u.per_si)}, {"se", num(t.se * u.per_si)}, {"unit", u.unit},
          {"definition", definition}};
}

json allan_json(const std::vector<id::AllanPoint>& pts, const id::AllanFit& f, Quantity q) {
  const Units u = units_for(q);
  json points = json::array();
  for (const auto& p : pts)
    points.push_back({{"tau_s", p.tau}, {"m", p.m}, {"adev", p.adev}, {"lo", p.lo}, {"hi", p.hi}, {"edf", p.edf}});
  json j;
  j["signal_unit"] = u.signal;
  j["interval"] = "68.3 % (chi-square, equivalent degrees of freedom of the overlapping estimator)";
  j["points"] = std::move(points);
  j["terms"] = {
      {"quantisation", term_json(f.Q, u.Q, "Q: AVAR = 3 Q^2/tau^2")},
      {"random_walk", term_json(f.N, u.N, q == Quantity::accel ? "N (velocity random walk): AVAR = N^2/tau"
                                                                : "N (angle random walk): AVAR = N^2/tau")},
      {"bias_instability", term_json(f.B, u.B, "B: AVAR = (2 ln2/pi) B^2 (flicker floor; sigma_min = 0.664 B)")},
      {"rate_random_walk", term_json(f.K, u.K, "K: AVAR = K^2 tau/3")},
      {"rate_ramp", term_json(f.R, u.R, "R: AVAR = R^2 tau^2/2")}};
  j["chi2"] = f.chi2;
  j["points_fitted"] = f.points;
  j["preferred"] = f.gm_present && f.gm_chi2 < f.chi2 ? "gauss_markov" : "power_law";
  j["adev_min"] = {{"si", f.adev_min}, {"tau_s", f.tau_min},
                   {"bias_instability_from_min_si", f.B_from_min},
                   {"bias_instability_from_min", f.B_from_min * u.B.per_si}, {"unit", u.B.unit}};
  j["gauss_markov"] = {{"present", f.gm_present},
                       {"sigma_si", num(f.gm_sigma)}, {"sigma", num(f.gm_sigma * u.B.per_si)}, {"sigma_unit", u.B.unit},
                       {"T_s", num(f.gm_T)},
                       {"random_walk", term_json(f.gm_N, u.N, "white level of the GM alternative")},
                       {"rate_random_walk", term_json(f.gm_K, u.K, "RRW level of the GM alternative")},
                       {"chi2", f.gm_chi2},
                       {"definition", "AVAR = (s^2 T^2/tau^2)(2 tau/T - 3 + 4 e^(-tau/T) - e^(-2 tau/T)), "
                                      "Q, N, K, R fitted with it in place of B"}};
  return j;
}

json nls_json(const id::NlsFit& f) {
  return {{"converged", f.converged}, {"usable", f.usable}, {"iterations", f.iterations},
          {"sigma", f.sigma}, {"alpha", f.alpha}, {"beta", f.beta}, {"T_s", num(1.0 / f.alpha)},
          {"se", {{"sigma", num(f.se_sigma)}, {"alpha", num(f.se_alpha)}, {"beta", num(f.se_beta)},
                  {"T_s", num(f.se_alpha / (f.alpha * f.alpha))}}},
          {"se_iid", {{"sigma", num(f.se_sigma_iid)}, {"alpha", num(f.se_alpha_iid)}, {"beta", num(f.se_beta_iid)}}},
          {"rss", f.rss}, {"lags", f.lags}, {"aic", f.aic}, {"bic", f.bic}, {"white_var", f.white_var}};
}

json shaping_json(const id::DriftModel& m, double dt, Quantity q, int axis) {
  const std::string sensor = q == Quantity::gyro ? "gyro" : q == Quantity::accel ? "accel" : "";
  return drift_model_json(m, dt, sensor, axis, units_for(q).signal);
}

struct Result {
  Series* s = nullptr;
  id::Identification ident;
  std::vector<id::AllanPoint> allan;
  id::AllanFit allan_fit;
  double dt_corr = 0;
};

// ------------------------------------------------------------------------------------- plots
std::string quote(const std::string& s) {
  std::string o = "'";
  for (char c : s) o += c == '\'' ? std::string("''") : std::string(1, c);
  return o + "'";
}

// The plots go through the report's gnuplot runner (bench/report/gnuplot.hpp): data files by name
// in its temporary folder, the PNGs written straight to their absolute paths.
void write_plots(const std::vector<Result>& res, const std::string& out_png) {
  std::map<std::string, std::string> files;
  const std::size_t n = res.size();
  const int cols = n <= 1 ? 1 : n <= 4 ? 2 : 3;
  const int rows = static_cast<int>((n + static_cast<std::size_t>(cols) - 1) / static_cast<std::size_t>(cols));
  const fs::path out = fs::absolute(out_png);
  fs::path allan_png = out;
  allan_png.replace_filename(out.stem().string() + "-allan" + out.extension().string());
  std::ostringstream gp;
  gp << "set terminal pngcairo size " << 640 * cols << "," << 420 * rows << " font ',9'\n";
  gp << "set output " << quote(out.string()) << "\nset multiplot layout " << rows << "," << cols << "\n";
  gp << "set grid\nset xlabel 'tau, s'\nset ylabel 'normalised correlation'\nset key top right\n";
  for (std::size_t i = 0; i < n; ++i) {
    const auto& r = res[i];
    const auto& I = r.ident;
    const std::string data = "corr" + std::to_string(i) + ".dat";
    std::ostringstream f;
    f.precision(10);
    const double K0 = I.K[0];
    const auto best = I.best().model();
    for (std::size_t j = 0; j < I.K.size(); ++j) {
      const double tau = static_cast<double>(j) * I.dt;
      const double ra1 = I.paper_exp.valid ? std::exp(-I.paper_exp.alpha * tau) : NAN;
      const double ra2 = I.paper_cos.valid ? std::exp(-I.paper_cos.alpha * tau) * std::cos(I.paper_cos.beta * tau) : NAN;
      const double rm = best.correlation(tau) / K0;
      f << tau << ' ' << I.K[j] / K0 << ' ' << ra1 << ' ' << ra2 << ' ' << rm << '\n';
    }
    gp << "set title " << quote(r.s->name + ": r_m = " + id::drift_model_name(I.chosen) + " (NLS)") << " noenhanced\n";
    files[data] = f.str();
    gp << "plot " << quote(data) << " u 1:2 w l lw 1 lc rgb '#777777' t 'r_e experimental', "
       << "'' u 1:3 w l lw 2 dt 2 lc rgb '#1f77b4' t 'ra_1 exponential (paper)', "
       << "'' u 1:4 w l lw 2 dt 3 lc rgb '#2ca02c' t 'ra_2 exp-cosine (paper)', "
       << "'' u 1:5 w l lw 2 lc rgb '#d62728' t 'r_m model in use', 0 w l lc rgb 'black' notitle\n";
  }
  gp << "unset multiplot\n";
  bool any_allan = false;
  for (const auto& r : res) any_allan = any_allan || !r.allan.empty();
  if (any_allan) {
    gp << "set output " << quote(allan_png.string()) << "\nset multiplot layout " << rows << "," << cols << "\n";
    gp << "set logscale xy\nset format y '%g'\nset xlabel 'tau, s'\nset ylabel 'Allan deviation (SI)'\n";
    for (std::size_t i = 0; i < n; ++i) {
      const auto& r = res[i];
      if (r.allan.empty()) continue;
      const std::string data = "allan" + std::to_string(i) + ".dat";
      std::ostringstream f;
      f.precision(10);
      const auto& F = r.allan_fit;
      for (const auto& p : r.allan) {
        const double model = id::avar_quantisation(F.Q.value, p.tau) + id::avar_white(F.N.value, p.tau) +
                             id::avar_bias_instability(F.B.value) + id::avar_rate_random_walk(F.K.value, p.tau) +
                             id::avar_rate_ramp(F.R.value, p.tau);
        const double gm = id::avar_quantisation(F.Q.value, p.tau) + id::avar_white(F.gm_N.value, p.tau) +
                          id::avar_gauss_markov(F.gm_sigma, F.gm_T, p.tau) +
                          id::avar_rate_random_walk(F.gm_K.value, p.tau);
        f << p.tau << ' ' << p.adev << ' ' << p.lo << ' ' << p.hi << ' ' << std::sqrt(model) << ' '
          << std::sqrt(gm) << '\n';
      }
      gp << "set title " << quote(r.s->name + " (" + units_for(r.s->q).signal + ")") << " noenhanced\n";
      files[data] = f.str();
      gp << "plot " << quote(data) << " u 1:2:3:4 w yerrorbars pt 7 ps 0.6 lc rgb '#1f77b4' t 'overlapping ADEV, 68% CI', "
         << "'' u 1:5 w l lw 2 lc rgb '#d62728' t 'fit Q+N+B+K+R', "
         << "'' u 1:6 w l lw 2 dt 2 lc rgb '#2ca02c' t 'fit with Gauss-Markov (T = " << F.gm_T << " s)'\n";
    }
    gp << "unset multiplot\n";
  }
  report::run_gnuplot(gp.str(), files, "");
}

// ---------------------------------------------------------------------------------------- run
std::vector<double> block_average(const std::vector<double>& x, std::size_t m) {
  if (m <= 1) return x;
  std::vector<double> y(x.size() / m);
  for (std::size_t i = 0; i < y.size(); ++i) {
    double s = 0;
    for (std::size_t k = 0; k < m; ++k) s += x[i * m + k];
    y[i] = s / static_cast<double>(m);
  }
  return y;
}

void run_identify(const IdentifyArgs& a) {
  for (const std::string* f : {&a.out, &a.plot})  // before the work: a wrong path costs nothing
    if (!f->empty()) check_output_path(*f);
  if (fs::is_directory(a.input) && a.from_s > -1e299)  // documented for CSV input; not silently ignored
    throw InputError("--from", 0, "", a.input + " is a recording folder: --from applies to CSV input (e.g. a fit drive --series)");
  Loaded L = fs::is_directory(a.input) ? load_recording(a) : load_csv(a);
  std::vector<Result> results;
  for (auto& s : L.series) {
    Result r;
    r.s = &s;
    const std::vector<double> xc = block_average(s.x, a.decimate);
    r.dt_corr = L.dt * static_cast<double>(std::max<std::size_t>(a.decimate, 1));
    if (xc.size() < kMinSamples)
      throw InputError(L.file, 0, s.name, "too short after --decimate: " + std::to_string(xc.size()) +
                                              " samples, need at least " + std::to_string(kMinSamples));
    // Constant column: clear error before any statistics.
    const auto [mn, mx] = std::minmax_element(s.x.begin(), s.x.end());
    if (*mn == *mx) throw InputError(L.file, 0, s.name, "constant column (zero variance): nothing to identify");
    id::IdentifyOptions opt;
    opt.max_lag_s = a.max_lag_s;
    try {
      r.ident = id::identify(xc, r.dt_corr, opt);
    } catch (const std::invalid_argument& e) {
      throw InputError(L.file, 0, s.name, e.what());
    }
    if (!a.no_allan) {
      r.allan = id::allan_deviation(s.x, L.dt);
      r.allan_fit = id::fit_allan(r.allan);
    }
    results.push_back(std::move(r));
  }

  json cols = json::array();
  json models = json::object();
  for (const auto& r : results) {
    const auto& I = r.ident;
    const auto& b = I.best();
    json c;
    c["column"] = r.s->name;
    c["model"] = id::drift_model_name(I.chosen);
    c["sigma"] = b.sigma;
    c["alpha"] = b.alpha;
    c["beta"] = I.chosen == id::DriftModelKind::exponential ? 0.0 : b.beta;
    c["T_s"] = num(1.0 / b.alpha);
    c["se"] = {{"sigma", num(b.se_sigma)}, {"alpha", num(b.se_alpha)}, {"beta", num(b.se_beta)},
               {"T_s", num(b.se_alpha / (b.alpha * b.alpha))}};
    c["unit"] = units_for(r.s->q).signal;
    if (!r.s->column_unit.empty()) c["converted_from"] = r.s->column_unit;  // in-motion series: SI here
    if (r.s->axis >= 0) {
      c["sensor"] = r.s->q == Quantity::gyro ? "gyro" : "accel";
      c["axis"] = r.s->axis;
    }
    c["samples"] = r.s->x.size();
    c["dt_s"] = L.dt;
    c["dt_correlation_s"] = r.dt_corr;
    c["mean"] = I.mean;
    c["white_var"] = b.white_var;
    c["max_lag_s"] = static_cast<double>(I.max_lag) * I.dt;
    c["evidence"] = {{"rule", I.reason},
                     {"sign_change", I.sign_change},
                     {"first_zero_s", I.first_zero_s > 0 ? json(I.first_zero_s) : json(nullptr)},
                     {"aic", {{"exponential", I.exp.aic}, {"exp_cosine", I.cos.aic}}},
                     {"bic", {{"exponential", I.exp.bic}, {"exp_cosine", I.cos.bic}}},
                     {"beta_z", num(I.cos.se_beta > 0 ? I.cos.beta / I.cos.se_beta : 0.0)},
                     {"negative_lobe_z", num(I.cos.min_model_se > 0 ? -I.cos.min_model / I.cos.min_model_se : 0.0)}};
    c["nls"] = {{"exponential", nls_json(I.exp)}, {"exp_cosine", nls_json(I.cos)}};
    c["paper"] = {
        {"exponential", {{"valid", I.paper_exp.valid}, {"sigma", I.paper_exp.sigma}, {"alpha", I.paper_exp.alpha},
                         {"T_s", num(1.0 / I.paper_exp.alpha)}, {"lags_used", I.paper_exp.lags_used},
                         {"equations", "sigma^2 = K(0) (eq 28), alpha from eq 31 over the leading run of K > 0"}}},
        {"exp_cosine", {{"valid", I.paper_cos.valid}, {"sigma", I.paper_cos.sigma}, {"alpha", I.paper_cos.alpha},
                        {"beta", I.paper_cos.beta}, {"T_s", num(1.0 / I.paper_cos.alpha)},
                        {"tau_beta_s", I.paper_cos.tau_beta}, {"lags_used", I.paper_cos.lags_used},
                        {"equations", "beta = 0.5 pi/tau_beta (eq 38), alpha from the formula after eq 38"}}}};
    if (!a.no_allan) c["allan"] = allan_json(r.allan, r.allan_fit, r.s->q);
    c["usable"] = b.usable;
    if (b.usable) {
      id::DriftModel m = b.model();
      if (I.chosen == id::DriftModelKind::exponential) m.beta = 0;
      json sf = shaping_json(m, r.dt_corr, r.s->q, r.s->axis);
      if (!r.s->column_unit.empty()) sf["converted_from"] = r.s->column_unit;
      c["shaping_filter"] = sf;
      models[r.s->name] = sf;
    } else {
      c["shaping_filter"] = nullptr;
    }
    cols.push_back(std::move(c));
  }

  if (!a.out.empty()) {
    json m;
    m["format"] = "calbench-drift-models/1";
    m["source"] = a.input;
    m["noise"] = "unit-intensity continuous white noise xi: E[xi(t) xi(s)] = delta(t - s); drift = H x";
    m["drift_models"] = models;
    write_text_atomic(a.out, m.dump(2) + "\n");
  }
  if (!a.plot.empty()) write_plots(results, a.plot);

  if (a.json_out) {
    json j;
    j["input"] = a.input;
    j["columns"] = std::move(cols);
    print_json(j.dump(2));
    return;
  }
  std::cout << "identify " << a.input << ": " << L.series.front().x.size() << " samples at " << L.dt << " s\n";
  if (L.inmotion_series && a.from_s < -1e299)
    std::cout << "note: an in-motion series; its first tens of seconds are the filter converging, not drift "
                 "(skip them with --from)\n";
  for (const auto& c : cols) {
    if (!c["usable"].get<bool>())
      std::printf("%-12s no usable drift model (no resolvable correlation: white noise, too short, or a trend?)\n",
                  c["column"].get<std::string>().c_str());
    std::printf("%-12s %-11s sigma %.4g ± %.2g  T %.4g ± %.2g s", c["column"].get<std::string>().c_str(),
                c["model"].get<std::string>().c_str(), c["sigma"].get<double>(),
                c["se"]["sigma"].is_null() ? NAN : c["se"]["sigma"].get<double>(),
                c["T_s"].is_null() ? NAN : c["T_s"].get<double>(),
                c["se"]["T_s"].is_null() ? NAN : c["se"]["T_s"].get<double>());
    if (c["model"] == "exp_cosine") std::printf("  beta %.4g rad/s", c["beta"].get<double>());
    const auto& pp = c["paper"][c["model"].get<std::string>()];
    std::printf("   [paper: sigma %.4g T %.4g s]  %s\n", pp["sigma"].get<double>(),
                pp["T_s"].is_null() ? NAN : pp["T_s"].get<double>(), c["unit"].get<std::string>().c_str());
    if (c.contains("allan")) {
      const auto& t = c["allan"]["terms"];
      std::printf("%-12s Allan: N %.4g %s  B %.4g %s  K %.4g %s\n", "", t["random_walk"]["value"].is_null() ? NAN : t["random_walk"]["value"].get<double>(),
                  t["random_walk"]["unit"].get<std::string>().c_str(),
                  t["bias_instability"]["value"].is_null() ? NAN : t["bias_instability"]["value"].get<double>(),
                  t["bias_instability"]["unit"].get<std::string>().c_str(),
                  t["rate_random_walk"]["value"].is_null() ? NAN : t["rate_random_walk"]["value"].get<double>(),
                  t["rate_random_walk"]["unit"].get<std::string>().c_str());
    }
  }
  if (!a.out.empty()) std::cout << "shaping filters written to " << a.out << "\n";
  if (!a.plot.empty()) std::cout << "plot written to " << a.plot << "\n";
}

const bool registered = add_command(40, [](CLI::App& app) {
  auto a = std::make_shared<IdentifyArgs>();
  auto* sub = app.add_subcommand(
      "identify",
      "Identify sensor-drift models (paper section IV): correlation function, exponential / "
      "exponential-cosine fits (paper's log-linear and NLS), shaping filters, Allan deviation");
  sub->add_option("input", a->input,
                  "CSV with a t_s column and value columns at a constant step, or a recording folder "
                  "(imu.csv, or the imu dataset of recording.h5, per axis; increments are divided by dt)")
      ->required()
      ->check(CLI::ExistingPath);
  sub->add_option("--column", a->columns, "columns to identify (default: all value columns)");
  sub->add_option("--max-lag", a->max_lag_s, "maximum lag of the correlation fits, s (default: automatic, 3 T)")
      ->check(finite_positive());
  sub->add_option("--decimate", a->decimate,
                  "block-average this many samples before the correlation analysis (Allan uses the raw samples)")
      ->check(whole_number(1, 1000000));
  sub->add_option("--from", a->from_s,
                  "CSV input: skip rows before this time, s (e.g. the in-motion filter's convergence at the start "
                  "of a fit drive --series)")
      ->check(finite_number());
  sub->add_flag("--no-allan", a->no_allan, "skip the Allan deviation");
  sub->add_flag("--json", a->json_out, "print the result as JSON on stdout");
  sub->add_option("--plot", a->plot, "write a Fig. 3-like PNG here (and OUT-allan.png), with gnuplot")
      ->check(non_empty());
  sub->add_option("--out", a->out, "write the shaping filters (MODELS.json, key drift_models)")
      ->check(non_empty());
  sub->callback([a] { run_identify(*a); });
});

}  // namespace
}  // namespace calbench::cli
