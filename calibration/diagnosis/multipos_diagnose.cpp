#include "calibration/diagnosis/multipos_diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "calibration/diagnosis/diagnosis_engine.hpp"
#include "calibration/diagnosis/greedy_search.hpp"
#include "calibration/diagnosis/residual_stats.hpp"
#include "common/units.hpp"

// The static poses of a multi-position recording as a problem of the catalogue search
// (greedy_search.hpp); the model and its noise are described in multipos_diagnose.hpp.

namespace calbench {

namespace {

using diag::kAxes;

// Global parameters: gyro bias (0–2), accelerometer bias (3–5), the accelerometer's ΔM lower
// triangle (6–11, the fit's gauge), then the candidate terms' parameters.
constexpr int kBase = 12;
constexpr int kLower[6][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 0}, {2, 1}, {2, 2}};
constexpr int kMag = 3;  // the axis whose dataset holds the gravity-magnitude rows; 4 and 5 are empty

struct PoseDesign {
  std::vector<ParentBlock> parents;  // one per used pose; step = its ordinal (held-out halves)
  std::vector<Term> terms;
  std::vector<int> term_off;
  std::vector<double> prior_sigma;  // per term parameter (0: none)
  int P = kBase;
  Eigen::VectorXd zp[4];            // gyro x..z, magnitude
  Eigen::MatrixXd Xp[4];
  std::vector<double> white[4];     // per pose: white-noise (and horizontal Earth-rate) variance
  std::vector<Vec3> v;              // C⁻ᵀ û per pose
  std::vector<std::vector<int>> touched;  // per term: axes (0–2, 3 = magnitude) with a column
};

PoseDesign build_design(const multipos::MultiposInput& in, const multipos::MultiposFit& fit, const SensorErrors& cur,
                        const EffectTerms& carried, MultiposDiagnoseResult& out) {
  PoseDesign D;
  out.poses.clear();
  for (std::size_t k = 0; k < fit.statics.size(); ++k)
    if (fit.statics[k].used) out.poses.push_back(static_cast<int>(k));
  const int N = static_cast<int>(out.poses.size());
  for (const Term& t : candidate_terms()) {
    const EffectSpec& x = effect_spec(t.effect);
    if (t.sensor == 2 || !x.bench_candidate) continue;  // the table's own errors; M_ii again
    D.terms.push_back(t);
  }
  for (const Term& t : D.terms) {
    D.term_off.push_back(D.P);
    D.P += t.nparams();
    const double ps = effect_spec(t.effect).drive_prior[t.sensor == 0 ? 0 : 1];
    for (int p = 0; p < t.nparams(); ++p) D.prior_sigma.push_back(ps > 0 ? ps : 0.0);
  }
  for (int a = 0; a < 4; ++a) {
    D.zp[a] = Eigen::VectorXd::Zero(N);
    D.Xp[a] = Eigen::MatrixXd::Zero(N, D.P);
    D.white[a].assign(N, 0.0);
  }
  std::vector<std::vector<char>> touch(D.terms.size(), std::vector<char>(4, 0));
  const Mat3 C = Mat3::Identity() + cur.accel.M;
  const Mat3 Ci = C.inverse();
  const Mat3 Cg = Mat3::Identity() + cur.gyro.M;
  const double sg2 = std::pow(fit.gyro_noise.used_sigma, 2), sa2 = std::pow(fit.accel_noise.used_sigma, 2);
  const double W = units::kEarthRate;
  out.earth_vertical_removed = in.lat_rad.has_value();
  const double w_up = in.lat_rad ? W * std::sin(*in.lat_rad) : 0.0;
  const double w_h2 = in.lat_rad ? std::pow(W * std::cos(*in.lat_rad), 2) : 0.0;
  for (int k = 0; k < N; ++k) {
    const multipos::StaticInterval& s = fit.statics[static_cast<std::size_t>(out.poses[k])];
    const int n = static_cast<int>(s.i1 - s.i0);
    ParentBlock pb;
    pb.step = k;
    pb.t_mid = 0.5 * (s.t0 + s.t1);
    pb.duration = s.t1 - s.t0;
    pb.n = n;
    // The catalogue terms the given coefficients carry, at this pose's own input (first pass: the
    // direction from the raw mean is good to far below their size).
    SubBlock sb;
    sb.f = s.f_mean.normalized() * in.gravity;
    sb.t_mid = pb.t_mid;
    sb.duration = pb.duration;
    sb.n = n;
    Vec3 cg = Vec3::Zero(), ca = Vec3::Zero();
    if (carried.any()) predict_extra(carried, sb, cg, ca);
    const Vec3 y = Ci * (s.f_mean - ca - cur.accel.bias);
    const Vec3 u = y.normalized();
    const Vec3 f = in.gravity * u;
    const Vec3 v = Ci.transpose() * u;
    D.v.push_back(v);
    pb.f = f;
    sb.f = f;
    D.parents.push_back(pb);
    D.zp[kMag](k) = y.norm() - in.gravity;
    D.white[kMag][k] = sa2 * v.squaredNorm() / std::max(n, 1);
    const Vec3 zg = s.w_mean - cg - cur.gyro.bias - Cg * (w_up * u);
    for (int a = 0; a < 3; ++a) {
      D.zp[a](k) = zg(a);
      D.Xp[a](k, a) = 1.0;
      // Horizontal Earth rate of an unknown heading: E[h_a²] = (1 − û_a²)/2 of its square; Ω²/3
      // when the latitude (and so the vertical part) is unknown.
      const double earth = in.lat_rad ? w_h2 * (1 - u(a) * u(a)) / 2 : W * W / 3;
      D.white[a][k] = sg2 / std::max(static_cast<int>(s.c1 - s.c0), 1) + earth;  // the rate's mean: the still centres
    }
    for (int i = 0; i < 3; ++i) D.Xp[kMag](k, 3 + i) = v(i);
    for (int c = 0; c < 6; ++c) D.Xp[kMag](k, 6 + c) = v(kLower[c][0]) * f(kLower[c][1]);
    for (std::size_t t = 0; t < D.terms.size(); ++t)
      for (int p = 0; p < D.terms[t].nparams(); ++p) {
        Vec3 dg, da;
        predict_extra(diag::unit_term(D.terms[t], p, carried.t0_c), sb, dg, da);
        const int col = D.term_off[t] + p;
        for (int a = 0; a < 3; ++a)
          if (dg(a) != 0) {
            D.Xp[a](k, col) = dg(a);
            touch[t][a] = 1;
          }
        const double m = v.dot(da);
        if (m != 0) {
          D.Xp[kMag](k, col) = m;
          touch[t][kMag] = 1;
        }
      }
  }
  D.touched.assign(D.terms.size(), {});
  for (std::size_t t = 0; t < D.terms.size(); ++t)
    for (int a = 0; a < 4; ++a)
      if (touch[t][a]) D.touched[t].push_back(a == kMag ? 3 : a);
  return D;
}

using Dataset = diag::LinearDataset;
using FitOut = diag::FitOut;

Dataset build_dataset(const PoseDesign& D, int a, int subset, double ds, double tau) {
  const int NP = static_cast<int>(D.parents.size());
  const bool empty = a > kMag;
  Dataset S = diag::subset_dataset(a, subset, ds, tau, empty ? 0 : NP, [&](int p) {
    if (subset == kSubsetAll) return true;
    return (p % 2 == 0) == (subset == kSubsetEven);
  });
  const int N = static_cast<int>(S.parents.size());
  Eigen::VectorXd z(N);
  Eigen::MatrixXd X(N, D.P);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(N, N);
  const int da = std::min(a, kMag);
  for (int k = 0; k < N; ++k) {
    const int pk = S.parents[k];
    z(k) = D.zp[da](pk);
    X.row(k) = D.Xp[da].row(pk);
    R(k, k) = D.white[da][pk];
    for (int l = 0; l <= k; ++l) {
      const int pl = S.parents[l];
      // The triad's drift, per axis independent: the magnitude sees its projection v_kᵀ v_l.
      const double proj = da == kMag ? D.v[pk].dot(D.v[pl]) : 1.0;
      const double c = proj * diag::drift_covariance(D.parents[pk], D.parents[pl], ds, tau);
      R(k, l) += c;
      if (l != k) R(l, k) += c;
    }
  }
  diag::whiten(S, R, z, X, 8);
  if (N == 0) {  // an empty axis: Gram and projections of the right size, all zero
    S.G = Eigen::MatrixXd::Zero(D.P, D.P);
    S.g = Eigen::VectorXd::Zero(D.P);
  }
  return S;
}

std::vector<int> model_params(const PoseDesign& D, const std::vector<int>& terms) {
  std::vector<int> idx;
  for (int p = 0; p < kBase; ++p) idx.push_back(p);
  for (int t : terms)
    for (int p = 0; p < D.terms[t].nparams(); ++p) idx.push_back(D.term_off[t] + p);
  return idx;
}

using diag::global_map;

FitOut fit_model(const PoseDesign& D, const std::vector<int>& terms, const std::vector<const Dataset*>& sets) {
  return diag::fit_global(model_params(D, terms), D.P, kBase, D.prior_sigma, sets);
}

struct PoseProblem : diag::GlobalProblem<PoseDesign> {
  Dataset build(int a, int subset, double ds, double tau) const { return build_dataset(D, a, subset, ds, tau); }
  Fit fit(const std::vector<int>& m, const std::vector<const Dataset*>& sets) const { return fit_model(D, m, sets); }
};

Eigen::VectorXd residual(const PoseDesign& D, int a, const Eigen::VectorXd& theta) {
  const int da = std::min(a, kMag);
  return D.zp[da] - D.Xp[da] * theta;
}

// Parameters of the model on dataset axis a (its base plus the terms with a column there).
int axis_params(const PoseDesign& D, const std::vector<int>& model, int a) {
  int n = a < 3 ? 1 : 9;
  for (int t : model)
    if (std::find(D.touched[t].begin(), D.touched[t].end(), std::min(a, kMag)) != D.touched[t].end())
      n += D.terms[t].nparams();
  return n;
}

// Systematic RMS of r on dataset S: its mean square less the mean variance the noise model gives a
// pose (white, Earth rate and the drift's σ², projected on the magnitude); floor = the noise level
// of that estimate (√(2·sd of the mean square)), below which it cannot be told from zero. Poses
// are few and the drift's wander over them is part of the model, so r is taken as it is.
double systematic(const PoseDesign& D, const Dataset& S, const Eigen::VectorXd& r, double* floor = nullptr) {
  const int da = std::min(S.axis, kMag);
  const int N = static_cast<int>(r.size());
  if (N == 0) return 0;
  double ms = 0, mv = 0, vv = 0;
  for (int k = 0; k < N; ++k) {
    const int p = S.parents[k];
    const double proj = da == kMag ? D.v[p].squaredNorm() : 1.0;
    const double var = D.white[da][p] + proj * S.drift_sigma * S.drift_sigma;
    ms += r(k) * r(k) / N;
    mv += var / N;
    vv += 2 * var * var;
  }
  if (floor) *floor = std::sqrt(2 * std::sqrt(vv) / N);
  return std::sqrt(std::max(0.0, ms - mv));
}

AxisStats axis_stats(const PoseDesign& D, const Dataset& S, const Eigen::VectorXd& r, int nparams) {
  AxisStats st;
  diag::whiteness(S, r, nparams, st);
  st.systematic_rms = systematic(D, S, r, &st.systematic_floor);
  st.step_rms = st.systematic_rms;
  return st;
}

bool axis_unexplained(const AxisStats& s, const Dataset& S) {
  const double z_low = (s.chi2_dof - 1) * std::sqrt(std::max(1, S.n_low) / 2.0);
  return z_low >= 6 || s.ljung_box_p <= 1e-4;
}

double rms(const Eigen::VectorXd& r) { return r.size() ? std::sqrt(r.squaredNorm() / r.size()) : 0.0; }

// The base model (no catalogue term) fitted under the class's drift prior.
FitOut base_fit(const PoseDesign& D, const NoiseSpec& noise) {
  const diag::DriftPrior prior = diag::drift_prior(noise);
  std::vector<Dataset> sets;
  for (int a = 0; a <= kMag; ++a) sets.push_back(build_dataset(D, a, kSubsetAll, prior.sigma[a / 3], prior.tau[a / 3]));
  std::vector<const Dataset*> ptrs;
  for (const auto& S : sets) ptrs.push_back(&S);
  return fit_model(D, {}, ptrs);
}

// The base model's correction θ (gyro bias, accelerometer bias, its lower-triangular ΔM) added to c.
void apply_base(SensorErrors& c, const Eigen::VectorXd& th) {
  for (int i = 0; i < 3; ++i) {
    c.gyro.bias(i) += th(i);
    c.accel.bias(i) += th(3 + i);
  }
  for (int k = 0; k < 6; ++k) c.accel.M(kLower[k][0], kLower[k][1]) += th(6 + k);
}

// The tested coefficients with the base model's correction (biases, the accelerometer's
// lower-triangular M) applied exactly, again and again until it is negligible. The search
// linearises about the coefficients it is given: a set far from the recording's (a bias of grams, a
// scale 10 % off) would leave the linearisation error to the catalogue, as a false nonlinearity or
// drift, and write absurd improved coefficients. `fit multipos`'s own set needs one round.
SensorErrors relinearised(const multipos::MultiposInput& in, const multipos::MultiposFit& fit, const SensorErrors& current,
                          const NoiseSpec& noise) {
  SensorErrors c = current;
  MultiposDiagnoseResult scratch;
  // Coefficients this far from the recording are another unit's, or none: refused rather than
  // relinearised from (Gauss–Newton from grams away may settle anywhere).
  {
    const PoseDesign D0 = build_design(in, fit, c, EffectTerms{}, scratch);
    const double rms0 = rms(D0.zp[kMag]);
    if (!(rms0 <= 0.1 * in.gravity))
      throw std::runtime_error("the coefficients tested leave |f| − g of " + std::to_string(rms0) +
                               " m/s² RMS over the static poses (more than 10 % of gravity): they are not a calibration "
                               "of this unit (fit multipos gives one)");
  }
  for (int it = 0; it < 20; ++it) {
    const PoseDesign D = build_design(in, fit, c, EffectTerms{}, scratch);
    if (D.parents.size() < 9) break;
    const Eigen::VectorXd th = base_fit(D, noise).theta;
    apply_base(c, th);
    if (!th.allFinite()) throw std::runtime_error("diagnose: the coefficients tested do not fit the static poses");
    if (th.segment<6>(0).cwiseAbs().maxCoeff() < 1e-9 && th.segment<6>(6).cwiseAbs().maxCoeff() < 1e-10) break;
  }
  return c;
}

}  // namespace

