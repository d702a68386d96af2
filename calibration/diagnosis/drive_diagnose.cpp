#include "calibration/diagnosis/drive_diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

#include "calibration/diagnosis/greedy_search.hpp"
#include "calibration/gauss_markov_window.hpp"
#include "calibration/ins/nav_math.hpp"

namespace calbench {

namespace {

constexpr int kAxes = 6;
constexpr int kLags = 3;

bool in_subset(const ParentBlock& p, int subset) {
  if (subset == kSubsetAll) return true;
  const bool even = (p.step % 2 + 2) % 2 == 0;
  return even == (subset == kSubsetEven);
}

bool drive_term(const Term& t, bool temperature, bool fixed_scale) {
  switch (effect_spec(t.effect).drive) {
    case DriveDiagnosis::always: return true;
    case DriveDiagnosis::with_temperature: return temperature;
    case DriveDiagnosis::fixed_scale: return fixed_scale;  // M free: it is M_ii
    case DriveDiagnosis::never: return false;
  }
  return false;
}

// Weighted mean of x over element i and up to h neighbours on each side within i's contiguous
// run (adjacent(l): elements l − 1 and l are contiguous); summed centre first, then backwards,
// then forwards.
template <class T, class X, class Wt, class Adj>
T run_window_mean(int N, int i, int h, X x, Wt wt, Adj adjacent) {
  T s = x(i) * wt(i);
  double sw = wt(i);
  for (int l = i - 1; l >= std::max(0, i - h) && adjacent(l + 1); --l) {
    s += x(l) * wt(l);
    sw += wt(l);
  }
  for (int l = i + 1; l < std::min(N, i + h + 1) && adjacent(l); ++l) {
    s += x(l) * wt(l);
    sw += wt(l);
  }
  return s / sw;
}

// Global parameters: 6 biases, then 18 ΔM (M free) or 3 mounting angles (M fixed), then the
// candidate terms' parameters.
struct Design {
  bool fixed = false;
  int n_base = 0;
  std::vector<Term> terms;
  std::vector<int> term_off;  // global index of each term's first parameter
  int P = 0;
  std::vector<Eigen::VectorXd> z;  // per axis, per sub
  std::vector<Eigen::VectorXd> zp;  // per axis, per parent
  std::vector<Eigen::MatrixXd> Xp;  // per axis: Nparent × P
  std::vector<std::vector<int>> touched;  // per term: axes with a non-zero column
  std::vector<char> contig;  // sub j follows sub j−1 without a gap
  // Short-range noise per axis: sub-level autocovariance (lags 0..3), and the parent-level
  // banded covariance (variance, covariance with the next parent).
  double gamma[kAxes][kLags + 1] = {};
  double endpoint_var[kAxes] = {};
  double white_scale[kAxes] = {1, 1, 1, 1, 1, 1};
  std::vector<double> prior_sigma;  // per term parameter
  std::vector<double> pvar[kAxes], pcov[kAxes];
};

Design build_design(const DriveDiagData& d, const SensorErrors& cur, const EffectTerms& carried, bool fixed) {
  Design D;
  D.fixed = fixed;
  D.n_base = 6 + (fixed ? 3 : 18);
  for (const Term& t : candidate_terms())
    if (drive_term(t, d.has_temperature, fixed)) D.terms.push_back(t);
  D.P = D.n_base;
  for (const Term& t : D.terms) {
    D.term_off.push_back(D.P);
    D.P += t.nparams();
    const double ps = effect_spec(t.effect).drive_prior[t.sensor == 0 ? 0 : 1];
    for (int p = 0; p < t.nparams(); ++p) D.prior_sigma.push_back(ps);
  }
  const int N = static_cast<int>(d.subs.size());
  const int NP = static_cast<int>(d.parents.size());
  D.z.assign(kAxes, Eigen::VectorXd::Zero(N));
  // Regressors are accumulated straight into the ~1 s parent means (duration-weighted): an
  // interval-level matrix would take N·P·6 doubles (0.5 GB for a 35-minute drive at 100 Hz).
  D.Xp.assign(kAxes, Eigen::MatrixXd::Zero(NP, D.P));
  Eigen::MatrixXd X(kAxes, D.P);
  D.contig.assign(N, 0);
  D.touched.assign(D.terms.size(), {});
  std::vector<std::vector<char>> touch(D.terms.size(), std::vector<char>(kAxes, 0));
  const bool carry = carried.any();
  for (int j = 1; j < N; ++j) {
    const SubBlock &p = d.subs[j - 1], &s = d.subs[j];
    D.contig[j] = std::abs((p.t_mid + 0.5 * p.duration) - (s.t_mid - 0.5 * s.duration)) < 1e-6;
  }
  // Input of the terms nonlinear in it (|x|, x·|x|): the reference over ~0.2 s. A reference
  // interval's own rate or force carries the reference's error of its ends divided by its length
  // (a 50 Hz reference: ≈ 0.4 m/s² on a simulated drive's specific force), and |x + e| is not
  // |x| — near x = 0 it is ≈ 0.8σ_e, so the regressor's variation is compressed and the fitted
  // asymmetry inflated (accelerometer: ≈ +7 %, outside its own 2σ with factory coefficients). The
  // error telescopes, so the mean over W intervals has 1/W of it. Linear terms take the interval's
  // own input (their block means are the same either way).
  const int Wnl = std::max(1, static_cast<int>(std::round(0.1 / std::max(d.mean_sub_s, 1e-4))));
  std::vector<Vec3> w_nl(N), f_nl(N);
  {
    auto dur = [&](int l) { return d.subs[l].duration; };
    auto adjacent = [&](int l) { return D.contig[l] != 0; };
    for (int j = 0; j < N; ++j) {
      w_nl[j] = run_window_mean<Vec3>(N, j, Wnl, [&](int l) { return d.subs[l].w; }, dur, adjacent);
      f_nl[j] = run_window_mean<Vec3>(N, j, Wnl, [&](int l) { return d.subs[l].f; }, dur, adjacent);
    }
  }
  for (int j = 0; j < N; ++j) {
    const SubBlock& s = d.subs[j];
    SubBlock s_nl = s;
    s_nl.w = w_nl[j];
    s_nl.f = f_nl[j];
    Vec3 cg = Vec3::Zero(), ca = Vec3::Zero();
    if (carry) predict_extra(carried, s, cg, ca);
    const Vec3 pg = cur.gyro.measure(s.w), pa = cur.accel.measure(s.f);
    X.setZero();
    for (int a = 0; a < kAxes; ++a) {
      const int i = a % 3;
      D.z[a](j) = a < 3 ? s.gyro(i) - pg(i) - cg(i) : s.accel(i) - pa(i) - ca(i);
      X(a, a) = 1.0;
      const Vec3& x = a < 3 ? s.w : s.f;
      if (!fixed) {
        for (int c = 0; c < 3; ++c) X(a, 6 + 3 * a + c) = x(c);
      } else {
        // measured ideal output with the MEMS turned by δ: Exp(−δ)·x = x + x×δ = skew(x)·δ + x.
        const Mat3 S = ins::skew(x);
        for (int c = 0; c < 3; ++c) X(a, 6 + c) = S(i, c);
      }
    }
    for (std::size_t t = 0; t < D.terms.size(); ++t) {
      const Term& term = D.terms[t];
      for (int p = 0; p < term.nparams(); ++p) {
        EffectTerms unit;
        unit.t0_c = carried.t0_c;
        term.add_param(unit, p, 1.0);
        Vec3 dg, da;
        if (effect_spec(term.effect).curvature) {
          // h(x_s) + h'(x_s)·(x − x_s): the curvature taken at the smoothed input, the interval's
          // own deviation kept to first order — otherwise h(x_s) alone differs from the block's
          // h(x) by a linear leak at its ends (h' ≈ 2g for x·|x| of the vertical accelerometer),
          // which correlates with the reference error in the residual (a false accel z
          // nonlinearity of 4e-3 on seed 1267).
          constexpr double eps = 1e-3;
          SubBlock s_eps = s_nl;
          s_eps.w += eps * (s.w - s_nl.w);
          s_eps.f += eps * (s.f - s_nl.f);
          Vec3 dg1, da1;
          predict_extra(unit, s_nl, dg, da);
          predict_extra(unit, s_eps, dg1, da1);
          dg += (dg1 - dg) / eps;
          da += (da1 - da) / eps;
        } else {
          predict_extra(unit, s, dg, da);
        }
        for (int a = 0; a < kAxes; ++a) {
          const double v = a < 3 ? dg(a) : da(a - 3);
          if (v != 0) {
            X(a, D.term_off[t] + p) = v;
            touch[t][a] = 1;
          }
        }
      }
    }
    if (s.parent >= 0) {
      const double w = s.duration / d.parents[s.parent].duration;
      for (int a = 0; a < kAxes; ++a) D.Xp[a].row(s.parent) += w * X.row(a);
    }
  }
  for (std::size_t t = 0; t < D.terms.size(); ++t)
    for (int a = 0; a < kAxes; ++a)
      if (touch[t][a]) D.touched[t].push_back(a);
  // Parent means of z (duration-weighted).
  D.zp.assign(kAxes, Eigen::VectorXd::Zero(NP));
  for (int k = 0; k < NP; ++k) {
    const ParentBlock& pb = d.parents[k];
    for (int j = pb.first; j < pb.first + pb.count; ++j) {
      const double w = d.subs[j].duration / pb.duration;
      for (int a = 0; a < kAxes; ++a) D.zp[a](k) += w * D.z[a](j);
    }
  }
  // Short-range noise: autocovariance of high-pass residuals (z minus a centred moving average of
  // ~2 s over contiguous intervals), corrected for the removed mean.
  const int W = std::max(9, 2 * static_cast<int>(std::round(1.0 / std::max(d.mean_sub_s, 1e-3))) + 1);
  std::vector<int> run_id(N, 0);
  for (int j = 1; j < N; ++j) run_id[j] = D.contig[j] ? run_id[j - 1] : run_id[j - 1] + 1;
  for (int a = 0; a < kAxes; ++a) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(N);
    std::vector<char> ok(N, 0);
    for (int j = 0; j < N; ++j) {
      const int lo = j - W / 2, hi = j + W / 2;
      if (lo < 0 || hi >= N || run_id[lo] != run_id[j] || run_id[hi] != run_id[j]) continue;
      e(j) = D.z[a](j) - D.z[a].segment(lo, W).mean();
      ok[j] = 1;
    }
    double g[kLags + 1] = {};
    for (int l = 0; l <= kLags; ++l) {
      double s = 0;
      long n = 0;
      for (int j = 0; j + l < N; ++j)
        if (ok[j] && ok[j + l] && run_id[j] == run_id[j + l]) {
          s += e(j) * e(j + l);
          ++n;
        }
      g[l] = n > 0 ? s / n : 0;
    }
    // Structural model of a block mean: the IMU's white noise (σ²/n, from its sample-to-sample
    // differences) plus the reference's errors at the interval ends, which telescope: a block of
    // length T gets (x_end − x_start)/T with var(x) = v, i.e. variance 2v/T² and covariance −v/(T·T')
    // with the next block. v from the sub-level autocovariance of a telescoping process:
    // v = −T_s²·Σ_l l·γ_l (exact for x of short memory; γ dominated by the reference at lag ≤ 3).
    double sl = 0;
    for (int l = 1; l <= kLags; ++l) sl += l * g[l];
    const double v_end = std::max(0.0, -sl * d.mean_sub_s * d.mean_sub_s);
    for (int l = 0; l <= kLags; ++l) D.gamma[a][l] = g[l];
    D.endpoint_var[a] = v_end;
    // The IMU's sample-to-sample scatter overstates its block noise when it is vibration (a real
    // car: high-frequency, averages out faster than white noise). Check against the blocks: the
    // variance V of a block's residual after an unweighted base fit, from first differences
    // (a = E δ², b = E δ_k δ_k+1, V = a + b; slow signals and drift cancel). Only a clear
    // overstatement (V below half the model) scales the white part down; never up, so an
    // unexplained effect cannot hide itself in the noise model.
    double white_scale = 1;
    {
      std::vector<int> base_cols = {a};
      for (int c = 6; c < D.n_base; ++c)
        if (D.Xp[a].col(c).squaredNorm() > 0) base_cols.push_back(c);
      Eigen::MatrixXd Xb(NP, base_cols.size());
      for (std::size_t c = 0; c < base_cols.size(); ++c) Xb.col(c) = D.Xp[a].col(base_cols[c]);
      const Eigen::VectorXd r = D.zp[a] - Xb * Xb.colPivHouseholderQr().solve(D.zp[a]);
      double sa = 0, sb = 0, white = 0, endp = 0;
      int na = 0, nb = 0;
      for (int k = 0; k + 1 < NP; ++k) {
        if (!D.contig[d.parents[k + 1].first]) continue;
        const double dk = r(k + 1) - r(k);
        sa += dk * dk;
        ++na;
        if (k + 2 < NP && D.contig[d.parents[k + 2].first]) {
          sb += dk * (r(k + 2) - r(k + 1));
          ++nb;
        }
      }
      for (int k = 0; k < NP; ++k) {
        white += d.sample_white_var[a] / std::max(d.parents[k].n, 1);
        endp += 2 * v_end / (d.parents[k].duration * d.parents[k].duration);
      }
      white /= NP;
      endp /= NP;
      if (na > 20 && nb > 20 && white > 0) {
        const double V = sa / na + sb / nb;
        if (V < 0.5 * (white + endp)) white_scale = std::clamp((V - endp) / white, 0.05, 1.0);
      }
    }
    D.white_scale[a] = white_scale;
    // Parent-level banded covariance.
    D.pvar[a].assign(NP, 0);
    D.pcov[a].assign(NP, 0);
    for (int k = 0; k < NP; ++k) {
      const ParentBlock& pk = d.parents[k];
      D.pvar[a][k] = white_scale * d.sample_white_var[a] / std::max(pk.n, 1) + 2 * v_end / (pk.duration * pk.duration);
      if (k + 1 < NP) {
        const ParentBlock& pl = d.parents[k + 1];
        const bool adjacent = D.contig[pl.first] != 0;
        if (adjacent) D.pcov[a][k] = -v_end / (pk.duration * pl.duration);
      }
    }
  }
  return D;
}

struct Dataset {
  int axis = 0;
  std::vector<int> parents;
  Eigen::MatrixXd L;
  Eigen::MatrixXd G;
  Eigen::VectorXd g;
  double zz = 0, logdet = 0;
  int n = 0;
  double ds = 0, tau = 1;
};

Eigen::MatrixXd parent_cov(const DriveDiagData& d, const Design& D, const std::vector<int>& P, int a, double ds,
                           double tau, bool with_drift) {
  const int N = static_cast<int>(P.size());
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(N, N);
  for (int k = 0; k < N; ++k) {
    R(k, k) = D.pvar[a][P[k]];
    if (k + 1 < N && P[k + 1] == P[k] + 1) R(k, k + 1) = R(k + 1, k) = D.pcov[a][P[k]];
    if (with_drift)
      for (int l = 0; l <= k; ++l) {
        const ParentBlock &pk = d.parents[P[k]], &pl = d.parents[P[l]];
        const double v = ds * ds * gm_window_correlation(pk.t_mid, pk.duration, pl.t_mid, pl.duration, tau);
        R(k, l) += v;
        if (l != k) R(l, k) += v;
      }
  }
  return R;
}

Dataset build_dataset(const DriveDiagData& d, const Design& D, int a, int subset, double ds, double tau) {
  Dataset S;
  S.axis = a;
  S.ds = ds;
  S.tau = tau;
  for (int p = 0; p < static_cast<int>(d.parents.size()); ++p)
    if (in_subset(d.parents[p], subset)) S.parents.push_back(p);
  const int N = static_cast<int>(S.parents.size());
  Eigen::VectorXd z(N);
  Eigen::MatrixXd X(N, D.P);
  for (int k = 0; k < N; ++k) {
    z(k) = D.zp[a](S.parents[k]);
    X.row(k) = D.Xp[a].row(S.parents[k]);
  }
  Eigen::MatrixXd R = parent_cov(d, D, S.parents, a, ds, tau, true);
  Eigen::LLT<Eigen::MatrixXd> llt(R);
  for (int tries = 0; llt.info() != Eigen::Success && tries < 8; ++tries) {
    R.diagonal() *= 1.05;
    llt.compute(R);
  }
  S.L = llt.matrixL();
  const Eigen::VectorXd zl = S.L.triangularView<Eigen::Lower>().solve(z);
  const Eigen::MatrixXd Xl = S.L.triangularView<Eigen::Lower>().solve(X);
  S.G = Xl.transpose() * Xl;
  S.g = Xl.transpose() * zl;
  S.zz = zl.squaredNorm();
  S.logdet = 2 * S.L.diagonal().array().log().sum();
  S.n = N;
  return S;
}

struct FitOut {
  Eigen::VectorXd theta;  // global, zeros outside the model
  Eigen::MatrixXd cov;    // global (model rows/cols filled)
  double chi2 = 0;
  double chi2_axis[kAxes] = {};
  double logdet_info = 0;  // ln det(Xᵀ R⁻¹ X + priors): the restricted-likelihood (REML) term
};

std::vector<int> model_params(const Design& D, const std::vector<int>& terms) {
  std::vector<int> idx(D.n_base);
  std::iota(idx.begin(), idx.end(), 0);
  for (int t : terms)
    for (int p = 0; p < D.terms[t].nparams(); ++p) idx.push_back(D.term_off[t] + p);
  return idx;
}

double axis_chi2(const Dataset& S, const std::vector<int>& idx, const Eigen::VectorXd& theta) {
  double c = S.zz;
  for (int p : idx) {
    c -= 2 * theta(p) * S.g(p);
    for (int q : idx) c += theta(p) * S.G(p, q) * theta(q);
  }
  return c;
}

FitOut fit_model(const Design& D, const std::vector<int>& terms, const std::vector<const Dataset*>& sets) {
  const std::vector<int> idx = model_params(D, terms);
  const int K = static_cast<int>(idx.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(K, K);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(K);
  for (const Dataset* S : sets)
    for (int u = 0; u < K; ++u) {
      b(u) += S->g(idx[u]);
      for (int v = 0; v < K; ++v) A(u, v) += S->G(idx[u], idx[v]);
    }
  // Weak zero-mean priors on the catalogue parameters: a component a drive cannot see (e.g. the
  // g-sensitivity to the always-vertical gravity, which the bias absorbs, or the lever arm along
  // the yaw axis) stays at zero with σ ≈ its prior instead of trading off against the bias.
  for (int u = D.n_base; u < K; ++u) A(u, u) += 1.0 / std::pow(D.prior_sigma[idx[u] - D.n_base], 2);
  Eigen::VectorXd s(K);
  for (int i = 0; i < K; ++i) s(i) = A(i, i) > 0 ? 1.0 / std::sqrt(A(i, i)) : 1.0;
  Eigen::MatrixXd As = s.asDiagonal() * A * s.asDiagonal();
  As.diagonal().array() += 1e-9;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(As);
  const Eigen::VectorXd th = s.asDiagonal() * ldlt.solve(s.asDiagonal() * b);
  const Eigen::MatrixXd C = s.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(K, K)) * s.asDiagonal();
  FitOut out;
  out.logdet_info = ldlt.vectorD().array().log().sum() - 2 * s.array().log().sum();
  out.theta = Eigen::VectorXd::Zero(D.P);
  out.cov = Eigen::MatrixXd::Zero(D.P, D.P);
  for (int u = 0; u < K; ++u) {
    out.theta(idx[u]) = th(u);
    for (int v = 0; v < K; ++v) out.cov(idx[u], idx[v]) = C(u, v);
  }
  for (const Dataset* S : sets) {
    const double c = axis_chi2(*S, idx, out.theta);
    out.chi2_axis[S->axis] += c;
    out.chi2 += c;
  }
  return out;
}

// The drive as a problem of the catalogue search (greedy_search.hpp): global parameters; a term
// with no column on any axis is no candidate; a term's penalty counts the parent rows of the axes
// it touches, correlated_drift's the parents.
struct DriveProblem {
  using Dataset = calbench::Dataset;
  using Fit = FitOut;
  const DriveDiagData& d;
  const Design& D;
  int n_terms() const { return static_cast<int>(D.terms.size()); }
  const Term& term(int t) const { return D.terms[t]; }
  Dataset build(int a, int subset, double ds, double tau) const { return build_dataset(d, D, a, subset, ds, tau); }
  Fit fit(const std::vector<int>& m, const std::vector<const Dataset*>& sets) const { return fit_model(D, m, sets); }
  double chi2(const Dataset& S, const std::vector<int>& m, const Fit& f) const {
    return axis_chi2(S, model_params(D, m), f.theta);
  }
  bool touches(int t, int a) const { return std::find(D.touched[t].begin(), D.touched[t].end(), a) != D.touched[t].end(); }
  int rows(const Dataset& S) const { return S.n; }
  int drift_rows(const Dataset& S) const { return S.n; }
  int param_index(const Fit& /*f*/, std::size_t /*k*/, int t) const { return D.term_off[t]; }
};

// Parent-level residual of axis a for global parameters theta.
Eigen::VectorXd residual(const Design& D, int a, const Eigen::VectorXd& theta) { return D.zp[a] - D.Xp[a] * theta; }

// The drift the noise model attributes to a residual (GLS smoother), per parent.
Eigen::VectorXd smoothed_drift(const DriveDiagData& d, const Dataset& S, const Eigen::VectorXd& r) {
  const int N = S.n;
  const Eigen::VectorXd w = S.L.triangularView<Eigen::Lower>().solve(r);
  const Eigen::VectorXd v = S.L.transpose().triangularView<Eigen::Upper>().solve(w);
  std::vector<double> centre(N), duration(N);
  for (int k = 0; k < N; ++k) {
    centre[k] = d.parents[S.parents[k]].t_mid;
    duration[k] = d.parents[S.parents[k]].duration;
  }
  return gm_window_smoothed(centre, duration, S.ds, S.tau, v);
}

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

AxisStats axis_stats(const DriveDiagData& d, const Design& D, const Dataset& S, const Eigen::VectorXd& r, int nparams,
                     Eigen::VectorXd& r_nodrift) {
  AxisStats st;
  const int N = S.n;
  const Eigen::VectorXd rw = S.L.triangularView<Eigen::Lower>().solve(r);
  st.chi2_dof = rw.squaredNorm() / std::max(1, N - nparams / kAxes);
  std::vector<double> rv(rw.data(), rw.data() + rw.size());
  ljung_box(rv, std::min(10, std::max(1, N / 5)), st.ljung_box_q, st.ljung_box_p);
  r_nodrift = r - smoothed_drift(d, S, r);
  st.systematic_rms = grouped_systematic(D, S.axis, r_nodrift, time_groups(N, 10), &st.systematic_floor);
  st.step_rms = st.systematic_rms;
  return st;
}

double pearson(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  const double mx = x.mean(), my = y.mean();
  const double sxy = ((x.array() - mx) * (y.array() - my)).sum();
  const double sxx = (x.array() - mx).square().sum(), syy = (y.array() - my).square().sum();
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
}

std::vector<ConditionCorrelation> correlations(const DriveDiagData& d, const Eigen::VectorXd& r) {
  std::vector<ConditionCorrelation> out;
  const int N = static_cast<int>(d.parents.size());
  for (const auto& name : drive_condition_names(d.has_temperature)) {
    Eigen::VectorXd c(N);
    for (int k = 0; k < N; ++k) c(k) = drive_condition_value(d, k, name);
    out.push_back({name, pearson(c, r)});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return std::abs(a.r) > std::abs(b.r); });
  return out;
}


}  // namespace

