#include "calibration/diagnosis/drive_design.hpp"

#include <cmath>
#include <numeric>

#include "calibration/ins/nav_math.hpp"

namespace calbench::drive_diag {

namespace {

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
    case DriveDiagnosis::alternative_only: return true;     // a column, never accepted (drive_diagnose)
    case DriveDiagnosis::never: return false;
  }
  return false;
}

// σ of the weak zero-mean prior on a term's parameters (SI; see fit_model).
double drive_prior_scale(const Term& t) { return effect_spec(t.effect).drive_prior[t.sensor == 0 ? 0 : 1]; }

// Terms nonlinear in their input (|x|, x·|x|): their regressor is taken at the smoothed input.
bool smoothed_input_term(const Term& term) { return effect_spec(term.effect).curvature; }

// Short-range noise of the design's z per axis: gamma, endpoint_var, white_scale, pvar, pcov.
void short_range_noise(const DriveDiagData& d, Design& D) {
  const int N = static_cast<int>(d.subs.size());
  const int NP = static_cast<int>(d.parents.size());
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
}

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
        const double v = diag::drift_covariance(pk, pl, ds, tau);
        R(k, l) += v;
        if (l != k) R(l, k) += v;
      }
  }
  return R;
}

}  // namespace

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
    const double ps = drive_prior_scale(t);
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
        const EffectTerms unit = diag::unit_term(term, p, carried.t0_c);
        Vec3 dg, da;
        if (smoothed_input_term(term)) {
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
  short_range_noise(d, D);
  return D;
}

Dataset build_dataset(const DriveDiagData& d, const Design& D, int a, int subset, double ds, double tau) {
  Dataset S = diag::subset_dataset(a, subset, ds, tau, static_cast<int>(d.parents.size()),
                                   [&](int p) { return in_subset(d.parents[p], subset); });
  const int N = static_cast<int>(S.parents.size());
  Eigen::VectorXd z(N);
  Eigen::MatrixXd X(N, D.P);
  for (int k = 0; k < N; ++k) {
    z(k) = D.zp[a](S.parents[k]);
    X.row(k) = D.Xp[a].row(S.parents[k]);
  }
  diag::whiten(S, parent_cov(d, D, S.parents, a, ds, tau, true), z, X, 8);
  return S;
}

std::vector<int> model_params(const Design& D, const std::vector<int>& terms) {
  std::vector<int> idx(D.n_base);
  std::iota(idx.begin(), idx.end(), 0);
  for (int t : terms)
    for (int p = 0; p < D.terms[t].nparams(); ++p) idx.push_back(D.term_off[t] + p);
  return idx;
}

FitOut fit_model(const Design& D, const std::vector<int>& terms, const std::vector<const Dataset*>& sets) {
  return diag::fit_global(model_params(D, terms), D.P, D.n_base, D.prior_sigma, sets);
}

}  // namespace calbench::drive_diag
