#include "calibration/diagnosis/bench_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "calibration/bench_fit.hpp"

namespace calbench::bench_diag {

namespace {

// Halves for the held-out check: the first and the second half of every plan step (splitting by
// whole steps would leave one half without the ±rate pairs or magnitudes a term needs).
bool in_subset(const DiagData& d, int p, int subset) {
  if (subset == kSubsetAll) return true;
  int first = p, last = p;
  while (first > 0 && d.parents[first - 1].step == d.parents[p].step) --first;
  while (last + 1 < static_cast<int>(d.parents.size()) && d.parents[last + 1].step == d.parents[p].step) ++last;
  const bool early = 2 * (p - first) < (last - first + 1);
  return early == (subset == kSubsetEven);
}

double sensor_ref(const SubBlock& s, int a, int c) {
  const Vec3& ref = a < 3 ? s.w : s.f;
  return ref(c);
}

double bench_sigma(const ParentBlock& p, int a, const TableSpec& table) {
  BenchBlock b;
  b.w = p.w;
  b.f = p.f;
  return bench_fit_detail::bench_error_sigma(b, a < 3 ? TriadId::gyro : TriadId::accel, a % 3, table);
}

// Parent-level raw means of z and columns.
void parent_means(const DiagData& d, const Design& D, int a, int p, double& z, Eigen::RowVectorXd& x) {
  const ParentBlock& pb = d.parents[p];
  z = 0;
  x = Eigen::RowVectorXd::Zero(D.ncols[a]);
  for (int j = pb.first; j < pb.first + pb.count; ++j) {
    const double w = static_cast<double>(d.subs[j].n) / pb.n;
    z += w * D.z[a](j);
    x += w * D.X[a].row(j);
  }
}

Eigen::MatrixXd parent_cov(const DiagData& d, const std::vector<int>& P, int a, double white_var, double ds, double tau,
                           const TableSpec& table) {
  const int N = static_cast<int>(P.size());
  Eigen::MatrixXd R(N, N);
  std::vector<double> sb(N);
  for (int k = 0; k < N; ++k) sb[k] = bench_sigma(d.parents[P[k]], a, table);
  for (int k = 0; k < N; ++k)
    for (int l = 0; l <= k; ++l) {
      const ParentBlock &pk = d.parents[P[k]], &pl = d.parents[P[l]];
      double v = diag::drift_covariance(pk, pl, ds, tau);
      if (pk.step == pl.step) v += sb[k] * sb[l];
      if (k == l) v += white_var / pk.n;
      R(k, l) = R(l, k) = v;
    }
  return R;
}

// The columns of D.terms: per axis, the base columns then every term touching it (col_of, ncols),
// and each term's offset in the global parameter vector.
void lay_out_terms(Design& D) {
  for (int a = 0; a < kAxes; ++a) {
    D.col_of[a].assign(D.terms.size(), -1);
    int c = kBase;
    for (std::size_t t = 0; t < D.terms.size(); ++t)
      if (D.terms[t].touches(a / 3, a % 3)) {
        D.col_of[a][t] = c;
        c += D.terms[t].nparams();
      }
    D.ncols[a] = c;
  }
  D.term_param_offset.clear();
  D.n_term_params = 0;
  for (const auto& t : D.terms) {
    D.term_param_offset.push_back(D.n_term_params);
    D.n_term_params += t.nparams();
  }
}

// The excitation check: per term, the information its columns carry beyond the base columns (b, M
// of each touched axis), sub-blocks weighted by their white-noise variance only (optimistic: the
// drift and the bench errors would only widen σ). A term whose best parameter's 1σ exceeds a third
// of its plausible size (the spec's prior σ) cannot be seen here: it is dropped from the candidates
// and listed, so that it is neither named nor reported as absent.
void drop_unexcited(const DiagData& d, Design& D) {
  const int N = static_cast<int>(d.subs.size());
  // Per axis, once: the weights, Bᵀ·W and the factorised BᵀWB of the base columns.
  std::vector<Eigen::VectorXd> w(kAxes);
  std::vector<Eigen::MatrixXd> BtW(kAxes);
  std::vector<Eigen::LDLT<Eigen::MatrixXd>> BB(kAxes);
  for (int a = 0; a < kAxes; ++a) {
    w[a].resize(N);
    for (int j = 0; j < N; ++j) w[a](j) = d.subs[j].n / D.white_var[a];
    BtW[a] = D.X[a].leftCols(kBase).transpose() * w[a].asDiagonal();
    BB[a].compute(BtW[a] * D.X[a].leftCols(kBase));
  }
  std::vector<Term> kept;
  std::vector<int> old_of;  // kept term → its index before
  for (std::size_t t = 0; t < D.terms.size(); ++t) {
    const Term& term = D.terms[t];
    const double plausible = effect_spec(term.effect).drive_prior[term.sensor == 1 ? 1 : 0];
    const int np = term.nparams();
    Eigen::MatrixXd info = Eigen::MatrixXd::Zero(np, np);
    for (int a = 0; a < kAxes; ++a) {
      const int c0 = D.col_of[a][t];
      if (c0 < 0) continue;
      const auto X = D.X[a].middleCols(c0, np);
      const Eigen::MatrixXd BX = BtW[a] * X;
      info += X.transpose() * w[a].asDiagonal() * X - BX.transpose() * BB[a].solve(BX);
    }
    // σ of each parameter with the others free; a parameter the record does not see at all has
    // (numerically) no information and an infinite σ.
    const Eigen::VectorXd scale = info.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd S = scale.asDiagonal() * info * scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
    const double lmax = std::max(es.eigenvalues().maxCoeff(), 1e-300);
    Eigen::VectorXd inv = Eigen::VectorXd::Zero(np);
    for (int k = 0; k < np; ++k)
      if (es.eigenvalues()(k) > 1e-12 * lmax) inv += es.eigenvectors().col(k).cwiseAbs2() / es.eigenvalues()(k);
      else inv += es.eigenvectors().col(k).cwiseAbs2() * std::numeric_limits<double>::infinity();
    double best = std::numeric_limits<double>::infinity();
    for (int p = 0; p < np; ++p)
      if (info(p, p) > 0) best = std::min(best, std::sqrt(inv(p)) * scale(p) / plausible);
    if (best * 3 < 1) {
      kept.push_back(term);
      old_of.push_back(static_cast<int>(t));
    } else {
      D.not_excited.push_back({term, best});
    }
  }
  if (kept.size() == D.terms.size()) return;
  // Lay the kept terms out again and move their columns.
  const std::vector<std::vector<int>> old_col_of(D.col_of, D.col_of + kAxes);
  D.terms = std::move(kept);
  lay_out_terms(D);
  for (int a = 0; a < kAxes; ++a) {
    Eigen::MatrixXd X(D.X[a].rows(), D.ncols[a]);
    X.leftCols(kBase) = D.X[a].leftCols(kBase);
    for (std::size_t u = 0; u < D.terms.size(); ++u)
      if (D.col_of[a][u] >= 0)
        X.middleCols(D.col_of[a][u], D.terms[u].nparams()) = D.X[a].middleCols(old_col_of[a][old_of[u]], D.terms[u].nparams());
    D.X[a] = std::move(X);
  }
}

}  // namespace

Design build_design(const DiagData& d, const EffectTerms& carried) {
  Design D;
  // The bench refits M: a scale_factor term would be M_ii again.
  for (const Term& t : candidate_terms())
    if (effect_spec(t.effect).bench_candidate) D.terms.push_back(t);
  lay_out_terms(D);
  const int N = static_cast<int>(d.subs.size());
  D.z.assign(kAxes, Eigen::VectorXd(N));
  D.X.resize(kAxes);
  for (int a = 0; a < kAxes; ++a) D.X[a] = Eigen::MatrixXd::Zero(N, D.ncols[a]);
  const bool carry = carried.any();
  for (int j = 0; j < N; ++j) {
    const SubBlock& s = d.subs[j];
    Vec3 cg = Vec3::Zero(), ca = Vec3::Zero();
    if (carry) predict_extra(carried, s, cg, ca);
    for (int a = 0; a < kAxes; ++a) {
      const int i = a % 3;
      D.z[a](j) = a < 3 ? s.gyro(i) - s.w(i) - cg(i) : s.accel(i) - s.f(i) - ca(i);
      D.X[a](j, 0) = 1.0;
      for (int c = 0; c < 3; ++c) D.X[a](j, 1 + c) = sensor_ref(s, a, c);
    }
    for (std::size_t t = 0; t < D.terms.size(); ++t) {
      const Term& term = D.terms[t];
      for (int p = 0; p < term.nparams(); ++p) {
        const EffectTerms unit = diag::unit_term(term, p, carried.t0_c);
        Vec3 dg, da;
        predict_extra(unit, s, dg, da);
        for (int a = 0; a < kAxes; ++a)
          if (D.col_of[a][t] >= 0) D.X[a](j, D.col_of[a][t] + p) = a < 3 ? dg(a) : da(a - 3);
      }
    }
  }
  // White noise per sample: pooled scatter inside static sub-blocks (all if none is static).
  for (int a = 0; a < kAxes; ++a) {
    double ss = 0, dof = 0, ss_all = 0, dof_all = 0;
    for (const auto& s : d.subs) {
      const double v = a < 3 ? s.gyro_ss(a) : s.accel_ss(a - 3);
      ss_all += v;
      dof_all += s.n - 1;
      if (!s.rotating()) {
        ss += v;
        dof += s.n - 1;
      }
    }
    D.white_var[a] = std::max(dof > 100 ? ss / dof : ss_all / std::max(dof_all, 1.0), 1e-30);
  }
  drop_unexcited(d, D);
  return D;
}

Dataset build_dataset(const DiagData& d, const Design& D, int a, int subset, double ds, double tau,
                      const DiagnoseOptions& opt) {
  Dataset S = diag::subset_dataset(a, subset, ds, tau, static_cast<int>(d.parents.size()),
                                   [&](int p) { return in_subset(d, p, subset); });
  const int N = static_cast<int>(S.parents.size());
  const int C = D.ncols[a];
  Eigen::VectorXd zP(N);
  Eigen::MatrixXd XP(N, C);
  for (int k = 0; k < N; ++k) {
    double z;
    Eigen::RowVectorXd x;
    parent_means(d, D, a, S.parents[k], z, x);
    zP(k) = z;
    XP.row(k) = x;
  }
  diag::whiten(S, parent_cov(d, S.parents, a, D.white_var[a], ds, tau, opt.table), zP, XP, 0);
  S.Gl = S.G;
  S.gl = S.g;
  S.zzl = S.zz;
  // High level: sub-block deviations from their parent's mean, white noise only.
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    if (pb.count < 2) continue;
    double zp;
    Eigen::RowVectorXd xp;
    parent_means(d, D, a, S.parents[k], zp, xp);
    for (int j = pb.first; j < pb.first + pb.count; ++j) {
      const double nj = d.subs[j].n;
      const double var = D.white_var[a] / nj * (1.0 - nj / pb.n);
      if (var <= 0) continue;
      const double w = 1.0 / std::sqrt(var);
      const double zh = (D.z[a](j) - zp) * w;
      const Eigen::RowVectorXd xh = (D.X[a].row(j) - xp) * w;
      S.G.noalias() += xh.transpose() * xh;
      S.g += xh.transpose() * zh;
      S.zz += zh * zh;
      ++S.n_high;
    }
  }
  return S;
}

