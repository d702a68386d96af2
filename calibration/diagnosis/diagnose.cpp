#include "calibration/diagnosis/diagnose.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "calibration/diagnosis/bench_design.hpp"
#include "calibration/diagnosis/condition_correlation.hpp"
#include "calibration/diagnosis/greedy_search.hpp"
#include "calibration/diagnosis/residual_stats.hpp"
#include "common/units.hpp"

// The bench side of the diagnosis: the design and its datasets come from bench_design.cpp, the
// linear problem from diagnosis_engine.cpp; here the bench's residual statistics (systematic RMS
// per step and table angle), the catalogue search and the report of its findings.

namespace calbench {

namespace {

using namespace bench_diag;

// The bench as a problem of the catalogue search (greedy_search.hpp): parameters [24 base | model
// terms in model order]; a term's penalty counts the parent and sub-block rows of the axes it
// touches, correlated_drift's the parent rows.
struct BenchProblem {
  using Dataset = bench_diag::Dataset;
  using Fit = FitOut;
  const DiagData& d;
  const Design& D;
  const DiagnoseOptions& opt;
  int n_terms() const { return static_cast<int>(D.terms.size()); }
  const Term& term(int t) const { return D.terms[t]; }
  Dataset build(int a, int subset, double ds, double tau) const { return build_dataset(d, D, a, subset, ds, tau, opt); }
  Fit fit(const Model& m, const std::vector<const Dataset*>& sets) const { return fit_model(D, m, sets); }
  double chi2(const Dataset& S, const Model& m, const Fit& f) const {
    std::vector<int> off;
    return diag::quadratic_chi2(S.G, S.g, S.zz, column_map(D, m, S.axis, off), f.theta);
  }
  bool touches(int t, int a) const { return D.col_of[a][t] >= 0; }
  int rows(const Dataset& S) const { return S.n_low + S.n_high; }
  int drift_rows(const Dataset& S) const { return S.n_low; }
  int param_index(const Fit& f, std::size_t k, int /*t*/) const { return f.offset[k]; }
};

// The drift as the noise model sees it in a sub-block residual series (of its parent means).
Eigen::VectorXd smoothed_drift(const DiagData& d, const Dataset& S, const Eigen::VectorXd& r) {
  return diag::smoothed_drift(d.parents, S, parent_means(d, S, r));
}

// An orthonormal basis of the span of axis S.axis's design columns `cols` at the parent level
// (their parent means), whitened by the residual's Cholesky factor: what a GLS fit of those columns
// removes from a whitened parent residual.
Eigen::MatrixXd whitened_column_basis(const DiagData& d, const Design& D, const Dataset& S, const std::vector<int>& cols) {
  const int N = static_cast<int>(S.parents.size());
  Eigen::MatrixXd X(N, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c)
    X.col(static_cast<Eigen::Index>(c)) = parent_means(d, S, D.X[S.axis].col(cols[c]));
  X = S.L.triangularView<Eigen::Lower>().solve(X);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qx(X);
  qx.setThreshold(1e-9);
  return qx.householderQ() * Eigen::MatrixXd::Identity(N, qx.rank());
}

// Issue 36, the remainder's power: one offset per plan step (AxisStats::step_q), for the three
// families of steps. The indicators and the model's columns (parent means) are whitened by the
// residual's Cholesky factor; the indicators' part outside the columns' span is what the test
// projects on, so its rank is the exact number of degrees of freedom.
void step_offset_test(const DiagData& d, const Design& D, const Dataset& S, const Eigen::VectorXd& rw,
                      const std::vector<int>& cols, AxisStats& st) {
  const int N = static_cast<int>(S.parents.size());
  const auto Lt = S.L.triangularView<Eigen::Lower>();
  const Eigen::MatrixXd Qx = whitened_column_basis(d, D, S, cols);
  // A step is static when none of its parent blocks turns (|ω| ≤ 1 °/s: the Earth rate only).
  std::map<int, bool> turns;
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    turns[pb.step] = turns[pb.step] || pb.w.norm() > 0.0174533;
  }
  static const char* const kFamily[3] = {"all", "static", "rotating"};
  st.step_p = 1;
  for (int fam = 0; fam < 3; ++fam) {
    std::map<int, int> col;
    for (const auto& [step, t] : turns)
      if (fam == 0 || (fam == 1) != t) col.emplace(step, static_cast<int>(col.size()));
    const int ns = static_cast<int>(col.size());
    if (ns < 2 || N <= ns) continue;
    Eigen::MatrixXd U = Eigen::MatrixXd::Zero(N, ns);
    for (int k = 0; k < N; ++k) {
      const auto it = col.find(d.parents[S.parents[k]].step);
      if (it != col.end()) U(k, it->second) = 1.0;
    }
    U = Lt.solve(U);
    U -= Qx * (Qx.transpose() * U);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qu(U);
    qu.setThreshold(1e-6);
    const int dof = static_cast<int>(qu.rank());
    if (dof < 1) continue;
    const Eigen::MatrixXd Qu = qu.householderQ() * Eigen::MatrixXd::Identity(N, dof);
    const double q = (Qu.transpose() * rw).squaredNorm();
    const double p = std::min(1.0, 3.0 * chi2_upper_p(q, dof));
    if (fam == 0 || p < st.step_p) {
      st.step_q = q;
      st.step_dof = dof;
      st.step_p = p;
      st.step_family = kFamily[fam];
    }
  }
}

// Statistics of a residual series on one axis (dataset gives the noise model). The systematic
// figure removes `drift` (parent level) when given, else the drift smoothed from r itself. The
// before figure is given the drift smoothed from the final residual: smoothed from the base
// model's own residual the drift would absorb a slow effect (a temperature ramp, 1–2 mg over a
// chamber cycle) and hide it from the before figure; one drift estimate keeps before and after
// comparable.
AxisStats axis_stats(const DiagData& d, const Design& D, const Dataset& S, const Eigen::VectorXd& r, const Model& m,
                     const Eigen::VectorXd* drift_given = nullptr) {
  const int nparams = model_params(D, m);
  std::vector<int> offset, cols;
  for (const auto& [c, p] : column_map(D, m, S.axis, offset)) cols.push_back(c);
  AxisStats st;
  const int a = S.axis;
  const int N = static_cast<int>(S.parents.size());
  const Eigen::VectorXd rP = parent_means(d, S, r);
  const Eigen::VectorXd rw = diag::whiteness(S, rP, nparams, st);
  step_offset_test(d, D, S, rw, cols, st);
  // Drift as the noise model sees it (smoothed), to be removed from the systematic figure.
  const Eigen::VectorXd drift = drift_given ? *drift_given : smoothed_drift(d, S, r);
  // Per-step means (drift removed, white noise expectation subtracted).
  std::map<int, std::array<double, 3>> steps;  // step → Σn·r, Σn, duration
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    auto& acc = steps[pb.step];
    acc[0] += pb.n * (rP(k) - drift(k));
    acc[1] += pb.n;
    acc[2] += pb.duration;
  }
  double ms = 0, wt = 0;
  for (const auto& [step, acc] : steps) {
    const double m = acc[0] / acc[1];
    ms += acc[2] * (m * m - D.white_var[a] / acc[1]);
    wt += acc[2];
  }
  st.step_rms = std::sqrt(std::max(0.0, ms / std::max(wt, 1e-9)));
  // Within steps: deviations from the parent mean, binned by table angle (12 bins per step) for
  // rotating steps; sub-block χ² for the rest.
  double hi_chi2 = 0;
  int hi_n = 0;
  std::map<int, std::array<std::array<double, 3>, 12>> bins;  // step → bin → Σn·dev, Σn, Σ expected var·n²
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    if (pb.count < 2) continue;
    for (int j = pb.first; j < pb.first + pb.count; ++j) {
      const SubBlock& s = d.subs[j];
      const double dev = r(j) - rP(k);
      const double var = D.white_var[a] / s.n * (1.0 - static_cast<double>(s.n) / pb.n);
      if (var <= 0) continue;
      hi_chi2 += dev * dev / var;
      ++hi_n;
      if (s.rotating() && std::isfinite(s.angle)) {
        double u = std::fmod(s.angle, 2 * M_PI);
        if (u < 0) u += 2 * M_PI;
        const int b = std::min(11, static_cast<int>(u / (2 * M_PI) * 12));
        auto& bb = bins[pb.step][b];
        bb[0] += s.n * dev;
        bb[1] += s.n;
        bb[2] += var * s.n * s.n;
      }
    }
  }
  st.high_chi2_dof = hi_n > 0 ? hi_chi2 / hi_n : 0;
  double wms = 0, wwt = 0;
  for (const auto& [step, bs] : bins) {
    double sms = 0, sn = 0;
    for (const auto& bb : bs) {
      if (bb[1] <= 0) continue;
      const double m = bb[0] / bb[1];
      sms += bb[1] * (m * m - bb[2] / (bb[1] * bb[1]));
      sn += bb[1];
    }
    if (sn > 0) {
      wms += sms;
      wwt += sn;
    }
  }
  st.within_rms = std::sqrt(std::max(0.0, wwt > 0 ? wms / wwt : 0.0));
  st.systematic_rms = std::hypot(st.step_rms, st.within_rms);
  // The same bins as a test: the table-angle profile summed over the steps, against white noise
  // (where in the angle the structure sits).
  std::array<double, 12> prof{}, prof_var{}, prof_n{};
  for (const auto& [step, bs] : bins)
    for (int b = 0; b < 12; ++b) {
      const auto& bb = bs[static_cast<std::size_t>(b)];
      if (bb[1] <= 0 || bb[2] <= 0) continue;
      prof[b] += bb[0];
      prof_var[b] += bb[2];
      prof_n[b] += bb[1];
    }
  double prof_chi2 = 0;
  int prof_dof = 0;
  for (int b = 0; b < 12; ++b)
    if (prof_var[b] > 0) {
      prof_chi2 += prof[b] * prof[b] / prof_var[b];
      ++prof_dof;
    }
  st.angle_profile_p = prof_dof > 0 ? chi2_upper_p(prof_chi2, prof_dof) : 1.0;
  for (int b = 0; b < 12; ++b)
    if (prof_var[b] > 0 && std::abs(prof[b]) / std::sqrt(prof_var[b]) > std::abs(st.worst_angle_bin_z)) {
      st.worst_angle_bin_z = prof[b] / std::sqrt(prof_var[b]);
      st.worst_angle_bin = b;
      st.worst_angle_bin_mean = prof[b] / prof_n[b];
    }
  st.bic = rw.squaredNorm() + S.logdet + nparams / static_cast<double>(kAxes) * std::log(std::max(N, 2));
  return st;
}

