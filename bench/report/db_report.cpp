#include "bench/report/db_report.hpp"
#include "bench/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <map>
#include <iomanip>
#include <sstream>

#include "common/input_error.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/report/bench_fit_section.hpp"
#include "bench/report/gnuplot.hpp"
#include "bench/report/html_parts.hpp"
#include "bench/report/inmotion_section.hpp"
#include "db/fleet.hpp"
#include "db/input_errors.hpp"
#include "db/audit_chain.hpp"
#include "db/signed_approval.hpp"
#include "db/signer.hpp"
#include "db/station_live.hpp"

namespace calbench::report {
namespace {
using namespace calbench::db;

std::string now_utc() {
  std::time_t t = std::time(nullptr);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&t));
  return b;
}
const char* kAxes[] = {"x", "y", "z"};

// Who signed an audit entry: the name, the station, and how it was authenticated ("login anna", or
// "OS user tess, not authenticated (SQLite)").
std::string signed_by(const Store& store, const AuditEntry& a) {
  const std::string note = signature_note(a.login, store.authenticated());
  return a.user + "@" + a.station + (note.empty() ? "" : " (" + note + ")");
}

const char* kStyle = R"CSS(
body{font-family:DejaVu Sans,Arial,sans-serif;font-size:11px;margin:16px;color:#111;max-width:1400px}
h1{font-size:18px;margin:0 0 4px} h2{font-size:14px;border-bottom:1px solid #999;margin:14px 0 6px}
h3{font-size:12px;margin:10px 0 4px} h4{font-size:11px;margin:8px 0 3px}
table{border-collapse:collapse;margin:4px 0 8px;max-width:100%} td,th{border:1px solid #bbb;padding:2px 6px;text-align:right;vertical-align:top}
th{background:#eee} td.l,th.l{text-align:left} td.t{white-space:nowrap}
.pass{color:#070;font-weight:bold} .fail{color:#b00;font-weight:bold} .warn{color:#a60;font-weight:bold} .muted{color:#666}
.verdict{font-size:16px;padding:4px 10px;border:2px solid;display:inline-block;margin:6px 0}
.verdict.draft{color:#a60}
.why{margin:2px 0 8px} .why li{margin:1px 0} .note{color:#333;margin:3px 0;max-width:1150px}
.digest{font-family:DejaVu Sans Mono,monospace;font-size:10px;word-break:break-all}
.plots svg{margin:0 8px 4px 0;page-break-inside:avoid} td.stage-drive{color:#1b6ac9} td.stage-bench{color:#555}
td.stage-both{color:#7570b3} td.stage-prior{color:#a60}
img{max-width:100%;page-break-inside:avoid} pre{font-size:10px;background:#f6f6f6;padding:4px;white-space:pre-wrap}
@media print{body{margin:0} h2,h3,h4{page-break-after:avoid}}
)CSS";

// After load, the page marks <body> with what the browser made of it (for the headless test):
// data-images="DECODED/TOTAL"; for the ΔS plots data-cpe-curves (polylines), data-cpe-min-points
// (fewest points the browser parsed in one of them) and data-cpe-min-span (smallest width of a
// curve as a fraction of its plot area: 1 = over the whole horizon); data-scroll-width, the page's
// width as laid out (wider than the window: something would be cut).
const char* kImageCheck = R"JS(
<script>
window.addEventListener('load', function () {
  var imgs = document.images, ok = 0;
  for (var i = 0; i < imgs.length; ++i) if (imgs[i].complete && imgs[i].naturalWidth > 0) ++ok;
  document.body.setAttribute('data-images', ok + '/' + imgs.length);
  var lines = document.querySelectorAll('svg.cpe polyline[data-curve]'), minPts = Infinity, minSpan = Infinity;
  for (var k = 0; k < lines.length; ++k) {
    var pl = lines[k], n = pl.points.numberOfItems, area = pl.ownerSVGElement.querySelector('rect.area');
    var span = n > 0 && area ? pl.getBBox().width / area.getBBox().width : 0;
    pl.setAttribute('data-plotted-points', n);
    minPts = Math.min(minPts, n);
    minSpan = Math.min(minSpan, span);
  }
  document.body.setAttribute('data-scroll-width', document.documentElement.scrollWidth);
  document.body.setAttribute('data-cpe-curves', lines.length);
  if (lines.length) {
    document.body.setAttribute('data-cpe-min-points', minPts);
    document.body.setAttribute('data-cpe-min-span', minSpan.toFixed(3));
  }
});
</script>
)JS";

std::string page(const std::string& title, const std::string& body) {
  return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + html_escape(title) +
         "</title><style>" + kStyle + "</style>" + kImageCheck + "</head><body>\n" + body + "\n</body></html>\n";
}

std::string img(const std::string& png, const std::string& alt) {
  return "<img alt=\"" + html_escape(alt) + "\" src=\"" + png_data_uri(png) + "\">\n";
}

std::string plot_or_note(const std::string& script, const std::map<std::string, std::string>& files, const std::string& alt) {
  try {
    return img(run_gnuplot(script, files), alt);
  } catch (const std::exception& e) {
    return "<p class=\"fail\">plot not available: " + html_escape(e.what()) + "</p>\n";
  }
}

// One coefficient set as a table: per triad bias and the rows of M, value ± σ in display units.
std::string set_table(const SensorErrors& e) {
  std::string h = "<table><tr><th class=\"l\">triad</th><th class=\"l\">term</th><th>x</th><th>y</th><th>z</th><th class=\"l\">unit</th></tr>\n";
  for (const char* triad : {"gyro", "accel"}) {
    const TriadErrors& t = std::string(triad) == "gyro" ? e.gyro : e.accel;
    std::string unit;
    double k;
    coefficient_unit(std::string(triad) + ".bias.x", unit, k);
    h += std::string("<tr><td class=\"l\">") + triad + "</td><td class=\"l\">bias</td>";
    for (int i = 0; i < 3; ++i) h += "<td>" + pm(t.bias(i), t.sigma_bias(i), k) + "</td>";
    h += "<td class=\"l\">" + unit + "</td></tr>\n";
    for (int i = 0; i < 3; ++i) {
      h += std::string("<tr><td class=\"l\">") + triad + "</td><td class=\"l\">M row " + kAxes[i] + "</td>";
      for (int j = 0; j < 3; ++j) h += "<td>" + pm(t.M(i, j), t.sigma_M(i, j), 1e6) + "</td>";
      h += "<td class=\"l\">ppm</td></tr>\n";
    }
  }
  return h + "</table>\n";
}

// Coefficient history: bias and scale of each axis against the set version, with σ error bars.
// Coefficient history: value ± 1σ per set version, four inline SVG plots (gyro/accel bias and
// scale), x, y and z side by side (±0.06 in version) so that no error bar hides another.
std::string history_plot(const std::vector<CoefficientSetRecord>& sets) {
  const char* titles[] = {"gyro bias", "gyro scale", "accel bias", "accel scale"};
  std::ostringstream out;
  out << "<div class=\"plots\" id=\"history-plots\">";
  for (int p = 0; p < 4; ++p) {
    const char* triad = p < 2 ? "gyro" : "accel";
    const bool bias = p % 2 == 0;
    std::vector<PlotCurve> curves(3);
    std::string unit;
    for (int i = 0; i < 3; ++i) {
      curves[static_cast<std::size_t>(i)].name = kAxes[i];
      const std::string name = std::string(triad) + (bias ? ".bias." + std::string(kAxes[i]) : ".M." + std::string(kAxes[i]) + kAxes[i]);
      double k = 1;
      display_unit(name, unit, k);
      for (const auto& st : sets) {
        const double sg = coefficient_sigma(st.errors, name);
        auto& c = curves[static_cast<std::size_t>(i)];
        c.x.push_back(st.version + (i - 1) * 0.06);
        c.y.push_back(coefficient_value(st.errors, name) * k);
        c.err.push_back(std::isfinite(sg) ? sg * k : 0.0);
      }
    }
    PlotSpec spec;
    spec.title = std::string(titles[p]) + " (value ± 1σ per set version)";
    spec.x_label = "set version";
    spec.y_label = std::string(titles[p]) + " [" + unit + "]";
    spec.x_min = sets.empty() ? 0 : sets.front().version - 0.5;
    spec.x_max = sets.empty() ? 1 : sets.back().version + 0.5;
    spec.width = 480;
    spec.height = 260;
    spec.css_class = "history";
    out << svg_line_plot(curves, spec);
  }
  out << "</div>\n";
  return out.str();
}

// The verdict on the device's current set (the newest that is not revoked), with the reasons
// when it fails the thresholds in force and the approval history of that set.
std::string verdict_block(Store& store, const Device& dev, const std::vector<CoefficientSetRecord>& sets, const Thresholds& t) {
  const CoefficientSetRecord* current = nullptr;
  for (const auto& s : sets)
    if (s.status != SetStatus::revoked) current = &s;
  std::ostringstream b;
  std::vector<std::string> reasons;
  std::string word = "FAIL", cls = "fail", said;
  const auto audit = store.audit_of_device(dev.id);
  const auto approval_row = [&](const AuditEntry& a) {
    return a.entity == "coefficient_set" && current && a.entity_id == current->id && a.action == "status" &&
           a.detail.rfind("draft -> approved", 0) == 0;
  };
  if (!current) {
    reasons.push_back(sets.empty() ? "the device has no coefficient set" : "every coefficient set of the device is revoked");
  } else {
    const ApprovalCheck chk = check_standing(store, *current, t);
    const bool approved = current->status == SetStatus::approved || current->status == SetStatus::provisioned;
    reasons = chk.reasons;
    const std::string set = "Set " + std::to_string(current->id);
    // A status changed behind calbench's back (e.g. by hand in a SQLite file) has no signed
    // approval in the audit log, or one that fails the log's hash chain or four-eyes: not a pass.
    bool record_intact = true;  // a signed approval if approved, and no audit row of the device edited outside calbench
    if (approved) {
      const db::SignedApproval sa = db::signed_approval(store, *current);
      record_intact = sa.ok;
      if (!sa.ok) reasons.push_back("set " + std::to_string(current->id) + " is " + to_string(current->status) + " but " + sa.why);
    }
    for (const auto& br : db::check_audit_chain(store, dev.id).breaks) {
      record_intact = false;  // a device whose audit rows were edited outside calbench is not a pass
      reasons.push_back("audit row " + std::to_string(br.id) + " of this device: " + br.why);
    }
    if (chk.ok && approved && record_intact) {
      word = "PASS";
      cls = "pass";
      said = set + " is " + to_string(current->status) + " and meets every threshold in force.";
    } else if (chk.ok && !approved && record_intact) {
      word = "NOT APPROVED";
      cls = "draft";
      said = set + " is a draft: it meets every threshold in force but has not been approved (calbench db approve " +
             std::to_string(current->id) + ").";
    } else {
      said = !approved && chk.ok ? set + " is a draft; the audit log of the device was changed outside calbench:"
             : !approved ? set + " is a draft and would be refused approval:"
             : chk.ok  ? set + " is " + to_string(current->status) + " without a valid signed approval:"
                       : set + " is " + to_string(current->status) + " but does not meet the thresholds in force:";
    }
  }
  b << "<div id=\"verdict\" class=\"verdict " << cls << "\" data-verdict=\"" << word << "\">" << word << "</div> ";
  if (current)
    b << "current set " << current->id << " (v" << current->version << ", " << source_label(*current) << ", "
      << to_string(current->status) << ")\n";
  // What the unit holds may be another set than the newest: say which, next to the verdict.
  const CoefficientSetRecord* in_unit = nullptr;
  for (const auto& s : sets)
    if (s.status == SetStatus::provisioned) in_unit = &s;
  if (in_unit && in_unit != current)
    b << "<p id=\"in-unit\" class=\"note\"><b>The unit holds set " << in_unit->id << "</b> (v" << in_unit->version << ", "
      << source_label(*in_unit) << ", provisioned); the verdict above is on the newer set " << current->id
      << ", which is not in the unit.</p>\n";
  else if (in_unit)
    b << "<p id=\"in-unit\" class=\"note\">The unit holds this set (provisioned).</p>\n";
  else
    b << "<p id=\"in-unit\" class=\"note\">No set has been provisioned into the unit.</p>\n";
  b << "<div class=\"why\">" << (said.empty() ? "" : "<p>" + html_escape(said) + "</p>") << "\n";
  if (!reasons.empty()) {
    b << "<ul id=\"verdict-reasons\" class=\"fail\">\n";
    for (const auto& r : reasons) b << "<li>" << html_escape(r) << "</li>\n";
    b << "</ul>\n";
  }
  if (current)  // what happened to this set at approval
    for (const auto& a : audit)
      if (approval_row(a) || (a.entity == "coefficient_set" && a.entity_id == current->id && a.action == "approve-refused"))
        b << "<p class=\"note\">" << html_escape(a.action == "status" ? "Approved" : "Approval refused") << " " << html_escape(a.at)
          << " by " << html_escape(signed_by(store, a)) << ": " << html_escape(a.detail) << "</p>\n";
  b << "<p class=\"note\">Thresholds in force for this verdict: " << html_escape(t.source) << "</p>\n<ul id=\"thresholds\" class=\"note\">";
  for (const auto& line : describe_thresholds(t)) b << "<li>" << html_escape(line) << "</li>";
  b << "</ul></div>\n";
  return b.str();
}

}  // namespace

const char* report_css() { return kStyle; }

std::string device_report_html(Store& store, const std::string& serial, const Thresholds& thresholds) {
  return page("calbench report " + serial, device_report_body(store, serial, thresholds));
}

std::string device_report_body(Store& store, const std::string& serial, const Thresholds& thresholds) {
  const auto dev = store.find_device(serial);
  if (!dev) throw arg_error("SERIAL", "unknown device '" + serial + "' in " + store.connection().path());
  const auto sets = store.sets_of(dev->id);
  std::ostringstream b;
  b << "<h1>" << html_escape(dev->model) << " &nbsp;serial " << html_escape(dev->serial) << "</h1>\n";
  b << "<div class=\"muted\">firmware " << html_escape(dev->firmware.empty() ? "unknown" : dev->firmware)
    << " · in database since " << html_escape(dev->created_at) << " · report generated " << now_utc() << " from "
    << html_escape(store.connection().path()) << "</div>\n"
    << verdict_block(store, *dev, sets, thresholds);

  b << "<h2>Coefficient history</h2>\n";
  if (!sets.empty()) {
    b << "<table><tr><th>set</th><th>version</th><th class=\"l\">source</th><th class=\"l\">status</th><th>parent</th>"
         "<th class=\"l\">created</th><th class=\"l\">by</th></tr>\n";
    for (const auto& s : sets)
      b << "<tr><td>" << s.id << "</td><td>" << s.version << "</td><td class=\"l\">" << source_label(s)
        << "</td><td class=\"l " << (s.status == SetStatus::revoked ? "fail" : "") << "\">" << to_string(s.status)
        << "</td><td>" << (s.parent_id ? std::to_string(*s.parent_id) : "–") << "</td><td class=\"l t\">"
        << html_escape(s.created_at) << "</td><td class=\"l\">" << html_escape(s.created_by) << "</td></tr>\n";
    b << "</table>\n" << history_plot(sets);
    for (const auto& s : sets) {
      b << "<h3>Set " << s.id << " (v" << s.version << ", " << source_label(s) << ", " << to_string(s.status)
        << ") — measured = (I + M)·true + b, value ± 1σ</h3>\n"
        << set_table(s.errors);
    }
  } else {
    b << "<p class=\"muted\">none</p>\n";
  }

  b << "<h2>Bench runs and residuals</h2>\n";
  bool any_bench = false;
  for (const auto& s : sets) {
    if (!s.bench_run_id) continue;
    const auto r = store.bench_run(*s.bench_run_id);
    if (!r) continue;
    any_bench = true;
    b << "<h3>Bench run " << r->id << " → set " << s.id << "</h3>\n<table>"
      << "<tr><th class=\"l\">station</th><td class=\"l\">" << html_escape(r->station) << "</td></tr>"
      << "<tr><th class=\"l\">plan</th><td class=\"l\">" << html_escape(r->plan) << "</td></tr>"
      << "<tr><th class=\"l\">recording</th><td class=\"l\">"
      << html_escape(r->recording_uri.empty() ? r->recording_path : r->recording_uri) << "<br>SHA-256 of "
      << html_escape(imu_table_file_label(r->recording_path)) << " " << digest(r->recording_sha256)
      << (r->recording_digest.empty() ? std::string() : "<br>SHA-256 of all its files " + digest(r->recording_digest))
      << "</td></tr>"
      << "<tr><th class=\"l\">time</th><td class=\"l\">" << html_escape(r->started_at) << " – " << html_escape(r->ended_at) << "</td></tr>"
      << "<tr><th class=\"l\">outcome</th><td class=\"l " << (r->outcome == "pass" ? "pass" : "fail") << "\">"
      << html_escape(r->outcome) << "</td></tr></table>\n"
      << qc_table(store.qc_of_bench_run(r->id), "qc-bench-" + std::to_string(r->id)) << bench_fit_part(s, thresholds);
  }
  if (!any_bench) b << "<p class=\"muted\">no bench runs</p>\n";

  b << "<h2>In-motion calibration</h2>\n";
  bool any_motion = false;
  for (const auto& s : sets) {
    if (!s.inmotion_run_id) continue;
    const auto r = store.inmotion_run(*s.inmotion_run_id);
    if (!r) continue;
    any_motion = true;
    b << inmotion_section(store, *r, s, sets);
  }
  if (!any_motion) b << "<p class=\"muted\">no in-motion runs</p>\n";

  b << "<h2>Provisioning</h2>\n";
  const auto prov = store.provisioning_of(dev->id);
  if (prov.empty()) b << "<p class=\"muted\">never provisioned</p>\n";
  else {
    b << "<table><tr><th class=\"l\">when</th><th>set</th><th class=\"l\">kind</th><th class=\"l\">target</th><th class=\"l\">result</th><th class=\"l\">by</th><th class=\"l\">message</th></tr>\n";
    for (const auto& p : prov)
      b << "<tr><td class=\"l t\">" << html_escape(p.at) << "</td><td>" << p.set_id << "</td><td class=\"l\">" << html_escape(p.kind)
        << "</td><td class=\"l\">" << html_escape(p.target) << "</td><td class=\"l " << (p.ok ? "pass\">ok" : "fail\">FAILED")
        << "</td><td class=\"l\">" << html_escape(p.actor) << "</td><td class=\"l\">" << html_escape(p.message) << "</td></tr>\n";
    b << "</table>\n";
  }

  b << "<h2>History (audit log)</h2>\n<table><tr><th class=\"l\">when</th><th class=\"l\">who</th><th class=\"l\">what</th><th class=\"l\">detail</th></tr>\n";
  for (const auto& a : store.audit_of_device(dev->id))
    b << "<tr><td class=\"l t\">" << html_escape(a.at) << "</td><td class=\"l\">" << html_escape(signed_by(store, a))
      << "</td><td class=\"l\">" << html_escape(a.entity + " " + std::to_string(a.entity_id) + " " + a.action) << "</td><td class=\"l\">"
      << html_escape(a.detail) << "</td></tr>\n";
  b << "</table>\n";
  return b.str();
}

// Which station calibrated what, and whether a station's units drift apart from the others'
// (db/fleet.hpp: a table or fixture fault shows there before any single unit is an outlier).
static std::string station_section_html(const std::vector<StationStats>& ss) {
  std::ostringstream b;
  b << "<h2>Stations</h2>\n<div class=\"muted\">each station's units against the other stations' units, per "
       "coefficient: offset z = difference of the medians over its standard error, flagged |z| &gt; "
    << kStationZ << "; spread = MAD here over MAD elsewhere, flagged &gt; " << kStationSpread << " (with ≥ "
    << kStationSpreadMinUnits << " units). A station needs ≥ 2 units and the others ≥ 3 to be compared.</div>\n"
    << "<table><tr><th class=\"l\">station</th><th>units</th><th class=\"l\">verdict</th>"
       "<th class=\"l\">flagged coefficients (median here / elsewhere, z, spread)</th><th class=\"l\">serials</th></tr>\n";
  for (const auto& s : ss) {
    std::string flags;
    for (const auto& c : s.coefficients)
      if (c.offset_flag || c.spread_flag)
        flags += (flags.empty() ? "" : "; ") + c.name + ": " + num(c.median * c.to_display) + " / " +
                 num(c.median_others * c.to_display) + " " + c.unit + ", z " + num(c.z, 3) + ", spread " +
                 num(c.spread_ratio, 3);
    std::string serials;  // at most 20 named (a station of a large fleet has thousands)
    for (std::size_t k = 0; k < s.serials.size() && k < 20; ++k) serials += (serials.empty() ? "" : ", ") + s.serials[k];
    if (s.serials.size() > 20) serials += " and " + std::to_string(s.serials.size() - 20) + " more";
    b << "<tr><td class=\"l\">" << html_escape(s.station.empty() ? "(unknown)" : s.station) << "</td><td>" << s.devices
      << "</td><td class=\"l " << (s.flagged ? "fail" : "") << "\">" << station_verdict(s) << "</td><td class=\"l\">"
      << html_escape(flags.empty() ? "–" : flags) << "</td><td class=\"l\">" << html_escape(serials) << "</td></tr>\n";
  }
  b << "</table>\n";
  return b.str();
}

// Units per hour over the last 24 h, per station: bench runs by their end time and outcome.
static std::string throughput_section_html(Store& store) {
  constexpr int kHours = 24;
  const double now = epoch_now_s();
  struct Counts {
    std::vector<double> passed = std::vector<double>(kHours, 0.0);
    int pass = 0, fail = 0, aborted = 0, last_hour = 0;
  };
  std::map<std::string, Counts> by;
  for (const auto& r : store.runs_ended_since(iso_utc_at(now - kHours * 3600.0))) {
    const double ago_h = age_s(r.ended_at, now) / 3600.0;  // NaN for an end time that does not parse
    if (!(ago_h >= 0 && ago_h < kHours)) continue;
    Counts& c = by[r.station];
    const int bin = kHours - 1 - static_cast<int>(ago_h);  // oldest first
    if (r.outcome == "pass") {
      ++c.pass;
      c.passed[static_cast<std::size_t>(bin)] += 1;
      if (ago_h < 1) ++c.last_hour;
    } else if (r.outcome == "fail") {
      ++c.fail;
    } else {
      ++c.aborted;
    }
  }
  std::ostringstream b;
  b << "<h2>Units per hour</h2>\n<div class=\"muted\">bench runs that ended in the last " << kHours
    << " h, by station: units calibrated (outcome pass) per hour, and the runs that failed or were aborted (runs stored "
       "without an end time, e.g. db store-bench without --ended, are not counted)</div>\n";
  if (by.empty()) {
    b << "<p id=\"throughput-none\">No bench run ended in the last " << kHours << " h.</p>\n";
    return b.str();
  }
  std::vector<PlotCurve> curves;
  for (const auto& [station, c] : by) {
    PlotCurve pc;
    pc.name = station.empty() ? "(unknown)" : station;
    for (int h = 0; h < kHours; ++h) pc.x.push_back(h - kHours + 1), pc.y.push_back(c.passed[static_cast<std::size_t>(h)]);
    curves.push_back(std::move(pc));
  }
  PlotSpec spec;
  spec.title = "units calibrated per hour";
  spec.x_label = "hour [h from now]";
  spec.y_label = "units per hour [1/h]";
  spec.css_class = "throughput";
  b << "<div class=\"plots\">" << svg_line_plot(curves, spec) << "</div>\n";
  b << "<table id=\"throughput\"><tr><th class=\"l\">station</th><th>last hour</th><th>last " << kHours
    << " h</th><th>per active hour</th><th>failed</th><th>aborted</th></tr>\n";
  for (const auto& [station, c] : by) {
    int active = 0;
    for (double v : c.passed) active += v > 0;
    b << "<tr data-station=\"" << html_escape(station) << "\"><td class=\"l\">" << html_escape(station.empty() ? "(unknown)" : station)
      << "</td><td>" << c.last_hour << "</td><td>" << c.pass << "</td><td>" << (active ? num(c.pass / static_cast<double>(active), 3) : "–")
      << "</td><td class=\"" << (c.fail ? "fail" : "") << "\">" << c.fail << "</td><td>" << c.aborted << "</td></tr>\n";
  }
  b << "</table>\n";
  return b.str();
}

std::string fleet_report_body(Store& store) {
  const auto values = store.fleet();
  const auto stats = fleet_stats(values);
  std::ostringstream b;
  const std::size_t n = stats.empty() ? 0 : stats.front().n;
  b << "<h1>Fleet report</h1>\n<div class=\"muted\" id=\"fleet-summary\">" << n << " device(s), newest non-revoked coefficient set of each · "
    << "outlier: robust z = 0.6745·(x − median)/MAD, |z| &gt; " << kOutlierZ << " · generated " << now_utc() << " from "
    << html_escape(store.connection().path()) << "</div>\n";
  // A histogram per coefficient (counts per bin, as a step curve), outliers as red points on the axis.
  b << "<h2>Distributions</h2>\n<div class=\"plots\" id=\"distributions\">";
  for (const auto& c : stats) {
    if (n == 0) break;
    double lo = c.min * c.to_display, hi = c.max * c.to_display;
    if (hi <= lo) {
      lo -= 1;
      hi += 1;
    }
    const int bins = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(c.n))) + 1, 5, 40);
    const double w = (hi - lo) / bins;
    std::vector<double> h(static_cast<std::size_t>(bins), 0.0);
    PlotCurve outl;
    outl.name = "outliers";
    outl.points = true;
    outl.colour = "#cc0000";
    for (const auto& p : c.points) {
      const double x = p.value * c.to_display;
      const int i = std::clamp(static_cast<int>((x - lo) / w), 0, bins - 1);
      h[static_cast<std::size_t>(i)] += 1;
      if (p.outlier) outl.x.push_back(x), outl.y.push_back(0);
    }
    PlotCurve hist;
    hist.name = "devices per bin";
    hist.colour = "#4477aa";
    for (int i = 0; i < bins; ++i) {  // a step curve: each bin's count across its width
      hist.x.push_back(lo + i * w), hist.y.push_back(h[static_cast<std::size_t>(i)]);
      hist.x.push_back(lo + (i + 1) * w), hist.y.push_back(h[static_cast<std::size_t>(i)]);
    }
    PlotSpec spec;
    spec.title = c.name;
    spec.x_label = c.name + " [" + c.unit + "]";
    spec.y_label = "devices";
    spec.width = 330;
    spec.height = 220;
    spec.css_class = "histogram";
    std::vector<PlotCurve> curves{hist};
    if (!outl.x.empty()) curves.push_back(outl);
    b << svg_line_plot(curves, spec);
  }
  b << "</div>\n";
  b << "<h2>Statistics</h2>\n<table id=\"fleet-stats\"><tr><th class=\"l\">coefficient</th><th class=\"l\">unit</th><th>n</th><th>median</th>"
       "<th>MAD</th><th>mean</th><th>std</th><th>min</th><th>max</th><th class=\"l\">outliers (serial: value, z)</th></tr>\n";
  for (const auto& c : stats) {
    std::string outl;  // the 20 largest |z| named, the count of the rest
    std::vector<const CoefficientStats::Point*> out_pts;
    for (const auto& p : c.points)
      if (p.outlier) out_pts.push_back(&p);
    std::sort(out_pts.begin(), out_pts.end(), [](const auto* a, const auto* z) { return std::abs(a->z) > std::abs(z->z); });
    for (std::size_t k = 0; k < out_pts.size() && k < 20; ++k)
      outl += (outl.empty() ? "" : "; ") + out_pts[k]->serial + ": " + num(out_pts[k]->value * c.to_display) + ", z " + num(out_pts[k]->z, 3);
    if (out_pts.size() > 20) outl += "; and " + std::to_string(out_pts.size() - 20) + " more";
    b << "<tr><td class=\"l\">" << c.name << "</td><td class=\"l\">" << c.unit << "</td><td>" << c.n << "</td><td>"
      << num(c.median * c.to_display) << "</td><td>" << num(c.mad * c.to_display) << "</td><td>" << num(c.mean * c.to_display)
      << "</td><td>" << num(c.stddev * c.to_display) << "</td><td>" << num(c.min * c.to_display) << "</td><td>"
      << num(c.max * c.to_display) << "</td><td class=\"l " << (outl.empty() ? "" : "fail") << "\">"
      << html_escape(!c.judged ? "not judged: " + std::to_string(c.n) + " units, " + std::to_string(kOutlierMinUnits) + " needed"
                               : outl.empty() ? "–" : outl)
      << "</td></tr>\n";
  }
  b << "</table>\n";
  b << station_section_html(station_stats(values));
  b << throughput_section_html(store);
  return b.str();
}

std::string fleet_report_html(Store& store) { return page("calbench fleet report", fleet_report_body(store)); }

}  // namespace calbench::report
