// ΔS(t) from the QC run into RESULT.json (decimated series) and onto the report page (inline SVG),
// and the report's number formats.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "bench/drive/qc_drive.hpp"
#include "bench/report/html_parts.hpp"
#include "bench/report/svg_plot.hpp"

namespace calbench {
namespace {

QcCurve quadratic(double horizon_s, double dt) {
  QcCurve c{"set", {}, {}};
  for (double t = dt; t <= horizon_s + 1e-9; t += dt) {
    c.t.push_back(t);
    c.cpe.push_back(1e-3 * t * t);
  }
  return c;
}

TEST(QcSeries, OneSecondSpacingOverTheWholeHorizonAndAtMost3600PointsBeyondAnHour) {
  for (double horizon : {81.22, 600.0, 7200.0}) {
    QcOutcome q;
    q.horizon_s = horizon;
    q.curves.push_back(quadratic(horizon, 0.02));
    const auto s = qc_json(q)["sets"][0]["cpe_series"];
    const auto& t = s["t_s"];
    const auto& v = s["cpe_m"];
    ASSERT_EQ(t.size(), v.size());
    const double step = std::max(1.0, horizon / 3600);
    EXPECT_LE(t.size(), 3602u) << horizon;
    EXPECT_GE(t.size(), static_cast<std::size_t>(horizon / step)) << horizon;
    EXPECT_NEAR(t.front().get<double>(), 0.02, 1e-9);
    EXPECT_NEAR(t.back().get<double>(), q.curves[0].t.back(), 1e-3) << "the last epoch is always kept";
    EXPECT_NEAR(v.back().get<double>(), q.curves[0].cpe.back(), 1e-4);
    for (std::size_t k = 1; k < t.size(); ++k) {
      const double d = t[k].get<double>() - t[k - 1].get<double>();
      ASSERT_GT(d, 0);
      ASSERT_LE(d, step + 0.02 + 1e-6) << horizon << " at " << k;
    }
  }
}

TEST(ReportSvg, EveryFinitePointIsPlottedAndNamesAreEscaped) {
  report::PlotCurve a{"input <bench>", {0, 1, 2, NAN, 4}, {0, 1, 4, 9, 16}};
  report::PlotCurve b{"in-motion", {0, 1, 2, 3, 4}, {0, 0.1, 0.4, 0.9, 1.6}};
  report::PlotSpec p;
  p.title = "ΔS";
  p.x_label = "t [s]";
  p.y_label = "ΔS [m]";
  p.css_class = "cpe";
  for (bool log : {false, true}) {
    p.log_y = log;
    const std::string svg = report::svg_line_plot({a, b}, p);
    const std::regex line("<polyline data-curve=\"([^\"]*)\"[^>]*points=\"([^\"]*)\"");
    std::vector<std::pair<std::string, std::size_t>> found;
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), line); it != std::sregex_iterator(); ++it) {
      const std::string pts = (*it)[2];
      found.emplace_back((*it)[1], static_cast<std::size_t>(std::count(pts.begin(), pts.end(), ',')));
    }
    ASSERT_EQ(found.size(), 2u);
    EXPECT_EQ(found[0], std::make_pair(std::string("input &lt;bench&gt;"), std::size_t{4}));
    EXPECT_EQ(found[1].second, 5u);
    EXPECT_NE(svg.find("class=\"area\""), std::string::npos);
  }
}

TEST(ReportFormat, NumbersInDisplayUnits) {
  EXPECT_EQ(report::num(2000.0), "2000");
  EXPECT_EQ(report::num(-11724.94), "-11725");
  EXPECT_EQ(report::num(0.05274, 4), "0.05274");
  EXPECT_EQ(report::num(3.1e-6, 2), "3.1e-06");
  EXPECT_EQ(report::num(NAN), "–");
  EXPECT_EQ(report::pm(-685.31, 3.62, 1.0), "-685.3 ± 3.6");
  EXPECT_EQ(report::pm(-11724.94, 9.1, 1.0), "-11724.9 ± 9.1");
  EXPECT_EQ(report::pm(-1577.3, 1117.6, 1.0), "-1577 ± 1100");
  EXPECT_EQ(report::pm(2e-3, 1e-5, 1e6), "2000 ± 10");
}

}  // namespace
}  // namespace calbench
