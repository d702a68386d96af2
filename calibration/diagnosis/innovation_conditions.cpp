#include "calibration/diagnosis/innovation_conditions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace calbench {

namespace {

struct Epoch {
  double v = 0;  // NIS/3
  double speed = 0, turn = 0, accel = 0;
  bool standstill = false, start = false;
};

ConditionBin make_bin(const std::string& label, const std::vector<const Epoch*>& e, double lo, double hi) {
  ConditionBin b;
  b.label = label;
  b.lo = lo;
  b.hi = hi;
  b.epochs = static_cast<long>(e.size());
  if (e.empty()) return b;
  double s = 0;
  for (const Epoch* p : e) s += p->v;
  b.nis_per_dof = s / static_cast<double>(e.size());
  double ss = 0;
  for (const Epoch* p : e) ss += (p->v - b.nis_per_dof) * (p->v - b.nis_per_dof);
  b.var = e.size() > 1 ? ss / static_cast<double>(e.size() - 1) : 0.0;
  return b;
}

// Lag-1 autocorrelation of the NIS of the epochs one breakdown bins, in time order, each less its
// bin's mean (so that the step between the bins' levels is not read as correlation); clamped to
// [0, 0.95]. bin_of[i]: the bin of epoch i, −1 when not binned.
double lag1(const std::vector<Epoch>& e, const std::vector<int>& bin_of, const std::vector<ConditionBin>& bins) {
  std::vector<double> r;
  for (std::size_t i = 0; i < e.size(); ++i)
    if (bin_of[i] >= 0) r.push_back(e[i].v - bins[static_cast<std::size_t>(bin_of[i])].nis_per_dof);
  if (r.size() < 3) return 0;
  double num = 0, den = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    den += r[i] * r[i];
    if (i) num += r[i] * r[i - 1];
  }
  return den > 0 ? std::clamp(num / den, 0.0, 0.95) : 0.0;
}

struct Comparison {
  int reference = -1, grown = -1;
  double ratio = 1, z = 0;
  bool grows = false;
};

// Bin `g` against bin `r`: ratio and z with the effective sample sizes.
Comparison compare(const ConditionBreakdown& b, int r, int g, double rho, const ConditionOptions& opt) {
  Comparison c;
  const ConditionBin &R = b.bins[static_cast<std::size_t>(r)], &G = b.bins[static_cast<std::size_t>(g)];
  if (R.epochs < opt.min_bin_epochs || G.epochs < opt.min_bin_epochs || !(R.nis_per_dof > 0)) return c;
  const double f = (1 - rho) / (1 + rho);
  const double se = std::sqrt(R.var / std::max(1.0, R.epochs * f) + G.var / std::max(1.0, G.epochs * f));
  c.reference = r;
  c.grown = g;
  c.ratio = G.nis_per_dof / R.nis_per_dof;
  c.z = se > 0 ? (G.nis_per_dof - R.nis_per_dof) / se : 0.0;
  c.grows = c.ratio >= opt.grow_ratio && c.z >= opt.grow_z;
  return c;
}

// The comparisons (reference, grown) of a breakdown: the one reported is a growing one if any
// (the most significant of those), else the most significant.
void decide(ConditionBreakdown& b, const std::vector<std::pair<int, int>>& pairs, double rho, const ConditionOptions& opt) {
  Comparison best;
  for (const auto& [r, g] : pairs) {
    const Comparison c = compare(b, r, g, rho, opt);
    if (c.grown < 0) continue;
    if (best.grown < 0 || (c.grows && !best.grows) || (c.grows == best.grows && c.z > best.z)) best = c;
  }
  b.reference = best.reference;
  b.grown = best.grown;
  b.ratio = best.ratio;
  b.z = best.z;
  b.grows = best.grows;
}

