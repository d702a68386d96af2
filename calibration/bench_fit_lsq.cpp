// Bench fit by generalised least squares over the whole recording: paper eq 5 generalised.
// Instead of x̂ = H⁻¹Z, each triad axis solves  min (z − Hθ)ᵀ R⁻¹ (z − Hθ)  with the full noise
// covariance R of the block observations (white + Gauss–Markov drift + per-step bench error):
// R = L·Lᵀ (Cholesky), whitened system L⁻¹H θ = L⁻¹z solved by Householder QR; Cov θ = (RᵀR)⁻¹
// from the QR's triangular factor. No explicit inverse of H or R is ever formed.
#include <cmath>

#include "calibration/bench_fit.hpp"
#include "calibration/gauss_markov_window.hpp"

namespace calbench {

using bench_fit_detail::AxisProblem;

BenchFitResult fit_bench_lsq(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt,
                             const std::vector<AxisProblem>& problems, BenchFitResult r) {
  using namespace bench_fit_detail;
  const int N = static_cast<int>(blocks.size());
  Eigen::MatrixXd R(N, N);
  for (const AxisProblem& p : problems) {
    std::vector<int> idx;
    for (int k = 0; k < kAxisParams; ++k)
      if (p.estimated[k]) idx.push_back(k);
    const int m = static_cast<int>(idx.size());
    TriadErrors& te = p.triad == TriadId::gyro ? r.estimate.gyro : r.estimate.accel;
    te.bias(p.axis) = 0;
    te.sigma_bias(p.axis) = kUnknownSigma;
    for (int j = 0; j < 3; ++j) {
      te.M(p.axis, j) = 0;
      te.sigma_M(p.axis, j) = kUnknownSigma;
    }
    if (m == 0) continue;

    Eigen::VectorXd z(N), sb(N);
    Eigen::MatrixXd H(N, m);
    for (int k = 0; k < N; ++k) {
      z(k) = observation(blocks[k], p.triad, p.axis);
      const auto row = design_row(blocks[k], p.triad);
      for (int a = 0; a < m; ++a) H(k, a) = row(idx[a]);
      sb(k) = bench_error_sigma(blocks[k], p.triad, p.axis, opt.table);
    }
    const double s2 = p.drift_sigma * p.drift_sigma;
    for (int k = 0; k < N; ++k) {
      for (int l = 0; l <= k; ++l) {
        double v = s2 * gm_window_correlation(blocks[k].t_mid, blocks[k].duration, blocks[l].t_mid, blocks[l].duration, p.drift_tau);
        if (blocks[k].step == blocks[l].step) v += sb(k) * sb(l);
        if (k == l) v += p.white_var / blocks[k].n;
        R(k, l) = v;
      }
    }
    const Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(R);
    if (llt.info() != Eigen::Success) throw std::runtime_error("bench fit: noise covariance not positive definite");
    const auto L = llt.matrixL();
    const Eigen::VectorXd zw = L.solve(z);
    const Eigen::MatrixXd Hw = L.solve(H);
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Hw);
    const Eigen::VectorXd theta = qr.solve(zw);
    const Eigen::MatrixXd Rq = qr.matrixQR().topLeftCorner(m, m).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd Rinv =
        Rq.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(m, m));  // m×m triangular
    const Eigen::MatrixXd cov = Rinv * Rinv.transpose();
    const double chi2 = (zw - Hw * theta).squaredNorm() / std::max(N - m, 1);
    (p.triad == TriadId::gyro ? r.gyro_chi2_dof : r.accel_chi2_dof)(p.axis) = chi2;
    for (int a = 0; a < m; ++a) {
      const int k = idx[a];
      const double sig = std::sqrt(cov(a, a));
      if (k == kParBias) {
        te.bias(p.axis) = theta(a);
        te.sigma_bias(p.axis) = sig;
      } else {
        te.M(p.axis, k - kParM0) = theta(a);
        te.sigma_M(p.axis, k - kParM0) = sig;
      }
    }
  }
  return r;
}

}  // namespace calbench
