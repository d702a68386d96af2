#include "calibration/diagnosis/drive_diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

#include "calibration/diagnosis/condition_correlation.hpp"
#include "calibration/diagnosis/drive_design.hpp"
#include "calibration/diagnosis/greedy_search.hpp"
#include "calibration/diagnosis/residual_stats.hpp"
#include "calibration/ins/nav_math.hpp"

// The drive side of the diagnosis: the design and its datasets come from drive_design.cpp, the
// linear problem from diagnosis_engine.cpp; here the drive's residual statistics (systematic RMS
// of grouped blocks against the banded short-range noise), the catalogue search with the
// mounting, and the report of its findings.

namespace calbench {

namespace {

using namespace drive_diag;

// The drive as a problem of the catalogue search (greedy_search.hpp): global parameters; a term
// with no column on any axis is no candidate; a term's penalty counts the parent rows of the axes
// it touches, correlated_drift's the parents.
struct DriveProblem : diag::GlobalProblem<Design> {
  const DriveDiagData& d;
  Dataset build(int a, int subset, double ds, double tau) const { return build_dataset(d, D, a, subset, ds, tau); }
  Fit fit(const std::vector<int>& m, const std::vector<const Dataset*>& sets) const { return fit_model(D, m, sets); }
};

// Systematic RMS of residual r (drift removed) over groups of parents: each group's mean squared
// minus the short-range noise variance of that mean.
// floor: the noise level of this estimate (√(2·sd of the estimated mean square)): a systematic
// RMS below it cannot be told from zero.
// lowpass (d given): the groups average the residual's three-block means (block and contiguous
// neighbours) instead of the blocks themselves — the reference's telescoping error, which
// dominates a block, has 1/9 of its variance in a three-block mean, while an effect that lasts
// seconds keeps most of its size ("low-passed residuals").
double grouped_systematic(const Design& D, int a, const Eigen::VectorXd& r, const std::vector<std::vector<int>>& groups,
                          double* floor = nullptr, const DriveDiagData* lowpass = nullptr) {
  double num = 0, den = 0, var_ms = 0;
  const int N = static_cast<int>(r.size());
  for (const auto& gr : groups) {
    if (gr.empty()) continue;
    const double n = static_cast<double>(gr.size());
    // The group's mean as weights on the blocks.
    std::map<int, double> w;
    for (int k : gr) {
      if (!lowpass) {
        w[k] += 1.0 / n;
        continue;
      }
      const bool lo = k > 0 && D.contig[lowpass->parents[k].first];
      const bool hi = k + 1 < N && D.contig[lowpass->parents[k + 1].first];
      const double wk = 1.0 / (n * (1 + lo + hi));
      w[k] += wk;
      if (lo) w[k - 1] += wk;
      if (hi) w[k + 1] += wk;
    }
    double m = 0, v = 0;
    for (auto it = w.begin(); it != w.end(); ++it) {
      m += it->second * r(it->first);
      v += it->second * it->second * D.pvar[a][it->first];
      const auto nx = std::next(it);
      if (nx != w.end() && nx->first == it->first + 1) v += 2 * it->second * nx->second * D.pcov[a][it->first];
    }
    num += n * (m * m - v);
    den += n;
    var_ms += n * n * 2 * v * v;
  }
  if (floor) *floor = den > 0 ? std::sqrt(2 * std::sqrt(var_ms) / den) : 0.0;
  return den > 0 ? std::sqrt(std::max(0.0, num / den)) : 0.0;
}

std::vector<std::vector<int>> time_groups(int N, int size) {
  std::vector<std::vector<int>> g;
  for (int k = 0; k < N; k += size) {
    std::vector<int> x;
    for (int l = k; l < std::min(N, k + size); ++l) x.push_back(l);
    g.push_back(x);
  }
  return g;
}

// Sort key for binning a residual by a term's contribution c (the finding's figures below). When
// c is built from the same sensor's reference input as the residual (a scale-type term, a time
// offset), that input carries
// the reference's own error of the block, which the residual carries with the opposite sign:
// binned by it, blocks of a still or cruising car sort by that error and the bins show a
// "systematic" residual that is selection (clean drives: ≈ 5 mg on accel x binned by f_x, 3.5×
// the figure's floor). The reference's block error telescopes — (x_end − x_start)/T — so the
// mean over the block and its contiguous neighbours, (x_k+1,end − x_k−1,start)/3T, is independent
// of block k's: that is the key then. Terms driven by the other sensor's input (g-sensitivity:
// gyro by force; lever arm: accelerometer by rate) keep c itself, which the neighbour mean would
// blur (the lever arm's ω̇×r changes sign within seconds).
bool own_input_term(const Term& t) { return effect_spec(t.effect).own_input; }

// Mean of c over each block and its contiguous neighbours.
Eigen::VectorXd neighbour_mean(const DriveDiagData& d, const Design& D, const Eigen::VectorXd& c) {
  const int N = static_cast<int>(c.size());
  Eigen::VectorXd k(N);
  for (int i = 0; i < N; ++i)
    k(i) = run_window_mean<double>(
        N, i, 1, [&](int l) { return c(l); }, [](int) { return 1.0; },
        [&](int l) { return D.contig[d.parents[l].first] != 0; });
  return k;
}

std::vector<std::vector<int>> quantile_groups(const Eigen::VectorXd& key, int bins) {
  const int N = static_cast<int>(key.size());
  std::vector<int> order(N);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int i, int j) { return key(i) < key(j); });
  std::vector<std::vector<int>> g(bins);
  for (int r = 0; r < N; ++r) g[std::min(bins - 1, r * bins / std::max(N, 1))].push_back(order[r]);
  return g;
}