MultiposNoiseCheck multipos_noise_check(const multipos::MultiposInput& in, const multipos::MultiposFit& fit,
                                        const SensorErrors& current, const NoiseSpec& noise) {
  MultiposDiagnoseResult scratch;
  const PoseDesign D = build_design(in, fit, current, EffectTerms{}, scratch);
  const int N = static_cast<int>(D.parents.size());
  const FitOut f = base_fit(D, noise);
  MultiposNoiseCheck out;
  out.accel_dof = N - 9;
  out.gyro_dof = N - 1;
  out.accel_chi2_dof = out.accel_dof > 0 ? f.chi2_axis[kMag] / out.accel_dof : 0.0;
  for (int a = 0; a < 3; ++a) out.gyro_chi2_dof[a] = out.gyro_dof > 0 ? f.chi2_axis[a] / out.gyro_dof : 0.0;
  return out;
}

MultiposDiagnoseResult diagnose_multipos(const multipos::MultiposInput& in, const multipos::MultiposFit& fit,
                                         const SensorErrors& current, const DiagnoseOptions& opt) {
  MultiposDiagnoseResult out;
  DiagnoseResult& res = out.core;
  const EffectTerms carried{};
  const SensorErrors base = relinearised(in, fit, current, opt.noise);
  const PoseDesign D = build_design(in, fit, base, carried, out);
  const int NP = static_cast<int>(D.parents.size());
  if (NP < 9) throw std::runtime_error("diagnose: " + std::to_string(NP) + " static poses used, at least 9 needed");
  res.parents = NP;
  for (const auto& p : D.parents) {
    res.data_s += p.duration;
    out.pose_t.push_back(p.t_mid);
  }
  for (int a = 0; a < kAxes; ++a)
    res.white_sigma[a] = a < 3 ? fit.gyro_noise.used_sigma : fit.accel_noise.used_sigma;
  res.base_before = current;

  const PoseProblem problem{{D}};
  GreedyPolicy policy = diag::search_policy(opt);
  policy.skip_untouched = true;
  const diag::DriftPrior prior = diag::drift_prior(opt.noise);
  GreedySearch<PoseProblem> search(problem, policy, prior.sigma, prior.tau);
  const std::vector<Dataset>& all = search.all;

  // Before: the base model (biases and the accelerometer's lower-triangular ΔM refitted).
  Eigen::VectorXd r_before[kAxes], r_after[kAxes];  // per pose, as fitted (the JSON's residuals)
  for (int a = 0; a <= kMag; ++a) {
    r_before[a] = residual(D, a, search.cur.theta);
    res.before[a] = axis_stats(D, all[a], r_before[a], axis_params(D, {}, a));
  }

  search.run();
  for (const auto& w : search.recheck_drift()) res.withdrawn.push_back(search.withdrawn_report(w, WithdrawnWhy::drift_recheck));
  // As on the drive: a drift that leaves an axis of its triad unexplained is given up; a term kept
  // only because unmodelled structure inflates its Δχ² is withdrawn (Δχ² over the axis's χ²/dof).
  search.recheck_unexplained(res.withdrawn, [&](int a) {
    if (a > kMag) return std::make_pair(false, 1.0);  // the accelerometer's one dataset is axis 3's
    const AxisStats st = axis_stats(D, all[a], residual(D, a, search.cur.theta), axis_params(D, search.model, a));
    const bool u = axis_unexplained(st, all[a]);
    return std::make_pair(u, u ? std::max(1.0, st.chi2_dof) : 1.0);
  });
  const FitOut& cur = search.cur;

  // Improved: the biases and the lower-triangular M corrected (from the relinearised base), the
  // terms added.
  res.improved = base;
  apply_base(res.improved, cur.theta);
  const auto sd = [&](int p) { return std::sqrt(std::max(cur.cov(p, p), 0.0)); };
  for (int i = 0; i < 3; ++i) {
    res.improved.gyro.sigma_bias(i) = sd(i);
    res.improved.accel.sigma_bias(i) = sd(3 + i);
  }
  for (int k = 0; k < 6; ++k) res.improved.accel.sigma_M(kLower[k][0], kLower[k][1]) = sd(6 + k);
  search.fitted_terms(carried, res.improved_terms, res.terms_sigma);
  std::copy(search.ds, search.ds + 2, res.drift_sigma);
  std::copy(search.tau, search.tau + 2, res.drift_tau);
  for (int a = 0; a <= kMag; ++a) {
    r_after[a] = residual(D, a, cur.theta);
    res.after[a] = axis_stats(D, all[a], r_after[a], axis_params(D, search.model, a));
  }
  for (int a = kMag + 1; a < kAxes; ++a) {  // the accelerometer's one dataset
    res.before[a] = res.before[kMag];
    res.after[a] = res.after[kMag];
    r_before[a] = r_before[kMag];
    r_after[a] = r_after[kMag];
  }
  for (int a = 0; a < kAxes; ++a) {
    res.residual[a].before.assign(r_before[a].data(), r_before[a].data() + r_before[a].size());
    res.residual[a].after.assign(r_after[a].data(), r_after[a].data() + r_after[a].size());
  }
  out.g_rms_before = rms(r_before[kMag]);
  out.g_rms_after = rms(r_after[kMag]);
  for (int a = 0; a < 3; ++a) {
    out.gyro_rms_before[a] = rms(r_before[a]);
    out.gyro_rms_after[a] = rms(r_after[a]);
  }

  // Unexplained: an axis still far from its noise model (the accelerometer once: axis −1, all).
  for (int a = 0; a <= kMag; ++a) {
    if (!axis_unexplained(res.after[a], all[a])) continue;
    DiagUnexplained u = diag::unexplained_axis(a, res.after[a], {});
    if (a == kMag) u.axis = -1;
    res.unexplained.push_back(u);
  }

  // Findings.
  std::vector<const Dataset*> sets;
  for (const auto& S : all) sets.push_back(&S);
  for (const auto& acc : search.steps) {
    if (acc.term < 0) {
      const int triad = -1 - acc.term;
      DiagFinding f = correlated_drift_finding(triad, search.ds[triad], search.tau[triad], search.drift_interval[triad],
                                               acc.dchi2, acc.dbic, res.before, res.after);
      const EffectSpec& drift = noise_effect_spec();
      *effect_param(drift, res.improved_terms, triad, -1, 0) = search.ds[triad];
      *effect_param(drift, res.improved_terms, triad, -1, 1) = search.tau[triad];
      finding_status(f, res, opt);
      res.findings.push_back(f);
      continue;
    }
    DiagFinding f = search.term_finding(acc, carried);
    const Term& t = D.terms[acc.term];
    f.alternatives = search.alternatives(acc.term, opt.ambiguity_chi2, opt.min_delta_chi2, opt.ambiguity_correlation, carried);
    f.condition = effect_spec(t.effect).condition ? effect_spec(t.effect).condition : "";
    // Systematic residual on the touched axis where the term stands out most: before = the final
    // model refitted without it (what the poses show without the term, the base model absorbing
    // what it can), after = the final model.
    std::vector<int> without = search.model;
    without.erase(std::find(without.begin(), without.end(), acc.term));
    const FitOut fw = fit_model(D, without, sets);
    double best = -1, floor_after = 0;
    for (int a : D.touched[acc.term]) {
      double fl = 0;
      const double rb = systematic(D, all[a], residual(D, a, fw.theta), &fl);
      const double rel = fl > 0 ? rb / fl : rb;
      if (rel > best) {
        best = rel;
        f.rms_before = rb;
        f.rms_after = systematic(D, all[a], residual(D, a, cur.theta), &floor_after);
      }
    }
    finding_status(f, res, opt);
    // An after figure below its own noise level cannot be told from zero (a few dozen poses): the
    // residual is then cut entirely as far as the poses can tell.
    if (f.rms_after < floor_after && f.rms_before > 0) {
      f.explained_fraction = 1;
      if (f.alternatives.empty()) f.status = "established";
    }
    if (f.report_sensor == 1)  // the accelerometer's one dataset: its remainder is axis −1's
      for (const auto& u : res.unexplained)
        if (u.sensor == 1) f.remainder_is_noise = false;
    if (!f.remainder_is_noise && std::string(f.status) == "established") f.status = "partial";
    res.findings.push_back(f);
  }
  return out;
}

}  // namespace calbench
