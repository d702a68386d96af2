#include "bench/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "bench/report/html_parts.hpp"

namespace calbench::report {
namespace {

const char* kColours[] = {"#d95f02", "#1b6ac9", "#1b9e77", "#7570b3", "#e7298a", "#66a61e"};

std::string px(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

std::string tick_label(double v) {
  if (std::abs(v) < 1e-12) return "0";
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Ticks at 1, 2 or 5 × 10^k covering [lo, hi] with about `target` intervals.
std::vector<double> linear_ticks(double lo, double hi, int target) {
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) t.push_back(v);
  return t;
}

}  // namespace

std::string svg_line_plot(const std::vector<PlotCurve>& curves, const PlotSpec& p) {
  constexpr double kLeft = 64, kRight = 14, kTop = 28, kBottom = 42;
  const double W = p.width, H = p.height, aw = W - kLeft - kRight, ah = H - kTop - kBottom;
  // Data ranges.
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0, ypos = x0;
  for (const auto& c : curves)
    for (std::size_t i = 0; i < c.x.size() && i < c.y.size(); ++i) {
      if (!std::isfinite(c.x[i]) || !std::isfinite(c.y[i])) continue;
      const double e = i < c.err.size() && std::isfinite(c.err[i]) ? std::abs(c.err[i]) : 0.0;
      x0 = std::min(x0, c.x[i]);
      x1 = std::max(x1, c.x[i]);
      y0 = std::min(y0, c.y[i] - e);
      y1 = std::max(y1, c.y[i] + e);
      if (c.y[i] > 0) ypos = std::min(ypos, c.y[i]);
    }
  if (p.x_max > p.x_min) {
    x0 = p.x_min;
    x1 = p.x_max;
  }
  if (!(x1 > x0)) {
    x0 = std::isfinite(x0) ? x0 - 1 : 0;
    x1 = x0 + 2;
  }
  std::vector<double> yt;
  double ly0 = 0, ly1 = 1;  // log10 range for log_y
  if (p.log_y) {
    if (!std::isfinite(ypos)) ypos = 1e-3;
    if (!(y1 > 0)) y1 = 1;
    ly1 = std::ceil(std::log10(y1) - 1e-9);
    ly0 = std::max(std::floor(std::log10(ypos)), ly1 - 6);  // at most six decades
    if (ly1 <= ly0) ly1 = ly0 + 1;
    for (double d = ly0; d <= ly1 + 1e-9; d += 1) yt.push_back(d);
  } else {
    y0 = std::min(0.0, std::isfinite(y0) ? y0 : 0.0);
    if (!(y1 > y0)) y1 = y0 + 1;
    yt = linear_ticks(y0, y1, 6);
    y1 = std::max(y1, yt.back());
    y0 = std::min(y0, yt.front());
  }
  const auto X = [&](double x) { return kLeft + (x - x0) / (x1 - x0) * aw; };
  const auto Y = [&](double y) {
    if (p.log_y) {
      const double l = y > 0 ? std::max(std::log10(y), ly0) : ly0;
      return kTop + ah - (l - ly0) / (ly1 - ly0) * ah;
    }
    return kTop + ah - (y - y0) / (y1 - y0) * ah;
  };

  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"" << html_escape(p.css_class) << "\" width=\"" << W
    << "\" height=\"" << H << "\" viewBox=\"0 0 " << W << " " << H << "\" role=\"img\" aria-label=\"" << html_escape(p.title)
    << "\" font-family=\"DejaVu Sans,Arial,sans-serif\" font-size=\"11\">\n";
  s << "<text x=\"" << px(kLeft + aw / 2) << "\" y=\"16\" text-anchor=\"middle\" font-weight=\"bold\">" << html_escape(p.title)
    << "</text>\n";
  s << "<rect class=\"area\" x=\"" << px(kLeft) << "\" y=\"" << px(kTop) << "\" width=\"" << px(aw) << "\" height=\"" << px(ah)
    << "\" fill=\"none\" stroke=\"#444\"/>\n<g stroke=\"#ddd\" stroke-width=\"1\">\n";
  const std::vector<double> xt = linear_ticks(x0, x1, 8);
  for (double v : xt) s << "<line x1=\"" << px(X(v)) << "\" x2=\"" << px(X(v)) << "\" y1=\"" << px(kTop) << "\" y2=\"" << px(kTop + ah) << "\"/>\n";
  for (double v : yt) {
    const double y = p.log_y ? kTop + ah - (v - ly0) / (ly1 - ly0) * ah : Y(v);
    s << "<line x1=\"" << px(kLeft) << "\" x2=\"" << px(kLeft + aw) << "\" y1=\"" << px(y) << "\" y2=\"" << px(y) << "\"/>\n";
  }
  s << "</g>\n<g fill=\"#222\">\n";
  for (double v : xt)
    s << "<text x=\"" << px(X(v)) << "\" y=\"" << px(kTop + ah + 14) << "\" text-anchor=\"middle\">" << tick_label(v) << "</text>\n";
  for (double v : yt) {
    const double y = p.log_y ? kTop + ah - (v - ly0) / (ly1 - ly0) * ah : Y(v);
    s << "<text x=\"" << px(kLeft - 5) << "\" y=\"" << px(y + 4) << "\" text-anchor=\"end\">"
      << (p.log_y ? tick_label(std::pow(10.0, v)) : tick_label(v)) << "</text>\n";
  }
  s << "<text x=\"" << px(kLeft + aw / 2) << "\" y=\"" << px(H - 6) << "\" text-anchor=\"middle\">" << html_escape(p.x_label)
    << "</text>\n<text transform=\"translate(14 " << px(kTop + ah / 2) << ") rotate(-90)\" text-anchor=\"middle\">"
    << html_escape(p.y_label) << "</text>\n</g>\n";
  // Curves: earlier ones wider, underneath.
  const std::size_t n = curves.size();
  const auto width_of = [&](std::size_t i) { return n > 1 ? 1.5 + 3.0 * static_cast<double>(n - 1 - i) / static_cast<double>(n - 1) : 1.8; };
  const auto colour = [&](std::size_t i) { return curves[i].colour.empty() ? std::string(kColours[i % 6]) : curves[i].colour; };
  for (std::size_t i = 0; i < n; ++i) {
    const auto& c = curves[i];
    if (!c.err.empty()) {  // error bars first, under the curve
      s << "<g data-errors=\"" << html_escape(c.name) << "\" stroke=\"" << colour(i) << "\" stroke-width=\"1\">";
      for (std::size_t k = 0; k < c.x.size() && k < c.y.size() && k < c.err.size(); ++k) {
        if (!std::isfinite(c.x[k]) || !std::isfinite(c.y[k]) || !std::isfinite(c.err[k])) continue;
        s << "<line x1=\"" << px(X(c.x[k])) << "\" x2=\"" << px(X(c.x[k])) << "\" y1=\"" << px(Y(c.y[k] - c.err[k]))
          << "\" y2=\"" << px(Y(c.y[k] + c.err[k])) << "\"/>";
      }
      s << "</g>\n";
    }
    if (c.points) {
      s << "<g data-curve=\"" << html_escape(c.name) << "\" fill=\"" << colour(i) << "\">";
      for (std::size_t k = 0; k < c.x.size() && k < c.y.size(); ++k)
        if (std::isfinite(c.x[k]) && std::isfinite(c.y[k]))
          s << "<circle cx=\"" << px(X(c.x[k])) << "\" cy=\"" << px(Y(c.y[k])) << "\" r=\"3.5\"/>";
      s << "</g>\n";
      continue;
    }
    s << "<polyline data-curve=\"" << html_escape(c.name) << "\" fill=\"none\" stroke=\"" << colour(i)
      << "\" stroke-width=\"" << width_of(i) << "\" stroke-linejoin=\"round\" points=\"";
    bool first = true;
    for (std::size_t k = 0; k < c.x.size() && k < c.y.size(); ++k) {
      if (!std::isfinite(c.x[k]) || !std::isfinite(c.y[k])) continue;
      s << (first ? "" : " ") << px(X(c.x[k])) << "," << px(Y(c.y[k]));
      first = false;
    }
    s << "\"/>\n";
  }
  // Legend, top left inside the area.
  for (std::size_t i = 0; i < n; ++i) {
    const double y = kTop + 14 + 15 * static_cast<double>(i);
    s << "<line x1=\"" << px(kLeft + 8) << "\" x2=\"" << px(kLeft + 34) << "\" y1=\"" << px(y) << "\" y2=\"" << px(y)
      << "\" stroke=\"" << colour(i) << "\" stroke-width=\"" << (curves[i].points ? 6.0 : width_of(i)) << "\"/><text x=\"" << px(kLeft + 40)
      << "\" y=\"" << px(y + 4) << "\">" << html_escape(curves[i].name) << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

}  // namespace calbench::report