const char* revealing_condition(EffectId e) { return effect_spec(e).condition; }

// Axis a finding is reported on: a lever arm with one dominant component on that component.
void report_axis_of(const Term& t, DiagFinding& f) {
  if (effect_spec(t.effect).dominant_component) {
    int imax = 0;
    for (int i = 1; i < 3; ++i)
      if (std::abs(f.value[i]) > std::abs(f.value[imax])) imax = i;
    double others = 0;
    for (int i = 0; i < 3; ++i)
      if (i != imax) others = std::max(others, std::abs(f.value[i]));
    f.report_axis = others < 0.3 * std::abs(f.value[imax]) ? imax : -1;
  }
}

// Systematic residual before/after of the axes a finding touches (its own axis when it has one;
// lever arm and reference terms: the worst-affected touched axis).
void finding_rms(const Term& t, const std::vector<int>& touched, const DiagnoseResult& res, DiagFinding& f) {
  double rb = 0, ra = 0;
  int n = 0;
  for (int a : touched) {
    if (t.sensor < 2 && f.report_axis >= 0 && !effect_spec(t.effect).dominant_component && a != t.sensor * 3 + t.axis) continue;
    rb += std::pow(res.before[a].systematic_rms, 2);
    ra += std::pow(res.after[a].systematic_rms, 2);
    ++n;
  }
  if (effect_spec(t.effect).dominant_component || t.sensor == 2) {
    // Report the worst-affected touched axis (largest systematic before).
    double worst = -1;
    for (int a : touched)
      if (res.before[a].systematic_rms > worst) {
        worst = res.before[a].systematic_rms;
        rb = worst * worst;
        ra = std::pow(res.after[a].systematic_rms, 2);
        n = 1;
      }
  }
  f.rms_before = n ? std::sqrt(rb / n) : 0;
  f.rms_after = n ? std::sqrt(ra / n) : 0;
}