std::vector<std::string> drive_condition_names(bool with_temperature) {
  std::vector<std::string> n = {"speed", "w_x", "w_y", "w_z", "f_x", "f_y", "f_z", "|w|", "|f|",
                                "ang_accel", "turn_rate", "along_accel", "time"};
  if (with_temperature) n.push_back("temperature");
  return n;
}

double drive_condition_value(const DriveDiagData& d, int k, const std::string& name) {
  const ParentBlock& p = d.parents[k];
  const DriveParentInfo& i = d.info[k];
  if (name == "speed") return i.speed;
  if (name == "w_x") return p.w(0);
  if (name == "w_y") return p.w(1);
  if (name == "w_z") return p.w(2);
  if (name == "f_x") return p.f(0);
  if (name == "f_y") return p.f(1);
  if (name == "f_z") return p.f(2);
  if (name == "|w|") return p.w.norm();
  if (name == "|f|") return p.f.norm();
  if (name == "ang_accel") return i.ang_accel;
  if (name == "turn_rate") return i.turn_rate;
  if (name == "along_accel") return i.along_accel;
  if (name == "time") return p.t_mid;
  if (name == "temperature") {
    double t = 0, w = 0;
    for (int j = p.first; j < p.first + p.count; ++j)
      if (std::isfinite(d.subs[j].temp_c)) {
        t += d.subs[j].temp_c;
        w += 1;
      }
    return w > 0 ? t / w : 0.0;
  }
  return 0.0;
}