// Local (column, global parameter) pairs of a model on axis a.
diag::ColumnMap column_map(const Design& D, const Model& m, int a, std::vector<int>& offset) {
  diag::ColumnMap cm;
  for (int c = 0; c < kBase; ++c) cm.push_back({c, a * kBase + c});
  offset.clear();
  int off = kAxes * kBase;
  for (int t : m) {
    offset.push_back(off);
    if (D.col_of[a][t] >= 0)
      for (int p = 0; p < D.terms[t].nparams(); ++p) cm.push_back({D.col_of[a][t] + p, off + p});
    off += D.terms[t].nparams();
  }
  return cm;
}

int model_params(const Design& D, const Model& m) {
  int n = kAxes * kBase;
  for (int t : m) n += D.terms[t].nparams();
  return n;
}

FitOut fit_model(const Design& D, const Model& m, const std::vector<const Dataset*>& sets) {
  const int P = model_params(D, m);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(P, P);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(P);
  FitOut out;
  for (const Dataset* S : sets) diag::accumulate_normal(A, b, *S, column_map(D, m, S->axis, out.offset));
  // Jacobi scaling, tiny ridge for parameters the subset cannot see.
  diag::solve_scaled(A, b, 1e-10, out.theta, out.cov, out.logdet_info);
  for (const Dataset* S : sets) {
    std::vector<int> off;
    const auto cm = column_map(D, m, S->axis, off);
    const double c2 = diag::quadratic_chi2(S->G, S->g, S->zz, cm, out.theta);
    out.chi2_axis[S->axis] += c2;
    out.chi2 += c2;
  }
  return out;
}

