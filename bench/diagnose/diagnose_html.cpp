#include <cmath>
#include <sstream>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/diagnose_text.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/io/json_util.hpp"
#include "bench/report/gnuplot.hpp"
#include "bench/report/html_parts.hpp"

// The HTML reports of `calbench diagnose` (--report), bench and drive: the text, and per finding
// its residual against the revealing condition before and after, plotted by the report's gnuplot
// runner.

namespace calbench {

namespace diagnose_out {

std::string residual_plot_html(const std::string& data, const std::string& xlabel, const std::string& ylabel,
                               bool svg) {
  // "before" as open circles under the smaller, half-transparent "after" dots: both stay visible.
  // The bench's inline SVG is the smaller figure of the two.
  const std::string output = svg ? "plot.svg" : "plot.png";
  const std::string script = std::string(svg ? "set terminal svg size 720,360 dynamic font 'sans,11'\n"
                                             : "set terminal pngcairo size 800,420\n") +
                             "set output '" + output + "'\nset xlabel '" + xlabel + "'\nset ylabel '" + ylabel +
                             "'\nset key " + (svg ? "outside top" : "outside") + "\nset grid\n" +
                             "plot 'd.txt' u 1:2 w p pt 6 ps " + (svg ? "0.6" : "0.8") +
                             " lc rgb '#d62728' t 'before', '' u 1:3 w p pt 7 ps " + (svg ? "0.35" : "0.45") +
                             " lc rgb '#601f77b4' t 'after'\n";
  try {
    const std::string out = report::run_gnuplot(script, {{"d.txt", data}}, output);
    if (!svg) return "<img src=\"" + report::png_data_uri(out) + "\">";
    const auto pos = out.find("<svg");
    return pos == std::string::npos ? out : out.substr(pos);
  } catch (const std::exception& e) {
    return "<p><i>(plot unavailable: " + report::html_escape(e.what()) + ")</i></p>";
  }
}

}  // namespace diagnose_out

using namespace diagnose_out;

namespace {

// One before/after plot of axis a's residual against a condition; returns inline SVG or a note.
std::string plot_svg(const DiagInput& in, const DiagnoseResult& r, int a, const std::string& cond) {
  using namespace units;
  const DiagData& d = in.data;
  const double scale = a < 3 ? 1.0 / kDegPerHour : 1.0 / kMilliG;
  const std::string unit = a < 3 ? "°/h" : "mg";
  const std::string cname = cond == "f" ? "f_z" : cond;
  const auto& rb = r.residual[a].before;
  const auto& ra = r.residual[a].after;
  std::ostringstream o;
  // Angle: within-block deviations of rotating sub-blocks; otherwise 1 s block means.
  for (const auto& p : d.parents) {
    double mb = 0, ma = 0;
    for (int j = p.first; j < p.first + p.count; ++j) {
      mb += d.subs[j].n * rb[j];
      ma += d.subs[j].n * ra[j];
    }
    if (cname == "angle") {
      mb /= p.n;
      ma /= p.n;
      for (int j = p.first; j < p.first + p.count; ++j)
        if (d.subs[j].rotating() && std::isfinite(d.subs[j].angle))
          o << condition_value(d, d.subs[j], "angle") << " " << (rb[j] - mb) * scale << " " << (ra[j] - ma) * scale << "\n";
    } else {
      double x = condition_value(d, d.subs[p.first + p.count / 2], cname);
      if (cname == "dT/dt") x = p.dtemp;
      o << x << " " << mb / p.n * scale << " " << ma / p.n * scale << "\n";
    }
  }
  return residual_plot_html(o.str(), condition_axis_label(cname), "residual (" + unit + ")", true);
}

}  // namespace

void write_diagnosis_report(const std::filesystem::path& html, const DiagInput& in, const DiagRun& run,
                            const std::string& title) {
  const DiagnoseResult& r = run.result;
  std::ostringstream o;
  o << report::html_page_start("calbench diagnose: " + title,
                               "body{font-family:sans-serif;max-width:1000px;margin:auto;padding:0 1em}"
                               "table{border-collapse:collapse}svg{max-width:100%;height:auto}p,pre{overflow-wrap:anywhere}"
                               "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}");
  o << "<h1>Diagnosis of " << report::html_escape(title) << "</h1>\n";
  o << "<p>Coefficients tested: " << (run.fitted_first ? "bench fit of this recording" : "given") << ". " << r.parents
    << " blocks of ~1 s, " << r.subs << " sub-blocks of 0.05 s, " << fmt(r.data_s, 4) << " s of plan steps. Noise model (drift prior) of "
    << report::html_escape(run.noise_class) << ".</p>\n";
  o << "<h2>Findings</h2>\n";
  if (r.findings.empty())
    o << "<p>No finding" << (r.unexplained.empty() ? ": the residual is consistent with the model and the sensor's noise" : " from the catalogue")
      << (r.drift_noted.empty() ? "" : "; see the notes (not findings) below") << ".</p>\n";
  for (const auto& f : r.findings) {
    o << "<h3>" << effect_name(f.term.effect) << " (" << f.status << ")</h3><p>" << report::html_escape(finding_sentence(f)) << "</p>\n";
    o << "<p>Evidence: Δχ² " << fmt(f.delta_chi2) << ", ΔBIC " << fmt(f.delta_bic) << ", held-out Δχ² "
      << fmt(f.heldout_delta_chi2) << ".</p>\n";
    const int a = finding_axis_index(f, r);
    o << "<p>Residual of " << kSensor[a / 3] << " " << kAxis[a % 3] << " against " << report::html_escape(f.condition)
      << ", before (red circles) and after (blue dots):</p>\n"
      << plot_svg(in, r, a, f.condition);
  }
  if (!r.drift_excess.empty()) {
    o << "<h2>Drift beyond the class's stability (not established)</h2>\n";
    for (const auto& x : r.drift_excess) o << "<p>" << report::html_escape(drift_excess_sentence(x)) << "</p>\n";
  }
  if (!r.drift_noted.empty()) {
    o << "<h2>Notes (not findings)</h2>\n";
    for (const auto& x : r.drift_noted) o << "<p>" << report::html_escape(drift_note_sentence(x)) << "</p>\n";
  }
  if (r.low_input.stated())
    o << "<h2>Smallest inputs</h2>\n<p>" << report::html_escape(low_input_sentence(r.low_input)) << "</p>\n";
  if (!r.saturation.empty()) {
    o << "<h2>Range exceeded</h2>\n";
    for (const auto& x : r.saturation) o << "<p>" << report::html_escape(saturation_sentence(x)) << "</p>\n";
  }
  if (!r.unexplained.empty()) {
    o << "<h2>Unexplained</h2>\n";
    for (const auto& u : r.unexplained) {
      o << "<p>" << kSensor[u.sensor] << " " << kAxis[u.axis] << ": χ²/dof " << fmt(u.chi2_dof) << ", within steps "
        << fmt(u.high_chi2_dof) << ", Ljung–Box p " << fmt(u.ljung_box_p) << "; worst steps";
      for (int s : u.worst_steps) o << " " << s;
      o << "; correlates with";
      o << report::html_escape(correlations_text(u.correlations));
      o << "</p>\n";
      const std::string c = u.correlations.empty() ? "time" : u.correlations.front().condition;
      o << plot_svg(in, r, u.sensor * 3 + u.axis, c);
    }
  }
  o << "<h2>Per axis, before → after</h2><table><tr><th>axis</th><th>systematic RMS</th><th>χ²/dof (1 s blocks)</th>"
       "<th>χ²/dof (within steps)</th><th>Ljung–Box p</th><th>criterion</th></tr>\n";
  for (int a = 0; a < 6; ++a) {
    const auto &b = r.before[a], &f = r.after[a];
    o << "<tr><td>" << kSensor[a / 3] << " " << kAxis[a % 3] << "</td><td>" << report::html_escape(human_rms(a / 3, b.systematic_rms))
      << " → " << report::html_escape(human_rms(a / 3, f.systematic_rms)) << "</td><td>" << fmt(b.chi2_dof) << " → "
      << fmt(f.chi2_dof) << "</td><td>" << fmt(b.high_chi2_dof) << " → " << fmt(f.high_chi2_dof) << "</td><td>"
      << fmt(b.ljung_box_p, 2) << " → " << fmt(f.ljung_box_p, 2) << "</td><td>" << fmt(b.bic, 6) << " → "
      << fmt(f.bic, 6) << "</td></tr>\n";
  }
  o << "</table>\n<p>Systematic RMS: RMS of per-step mean residuals (estimated drift removed) and of within-step "
       "residuals binned by table angle, with the white-noise expectation subtracted. Criterion: −2 log-likelihood of "
       "the 1 s block residuals plus parameters·ln N.</p></body></html>\n";
  write_text_atomic(html, o.str());
}

void write_drive_diagnosis_report(const std::filesystem::path& html, const DriveDiagInput& in, const DriveDiagRun& run,
                                  const std::string& title) {
  const DiagnoseResult& r = run.result.core;
  std::ostringstream h;
  h << report::html_page_start("calbench diagnose (drive) " + title,
                               "body{font-family:sans-serif;max-width:1000px;margin:auto;padding:0 1em}"
                               "pre{white-space:pre-wrap;overflow-wrap:anywhere}img{max-width:100%;height:auto}")
    << "<h1>Drive diagnosis: " << report::html_escape(title)
    << "</h1><pre>" << report::html_escape(drive_diagnosis_text(in, run)) << "</pre>";
  std::vector<std::pair<int, std::string>> plots;  // axis, condition
  for (const auto& f : r.findings) {
    if (effect_spec(f.term.effect).shape == EffectShape::noise) {
      plots.push_back({f.term.sensor * 3, "time"});
      continue;
    }
    int a = f.report_sensor * 3 + std::max(0, f.report_axis);
    if (effect_spec(f.term.effect).dominant_component || f.term.sensor == 2) {
      double worst = -1;
      for (int b = 0; b < 6; ++b)
        if ((f.term.sensor == 2 || b >= 3) && r.before[b].systematic_rms > worst) {
          worst = r.before[b].systematic_rms;
          a = b;
        }
    }
    plots.push_back({a, f.condition.empty() ? "time" : f.condition});
  }
  if (plots.empty())
    for (int a = 0; a < 6; ++a) plots.push_back({a, "time"});
  for (const auto& [a, cond] : plots) {
    std::ostringstream data;
    const int s = a / 3;
    for (int k = 0; k < r.parents; ++k)
      data << drive_condition_value(in.data, k, cond) << " " << disp(r.residual[a].before[k], s) << " "
           << disp(r.residual[a].after[k], s) << "\n";
    h << "<h2>" << kAxisName[a] << " vs " << report::html_escape(cond) << "</h2>"
      << residual_plot_html(data.str(), condition_axis_label(cond),
                            std::string(kAxisName[a]) + " residual (" + disp_unit(s) + ")", false);
  }
  h << "</body></html>\n";
  write_text_atomic(html, h.str());
}

}  // namespace calbench
