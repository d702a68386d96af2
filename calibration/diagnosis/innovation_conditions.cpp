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

// Lag-1 autocorrelation of the NIS series (time order), clamped to [0, 0.95].
double lag1(const std::vector<Epoch>& e) {
  const std::size_t n = e.size();
  if (n < 3) return 0;
  double m = 0;
  for (const Epoch& x : e) m += x.v;
  m /= static_cast<double>(n);
  double num = 0, den = 0;
  for (std::size_t i = 0; i < n; ++i) {
    den += (e[i].v - m) * (e[i].v - m);
    if (i) num += (e[i].v - m) * (e[i - 1].v - m);
  }
  return den > 0 ? std::clamp(num / den, 0.0, 0.95) : 0.0;
}

// Bin `g` against bin `r`: ratio and z with the effective sample sizes.
void compare(ConditionBreakdown& b, int r, int g, double rho, const ConditionOptions& opt) {
  const ConditionBin &R = b.bins[static_cast<std::size_t>(r)], &G = b.bins[static_cast<std::size_t>(g)];
  if (R.epochs < opt.min_bin_epochs || G.epochs < opt.min_bin_epochs || !(R.nis_per_dof > 0)) return;
  const double f = (1 - rho) / (1 + rho);
  const double se = std::sqrt(R.var / std::max(1.0, R.epochs * f) + G.var / std::max(1.0, G.epochs * f));
  const double ratio = G.nis_per_dof / R.nis_per_dof;
  const double z = se > 0 ? (G.nis_per_dof - R.nis_per_dof) / se : 0.0;
  if (b.grown >= 0 && !(z > b.z)) return;
  b.reference = r;
  b.grown = g;
  b.ratio = ratio;
  b.z = z;
  b.grows = ratio >= opt.grow_ratio && z >= opt.grow_z;
}

ConditionBreakdown terciles(const char* name, std::vector<const Epoch*> moving, double Epoch::*field, double rho,
                            const ConditionOptions& opt) {
  ConditionBreakdown b;
  b.condition = name;
  std::sort(moving.begin(), moving.end(), [&](const Epoch* a, const Epoch* c) { return a->*field < c->*field; });
  const std::size_t n = moving.size();
  const char* labels[3] = {"low", "mid", "high"};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t i0 = n * k / 3, i1 = n * (k + 1) / 3;
    std::vector<const Epoch*> part(moving.begin() + static_cast<long>(i0), moving.begin() + static_cast<long>(i1));
    const double lo = part.empty() ? 0.0 : part.front()->*field, hi = part.empty() ? 0.0 : part.back()->*field;
    b.bins.push_back(make_bin(labels[k], part, lo, hi));
  }
  compare(b, 0, 2, rho, opt);
  return b;
}

}  // namespace

std::vector<ConditionBreakdown> innovation_conditions(const std::vector<InnovationSample>& x, const ConditionOptions& opt) {
  std::vector<Epoch> e;
  double moving_since = -1e300;
  bool still = true;
  for (const InnovationSample& s : x) {
    const bool standstill = s.speed < opt.standstill_speed;
    if (!standstill && still) moving_since = s.t;
    still = standstill;
    if (s.status == 1 || !std::isfinite(s.nis)) continue;
    Epoch p;
    p.v = s.nis / 3.0;
    p.speed = s.speed;
    p.turn = std::abs(s.turn_rate);
    p.accel = s.accel;
    p.standstill = standstill;
    p.start = !standstill && s.t - moving_since < opt.start_of_motion_s;
    e.push_back(p);
  }
  const double rho = lag1(e);
  std::vector<const Epoch*> st, start, moving;
  for (const Epoch& p : e) (p.standstill ? st : p.start ? start : moving).push_back(&p);
  std::vector<ConditionBreakdown> out;
  ConditionBreakdown m;
  m.condition = "motion";
  m.bins = {make_bin("moving", moving, 0, 0), make_bin("standstill", st, 0, 0), make_bin("start of motion", start, 0, 0)};
  compare(m, 1, 0, rho, opt);  // moving against standstill
  compare(m, 0, 1, rho, opt);  // standstill against moving
  compare(m, 0, 2, rho, opt);  // start of motion against moving
  out.push_back(m);
  out.push_back(terciles("speed", moving, &Epoch::speed, rho, opt));
  out.push_back(terciles("turn rate", moving, &Epoch::turn, rho, opt));
  out.push_back(terciles("acceleration", moving, &Epoch::accel, rho, opt));
  return out;
}

std::string growing_conditions_text(const std::vector<ConditionBreakdown>& b) {
  std::string s;
  for (const ConditionBreakdown& c : b) {
    if (!c.grows) continue;
    char buf[160];
    const std::string what = c.condition == "motion" ? c.bins[static_cast<std::size_t>(c.grown)].label : c.condition;
    std::snprintf(buf, sizeof buf, "%s%s x%.2g (z %.2g)", s.empty() ? "" : ", ", what.c_str(), c.ratio, c.z);
    s += buf;
  }
  return s;
}

}  // namespace calbench
