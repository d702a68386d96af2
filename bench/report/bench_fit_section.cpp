#include "bench/report/bench_fit_section.hpp"

#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include "bench/report/html_parts.hpp"
#include "bench/report/svg_plot.hpp"
#include "common/coefficients_codec.hpp"
#include "common/input_error.hpp"
#include "common/json_parse.hpp"
#include "common/units.hpp"

namespace calbench::report {
namespace {
using namespace calbench::units;
const char* const kAxis[] = {"x", "y", "z"};

std::string residual_plot(const BenchFitQuality& q, bool gyro, const std::map<std::string, double>& limits) {
  const double unit = gyro ? kDegPerHour : kMilliG;
  std::vector<PlotCurve> curves;
  for (int i = 0; i < 3; ++i) {
    PlotCurve c{std::string(gyro ? "gyro " : "accel ") + kAxis[i], {}, {}};
    for (const auto& s : q.steps) {
      c.x.push_back(s.step);
      c.y.push_back((gyro ? s.gyro(i) : s.accel(i)) / unit);
    }
    curves.push_back(std::move(c));
  }
  if (!q.steps.empty())
    for (const auto& [kind, lim] : limits)
      for (const double sign : {1.0, -1.0}) {
        PlotCurve c{(sign > 0 ? "+limit " : "-limit ") + kind, {}, {}};
        for (const auto& s : q.steps) {
          c.x.push_back(s.step);
          c.y.push_back(s.kind == kind ? sign * lim / unit : std::nan(""));
        }
        curves.push_back(std::move(c));
      }
  PlotSpec p;
  p.title = std::string(gyro ? "gyro" : "accelerometer") + ": mean residual of each step";
  p.x_label = "plan step";
  p.y_label = gyro ? "mean residual [°/h]" : "mean residual [mg]";
  p.css_class = gyro ? "residual-gyro" : "residual-accel";
  return svg_line_plot(curves, p);
}
}  // namespace

namespace {
// A set fitted from a multipos recording (fit multipos, no rate table): the fit's poses, rotations,
// χ²/dof against the approval's limits and its residual figures (docs/multipos.md).
std::string multipos_fit_part(const db::CoefficientSetRecord& set, const nlohmann::json& m, const db::Thresholds& t) {
  std::ostringstream h;
  const auto num_of = [&](const char* k) { return m.contains(k) && m[k].is_number() ? m[k].get<double>() : NAN; };
  const auto count_used = [&](const char* k) {
    int n = 0;
    if (m.contains(k) && m[k].is_array())
      for (const auto& x : m[k]) n += x.is_object() && x.value("used", true);
    return n;
  };
  const auto& L = t.quality;
  const double ca = num_of("accel_chi2_dof_class"), cg = num_of("gyro_chi2_dof_class");
  // A unit of no known class (device_class.name null) is judged under its measured noise and wide priors.
  const bool no_class = m.contains("device_class") && m["device_class"].is_object() && m["device_class"].contains("name") &&
                        m["device_class"]["name"].is_null();
  const char* model = no_class ? "measured noise, wide drift priors: no device class" : "class noise and drift";
  h << "<table class=\"multipos\" id=\"multipos-" << set.id << "\"><tr><th class=\"l\">multi-position fit (no rate table)</th>"
       "<th>value</th><th>limit</th></tr>\n"
    << "<tr><td class=\"l\">static poses used</td><td>" << count_used("statics") << "</td><td>–</td></tr>\n"
    << "<tr><td class=\"l\">rotations used</td><td>" << count_used("rotations") << "</td><td>–</td></tr>\n"
    << "<tr><td class=\"l\">accelerometer χ²/dof (gravity magnitude, " << model << ")</td><td class=\"" << (ca <= L.max_chi2_dof_accel ? "pass" : "fail")
    << "\">" << num(ca, 3) << "</td><td>" << num(L.max_chi2_dof_accel) << "</td></tr>\n"
    << "<tr><td class=\"l\">gyro χ²/dof (gravity direction after rotations, " << model << ")</td><td class=\""
    << (cg <= L.max_chi2_dof_gyro ? "pass" : "fail") << "\">" << num(cg, 3) << "</td><td>" << num(L.max_chi2_dof_gyro)
    << "</td></tr>\n"
    << "<tr><td class=\"l\">|f| − g RMS over the poses, before → after</td><td>" << num(num_of("g_spread_raw_m_s2") / kMilliG, 3)
    << " → " << num(num_of("g_spread_m_s2") / kMilliG, 3) << " mg</td><td>–</td></tr>\n"
    << "<tr><td class=\"l\">gravity direction after rotations, RMS</td><td>" << num(num_of("rotation_rms_deg"), 3)
    << "°</td><td>–</td></tr>\n</table>\n";
  if (m.contains("notes") && m["notes"].is_array())
    for (const auto& n : m["notes"])
      if (n.is_string()) h << "<p class=\"note\">" << html_escape(n.get<std::string>()) << "</p>\n";
  h << "<p class=\"note\">The accelerometer's residual is the gravity magnitude on each static pose, the gyros' the "
       "gravity direction after each rotation; χ²/dof ≈ 1 when the model and the noise measured on the statics fit. "
       "<code>calbench diagnose</code> on the recording looks for what the 12 + 12 model leaves out.</p>\n";
  return h.str();
}
}  // namespace

std::string bench_fit_part(const db::CoefficientSetRecord& set, const db::Thresholds& t) {
  std::ostringstream h;
  h << "<h4>Fit residuals</h4>\n";
  std::optional<BenchFitQuality> q;
  nlohmann::json mp;
  try {
    const std::string where = "set " + std::to_string(set.id);
    const CoefficientSet c = coefficients_from_json(parse_json_text(set.payload_json, where), where);
    q = c.fit_quality;
    if (const auto m = c.extra.find("multipos"); m != c.extra.end() && m->is_object()) mp = *m;
  } catch (const InputError& e) {
    return h.str() + "<p class=\"fail\">unreadable: " + html_escape(e.what()) + "</p>\n";
  }
  if (!mp.is_null()) return h.str() + multipos_fit_part(set, mp, t);
  if (!q) return h.str() + "<p class=\"muted\">not recorded with the set (a fit before calbench stored its residuals, or a set from elsewhere)</p>\n";
  const auto& L = t.quality;
  h << "<table class=\"chi2\" id=\"chi2-" << set.id << "\"><tr><th class=\"l\">triad</th><th>χ²/dof x</th><th>χ²/dof y</th>"
       "<th>χ²/dof z</th><th>limit</th></tr>\n";
  for (const bool gyro : {true, false}) {
    const Vec3& c = gyro ? q->gyro_chi2_dof : q->accel_chi2_dof;
    const double lim = gyro ? L.max_chi2_dof_gyro : L.max_chi2_dof_accel;
    h << "<tr><td class=\"l\">" << (gyro ? "gyro" : "accel") << "</td>";
    for (int i = 0; i < 3; ++i) h << "<td class=\"" << (c(i) > lim ? "fail" : "pass") << "\">" << num(c(i), 3) << "</td>";
    h << "<td>" << num(lim) << "</td></tr>\n";
  }
  h << "</table>\n<table class=\"systematic\" id=\"systematic-" << set.id
    << "\"><tr><th class=\"l\">triad</th><th class=\"l\">steps</th><th>count</th><th>largest systematic residual</th>"
       "<th>at step, axis</th><th>limit</th></tr>\n";
  for (const bool gyro : {true, false}) {
    const double unit = gyro ? kDegPerHour : kMilliG;
    const char* un = gyro ? " °/h" : " mg";
    const auto& limits = gyro ? L.max_residual_gyro : L.max_residual_accel;
    for (const auto& r : largest_residuals(*q, gyro)) {
      const auto lim = limits.find(r.kind);
      const bool bad = lim != limits.end() && r.value > lim->second;
      h << "<tr data-kind=\"" << r.kind << "\"><td class=\"l\">" << (gyro ? "gyro" : "accel") << "</td><td class=\"l\">"
        << (r.kind == kStepStatic ? "static positions" : "rate steps") << "</td><td>" << r.steps << "</td><td class=\""
        << (bad ? "fail" : "pass") << "\">" << num(r.value / unit, 3) << un << "</td><td>" << r.step << ", " << kAxis[r.axis]
        << "</td><td>" << (lim == limits.end() ? std::string("–") : num(lim->second / unit) + un) << "</td></tr>\n";
    }
  }
  h << "</table>\n<div class=\"plots\">" << residual_plot(*q, true, L.max_residual_gyro)
    << residual_plot(*q, false, L.max_residual_accel) << "</div>\n"
    << "<p class=\"note\">χ²/dof: the whitened residuals Σr²/dof of each axis (≈ 1 when the model and its noise fit the "
       "data). A step's mean residual is what the model leaves in that step (in-run drift, bench error, or an effect the "
       "model lacks).</p>\n";
  return h.str();
}

}  // namespace calbench::report
