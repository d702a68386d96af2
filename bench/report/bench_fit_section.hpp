// The device report's bench-fit residuals (issue 35 item 5): from the set's stored coefficients.json
// "fit_quality" (common/fit_quality.hpp), the χ²/dof of every triad axis, the largest systematic
// residual per kind of step against the approval's limits, and the mean residual of every step
// plotted (inline SVG, °/h and mg) with the limits.
#pragma once
#include <string>

#include "db/approval.hpp"

namespace calbench::report {

std::string bench_fit_part(const db::CoefficientSetRecord& set, const db::Thresholds& t);

}  // namespace calbench::report