// The step-offset test's level per axis (docs/diagnosis.md, "Decision rules": its false-alarm rate).
constexpr double kStepOffsetP = 1e-4;

// Is an axis's final residual still far from its noise model? Parent-level or sub-block χ²/dof
// beyond 6σ of its sampling spread, Ljung–Box p < 1e-4, or structure in the table angle: the
// residual's angle profile (12 bins summed over the rotating steps) with χ² p < 1e-6.
// `parent_level`: only the criteria the drift model covers (parent-level χ², whiteness, angle
// profile); the sub-block χ² is white noise only, which a large drift itself inflates.
bool axis_unexplained(const AxisStats& s, const Dataset& S, bool parent_level = false) {
  const double z_low = (s.chi2_dof - 1) * std::sqrt(std::max(1, S.n_low) / 2.0);
  const double z_high = (s.high_chi2_dof - 1) * std::sqrt(std::max(1, S.n_high) / 2.0);
  return z_low >= 6 || (!parent_level && z_high >= 6) || s.ljung_box_p <= 1e-4 || s.angle_profile_p < 1e-6 ||
         s.step_p < kStepOffsetP;
}

// The condition that reveals a finding (g-sensitivity: the force component it follows most).
void finding_condition(const Term& t, DiagFinding& f) {
  f.condition = revealing_condition(t.effect);
  if (effect_spec(t.effect).condition_by_column) {
    int jmax = 0;
    for (int j = 1; j < 3; ++j)
      if (std::abs(f.value[j]) > std::abs(f.value[jmax])) jmax = j;
    f.condition = std::string("f_") + "xyz"[jmax];
  }
}