namespace {

// Mounting rotation δ of the base model (bias and δ, M fixed, data-sheet drift), MEMS axes.
Vec3 base_mounting_delta(const DriveDiagData& data, const SensorErrors& current, const EffectTerms& carried,
                         const DriveDiagnoseOptions& opt) {
  const Design D = build_design(data, current, carried, true);
  std::vector<Dataset> sets;
  const double ds[2] = {opt.noise.gyro.drift_sigma, opt.noise.accel.drift_sigma};
  const double tau[2] = {opt.noise.gyro.drift_tau_s, opt.noise.accel.drift_tau_s};
  for (int a = 0; a < kAxes; ++a) sets.push_back(build_dataset(data, D, a, kSubsetAll, ds[a / 3], tau[a / 3]));
  std::vector<const Dataset*> ptrs;
  for (const auto& S : sets) ptrs.push_back(&S);
  return fit_model(D, {}, ptrs).theta.segment<3>(6);
}

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

  const DriveProblem problem{data, D};
  GreedyPolicy policy;
  policy.min_delta_chi2 = opt.min_delta_chi2;
  policy.penalty_per_param = opt.penalty_per_param;
  policy.max_findings = opt.max_findings;
  // A drift larger than the data sheet says (correlated_drift) competes with the linear terms in
  // every round: a wandering bias would otherwise be half-explained by spurious linear terms.
  policy.drift_competes = true;
  policy.skip_untouched = true;
  const double drift_sigma[2] = {opt.noise.gyro.drift_sigma, opt.noise.accel.drift_sigma};
  const double drift_tau[2] = {opt.noise.gyro.drift_tau_s, opt.noise.accel.drift_tau_s};
  GreedySearch<DriveProblem> search(problem, policy, drift_sigma, drift_tau);
  const std::vector<Dataset>& all = search.all;