ConditionBreakdown terciles(const char* name, const std::vector<Epoch>& all, const std::vector<std::size_t>& moving,
                            double Epoch::*field, const ConditionOptions& opt) {
  ConditionBreakdown b;
  b.condition = name;
  std::vector<std::size_t> idx = moving;
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t c) { return all[a].*field < all[c].*field; });
  std::vector<int> bin_of(all.size(), -1);
  const std::size_t n = idx.size();
  const char* labels[3] = {"low", "mid", "high"};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t i0 = n * k / 3, i1 = n * (k + 1) / 3;
    std::vector<const Epoch*> part;
    for (std::size_t i = i0; i < i1; ++i) {
      part.push_back(&all[idx[i]]);
      bin_of[idx[i]] = static_cast<int>(k);
    }
    const double lo = part.empty() ? 0.0 : part.front()->*field, hi = part.empty() ? 0.0 : part.back()->*field;
    b.bins.push_back(make_bin(labels[k], part, lo, hi));
  }
  decide(b, {{0, 2}}, lag1(all, bin_of, b.bins), opt);
  return b;
}

}  // namespace

std::vector<ConditionBreakdown> innovation_conditions(const std::vector<InnovationSample>& x, const ConditionOptions& opt) {
  // Standstill and motion with hysteresis (a speed between the two thresholds keeps the state), and
  // the start of motion only after a standstill of at least min_standstill_s (not a dip of the
  // filter's speed while moving).
  std::vector<Epoch> e;
  double moving_since = -1e300, still_since = -1e300;
  bool still = true, first = true;
  for (const InnovationSample& s : x) {
    if (first) {
      still = s.speed < opt.moving_speed;
      still_since = s.t;
      first = false;
    } else if (still && s.speed >= opt.moving_speed) {
      still = false;
      if (s.t - still_since >= opt.min_standstill_s) moving_since = s.t;
    } else if (!still && s.speed < opt.standstill_speed) {
      still = true;
      still_since = s.t;
    }
    if (s.status == 1 || !std::isfinite(s.nis)) continue;
    Epoch p;
    p.v = s.nis / 3.0;
    p.speed = s.speed;
    p.turn = std::abs(s.turn_rate);
    p.accel = s.accel;
    p.standstill = still;
    p.start = !still && s.t - moving_since < opt.start_of_motion_s;
    e.push_back(p);
  }
  std::vector<const Epoch*> st, start, mv;
  std::vector<std::size_t> moving;
  std::vector<int> bin_of(e.size(), -1);
  for (std::size_t i = 0; i < e.size(); ++i) {
    const Epoch& p = e[i];
    const int b = p.standstill ? 1 : p.start ? 2 : 0;
    (b == 1 ? st : b == 2 ? start : mv).push_back(&p);
    if (b == 0) moving.push_back(i);
    bin_of[i] = b;
  }
  std::vector<ConditionBreakdown> out;
  ConditionBreakdown m;
  m.condition = "motion";
  m.bins = {make_bin("moving", mv, 0, 0), make_bin("standstill", st, 0, 0), make_bin("start of motion", start, 0, 0)};
  // moving against standstill, standstill against moving, start of motion against moving
  decide(m, {{1, 0}, {0, 1}, {0, 2}}, lag1(e, bin_of, m.bins), opt);
  out.push_back(m);
  out.push_back(terciles("speed", e, moving, &Epoch::speed, opt));
  out.push_back(terciles("turn rate", e, moving, &Epoch::turn, opt));
  out.push_back(terciles("acceleration", e, moving, &Epoch::accel, opt));
  return out;
}

std::string growing_conditions_text(const std::vector<ConditionBreakdown>& b) {
  std::string s;
  for (const ConditionBreakdown& c : b) {
    if (!c.grows) continue;
    char buf[240];
    const ConditionBin &g = c.bins[static_cast<std::size_t>(c.grown)], &r = c.bins[static_cast<std::size_t>(c.reference)];
    const std::string what = c.condition == "motion" ? g.label : c.condition;
    const std::string gl = c.condition == "motion" ? g.label : g.label + " " + c.condition;
    const std::string rl = c.condition == "motion" ? r.label : r.label + " " + c.condition;
    std::snprintf(buf, sizeof buf, "%s%s x%.2g (NIS/dof %.2g %s against %.2g %s, z %.2g%s)", s.empty() ? "" : "; ", what.c_str(),
                  c.ratio, g.nis_per_dof, gl.c_str(), r.nis_per_dof, rl.c_str(), c.z,
                  r.nis_per_dof < 0.5 ? ": the reference is far below 1" : "");
    s += buf;
  }
  return s;
}

}  // namespace calbench