// What the drift model absorbed on axis a (DiagDriftExcess): the smoothed drift path under the class's
// noise model in the final residual, its tie to temperature, and whether a larger drift of that axis
// alone (on the drift grid, the other axes as they are) fits better.
DiagDriftExcess drift_excess(const BenchProblem& P, const GreedySearch<BenchProblem>& search, int a, double sigma0) {
  DiagDriftExcess x;
  x.sensor = a / 3;
  x.axis = a % 3;
  x.stability = sigma0;
  const Dataset& S0 = search.all[a];
  const Eigen::VectorXd path = smoothed_drift(P.d, S0, residual(P.D, search.model, a, search.cur.theta));
  x.change = path.maxCoeff() - path.minCoeff();
  if (x.change <= kDriftExcessFactor * sigma0 && !P.d.has_temperature) return x;
  // The range's null distribution: parent residuals drawn from the noise model (white, drift, bench
  // errors: r = L·n), smoothed the same way. The fitted bias and scale columns are not projected
  // out of the draws, which widens it a little (conservative). A fixed seed: the same recording
  // gives the same report.
  const int N = static_cast<int>(S0.parents.size());
  std::mt19937_64 rng(0x36d1f7u + static_cast<unsigned>(a));
  std::normal_distribution<double> n01;
  double m1 = 0, m2 = 0;
  int reach = 0;
  for (int i = 0; i < kDriftExcessDraws; ++i) {
    Eigen::VectorXd n(N);
    for (int k = 0; k < N; ++k) n(k) = n01(rng);
    const Eigen::VectorXd rP = S0.L.triangularView<Eigen::Lower>() * n;
    const Eigen::VectorXd q = diag::smoothed_drift(P.d.parents, S0, rP);
    const double range = q.maxCoeff() - q.minCoeff();
    reach += range >= x.change;
    m1 += range;
    m2 += range * range;
  }
  m1 /= kDriftExcessDraws;
  const double sd = std::sqrt(std::max(m2 / kDriftExcessDraws - m1 * m1, 1e-300));
  x.null_mean = m1;
  x.null_sd = sd;
  x.z = (x.change - m1) / sd;
  x.null_exceed_count = reach;
  auto fit_with = [&](const Dataset& S) {
    std::vector<const Dataset*> p;
    for (int b = 0; b < kAxes; ++b) p.push_back(b == a ? &S : &search.all[b]);
    return P.fit(search.model, p);
  };
  const double base = search.cur.chi2_axis[a] + S0.logdet;
  x.gain = -std::numeric_limits<double>::infinity();
  for (double m : greedy_drift_multipliers())
    for (double t : greedy_drift_taus()) {
      const Dataset S = P.build(a, kSubsetAll, sigma0 * m, t);
      const double gain = base - (fit_with(S).chi2_axis[a] + S.logdet);
      if (gain > x.gain) {
        x.gain = gain;
        x.sigma = sigma0 * m;
        x.tau_s = t;
      }
    }
  if (!P.d.has_temperature) return x;
  Eigen::VectorXd T(N);
  for (int k = 0; k < N; ++k) T(k) = P.d.parents[S0.parents[k]].temp_c;
  if (!T.allFinite()) return x;
  x.has_temperature = true;
  x.temperature_change = T.maxCoeff() - T.minCoeff();
  x.temperature_r = diag::pearson(path, T);
  const Eigen::VectorXd Tc = T.array() - T.mean();
  if (Tc.squaredNorm() > 0) x.per_degree = Tc.dot(path) / Tc.squaredNorm();
  x.follows_temperature = x.temperature_change >= 1.0 && std::abs(x.temperature_r) >= kDriftTemperatureR;
  // The catalogue's temperature bias of this axis, added to the final model: its evidence (Δχ²)
  // and the change it gives over the run.
  for (int t = 0; t < P.n_terms(); ++t) {
    const Term& term = P.term(t);
    if (term.effect != EffectId::temperature_bias || term.sensor != a / 3 || term.axis != a % 3) continue;
    if (std::find(search.model.begin(), search.model.end(), t) != search.model.end()) break;
    std::vector<int> m = search.model;
    m.push_back(t);
    const FitOut f = P.fit(m, GreedySearch<BenchProblem>::ptrs(search.all));
    x.temperature_dchi2 = search.cur.chi2 - f.chi2;
    const int first = P.param_index(f, m.size() - 1, t);
    x.temperature_coef = f.theta(first);
    x.temperature_coef_sigma = std::sqrt(std::max(f.cov(first, first), 0.0));
    break;
  }
  return x;
}

// Issue 36, the smallest inputs (DiagLowInput): the widths tried, × the Earth rate. 1.25 Ω takes
// the statics (the Earth rate alone) as not sensed; the larger ones add low-rate steps.
constexpr double kLowInputGrid[] = {1.25, 2.5, 5.0, 10.0, 20.0};

// The rate gyro axis a receives: the reference through the tested scale and misalignment, row a of
// (I + M)·ω (a turn about another axis reaches it through M; a dead band acts on what it receives).
double received_rate(const SubBlock& s, int a, const Mat3& M) { return s.w(a) + M.row(a).dot(s.w); }

// The record with the inputs of the hypothesis's axes taken as not sensed: measured + received rate
// where the received rate is below the axis's width.
DiagData not_sensed(const DiagData& d, const std::vector<DiagLowInput::Axis>& axes, const Mat3& M) {
  DiagData c = d;
  for (const auto& x : axes)
    for (auto& s : c.subs)
      if (const double r = received_rate(s, x.axis, M); std::abs(r) < x.width) s.gyro(x.axis) += r;
  return c;
}

// The screen: per gyro axis, the width whose "not sensed" correction gains most on the base model
// (bias and scale/misalignment) at the parent level under the class's drift (the whitened GLS
// χ² of the parent means); axes whose gain reaches min_delta_chi2, each charged one parameter.
// `built`: the gyro datasets under the class's drift when the search still has them (else built here).
DiagLowInput low_input_screen(const DiagData& d, const Design& D, const Mat3& M, const DiagnoseOptions& opt,
                              double sigma, double tau, const std::vector<Dataset>* built) {
  DiagLowInput lo;
  const int n = static_cast<int>(d.subs.size());
  for (int a = 0; a < 3; ++a) {
    const Dataset own = built ? Dataset{} : build_dataset(d, D, a, kSubsetAll, sigma, tau, opt);
    const Dataset& S0 = built ? (*built)[a] : own;
    const auto Lt = S0.L.triangularView<Eigen::Lower>();
    const Eigen::MatrixXd Q = whitened_column_basis(d, D, S0, {0, 1, 2, 3});  // the base columns (kBase)
    auto chi2 = [&](const Eigen::VectorXd& z) {
      const Eigen::VectorXd zw = Lt.solve(parent_means(d, S0, z));
      return zw.squaredNorm() - (Q.transpose() * zw).squaredNorm();
    };
    const double chi0 = chi2(D.z[a]);
    DiagLowInput::Axis best;
    best.axis = a;
    int last = -1;
    for (double k : kLowInputGrid) {
      const double width = k * units::kEarthRate;
      Eigen::VectorXd z = D.z[a];
      int count = 0;
      double below_max = 0, above_min = std::numeric_limits<double>::infinity();
      for (int j = 0; j < n; ++j) {
        const double r = received_rate(d.subs[j], a, M);
        if (std::abs(r) < width) {
          z(j) += r;
          ++count;
          below_max = std::max(below_max, std::abs(r));
        } else {
          above_min = std::min(above_min, std::abs(r));
        }
      }
      if (count == last || count == 0 || count == n) continue;
      last = count;
      const double gain = chi0 - chi2(z);
      if (gain > best.screen_gain) {
        best.screen_gain = gain;
        best.width = width;
        best.below_max = below_max;
        best.above_min = std::isfinite(above_min) ? above_min : 0;
        best.blocks = count;
      }
    }
    if (best.screen_gain < opt.min_delta_chi2) continue;
    best.penalty = greedy_term_penalty(1, S0.n_low + S0.n_high, opt.penalty_per_param);
    lo.axes.push_back(best);
  }
  return lo;
}