// Residual per sub-block of axis a for parameters theta of model m.
Eigen::VectorXd residual(const Design& D, const Model& m, int a, const Eigen::VectorXd& theta) {
  std::vector<int> off;
  const auto cm = column_map(D, m, a, off);
  Eigen::VectorXd r = D.z[a];
  for (const auto& [c, p] : cm) r -= theta(p) * D.X[a].col(c);
  return r;
}

// Residual of the given coefficients (b, M) on axis a.
Eigen::VectorXd residual_coeffs(const Design& D, const SensorErrors& e, int a) {
  const TriadErrors& te = a < 3 ? e.gyro : e.accel;
  const int i = a % 3;
  Eigen::VectorXd r = D.z[a];
  r.array() -= te.bias(i);
  for (int c = 0; c < 3; ++c) r -= te.M(i, c) * D.X[a].col(1 + c);
  return r;
}

// Parent-block means of a sub-block residual series on one axis.
Eigen::VectorXd parent_means(const DiagData& d, const Dataset& S, const Eigen::VectorXd& r) {
  const int N = static_cast<int>(S.parents.size());
  Eigen::VectorXd rP(N);
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    double z = 0;
    for (int j = pb.first; j < pb.first + pb.count; ++j) z += d.subs[j].n * r(j);
    rP(k) = z / pb.n;
  }
  return rP;
}

}  // namespace calbench::bench_diag