// An axis still far from its noise model: low-rate χ²/dof beyond 6σ of its sampling spread, or
// Ljung–Box p ≤ 10⁻⁴.
bool axis_unexplained(const AxisStats& s, const Dataset& S) {
  const double z_low = (s.chi2_dof - 1) * std::sqrt(std::max(1, S.n_low) / 2.0);
  return z_low >= 6 || s.ljung_box_p <= 1e-4;
}

AxisStats axis_stats(const DriveDiagData& d, const Design& D, const Dataset& S, const Eigen::VectorXd& r, int nparams,
                     Eigen::VectorXd& r_nodrift) {
  AxisStats st;
  const int N = S.n_low;
  diag::whiteness(S, r, nparams, st);
  r_nodrift = r - diag::smoothed_drift(d.parents, S, r);
  st.systematic_rms = grouped_systematic(D, S.axis, r_nodrift, time_groups(N, 10), &st.systematic_floor);
  st.step_rms = st.systematic_rms;
  return st;
}

// Axis a finding is reported on: a lever arm with one dominant significant component on that one.
void report_axis_of(const Term& t, DiagFinding& f) {
  if (effect_spec(t.effect).dominant_component) {
    // Dominant component among the significant ones (|value| > 3σ; a land vehicle barely
    // rolls or pitches, so the component along the yaw axis is poorly determined).
    auto sig = [&](int i) { return std::abs(f.value[i]) > 3 * f.sigma[i] ? std::abs(f.value[i]) : 0.0; };
    int imax = 0;
    for (int i = 1; i < 3; ++i)
      if (sig(i) > sig(imax)) imax = i;
    double others = 0;
    for (int i = 0; i < 3; ++i)
      if (i != imax) others = std::max(others, sig(i));
    f.report_axis = others < 0.3 * sig(imax) ? imax : -1;
  }
}

// Mounting rotation δ of the base model (bias and δ, M fixed, data-sheet drift), MEMS axes.
Vec3 base_mounting_delta(const DriveDiagData& data, const SensorErrors& current, const EffectTerms& carried,
                         const DriveDiagnoseOptions& opt) {
  const Design D = build_design(data, current, carried, true);
  std::vector<Dataset> sets;
  const diag::DriftPrior prior = diag::drift_prior(opt.noise);
  for (int a = 0; a < kAxes; ++a)
    sets.push_back(build_dataset(data, D, a, kSubsetAll, prior.sigma[a / 3], prior.tau[a / 3]));
  std::vector<const Dataset*> ptrs;
  for (const auto& S : sets) ptrs.push_back(&S);
  return fit_model(D, {}, ptrs).theta.segment<3>(6);
}

