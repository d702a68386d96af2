#include "bench/report/inmotion_section.hpp"

#include "calibration/inmotion/adaptive_noise.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bench/report/gnuplot.hpp"
#include "bench/report/html_parts.hpp"
#include "bench/report/svg_plot.hpp"
#include "calibration/qc/nis_test.hpp"
#include "common/drive_result.hpp"
#include "common/json_parse.hpp"
#include "db/inmotion_import.hpp"

namespace calbench::report {
namespace {
using nlohmann::json;
using namespace calbench::db;

// The stored RESULT.json through its codec (common/drive_result.hpp). The store holds only results
// the codec accepted on import; one it refuses now shows as "not recorded", with the reason.
struct StoredResult {
  DriveResult res;
  std::string error;  // why the codec refused it; empty when read
};
StoredResult read_stored_result(const InMotionRun& r) {
  StoredResult out;
  const std::string where = "in-motion run " + std::to_string(r.id);
  try {
    out.res = drive_result_from_json(parse_json_text(r.result_json, where), where);
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  return out;
}
std::string row(const std::string& head, const std::string& cell) {
  return "<tr><th class=\"l\">" + head + "</th><td class=\"l\">" + cell + "</td></tr>";
}

// ---- the run: recording, digests, reference, window, mounting ----
std::string run_table(const InMotionRun& r, const DriveResult& res) {
  std::string dig = "imu.csv " + digest(r.recording_sha256);
  for (const auto& [d, file] : {std::pair{&res.recording.sha256_reference, "reference.csv"}, std::pair{&res.recording.sha256_meta, "meta.json"}})
    if (*d) dig += "<br>" + std::string(file) + " " + digest(**d);
  if (!r.recording_digest.empty()) dig += "<br>all its files " + digest(r.recording_digest);  // as for bench runs
  std::string window = "not recorded";
  if (res.window_s) window = num(res.window_s->first) + " – " + num(res.window_s->second) + " s";
  std::string mount;
  for (std::size_t i = 0; i < 3; ++i)
    mount += (i ? " / " : "") + pm(r.mounting_rpy_deg[i], r.mounting_sigma_deg[i], 1.0);
  return "<table class=\"run\">" + row("drive recording", html_escape(r.recording_uri.empty() ? r.recording_path : r.recording_uri)) +
         row("SHA-256 of the files", dig) +
         row("reference system",
             r.reference_system.empty()
                 ? "<span class=\"muted\">not recorded in this result (calbench fit drive writes \"reference_system\" "
                   "since issue 16)</span>"
                 : html_escape(r.reference_system)) +
         row("fit window", window + " · observations " + html_escape(res.observations.value_or("not recorded")) +
                               (res.smoothed.value_or(false) ? " · RTS-smoothed" : "")) +
         row("mounting roll / pitch / yaw [°]", mount) + "</table>\n";
}

// ---- which stage determined each coefficient ----
std::string stage_table(const InMotionRun& r, const CoefficientSetRecord& set, const std::vector<CoefficientSetRecord>& sets,
                        const StoredResult& stored) {
  const DriveResult& res = stored.res;
  const CoefficientSetRecord* parent = nullptr;
  for (const auto& s : sets)
    if (set.parent_id && s.id == *set.parent_id) parent = &s;
  const std::optional<DeterminedBy>& det = res.determined_by;
  std::string note;
  if (!stored.error.empty())
    note = "Stage not shown: this stored result is malformed: " + stored.error;
  else if (!det)
    note = "Stage not recorded: this in-motion result has no \"determined_by\" (results of calbench fit drive before "
           "issue 16 do not say which stage determined each coefficient).";
  std::ostringstream h;
  // The parent is whatever set the fit started from: a bench set, or an earlier combined set.
  const std::string parent_name = parent ? std::string(to_string(parent->source)) + " (set " + std::to_string(parent->id) + ")" : "";
  h << "<h4>Coefficients: " << (parent ? parent_name + " → " : std::string())
    << to_string(set.source) << " (set " << set.id << "), value ± 1σ, and the stage that determined each</h4>\n";
  if (det && !det->rule.empty()) h << "<p class=\"note\">Rule: " << html_escape(det->rule) << "</p>\n";
  if (res.priors.is_object())
    h << "<p class=\"note\">Drive-filter priors: " << html_escape(res.priors_mode.empty() ? "mode not stated" : res.priors_mode)
      << ", device class " << html_escape(res.priors_device_class.empty() ? "not stated" : res.priors_device_class) << ".</p>\n";
  if (!note.empty()) h << "<p class=\"note\">" << html_escape(note) << "</p>\n";
  if (!parent)
    h << "<p class=\"note\">No parent set: the fit ran on raw data (or on a set that is not in the database); the bench "
         "column is empty.</p>\n";
  h << "<table class=\"stages\" id=\"stages-" << r.id << "\"><tr><th class=\"l\">coefficient</th><th class=\"l\">unit</th><th>"
    << (parent ? parent_name : std::string("parent")) << "</th><th>" << to_string(set.source) << " (set "
    << set.id << ")</th><th>change</th><th>drive prior σ</th><th>drive posterior σ</th><th>drive share</th>"
       "<th class=\"l\">stage</th></tr>\n";
  for (const auto& name : coefficient_names()) {
    std::string unit;
    double k;
    coefficient_unit(name, unit, k);
    const double v = coefficient_value(set.errors, name), sg = coefficient_sigma(set.errors, name);
    h << "<tr><td class=\"l\">" << name << "</td><td class=\"l\">" << unit << "</td><td>";
    if (parent) {
      const double pv = coefficient_value(parent->errors, name);
      h << pm(pv, coefficient_sigma(parent->errors, name), k) << "</td><td>" << pm(v, sg, k) << "</td><td>" << num((v - pv) * k, 3);
    } else {
      h << "–</td><td>" << pm(v, sg, k) << "</td><td>–";
    }
    const CoefficientStage* st = nullptr;
    if (det) {
      auto it = det->coefficients.find(name);
      if (it != det->coefficients.end()) st = &it->second;
    }
    const auto opt = [&](const std::optional<double>& x, double scale) { return x ? num(*x * scale, 2) : std::string("–"); };
    const std::string stage = st ? st->stage : "–";
    h << "</td><td>" << (st ? opt(st->prior_sigma, k) : "–") << "</td><td>" << (st ? opt(st->posterior_sigma, k) : "–")
      << "</td><td>" << (st && st->drive_share ? num(*st->drive_share * 100, 3) + " %" : std::string("–"))
      << "</td><td class=\"l stage-" << (st ? stage : "none") << "\" data-stage=\"" << html_escape(stage) << "\">"
      << html_escape(st ? stage : det ? "not stated in determined_by" : "–") << "</td></tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

// ---- ΔS(t) ----
struct CpeData {
  std::vector<PlotCurve> curves;
  bool from_marks = false;
};

double figure(const std::optional<double>& v) { return v.value_or(std::nan("")); }

CpeData cpe_curves(const CpeQc& qc) {
  CpeData d;
  for (const auto& s : qc.sets) {  // the series of issue 16
    PlotCurve c{s.name.value_or("set"), s.series_t_s, s.series_cpe_m};
    if (c.x.size() == c.y.size() && c.x.size() >= 2) d.curves.push_back(std::move(c));
  }
  if (d.curves.empty() && qc.series_t_s) {  // {"t_s": [...], NAME: [...]}
    for (const auto& [name, v] : qc.series) {
      PlotCurve c{name, *qc.series_t_s, v};
      if (c.x.size() != c.y.size() || c.x.size() < 2) continue;
      d.curves.push_back(std::move(c));
    }
  }
  if (d.curves.empty() && !qc.sets.empty()) {  // older results: the marks only
    d.from_marks = true;
    const double horizon = figure(qc.horizon_s);
    for (const auto& s : qc.sets) {
      std::vector<std::pair<double, double>> pts;
      for (const auto& [mark, v] : s.cpe_m_at) {
        char* end = nullptr;
        const double t = std::strtod(mark.c_str(), &end);
        if (end && *end == 0 && !std::isnan(v)) pts.emplace_back(t, v);
      }
      const double fin = figure(s.final_cpe_m);
      if (std::isfinite(horizon) && std::isfinite(fin)) pts.emplace_back(horizon, fin);
      std::sort(pts.begin(), pts.end());
      PlotCurve c{s.name.value_or("set"), {}, {}};
      for (const auto& [t, v] : pts) {
        c.x.push_back(t);
        c.y.push_back(v);
      }
      if (c.x.size() >= 2) d.curves.push_back(std::move(c));
    }
  }
  return d;
}

// ΔS at the marks of each set, its final and largest value.
std::string cpe_marks_table(const CpeQc& qc, const InMotionRun& r) {
  if (qc.sets.empty()) return "";
  std::map<double, std::string> marks;  // t → key
  for (const auto& s : qc.sets)
    for (const auto& [mark, v] : s.cpe_m_at) {
      char* end = nullptr;
      const double t = std::strtod(mark.c_str(), &end);
      if (end && *end == 0) marks[t] = mark;
    }
  std::ostringstream h;
  h << "<table class=\"cpe-marks\" id=\"cpe-marks-" << r.id << "\"><tr><th class=\"l\">set</th>";
  for (const auto& [t, key] : marks) h << "<th>ΔS at " << num(t) << " s [m]</th>";
  h << "<th>final ΔS (at " << num(figure(qc.horizon_s)) << " s) [m]</th><th>largest ΔS [m]</th></tr>\n";
  for (const auto& s : qc.sets) {
    h << "<tr><td class=\"l\">" << html_escape(s.name.value_or("set")) << "</td>";
    for (const auto& [t, key] : marks) {
      const auto v = s.cpe_m_at.find(key);
      h << "<td>" << num(v == s.cpe_m_at.end() ? std::nan("") : v->second) << "</td>";
    }
    h << "<td>" << num(figure(s.final_cpe_m)) << "</td><td>" << num(figure(s.max_cpe_m)) << "</td></tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

std::string cpe_part(const CpeQc& qc, const DriveResult& res, const InMotionRun& r) {
  std::ostringstream h;
  h << "<h4>Circular position error ΔS(t), inertial-only navigation (eq 39)</h4>\n";
  const double from = figure(qc.from_s), horizon = figure(qc.horizon_s);
  std::string ctx = "Inertial-only navigation with each set";
  if (std::isfinite(from)) ctx += " from T0 = " + num(from) + " s";
  if (std::isfinite(horizon)) ctx += " for " + num(horizon) + " s";
  ctx += "; data: " + qc.sample.value_or("not stated whether in- or out-of-sample");
  if (res.window_s) ctx += "; the fit used " + num(res.window_s->first) + " – " + num(res.window_s->second) + " s";
  h << "<p class=\"note\">" << html_escape(ctx) << ".</p>\n";
  const CpeData d = cpe_curves(qc);
  if (d.curves.empty()) return h.str() + "<p class=\"muted\">no ΔS data in this run's QC</p>\n";
  if (d.from_marks)
    h << "<p class=\"note\">This result carries ΔS only at a few marks and at the horizon (written before issue 16): "
         "the points are joined by straight lines, not the curve.</p>\n";
  PlotSpec p;
  p.x_label = "time since T0" + (std::isfinite(from) ? " = " + num(from) + " s" : std::string()) + " [s]";
  p.y_label = "ΔS [m]";
  p.x_min = 0;
  p.x_max = std::isfinite(horizon) ? horizon : 0;
  for (const auto& c : d.curves)
    for (double x : c.x)
      if (std::isfinite(x)) p.x_max = std::max(p.x_max, x);
  p.css_class = "cpe";
  p.title = "ΔS, linear scale";
  h << "<div class=\"plots\">" << svg_line_plot(d.curves, p);
  p.log_y = true;
  p.title = "ΔS, logarithmic scale";
  h << svg_line_plot(d.curves, p) << "</div>\n" << cpe_marks_table(qc, r);
  return h.str();
}

// ---- simulated GNSS outages (GNSS-only drives, qc.outages) ----
double figure(const std::map<std::string, double>& by_set, const std::string& name) {
  const auto it = by_set.find(name);
  return it == by_set.end() ? std::nan("") : it->second;
}

std::string outage_part(const std::optional<OutageQc>& oq, const InMotionRun& r) {
  if (!oq) return "";
  const OutageQc& o = *oq;
  std::ostringstream h;
  h << "<h4>Simulated GNSS outages, inertial-only navigation (ΔS against the fixes)</h4>\n";
  std::string ctx = "Each outage navigated inertial-only with each set from the aided filter's state at its start (" +
                    o.aided_by.value_or("aiding not stated") + "); error: " + o.error.value_or("not stated") +
                    "; data: " + o.sample.value_or("not stated whether in- or out-of-sample");
  h << "<p class=\"note\">" << html_escape(ctx) << ".</p>\n";
  if (!o.not_placed.empty())
    h << "<p class=\"note\">" << o.not_placed.size() << " requested outage(s) not placed: "
      << html_escape(o.not_placed[0].empty() ? "reason not stated" : o.not_placed[0]) << ".</p>\n";
  if (o.sets.empty() || o.outages.empty()) return h.str() + "<p class=\"muted\">no outage could be placed on this drive</p>\n";
  // Median of the per-outage maxima against the outage length, and each outage's maximum against its start.
  std::vector<PlotCurve> by_length, by_start;
  for (const auto& s : o.sets) {
    PlotCurve c{s.name, {}, {}}, d{s.name, {}, {}};
    for (const auto& p : s.per_length) {
      c.x.push_back(p.length_s);
      c.y.push_back(figure(p.median_max_m));
    }
    for (const auto& e : o.outages) {
      if (e.max_m.empty()) continue;
      d.x.push_back(figure(e.start_s));
      d.y.push_back(figure(e.max_m, s.name));
    }
    by_length.push_back(std::move(c));
    by_start.push_back(std::move(d));
  }
  PlotSpec p;
  p.css_class = "outages";
  p.log_y = true;
  p.title = "median of the largest error per outage length";
  p.x_label = "outage length [s]";
  p.y_label = "median largest error [m]";
  p.x_min = 0;
  h << "<div class=\"plots\">" << svg_line_plot(by_length, p);
  p.title = "largest error of each outage";
  p.x_label = "outage start [s]";
  p.y_label = "largest error [m]";
  h << svg_line_plot(by_start, p) << "</div>\n";
  h << "<table class=\"outages\" id=\"outages-" << r.id << "\"><tr><th class=\"l\">set</th><th>length [s]</th><th>outages</th>"
       "<th>median largest [m]</th><th>largest [m]</th><th>median at the end [m]</th><th>largest at the end [m]</th></tr>\n";
  for (const auto& s : o.sets)
    for (const auto& q : s.per_length)
      h << "<tr><td class=\"l\">" << html_escape(s.name) << "</td><td>" << num(q.length_s) << "</td><td>" << num(figure(q.count))
        << "</td><td>" << num(figure(q.median_max_m), 4) << "</td><td>" << num(figure(q.max_max_m), 4) << "</td><td>"
        << num(figure(q.median_end_m), 4) << "</td><td>" << num(figure(q.max_end_m), 4) << "</td></tr>\n";
  h << "</table>\n<table class=\"outage-list\" id=\"outage-list-" << r.id
    << "\"><tr><th>start [s]</th><th>length [s]</th><th>fixes</th>";
  for (const auto& s : o.sets) h << "<th>" << html_escape(s.name) << ": largest / end [m]</th>";
  h << "</tr>\n";
  for (const auto& e : o.outages) {
    h << "<tr><td>" << num(figure(e.start_s)) << "</td><td>" << num(figure(e.length_s)) << "</td><td>" << num(figure(e.fixes))
      << "</td>";
    for (const auto& s : o.sets)
      h << "<td>" << num(figure(e.max_m, s.name), 4) << " / " << num(figure(e.end_m, s.name), 4) << "</td>";
    h << "</tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

// ---- innovation consistency ----
struct NisWords {
  const char *tag, *cls, *text;
};
NisWords nis_words(qc::NisVerdict v) {
  switch (v) {
    case qc::NisVerdict::consistent: return {"consistent", "pass", "consistent: mean NIS inside the region"};
    case qc::NisVerdict::too_large:
      return {"too-large", "warn",
              "NIS too large: the innovations exceed the filter's predicted covariance (assumed noise too small, or an "
              "error the model lacks)"};
    case qc::NisVerdict::too_small:
      return {"too-small", "warn",
              "NIS too small: the assumed noise (reference σ or process noise) is too large; the filter is pessimistic "
              "and its σ overstate the uncertainty"};
    case qc::NisVerdict::no_data: break;
  }
  return {"untested", "muted", "no epochs used"};
}

std::string consistency_table(const std::map<std::string, NisConsistency>& nis, const InMotionRun& r) {
  std::ostringstream h;
  h << "<h4>Innovation consistency (normalised innovation squared, NIS)</h4>\n";
  if (nis.empty()) return h.str() + "<p class=\"muted\">not recorded</p>\n";
  constexpr double kLevel = 0.95;
  h << "<table class=\"consistency\" id=\"consistency-" << r.id
    << "\"><tr><th class=\"l\">observation</th><th>eq</th><th>epochs used</th><th>rejected (NIS &gt; gate)</th><th>forced</th>"
       "<th>mean NIS</th><th>expected</th><th>95 % region of the mean</th><th>within the 95 % bound</th>"
       "<th>95 % region of the fraction</th><th class=\"l\">verdict (two-sided, 95 %)</th></tr>\n";
  const auto nan_if_absent = [](const auto& v) { return v ? static_cast<double>(*v) : std::nan(""); };
  for (const auto& [obs, c] : nis) {
    const double epochs = nan_if_absent(c.epochs), mean = nan_if_absent(c.mean_nis), frac = nan_if_absent(c.fraction_within_95pct),
                 rejected = nan_if_absent(c.rejected), forced = nan_if_absent(c.forced);
    double expected = nan_if_absent(c.expected_nis);
    if (!std::isfinite(expected)) expected = 3;  // eqs 13–15: three components each
    const int dof = static_cast<int>(std::lround(expected));
    std::string verdict = "not testable: epochs or mean NIS not recorded", cls = "muted", tag = "untested";
    qc::NisTest t;
    if (std::isfinite(epochs) && std::isfinite(mean) && dof > 0) {
      t = qc::nis_test(static_cast<long>(epochs), dof, mean, std::isfinite(frac) ? frac : 0.95, kLevel);
      const NisWords w = nis_words(t.mean);
      verdict = w.text;
      cls = w.cls;
      tag = w.tag;
      if (t.mean != qc::NisVerdict::no_data && std::isfinite(frac) && t.fraction != qc::NisVerdict::consistent)
        verdict += std::string("; the fraction within the bound is ") +
                   (t.fraction == qc::NisVerdict::too_large ? "below" : "above") + " its region";
    }
    if (std::isfinite(rejected) && rejected > 0) verdict += "; " + num(rejected) + " epoch(s) rejected, not in the mean";
    if (std::isfinite(forced) && forced > 0) verdict += "; the filter lost track " + num(forced) + " time(s)";
    const bool tested = t.mean != qc::NisVerdict::no_data;
    h << "<tr data-verdict=\"" << tag << "\"><td class=\"l\">" << html_escape(obs) << "</td><td>"
      << html_escape(c.equation.value_or("–")) << "</td><td>" << num(epochs, 6) << "</td><td>" << num(rejected, 6)
      << "</td><td>" << num(forced, 6) << "</td><td>" << num(mean, 4) << "</td><td>" << num(expected, 3) << "</td><td>"
      << (tested ? num(t.mean_lo, 4) + " – " + num(t.mean_hi, 4) : "–") << "</td><td>" << num(frac, 4) << "</td><td>"
      << (tested ? num(t.frac_lo, 4) + " – " + num(t.frac_hi, 4) : "–") << "</td><td class=\"l " << cls << "\">"
      << html_escape(verdict) << "</td></tr>\n";
  }
  h << "</table>\n<p class=\"note\">Test: time-average NIS (Bar-Shalom, Li &amp; Kirubarajan 2001, §5.4). For a consistent "
       "filter N·(mean NIS) is χ² with N·3 degrees of freedom; the region is its two-sided 95 % interval divided by N "
       "(Wilson–Hilferty). The fraction of epochs with NIS under the 3-dof 95 % bound (7.81) is tested against 0.95 "
       "(binomial). Both assume independent innovations: with time-correlated reference errors the true regions are "
       "wider, so a value just outside is weak evidence.</p>\n";
  return h.str();
}

// The adaptive noise scale the run's filter ended with (issue 53): beside the NIS, which a filter
// that scaled the IMU away keeps consistent by following the fixes.
std::string adaptive_part(const std::optional<AdaptiveNoiseSummary>& a, const InMotionRun& r) {
  if (!a || !(a->scale_max > 1)) return "";
  const bool failed = a->scale_end > inmotion::AdaptiveNoise::kFailScale;
  std::ostringstream h;
  h << "<p class=\"" << (failed ? "fail" : "note") << "\" id=\"adaptive-" << r.id << "\" data-verdict=\""
    << (failed ? "failed" : "ok") << "\">Adaptive process noise: the navigation noise variance was scaled up to ×"
    << num(a->scale_max, 3) << " and ended at ×" << num(a->scale_end, 3) << " (limit "
    << num(inmotion::AdaptiveNoise::kFailScale, 3) << " at the end). "
    << (failed ? "FAILED: the filter followed the fixes with the IMU's noise scaled away; the NIS above is not evidence "
                 "that the IMU model holds, and the set is refused at approval."
               : "The NIS above is that of a filter whose IMU carried the navigation at the end.")
    << "</p>\n";
  return h.str();
}

}  // namespace

std::string inmotion_section(Store& store, const InMotionRun& r, const CoefficientSetRecord& set,
                             const std::vector<CoefficientSetRecord>& sets) {
  const StoredResult stored = read_stored_result(r);
  const DriveResult& res = stored.res;
  // The typed QC sections of the codec: ΔS (res.cpe), outage QC (res.outages), consistency (res.nis).
  std::ostringstream h;
  h << "<h3>In-motion run " << r.id << " → set " << set.id << " (" << to_string(set.source)
    << (set.parent_id ? ", parent set " + std::to_string(*set.parent_id) : std::string()) << ")</h3>\n"
    << run_table(r, res) << stage_table(r, set, sets, stored) << (res.outages && res.cpe.sets.empty() ? std::string() : cpe_part(res.cpe, res, r))  // GNSS-only: outages only
    << outage_part(res.outages, r) << "<h4>QC metrics</h4>\n"
    << qc_table(store.qc_of_inmotion_run(r.id), "qc-inmotion-" + std::to_string(r.id)) << consistency_table(res.nis, r)
    << adaptive_part(res.adaptive_noise, r);
  return h.str();
}

}  // namespace calbench::report
