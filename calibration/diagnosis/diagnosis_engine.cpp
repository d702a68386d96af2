#include "calibration/diagnosis/diagnosis_engine.hpp"

#include <cmath>

namespace calbench::diag {

void whiten(LinearDataset& S, Eigen::MatrixXd R, const Eigen::VectorXd& z, const Eigen::MatrixXd& X, int retries) {
  Eigen::LLT<Eigen::MatrixXd> llt(R);
  for (int tries = 0; llt.info() != Eigen::Success && tries < retries; ++tries) {
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
  S.n_low = static_cast<int>(z.size());
}

void solve_scaled(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, double ridge, Eigen::VectorXd& theta,
                  Eigen::MatrixXd& cov, double& logdet_info) {
  const int P = static_cast<int>(A.rows());
  Eigen::VectorXd s(P);
  for (int i = 0; i < P; ++i) s(i) = A(i, i) > 0 ? 1.0 / std::sqrt(A(i, i)) : 1.0;
  Eigen::MatrixXd As = s.asDiagonal() * A * s.asDiagonal();
  As.diagonal().array() += ridge;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(As);
  theta = s.asDiagonal() * ldlt.solve(s.asDiagonal() * b);
  cov = s.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(P, P)) * s.asDiagonal();
  logdet_info = ldlt.vectorD().array().log().sum() - 2 * s.array().log().sum();
}

FitOut fit_global(const std::vector<int>& idx, int P, int n_base, const std::vector<double>& prior_sigma,
                  const std::vector<const LinearDataset*>& sets) {
  const int K = static_cast<int>(idx.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(K, K);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(K);
  ColumnMap cm;  // global column → the model's own parameter index
  for (int u = 0; u < K; ++u) cm.push_back({idx[u], u});
  for (const LinearDataset* S : sets) accumulate_normal(A, b, *S, cm);
  for (int u = 0; u < K; ++u) {
    if (idx[u] < n_base) continue;
    const double ps = prior_sigma[static_cast<std::size_t>(idx[u] - n_base)];
    if (ps > 0) A(u, u) += 1.0 / std::pow(ps, 2);
  }
  Eigen::VectorXd th;
  Eigen::MatrixXd C;
  FitOut out;
  solve_scaled(A, b, 1e-9, th, C, out.logdet_info);
  out.theta = Eigen::VectorXd::Zero(P);
  out.cov = Eigen::MatrixXd::Zero(P, P);
  for (int u = 0; u < K; ++u) {
    out.theta(idx[u]) = th(u);
    for (int v = 0; v < K; ++v) out.cov(idx[u], idx[v]) = C(u, v);
  }
  const ColumnMap gm = global_map(idx);
  for (const LinearDataset* S : sets) {
    const double c = quadratic_chi2(S->G, S->g, S->zz, gm, out.theta);
    out.chi2_axis[S->axis] += c;
    out.chi2 += c;
  }
  return out;
}

Eigen::VectorXd smoothed_drift(const std::vector<ParentBlock>& parents, const LinearDataset& S,
                               const Eigen::VectorXd& rP) {
  const int N = static_cast<int>(S.parents.size());
  const Eigen::VectorXd rw = S.L.triangularView<Eigen::Lower>().solve(rP);
  const Eigen::VectorXd v = S.L.transpose().triangularView<Eigen::Upper>().solve(rw);
  std::vector<double> centre(N), duration(N);
  for (int k = 0; k < N; ++k) {
    centre[k] = parents[S.parents[k]].t_mid;
    duration[k] = parents[S.parents[k]].duration;
  }
  return gm_window_smoothed(centre, duration, S.drift_sigma, S.drift_tau, v);
}

}  // namespace calbench::diag
