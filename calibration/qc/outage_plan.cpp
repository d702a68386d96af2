#include "calibration/qc/outage_plan.hpp"

#include <algorithm>
#include <cstdio>

namespace calbench::qc {

namespace {
std::string seconds(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f s", v);
  return b;
}

// First eligible epoch at or after `from` (t.size(): none).
std::size_t first_eligible(const std::vector<double>& t, const std::vector<bool>& eligible, double from) {
  std::size_t k = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), from - 1e-9) - t.begin());
  while (k < t.size() && !eligible[k]) ++k;
  return k;
}
}  // namespace

OutagePlan plan_outages(const std::vector<double>& t, const std::vector<bool>& eligible, double t_end, const OutageRequest& req) {
  OutagePlan plan;
  std::vector<double> seq;
  for (int c = 0; c < req.count; ++c)
    for (double L : req.lengths_s) seq.push_back(L);
  const std::size_t a_idx = first_eligible(t, eligible, req.earliest_s);
  if (a_idx >= t.size()) {
    for (double L : seq)
      plan.not_placed.push_back({L, "no epoch where the aided filter had converged while moving" +
                                        std::string(req.earliest_s > -1e299 ? " after " + seconds(req.earliest_s) : "")});
    return plan;
  }
  const double a = t[a_idx], span = t_end - a;
  auto need = [&](std::size_t n) {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += seq[i];
    return s + (n > 1 ? static_cast<double>(n - 1) * req.gap_s : 0.0);
  };
  std::size_t n = seq.size();
  while (n > 0 && need(n) > span + 1e-9) --n;
  for (std::size_t i = n; i < seq.size(); ++i)
    plan.not_placed.push_back({seq[i], "no room: " + seconds(need(i + 1)) + " of outages and gaps needed, " + seconds(span) +
                                           " from the first converged moving epoch (" + seconds(a) + ") to the last fix"});
  const double extra = n > 0 ? (span - need(n)) / static_cast<double>(n + 1) : 0.0;
  double planned = a + extra, prev_end = -1e300;
  for (std::size_t i = 0; i < n; ++i) {
    const double L = seq[i];
    const std::size_t k = first_eligible(t, eligible, std::max(planned, prev_end + req.gap_s));
    planned += L + req.gap_s + extra;
    if (k >= t.size() || t[k] + L > t_end + 1e-9) {
      plan.not_placed.push_back({L, "no converged moving epoch early enough to end by the last fix (" + seconds(t_end) + ")"});
      continue;
    }
    plan.outages.push_back({t[k], L, k});
    prev_end = t[k] + L;
  }
  return plan;
}

}  // namespace calbench::qc