// The motion condition that best explains a residual by generalised least squares under a noise
// model (S): the residual and each condition's block values whitened by its Cholesky factor, the
// model's columns (mp) projected out of the condition; Δχ² = (ũ·r̃)²/‖ũ‖², χ²₁ under the model.
struct ConditionGls {
  std::string name;
  double dchi2 = 0, r = 0;
};
ConditionGls best_condition_gls(const DriveDiagData& data, const Design& D, const Dataset& S, int a,
                                const Eigen::VectorXd& resid, const std::vector<int>& mp) {
  ConditionGls best;
  const int NP = static_cast<int>(data.parents.size());
  if (static_cast<int>(S.parents.size()) != NP) return best;
  const auto L = S.L.triangularView<Eigen::Lower>();
  const Eigen::VectorXd rw = L.solve(resid);
  Eigen::MatrixXd X(NP, static_cast<int>(mp.size()));
  for (std::size_t j = 0; j < mp.size(); ++j) X.col(static_cast<int>(j)) = D.Xp[a].col(mp[j]);
  X = L.solve(X);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  const Eigen::MatrixXd Q = (qr.householderQ() * Eigen::MatrixXd::Identity(NP, NP)).leftCols(qr.rank());
  for (const auto& name : drive_condition_names(data.has_temperature)) {
    if (name == "time") continue;
    Eigen::VectorXd c(NP);
    for (int k = 0; k < NP; ++k) c(k) = drive_condition_value(data, k, name);
    if (!c.allFinite()) continue;
    Eigen::VectorXd u = L.solve(c);
    const double whole = u.squaredNorm();
    u -= Q * (Q.transpose() * u);
    const double uu = u.squaredNorm();
    if (uu <= 1e-12 * whole) continue;  // in the model's span
    const double d = std::pow(u.dot(rw), 2) / uu;
    if (d > best.dchi2) best = {name, d, diag::pearson(resid, c)};
  }
  return best;
}

// Issue 36 (drives): the χ²₁ level of the condition test, see "Unexplained" below.
constexpr double kConditionTestChi2 = DriveDiagnoseResult::kConditionTestLevel;

}  // namespace