// The test (DiagLowInput): the whole diagnosis redone on the record with the screened inputs taken
// as not sensed, and the verdict; `res` becomes that diagnosis when it fits decisively better.
void check_low_inputs(const DiagData& data, const Design& D, const SensorErrors& current, const EffectTerms& carried,
                      const DiagnoseOptions& opt, double sigma, double tau, const std::vector<Dataset>* built,
                      DiagnoseResult& res) {
  const Mat3& M = current.gyro.M;
  DiagLowInput lo = low_input_screen(data, D, M, opt, sigma, tau, built);
  if (lo.axes.empty()) return;
  std::copy(res.after, res.after + 3, lo.catalogue_after);
  for (const auto& u : res.unexplained)
    if (u.sensor == 0) lo.catalogue_unexplained.push_back(u.axis);
  DiagnoseOptions o1 = opt;
  o1.low_input_check = false;
  auto rediagnose = [&](const std::vector<DiagLowInput::Axis>& axes) {
    return diagnose_bench(not_sensed(data, axes, M), current, carried, o1);
  };
  DiagnoseResult r1 = rediagnose(lo.axes);
  lo.delta_score = res.score - (r1.score + DiagLowInput::penalty_of(lo.axes));
  // Every axis must earn its place: after a joint win, an axis whose removal costs less than
  // ambiguity_chi2 (a real effect of its own passed its screen) is dropped, one at a time.
  if (lo.delta_score >= opt.ambiguity_chi2)
    for (std::size_t i = 0; i < lo.axes.size() && lo.axes.size() > 1;) {
      std::vector<DiagLowInput::Axis> fewer = lo.axes;
      fewer.erase(fewer.begin() + static_cast<std::ptrdiff_t>(i));
      DiagnoseResult r2 = rediagnose(fewer);
      const double loss = (r2.score + DiagLowInput::penalty_of(fewer)) - (r1.score + DiagLowInput::penalty_of(lo.axes));
      if (loss >= opt.ambiguity_chi2) {
        ++i;
        continue;
      }
      lo.axes = std::move(fewer);
      r1 = std::move(r2);
      i = 0;
    }
  lo.delta_score = res.score - (r1.score + lo.penalty());
  auto same = [](const DiagnoseResult& r, const Term& t) -> const DiagFinding* {
    for (const auto& f : r.findings)
      if (f.term.effect == t.effect && f.term.sensor == t.sensor && f.term.axis == t.axis) return &f;
    return nullptr;
  };
  // Gyro findings (a g-sensitivity, a gyro drift) the corrected record does without, or gives
  // another value (beyond 2σ of this one's: a real g-sensitivity plus the missing Earth rate).
  std::vector<DiagFinding*> competing;
  for (auto& f : res.findings) {
    if (f.term.sensor != 0) continue;
    const DiagFinding* g = same(r1, f.term);
    bool moved = false;
    if (g && g->value.size() == f.value.size())
      for (std::size_t k = 0; k < f.value.size(); ++k)
        moved = moved || (k < f.sigma.size() && std::isfinite(f.sigma[k]) && std::abs(g->value[k] - f.value[k]) > 2 * f.sigma[k]);
    if (g && !moved) continue;
    competing.push_back(&f);
    lo.competing.push_back(f.term.label() + (g ? " (another value)" : ""));
  }
  if (lo.delta_score >= opt.ambiguity_chi2) {
    lo.verdict = "not sensed";
    r1.low_input = std::move(lo);
    res = std::move(r1);
    return;
  }
  const bool cannot_tell = lo.delta_score > -opt.ambiguity_chi2;
  lo.verdict = cannot_tell ? "cannot tell" : "sensed";
  if (cannot_tell) {
    for (DiagFinding* f : competing) {
      f->low_input_alternative = true;
      finding_status(*f, res, opt);
    }
  } else {
    lo.competing.clear();
  }
  res.low_input = std::move(lo);
}

}  // namespace

bool drift_excess_reported(const DiagDriftExcess& x) {
  const double limit = kDriftExcessFactor * x.stability;
  return (x.change > limit && x.z >= kDriftExcessZ) ||
         (x.has_temperature && x.temperature_dchi2 >= kDriftTemperatureChi2 && x.temperature_change_total() > limit);
}

bool drift_excess_noted(const DiagDriftExcess& x) {
  const double limit = kDriftExcessFactor * x.stability;
  return !drift_excess_reported(x) && x.change > limit && x.null_exceed() <= kDriftNoteTail;  // NaN (not drawn): false
}

