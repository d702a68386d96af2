#include "calibration/diagnosis/diagnosis_engine.hpp"

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