DriveDiagnoseResult diagnose_drive(const DriveDiagData& data_in, const SensorErrors& current,
                                   const EffectTerms& carried, const DriveDiagnoseOptions& opt) {
  DriveDiagnoseResult out;
  DiagnoseResult& res = out.core;
  if (data_in.parents.size() < 20) throw std::runtime_error("diagnose: fewer than 20 blocks of drive data");
  // With M fixed the mounting δ enters the model linearised (x_m ≈ x − δ×x). A unit mounted ~1° off
  // the nominal mounting leaves a second-order scale error (1 − cos θ: 1.3e-4 at 0.9°) that the
  // fixed M cannot absorb, and the drive's scale-like terms took it (clean drives diagnosed with the
  // bench coefficients were named a gyro z nonlinearity of −4e-4/(rad/s)). So the base model's δ is
  // applied exactly — the prediction re-rotated to the MEMS (remount) — until it is below 1e-7 rad;
  // the search then runs on that data, and the reported δ is the total.
  DriveDiagData remounted;
  Mat3 C_pre = Mat3::Identity();
  if (opt.fixed_scale) {
    remounted = data_in;
    for (int it = 0; it < 5; ++it) {
      const Vec3 d = base_mounting_delta(remounted, current, carried, opt);
      if (d.norm() < 1e-7) break;
      C_pre = C_pre * ins::quat_from_rotvec(d).toRotationMatrix();
      remount(remounted, data_in.C_mb * C_pre);
    }
  }
  const DriveDiagData& data = opt.fixed_scale ? remounted : data_in;
  const Design D = build_design(data, current, carried, opt.fixed_scale);
  const int NP = static_cast<int>(data.parents.size());
  res.parents = NP;
  res.subs = static_cast<int>(data.subs.size());
  for (const auto& p : data.parents) {
    res.data_s += p.duration;
    out.parent_t.push_back(p.t_mid);
  }
  for (int a = 0; a < kAxes; ++a) {
    res.white_sigma[a] = std::sqrt(data.sample_white_var[a]);
    for (int l = 0; l <= kLags; ++l) out.gamma[a][l] = D.gamma[a][l];
    out.white_scale[a] = D.white_scale[a];
    double v = 0;
    for (int k = 0; k < NP; ++k) v += D.pvar[a][k];
    out.block_noise_sigma[a] = std::sqrt(v / NP);
  }
  res.base_before = current;

  const DriveProblem problem{{D}, data};
  GreedyPolicy policy = diag::search_policy(opt);
  policy.skip_untouched = true;
  const diag::DriftPrior prior_drift = diag::drift_prior(opt.noise);
  GreedySearch<DriveProblem> search(problem, policy, prior_drift.sigma, prior_drift.tau);
  for (std::size_t t = 0; t < D.terms.size(); ++t)  // columns for the alternatives only
    if (effect_spec(D.terms[t].effect).drive == DriveDiagnosis::alternative_only) search.banned.push_back(static_cast<int>(t));
  const std::vector<Dataset>& all = search.all;

  // Before: the base model (bias, and M or the mounting) refitted, no catalogue term.
  const FitOut base_fit = search.cur;
  Eigen::VectorXd r_before[kAxes], rn_before[kAxes];
  const int nbase = D.n_base;
  for (int a = 0; a < kAxes; ++a) {
    r_before[a] = residual(D, a, base_fit.theta);
    res.before[a] = axis_stats(data, D, all[a], r_before[a], nbase, rn_before[a]);
    res.correlations_before[a] = diag::correlations(data, rn_before[a]);
  }

  search.run();
  for (const auto& w : search.recheck_drift()) res.withdrawn.push_back(search.withdrawn_report(w, WithdrawnWhy::drift_recheck));
  // A drift beyond the data sheet whose smoothed path follows a condition of the motion (speed², a
  // vibration rectifying with speed, a term driven by turning) has stood in for a deterministic
  // effect outside the catalogue: a random wander is not tied to how the car moves. Its path on each
  // axis of the triad is correlated with every motion condition; with the record's independent
  // stretches n = length / 2τ, a Fisher z = atanh|r|·√(n − 3) beyond kFollowsZ (two-sided p ≈ 7·10⁻⁶,
  // Bonferroni over ~40 tests ≈ 3·10⁻⁴) gives the drift up, and the axis is left to `unexplained`.
  constexpr double kFollowsZ = 4.5;
  for (int triad = 0; triad < 2; ++triad) {
    if (search.ds[triad] == prior_drift.sigma[triad] && search.tau[triad] == prior_drift.tau[triad]) continue;
    double length = 0;
    for (const auto& p : data.parents) length += p.duration;
    const double n_eff = length / (2 * search.tau[triad]);
    DiagWithdrawn why;
    for (int a = 3 * triad; a < 3 * triad + 3 && n_eff >= 10; ++a) {
      const Eigen::VectorXd path = diag::smoothed_drift(data.parents, all[a], residual(D, a, search.cur.theta));
      for (const auto& name : drive_condition_names(data.has_temperature)) {
        if (name == "time") continue;
        Eigen::VectorXd c(NP);
        for (int k = 0; k < NP; ++k) c(k) = drive_condition_value(data, k, name);
        const double r = diag::pearson(path, c);
        const double z = std::atanh(std::min(std::abs(r), 0.999999)) * std::sqrt(n_eff - 3);
        if (z > kFollowsZ && z > why.condition_z) {
          why.condition = name;
          why.axis = a % 3;
          why.condition_r = r;
          why.condition_z = z;
        }
      }
    }
    // Issue 36: a drift must be weighed against the structured alternative. Under the class's drift,
    // the condition that best explains each axis of the triad (the GLS test of "Unexplained"); when
    // one reaches kConditionTestChi2 and together they explain as much as the larger drift gained
    // (−2 ln L, with one parameter per axis to its two), the drift stood in for a condition of the
    // motion (a bias following speed on a short drive, where the Fisher test above has too few
    // independent stretches). It is given up and the axis left to the condition test.
    if (why.condition.empty()) {
      double gain = 0;
      for (const auto& st : search.steps)
        if (st.term == -1 - triad) gain = st.dchi2;
      const std::vector<int> mp = model_params(D, search.model);
      double sum = 0;
      for (int a = 3 * triad; a < 3 * triad + 3; ++a) {
        const Dataset P = problem.build(a, kSubsetAll, prior_drift.sigma[triad], prior_drift.tau[triad]);
        const ConditionGls b = best_condition_gls(data, D, P, a, residual(D, a, search.cur.theta), mp);
        sum += b.dchi2;
        if (b.dchi2 >= kConditionTestChi2 && b.dchi2 > why.condition_dchi2) {
          why.condition = b.name;
          why.axis = a % 3;
          why.condition_r = b.r;
          why.condition_dchi2 = b.dchi2;
        }
      }
      if (why.condition.empty() || sum < gain) continue;
      why.drift_gain = gain;
    }
    DiagWithdrawn w = search.withdrawn_report(search.give_up_drift(triad), WithdrawnWhy::follows_condition);
    w.condition = why.condition;
    w.axis = why.axis;
    w.condition_r = why.condition_r;
    w.condition_z = why.condition_z;
    w.condition_dchi2 = why.condition_dchi2;
    w.drift_gain = why.drift_gain;
    res.withdrawn.push_back(w);
  }
  // As on the bench: a drift that leaves an axis of its triad unexplained has not explained the
  // residual (it stood in for structure outside the catalogue) and is given up; and on an axis that
  // stays unexplained, a term kept only because the unmodelled structure inflates its Δχ² is
  // withdrawn (quasi-likelihood: each axis's Δχ² divided by its χ²/dof φ). The statistics are taken
  // again after each change.
  search.recheck_unexplained(res.withdrawn, [&](int a) {
    Eigen::VectorXd rn;
    const AxisStats st = axis_stats(data, D, all[a], residual(D, a, search.cur.theta),
                                    static_cast<int>(model_params(D, search.model).size()), rn);
    const bool u = axis_unexplained(st, all[a]);
    return std::make_pair(u, u ? std::max(1.0, st.chi2_dof) : 1.0);
  });
  const std::vector<int>& model = search.model;
  const FitOut& cur = search.cur;
  const double* ds = search.ds;
  const double* tau = search.tau;

  // Improved model: b (and M) corrected, catalogue terms added.
  res.improved = current;
  for (int a = 0; a < kAxes; ++a) {
    TriadErrors& te = a < 3 ? res.improved.gyro : res.improved.accel;
    const int i = a % 3;
    te.bias(i) += cur.theta(a);
    te.sigma_bias(i) = std::sqrt(std::max(cur.cov(a, a), 0.0));
    if (!opt.fixed_scale)
      for (int c = 0; c < 3; ++c) {
        const int p = 6 + 3 * a + c;
        te.M(i, c) += cur.theta(p);
        te.sigma_M(i, c) = std::sqrt(std::max(cur.cov(p, p), 0.0));
      }
  }
  if (opt.fixed_scale) {
    const Vec3 d = cur.theta.segment<3>(6);
    out.mounting_delta = ins::rotvec_from_dcm(C_pre * ins::quat_from_rotvec(d).toRotationMatrix());
    for (int c = 0; c < 3; ++c) out.mounting_sigma(c) = std::sqrt(std::max(cur.cov(6 + c, 6 + c), 0.0));
  }
  search.fitted_terms(carried, res.improved_terms, res.terms_sigma);
  // A scale_factor finding is a change of the spec's coefficient M_ii: IMPROVED.json carries it there.
  for (const EffectSpec& x : effect_specs()) {
    if (!x.folds_into_scale) continue;
    for (int triad = 0; triad < 2; ++triad) {
      if (!effect_allows_sensor(x, triad)) continue;
      TriadErrors& te = triad == 0 ? res.improved.gyro : res.improved.accel;
      Eigen::Map<Vec3> v = effect_triad(res.improved_terms, x.id, triad);
      const Eigen::Map<const Vec3> sg = effect_triad(static_cast<const EffectTerms&>(res.terms_sigma), x.id, triad);
      for (int i = 0; i < 3; ++i)
        if (v(i) != 0) {
          te.M(i, i) += v(i);
          if (sg(i) > 0) te.sigma_M(i, i) = sg(i);
        }
      v.setZero();
    }
  }
  std::copy(ds, ds + 2, res.drift_sigma);
  std::copy(tau, tau + 2, res.drift_tau);
  Eigen::VectorXd r_after[kAxes], rn_after[kAxes];
  const int np = static_cast<int>(model_params(D, model).size());
  for (int a = 0; a < kAxes; ++a) {
    r_after[a] = residual(D, a, cur.theta);
    res.after[a] = axis_stats(data, D, all[a], r_after[a], np, rn_after[a]);
    out.correlations_after[a] = diag::correlations(data, rn_after[a]);
    res.residual[a].before.assign(rn_before[a].data(), rn_before[a].data() + NP);
    res.residual[a].after.assign(rn_after[a].data(), rn_after[a].data() + NP);
  }

  // Findings.
  for (const auto& acc : search.steps) {
    if (acc.term < 0) {
      const int triad = -1 - acc.term;
      const DiagFinding f = correlated_drift_finding(triad, ds[triad], tau[triad], search.drift_interval[triad],
                                                     acc.dchi2, acc.dbic, res.before, res.after);
      // Noise level of the triad's figure (RMS over its axes of the 10 s window figure's floor).
      double floor2 = 0;
      for (int a = triad * 3; a < triad * 3 + 3; ++a) floor2 += std::pow(res.after[a].systematic_floor, 2) / 3;
      out.rms_floor.push_back(std::sqrt(floor2));
      out.rms_lowpass.push_back(false);
      out.shown_on.push_back(triad * 3);
      const EffectSpec& drift = noise_effect_spec();
      *effect_param(drift, res.improved_terms, triad, -1, 0) = ds[triad];
      *effect_param(drift, res.improved_terms, triad, -1, 1) = tau[triad];
      res.findings.push_back(f);
      continue;
    }
    DiagFinding f = search.term_finding(acc, carried);
    const Term& t = D.terms[acc.term];
    // Another candidate in its place that fits within ambiguity_chi2 and itself explains the
    // residual (as on the bench): the drive does not tell them apart.
    f.alternatives = search.alternatives(acc.term, opt.ambiguity_chi2, opt.min_delta_chi2, opt.ambiguity_correlation, carried);
    report_axis_of(t, f);
    // Systematic residual along the finding's own signature, on each axis the term touches:
    // parents binned by the term's fitted contribution c; before = the final residual with the
    // term taken out (residual + c: what this drive shows without the term, other parameters as
    // fitted; the base-model residual would hide part of it in M), after = the final residual.
    // Two views: the blocks, and (terms driven by the other sensor's input, whose key carries no
    // noise of the residual) the three-block means, binned by the three-block mean of c. Reported
    // on the axis and view where it stands out most from the figure's noise floor.
    int show = D.touched[acc.term].front();
    double best_rel = -1, floor = 0;
    bool lowpass_show = false;
    Eigen::VectorXd contrib_show;
    for (int a : D.touched[acc.term]) {
      Eigen::VectorXd c = Eigen::VectorXd::Zero(NP);
      for (int p = 0; p < t.nparams(); ++p) {
        const int idx = D.term_off[acc.term] + p;
        c += D.Xp[a].col(idx) * cur.theta(idx);
      }
      if ((c.array() - c.mean()).abs().maxCoeff() <= 0) continue;
      const Eigen::VectorXd without = rn_after[a] + (c.array() - c.mean()).matrix();
      for (const bool lp : {false, true}) {
        if (lp && own_input_term(t)) continue;
        const auto groups = quantile_groups(lp || own_input_term(t) ? neighbour_mean(data, D, c) : c, 10);
        const DriveDiagData* lpd = lp ? &data : nullptr;
        double fl = 0;
        const double rb = grouped_systematic(D, a, without, groups, &fl, lpd);
        const double rel = fl > 0 ? rb / fl : 0.0;
        if (rel > best_rel) {
          best_rel = rel;
          show = a;
          contrib_show = c;
          lowpass_show = lp;
          floor = fl;
          f.rms_before = rb;
          f.rms_after = grouped_systematic(D, a, rn_after[a], groups, nullptr, lpd);
        }
      }
    }
    if (contrib_show.size() == 0) contrib_show = Eigen::VectorXd::Zero(NP);
    if (t.sensor == 2) {
      f.report_sensor = show / 3;  // reported on the axis where it shows most
    }
    // Revealing condition: the one most correlated with the term's signature.
    double best_r = 0;
    for (const auto& name : drive_condition_names(data.has_temperature)) {
      if (name == "time") continue;
      Eigen::VectorXd c(NP);
      for (int k = 0; k < NP; ++k) c(k) = drive_condition_value(data, k, name);
      const double r = diag::pearson(c, contrib_show);
      if (std::abs(r) > std::abs(best_r)) {
        best_r = r;
        f.condition = name;
      }
    }
    for (const auto& c : res.correlations_before[show])
      if (c.condition == f.condition) f.condition_r = c.r;
    res.findings.push_back(f);
    out.rms_floor.push_back(floor);
    out.rms_lowpass.push_back(lowpass_show);
    out.shown_on.push_back(show);
  }

  // Unexplained: an axis still far from its noise model.
  for (int a = 0; a < kAxes; ++a) {
    const AxisStats& s = res.after[a];
    if (!axis_unexplained(s, all[a])) continue;
    DiagUnexplained u = diag::unexplained_axis(a, s, out.correlations_after[a]);
    diag::time_spectrum(data, rn_after[a], u.period_hz, u.period_amp);
    std::map<int, std::pair<double, double>> win;
    for (int k = 0; k < NP; ++k) {
      auto& x = win[data.parents[k].step];
      x.first += rn_after[a](k);
      x.second += 1;
    }
    u.worst_steps = diag::worst_windows(win, out.block_noise_sigma[a]);
    res.unexplained.push_back(u);
  }

  // Issue 36, a remainder that follows a motion condition (a term outside the catalogue, e.g. a bias
  // proportional to speed): the noise model's drift absorbs such slow structure and the axis's
  // χ² stays near 1. Each condition's block values are tested against the final residual by
  // generalised least squares under the same noise model (both whitened by its Cholesky factor, the
  // model's columns projected out of the condition): Δχ² = (ũ·r̃)²/‖ũ‖², χ²₁ under the noise
  // model. On an axis with no finding and not already unexplained, Δχ² ≥ kConditionTestChi2 makes
  // the axis unexplained with that condition named (the level: DriveDiagnoseResult::kConditionTestLevel,
  // a family-wise false-alarm rate of 10⁻³ per recording); every tested axis keeps its figure
  // (condition_test). It names no term, so it needs less than a catalogue term's 40 (which also buys the names).
  {
    const std::vector<int> mp = model_params(D, model);
    for (int a = 0; a < kAxes; ++a) {
      if (diag::axis_reported(res, a)) continue;
      const ConditionGls best = best_condition_gls(data, D, all[a], a, r_after[a], mp);
      out.condition_test[a] = {!best.name.empty(), best.name, best.dchi2, best.r};
      if (best.dchi2 < kConditionTestChi2) continue;
      DiagUnexplained u = diag::unexplained_axis(a, res.after[a], out.correlations_after[a]);
      u.condition_test = best.name;
      u.condition_dchi2 = best.dchi2;
      u.condition_r = best.r;
      res.unexplained.push_back(u);
    }
  }

  // Per motion class: mean residual and its z-score (short-range noise only).
  for (MotionClass mc : {MotionClass::stationary, MotionClass::straight, MotionClass::turning, MotionClass::accelerating}) {
    DriveSegmentStat st;
    st.motion = motion_class_name(mc);
    std::vector<int> idx;
    for (int k = 0; k < NP; ++k)
      if (data.info[k].motion == mc) {
        idx.push_back(k);
        st.seconds += data.parents[k].duration;
      }
    st.blocks = static_cast<int>(idx.size());
    if (idx.empty()) continue;
    for (int a = 0; a < kAxes; ++a) {
      double mb = 0, ma = 0, v = 0;
      for (std::size_t i = 0; i < idx.size(); ++i) {
        mb += rn_before[a](idx[i]);
        ma += rn_after[a](idx[i]);
        v += D.pvar[a][idx[i]];
        if (i + 1 < idx.size() && idx[i + 1] == idx[i] + 1) v += 2 * D.pcov[a][idx[i]];
      }
      const double n = static_cast<double>(idx.size());
      st.mean_before[a] = mb / n;
      st.mean_after[a] = ma / n;
      const double sd = std::sqrt(std::max(v, 1e-300)) / n;
      st.z_before[a] = st.mean_before[a] / sd;
      st.z_after[a] = st.mean_after[a] / sd;
    }
    out.segments.push_back(st);
  }
  return out;
}

}  // namespace calbench
