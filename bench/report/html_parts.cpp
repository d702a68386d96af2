#include "bench/report/html_parts.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bench/report/gnuplot.hpp"
#include "db/fleet.hpp"

namespace calbench::report {

std::string html_escape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      case '\'': o += "&#39;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string html_page_start(const std::string& title, const std::string& css) {
  return "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>" + html_escape(title) + "</title><style>" + css +
         "</style></head><body>\n";
}

namespace {
std::string fixed(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}
// Decimal places that show `sig` significant digits of v (0 … 9).
int decimals_for(double v, int sig) {
  if (v == 0) return 0;
  const int e = static_cast<int>(std::floor(std::log10(std::abs(v))));
  return std::clamp(sig - 1 - e, 0, 9);
}
}  // namespace

std::string num(double v, int sig) {
  if (!std::isfinite(v)) return "–";
  if (std::abs(v) < 1e7 && v == std::round(v)) return fixed(v, 0);  // counts, whole seconds
  if (v != 0 && (std::abs(v) < 1e-4 || std::abs(v) >= 1e7)) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*e", std::max(0, sig - 1), v);
    return b;
  }
  return fixed(v, decimals_for(v, sig));
}

std::string pm(double v, double sigma, double k) {
  if (!std::isfinite(sigma)) return num(v * k) + " <span class=\"muted\">(σ unknown)</span>";
  const double s = sigma * k;
  if (s == 0 || std::abs(s) < 1e-4 || std::abs(v * k) >= 1e7) return num(v * k) + " ± " + num(s, 2);
  const int d = decimals_for(s, 2);
  const double unit = std::pow(10.0, std::floor(std::log10(s)) - 1);  // σ above 99: two significant digits
  return fixed(v * k, d) + " ± " + fixed(d == 0 && s >= 100 ? std::round(s / unit) * unit : s, d);
}

void coefficient_unit(const std::string& name, std::string& unit, double& k) {
  db::display_unit(name, unit, k);
  if (unit == "deg/h") unit = "°/h";
}

std::string digest(const std::string& hex) {
  return "<span class=\"digest\">" + html_escape(hex.empty() ? "not recorded" : hex) + "</span>";
}

std::string qc_table(const std::vector<db::QcResult>& qc, const std::string& id) {
  if (qc.empty()) return "<p class=\"muted\">no QC results recorded</p>\n";
  std::string h = "<table class=\"qc\" id=\"" + html_escape(id) +
                  "\"><tr><th class=\"l\">metric</th><th>value</th><th class=\"l\">unit</th><th>threshold</th>"
                  "<th class=\"l\">criterion</th><th class=\"l\">in/out of sample</th><th class=\"l\">result</th></tr>\n";
  for (const auto& q : qc) {
    const bool info = q.informative();
    const std::string sample = q.sample.empty() ? "not recorded" : q.sample;
    h += "<tr data-sample=\"" + html_escape(sample) + "\" data-threshold=\"" + (q.threshold ? num(*q.threshold, 6) : "") +
         "\"><td class=\"l\">" + html_escape(q.metric) + "</td><td>" + num(q.value, 6) + "</td><td class=\"l\">" +
         html_escape(q.unit) + "</td><td>" + (q.threshold ? num(*q.threshold, 6) : std::string("–")) +
         "</td><td class=\"l\">" +
         html_escape(info ? std::string("informative (no threshold)") : q.criterion.empty() ? "|value| ≤ threshold" : q.criterion) +
         "</td><td class=\"l" + (q.sample.empty() ? " muted" : "") + "\">" + html_escape(sample) + "</td><td class=\"l " +
         (info ? "muted\">informative" : q.pass ? "pass\">pass" : "fail\">FAIL") + "</td></tr>\n";
  }
  return h + "</table>\n";
}

}  // namespace calbench::report