  // Before: the base model (bias, and M or the mounting) refitted, no catalogue term.
  const FitOut base_fit = search.cur;
  Eigen::VectorXd r_before[kAxes], rn_before[kAxes];
  const int nbase = D.n_base;
  for (int a = 0; a < kAxes; ++a) {
    r_before[a] = residual(D, a, base_fit.theta);
    res.before[a] = axis_stats(data, D, all[a], r_before[a], nbase, rn_before[a]);
    res.correlations_before[a] = correlations(data, rn_before[a]);
  }

  search.run();
  for (const auto& w : search.recheck_drift()) res.withdrawn.push_back(search.withdrawn_report(w));
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
  for (int triad = 0; triad < 2; ++triad) {
    TriadErrors& te = triad == 0 ? res.improved.gyro : res.improved.accel;
    TriadEffectTerms& v = triad == 0 ? res.improved_terms.gyro : res.improved_terms.accel;
    const TriadEffectTerms& sg = triad == 0 ? res.terms_sigma.gyro : res.terms_sigma.accel;
    for (int i = 0; i < 3; ++i)
      if (v.scale(i) != 0) {
        te.M(i, i) += v.scale(i);
        if (sg.scale(i) > 0) te.sigma_M(i, i) = sg.scale(i);
      }
    v.scale.setZero();
  }
  for (int triad = 0; triad < 2; ++triad) {
    res.drift_sigma[triad] = ds[triad];
    res.drift_tau[triad] = tau[triad];
  }
  Eigen::VectorXd r_after[kAxes], rn_after[kAxes];
  const int np = static_cast<int>(model_params(D, model).size());
  for (int a = 0; a < kAxes; ++a) {
    r_after[a] = residual(D, a, cur.theta);
    res.after[a] = axis_stats(data, D, all[a], r_after[a], np, rn_after[a]);
    out.correlations_after[a] = correlations(data, rn_after[a]);
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
      TriadEffectTerms& te = triad == 0 ? res.improved_terms.gyro : res.improved_terms.accel;
      te.drift_sigma = ds[triad];
      te.drift_tau_s = tau[triad];
      res.findings.push_back(f);
      continue;
    }
    DiagFinding f = search.term_finding(acc, carried);
    const Term& t = D.terms[acc.term];
    // Another candidate in its place that fits within ambiguity_chi2 and itself explains the
    // residual (as on the bench): the drive does not tell them apart.
    f.alternatives = search.alternatives(acc.term, opt.ambiguity_chi2, opt.min_delta_chi2, carried);
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
      const double r = pearson(c, contrib_show);
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
    const double z_low = (s.chi2_dof - 1) * std::sqrt(std::max(1, all[a].n) / 2.0);
    if (z_low < 6 && s.ljung_box_p > 1e-4) continue;
    DiagUnexplained u;
    u.sensor = a / 3;
    u.axis = a % 3;
    u.chi2_dof = s.chi2_dof;
    u.ljung_box_p = s.ljung_box_p;
    u.systematic_rms = s.systematic_rms;
    u.correlations = out.correlations_after[a];
    if (u.correlations.size() > 4) u.correlations.resize(4);
    std::map<int, std::pair<double, double>> win;
    for (int k = 0; k < NP; ++k) {
      auto& x = win[data.parents[k].step];
      x.first += rn_after[a](k);
      x.second += 1;
    }
    std::vector<std::pair<double, int>> score;
    const double sig = out.block_noise_sigma[a];
    for (const auto& [w, x] : win) score.push_back({std::abs(x.first / x.second) * std::sqrt(x.second) / sig, w});
    std::sort(score.rbegin(), score.rend());
    for (std::size_t k = 0; k < score.size() && k < 3; ++k) u.worst_steps.push_back(score[k].second);
    res.unexplained.push_back(u);
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
