// Line plots as inline SVG for the HTML reports: the curves stay data in the page (a browser, a
// test or a reader can count and inspect every plotted point), print sharply and need no program.
// Earlier curves are drawn wider underneath later ones, so a curve that coincides with a later
// one still shows as a border around it instead of disappearing.
#pragma once
#include <string>
#include <vector>

namespace calbench::report {

struct PlotCurve {
  std::string name;
  std::vector<double> x, y;  // same length; non-finite points are left out
  std::vector<double> err;   // optional: ±err bars at each point (same length as y)
  bool points = false;       // markers only (a circle per point, no line), e.g. outliers
  std::string colour;        // "" : the plot's palette by curve order
};

struct PlotSpec {
  std::string title, x_label, y_label;  // labels carry their unit, e.g. "ΔS [m]"
  double x_min = 0, x_max = 0;          // x_max <= x_min: the data's range
  bool log_y = false;                   // log10 axis; values at or below its floor sit on the floor
  int width = 560, height = 330;
  std::string css_class;                // class of the <svg> element
};

// <svg> text; each curve is one <polyline data-curve="NAME">, the plot area one <rect class="area">.
std::string svg_line_plot(const std::vector<PlotCurve>& curves, const PlotSpec& spec);

}  // namespace calbench::report