void finding_status(DiagFinding& f, const DiagnoseResult& res, const DiagnoseOptions& opt) {
  f.explained_fraction = f.rms_before > 0 ? 1 - f.rms_after / f.rms_before : 1.0;
  f.remainder_is_noise = true;
  for (const auto& u : res.unexplained)
    if (u.sensor == f.report_sensor && (f.report_axis < 0 || u.axis == f.report_axis)) f.remainder_is_noise = false;
  f.status = !f.alternatives.empty() || f.low_input_alternative                             ? "not told apart"
             : f.explained_fraction >= opt.established_cut && f.remainder_is_noise ? "established"
                                                                                         : "partial";
}

std::vector<DiagSaturation> find_saturation(const DiagData& d, const double (&white_var)[6]) {
  std::vector<DiagSaturation> out;
  for (int a = 0; a < kAxes; ++a) {
    const int i = a % 3;
    auto meas = [&](const SubBlock& s) { return a < 3 ? s.gyro(i) : s.accel(i); };
    auto ref = [&](const SubBlock& s) { return a < 3 ? s.w(i) : s.f(i); };
    auto frozen = [&](const SubBlock& s) {
      return s.n >= 10 && (a < 3 ? s.gyro_ss(i) : s.accel_ss(i)) < kFrozenScatter * (s.n - 1) * white_var[a];
    };
    double top = 0;
    for (const auto& s : d.subs) top = std::max(top, std::abs(meas(s)));
    if (top <= 0) continue;
    // Per step: frozen sub-blocks at the top of the axis's outputs, and all sub-blocks.
    std::map<int, std::array<double, 2>> per_step;
    for (const auto& s : d.subs) {
      if (s.n < 10) continue;
      auto& c = per_step[s.step];
      c[1] += 1;
      if (frozen(s) && std::abs(meas(s)) >= 0.9 * top) c[0] += 1;
    }
    DiagSaturation sat;
    sat.sensor = a / 3;
    sat.axis = i;
    double n_frozen = 0, total = 0;
    for (const auto& [step, c] : per_step)
      if (c[0] >= 0.5 * c[1]) {
        sat.steps.push_back(step);
        n_frozen += c[0];
        total += c[1];
      }
    if (sat.steps.empty()) continue;
    sat.frozen_fraction = n_frozen / total;
    double pos = 0, neg = 0, np = 0, nn = 0;
    for (const auto& s : d.subs) {
      if (!std::binary_search(sat.steps.begin(), sat.steps.end(), s.step)) continue;
      sat.reference_max = std::max(sat.reference_max, std::abs(ref(s)));
      if (!frozen(s)) continue;
      (meas(s) > 0 ? pos : neg) += meas(s);
      (meas(s) > 0 ? np : nn) += 1;
    }
    if (np > 0) sat.level_pos = pos / np;
    if (nn > 0) sat.level_neg = neg / nn;
    for (const auto& p : d.parents)
      if (std::binary_search(sat.steps.begin(), sat.steps.end(), p.step)) sat.excluded_s += p.duration;
    out.push_back(std::move(sat));
  }
  return out;
}

DiagData without_steps(const DiagData& d, const std::vector<int>& steps) {
  DiagData o;
  o.sample_rate_hz = d.sample_rate_hz;
  o.has_temperature = d.has_temperature;
  o.has_angle = d.has_angle;
  o.stretch_axes = d.stretch_axes;
  for (const auto& p : d.parents) {
    if (std::find(steps.begin(), steps.end(), p.step) != steps.end()) continue;
    ParentBlock q = p;
    q.first = static_cast<int>(o.subs.size());
    for (int j = p.first; j < p.first + p.count; ++j) {
      SubBlock s = d.subs[j];
      s.parent = static_cast<int>(o.parents.size());
      o.subs.push_back(s);
    }
    o.parents.push_back(q);
  }
  return o;
}

DiagnoseResult diagnose_bench(const DiagData& data, const SensorErrors& current, const EffectTerms& carried,
                              const DiagnoseOptions& opt) {
  if (data.parents.size() < 8) throw std::runtime_error("diagnose: fewer than 8 data blocks in plan steps");
  const Design D = build_design(data, carried);
  // A plateau at the highest outputs (a range exceeded): its steps are left out, then the rest is
  // diagnosed (the white noise per axis comes from static sub-blocks, which a plateau at the top
  // rates does not touch).
  if (std::vector<DiagSaturation> sat = find_saturation(data, D.white_var); !sat.empty()) {
    std::vector<int> steps;
    for (const auto& s : sat) steps.insert(steps.end(), s.steps.begin(), s.steps.end());
    std::sort(steps.begin(), steps.end());
    steps.erase(std::unique(steps.begin(), steps.end()), steps.end());
    const DiagData rest = without_steps(data, steps);
    if (rest.parents.size() < 8) throw std::runtime_error("diagnose: fewer than 8 data blocks left outside the steps whose output is clipped");
    DiagnoseResult res = diagnose_bench(rest, current, carried, opt);
    res.saturation = std::move(sat);
    return res;
  }
  DiagnoseResult res;
  res.not_excited = D.not_excited;
  res.parents = static_cast<int>(data.parents.size());
  res.subs = static_cast<int>(data.subs.size());
  for (const auto& p : data.parents) res.data_s += p.duration;
  for (int a = 0; a < kAxes; ++a) res.white_sigma[a] = std::sqrt(D.white_var[a]);
  res.base_before = current;

  const BenchProblem problem{data, D, opt};
  const diag::DriftPrior prior_drift = diag::drift_prior(opt.noise);
  const double(&drift_sigma)[2] = prior_drift.sigma;
  const double(&drift_tau)[2] = prior_drift.tau;
  GreedySearch<BenchProblem> search(problem, diag::search_policy(opt), drift_sigma, drift_tau);
  const std::vector<Dataset>& all = search.all;
  const double* ds = search.ds;
  const double* tau = search.tau;

  // Before: the given coefficients.
  Eigen::VectorXd r_before[kAxes];
  for (int a = 0; a < kAxes; ++a) {
    r_before[a] = residual_coeffs(D, current, a);
    res.before[a] = axis_stats(data, D, all[a], r_before[a], Model{});
    res.correlations_before[a] = diag::correlations(data, r_before[a]);
  }

  search.run();
  // Backward check (stepwise): a term accepted in an early round can lose its evidence once later
  // terms or a larger drift (correlated_drift) are in the model — e.g. a g-sensitivity that only
  // half-fitted an effect outside the catalogue. Withdrawn terms are reported, not findings.
  for (const auto& w : search.recheck_drift()) res.withdrawn.push_back(search.withdrawn_report(w, WithdrawnWhy::drift_recheck));
  for (const auto& w : search.withdraw_weak()) res.withdrawn.push_back(search.withdrawn_report(w, WithdrawnWhy::weak));
  // The final residual and its statistics; an axis still unexplained after the search counts as
  // overdispersed (its residual χ²/dof beyond the noise model's): a term kept only because the
  // unmodelled structure inflates its Δχ² is withdrawn (quasi-likelihood: Δχ²/φ), and the
  // statistics are taken again.
  const Model& model = search.model;
  const FitOut& cur = search.cur;
  Eigen::VectorXd r_after[kAxes];
  for (int round = 0;; ++round) {
    double phi[kAxes];
    for (int a = 0; a < kAxes; ++a) {
      r_after[a] = residual(D, model, a, cur.theta);
      res.after[a] = axis_stats(data, D, all[a], r_after[a], model);
      phi[a] = axis_unexplained(res.after[a], all[a]) ? std::max(1.0, res.after[a].chi2_dof) : 1.0;
    }
    if (round == 3) break;
    bool changed = false;
    for (int triad = 0; triad < 2 && !changed; ++triad) {
      if (ds[triad] == drift_sigma[triad] && tau[triad] == drift_tau[triad]) continue;
      for (int a = 3 * triad; a < 3 * triad + 3 && !changed; ++a)
        if (axis_unexplained(res.after[a], all[a], true)) {
          res.withdrawn.push_back(search.withdrawn_report(search.give_up_drift(triad), WithdrawnWhy::leaves_unexplained));
          changed = true;
        }
    }
    if (changed) continue;
    const auto w = search.withdraw_overdispersed(phi);
    for (const auto& x : w) res.withdrawn.push_back(search.withdrawn_report(x, WithdrawnWhy::overdispersed));
    if (w.empty()) break;
  }
  for (int a = 0; a < kAxes; ++a) {
    // The before figures keep their own χ², whiteness and BIC (base model, data-sheet noise); the
    // systematic part is re-measured against the drift the data-sheet noise model sees in the final
    // residual (for linear findings the same drift the after figure removes; a correlated_drift
    // finding's excess drift stays in the before figure).
    // The data-sheet noise model: `all` unless a correlated_drift finding rebuilt this triad's
    // datasets (only then is it built again, not copied up front).
    const int triad = a / 3;
    const bool drift_changed = ds[triad] != drift_sigma[triad] || tau[triad] != drift_tau[triad];
    const Dataset prior = drift_changed ? problem.build(a, kSubsetAll, drift_sigma[triad], drift_tau[triad]) : Dataset{};
    const Dataset& noise_before = drift_changed ? prior : all[a];
    const Eigen::VectorXd drift = smoothed_drift(data, noise_before, r_after[a]);
    const AxisStats sys = axis_stats(data, D, noise_before, r_before[a], Model{}, &drift);
    res.before[a].step_rms = sys.step_rms;
    res.before[a].within_rms = sys.within_rms;
    res.before[a].systematic_rms = sys.systematic_rms;
    res.residual[a].before.assign(r_before[a].data(), r_before[a].data() + r_before[a].size());
    res.residual[a].after.assign(r_after[a].data(), r_after[a].data() + r_after[a].size());
  }

  // The improved model.
  search.fitted_terms(carried, res.improved_terms, res.terms_sigma);
  for (int a = 0; a < kAxes; ++a) {
    TriadErrors& te = a < 3 ? res.improved.gyro : res.improved.accel;
    const int i = a % 3;
    te.bias(i) = cur.theta(a * kBase);
    te.sigma_bias(i) = std::sqrt(std::max(cur.cov(a * kBase, a * kBase), 0.0));
    for (int c = 0; c < 3; ++c) {
      te.M(i, c) = cur.theta(a * kBase + 1 + c);
      te.sigma_M(i, c) = std::sqrt(std::max(cur.cov(a * kBase + 1 + c, a * kBase + 1 + c), 0.0));
    }
  }
  std::copy(ds, ds + 2, res.drift_sigma);
  std::copy(tau, tau + 2, res.drift_tau);
  // Findings.
  for (const auto& acc : search.steps) {
    if (acc.term < 0) {
      const int triad = -1 - acc.term;
      const DiagFinding f = correlated_drift_finding(triad, ds[triad], tau[triad], search.drift_interval[triad],
                                                     acc.dchi2, acc.dbic, res.before, res.after);
      res.findings.push_back(f);
      const EffectSpec& drift = noise_effect_spec();
      const double prior[2] = {opt.noise.gyro.drift_sigma, opt.noise.accel.drift_sigma};
      for (int k = 0; k < 2; ++k) {
        *effect_param(drift, res.improved_terms, k, -1, 0) = ds[k] > prior[k] ? ds[k] : 0;
        *effect_param(drift, res.improved_terms, k, -1, 1) = ds[k] > prior[k] ? tau[k] : 0;
      }
      continue;
    }
    DiagFinding f = search.term_finding(acc, carried);
    const Term& t = D.terms[acc.term];
    // Could another candidate in its place explain the recording as well? It must itself explain
    // the residual (Δχ² ≥ min_delta_chi2 against the model without the finding) and fit within
    // ambiguity_chi2 of the finding.
    f.alternatives = search.alternatives(acc.term, opt.ambiguity_chi2, opt.min_delta_chi2, opt.ambiguity_correlation, carried);
    // Temperature or drift, by likelihood: a temperature term against a drift of its triad with the
    // drift's own σ, τ. Within ambiguity_chi2 the record cannot tell: the drift is an alternative.
    if (effect_spec(t.effect).temperature_driven && t.sensor < 2) {
      const auto vd = search.versus_drift(acc.term);
      f.versus_drift = {true, vd.delta_score, vd.sigma, vd.tau,
                        vd.delta_score >= opt.ambiguity_chi2 ? "temperature" : vd.delta_score <= -opt.ambiguity_chi2 ? "drift" : "cannot tell"};
      if (vd.delta_score < opt.ambiguity_chi2 && vd.sigma > drift_sigma[t.sensor]) {
        DiagAlternative alt;
        alt.term = Term{noise_effect_spec().id, t.sensor, -1};
        alt.value = {vd.sigma};
        alt.unit = term_unit(alt.term);
        alt.chi2_worse = vd.delta_score;
        f.alternatives.push_back(alt);
      }
    }
    // Axis on which it shows: the touched axis whose residual it explains most.
    std::vector<int> touched;
    for (int a = 0; a < kAxes; ++a)
      if (D.col_of[a][acc.term] >= 0) touched.push_back(a);
    report_axis_of(t, f);
    finding_rms(t, touched, res, f);
    finding_condition(t, f);
    const int ra_axis = f.report_axis >= 0 && t.sensor < 2 ? t.sensor * 3 + f.report_axis : touched.front();
    for (const auto& c : res.correlations_before[ra_axis])
      if (c.condition == f.condition) f.condition_r = c.r;
    res.findings.push_back(f);
  }

  // Unexplained structure: an axis still far from its noise model.
  for (int a = 0; a < kAxes; ++a) {
    const AxisStats& s = res.after[a];
    if (!axis_unexplained(s, all[a])) continue;
    DiagUnexplained u = diag::unexplained_axis(a, s, diag::correlations(data, r_after[a]));
    diag::angle_spectrum(data, r_after[a], u.angle_harmonic, u.angle_harmonic_amp);
    diag::time_spectrum(data, r_after[a], u.period_hz, u.period_amp);
    if (s.worst_angle_bin >= 0 && std::abs(s.worst_angle_bin_z) >= 4) {
      u.angle_bin_deg[0] = 30.0 * s.worst_angle_bin;
      u.angle_bin_deg[1] = 30.0 * (s.worst_angle_bin + 1);
      u.angle_bin_mean = s.worst_angle_bin_mean;
      u.angle_bin_z = s.worst_angle_bin_z;
    }
    // Worst steps by |mean residual| relative to its white-noise σ.
    std::map<int, std::pair<double, double>> st;
    for (const auto& sb : data.subs) {
      auto& x = st[sb.step];
      x.first += sb.n * r_after[a](&sb - &data.subs[0]);
      x.second += sb.n;
    }
    u.worst_steps = diag::worst_windows(st, 1.0);
    res.unexplained.push_back(u);
  }
  // Drift against the class's stability (issue 36): on an axis with no finding and not unexplained,
  // under a triad drift still at the class's, what a larger drift of that axis alone absorbs.
  for (int a = 0; a < kAxes; ++a) {
    const int triad = a / 3;
    if (ds[triad] != drift_sigma[triad] || tau[triad] != drift_tau[triad] || diag::axis_reported(res, a)) continue;
    DiagDriftExcess x = drift_excess(problem, search, a, drift_sigma[triad]);
    res.drift_checked.push_back(x);
    if (drift_excess_reported(x)) res.drift_excess.push_back(x);
    if (drift_excess_noted(x)) res.drift_noted.push_back(x);
  }
  for (auto& f : res.findings) finding_status(f, res, opt);
  res.score = search.total_score();
  if (opt.low_input_check)
    check_low_inputs(data, D, current, carried, opt, drift_sigma[0], drift_tau[0],
                     ds[0] == drift_sigma[0] && tau[0] == drift_tau[0] ? &all : nullptr, res);
  return res;
}

}  // namespace calbench
