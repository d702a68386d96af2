// Overlapping Allan deviation and the IEEE 952 noise-term fit (see the header).
#include "calibration/identification/allan.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "calibration/qc/nis_test.hpp"

namespace calbench::identification {

double avar_quantisation(double Q, double tau) { return 3.0 * Q * Q / (tau * tau); }
double avar_white(double N, double tau) { return N * N / tau; }
double avar_bias_instability(double B) { return 2.0 * std::numbers::ln2 / std::numbers::pi * B * B; }
double avar_rate_random_walk(double K, double tau) { return K * K * tau / 3.0; }
double avar_rate_ramp(double R, double tau) { return R * R * tau * tau / 2.0; }
double avar_gauss_markov(double sigma, double T, double tau) {
  const double x = tau / T;
  if (x < 1e-4) return sigma * sigma * 2.0 / 3.0 * x;  // series: (2/3)σ² τ/T
  return sigma * sigma / (x * x) * (2.0 * x - 3.0 + 4.0 * std::exp(-x) - std::exp(-2.0 * x));
}

namespace {

// Equivalent degrees of freedom of the overlapping Allan variance (NIST SP 1065, table 5).
// M = number of phase (angle) points, m = cluster size, slope = d ln σ / d ln τ of the curve.
double edf_overlapping(double M, double m, double slope) {
  double e;
  if (slope <= -0.75) {  // white PM (quantisation)
    e = (M + 1.0) * (M - 2.0 * m) / (2.0 * (M - m));
  } else if (slope <= -0.25) {  // white FM (angle random walk)
    e = (3.0 * (M - 1.0) / (2.0 * m) - 2.0 * (M - 2.0) / M) * 4.0 * m * m / (4.0 * m * m + 5.0);
  } else if (slope <= 0.25) {  // flicker FM (bias instability)
    e = m == 1 ? 2.0 * (M - 2.0) / (2.3 * M - 4.9) : 5.0 * M * M / (4.0 * m * (M + 3.0 * m));
  } else {  // random-walk FM (rate random walk)
    e = (M - 2.0) / m * ((M - 1.0) * (M - 1.0) - 3.0 * m * (M - 1.0) + 4.0 * m * m) /
        ((M - 3.0) * (M - 3.0));
  }
  // Guard: the slope of a noisy curve can pick a formula outside its range (white PM at long τ
  // would claim ~M/2 degrees of freedom); never more than twice the number of disjoint clusters.
  return std::clamp(e, 1.0, std::max(1.0, 2.0 * (M - 1.0) / m));
}

}  // namespace

std::vector<AllanPoint> allan_deviation(std::span<const double> y, double dt, std::size_t max_m) {
  const std::size_t n = y.size();
  if (n < 8) throw std::invalid_argument("Allan deviation: need at least 8 samples");
  if (!(dt > 0)) throw std::invalid_argument("Allan deviation: dt must be positive");
  long double mean = 0;
  for (double v : y) mean += v;
  mean /= static_cast<long double>(n);
  // Angle θ_k = Σ_{i<k} (y_i − ȳ) dt; the mean does not change AVAR but would cost precision.
  std::vector<double> th(n + 1);
  long double acc = 0;
  th[0] = 0;
  for (std::size_t i = 0; i < n; ++i) {
    acc += (static_cast<long double>(y[i]) - mean) * dt;
    th[i + 1] = static_cast<double>(acc);
  }
  const std::size_t M = n + 1;
  std::vector<AllanPoint> pts;
  for (std::size_t m = 1; 2 * m + 1 <= M && (max_m == 0 || m <= max_m); m *= 2) {
    const std::size_t terms = M - 2 * m;
    double s = 0;
    const double* p = th.data();
    for (std::size_t k = 0; k < terms; ++k) {
      const double d = p[k + 2 * m] - 2.0 * p[k + m] + p[k];
      s += d * d;
    }
    AllanPoint a;
    a.m = m;
    a.tau = static_cast<double>(m) * dt;
    a.adev = std::sqrt(s / (2.0 * a.tau * a.tau * static_cast<double>(terms)));
    pts.push_back(a);
  }
  // Local slope → noise type → edf → χ² interval (68.3 %: z = ±1).
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, pts.size() - 1);
    double slope = -0.5;
    if (b > a && pts[a].adev > 0 && pts[b].adev > 0)
      slope = std::log(pts[b].adev / pts[a].adev) / std::log(pts[b].tau / pts[a].tau);
    auto& pt = pts[i];
    pt.edf = edf_overlapping(static_cast<double>(M), static_cast<double>(pt.m), slope);
    const double avar = pt.adev * pt.adev;
    pt.lo = std::sqrt(avar * pt.edf / qc::chi2_quantile(pt.edf, 1.0));
    pt.hi = std::sqrt(avar * pt.edf / qc::chi2_quantile(pt.edf, -1.0));
  }
  return pts;
}

namespace {

constexpr int kMaxCols = 5;
using Basis = std::array<double (*)(double, double), kMaxCols>;

struct NnlsResult {
  Eigen::VectorXd c;     // coefficients (≥ 0), of the basis columns
  Eigen::MatrixXd cov;   // covariance of c (zero rows/cols for inactive ones)
  double chi2 = 0;
  bool ok = false;
};

// Weighted NNLS of avar ≈ Σ_j c_j f_j(τ) minimising χ² = Σ edf/2 · ((model − avar)/avar)²
// (relative residuals, weights from the measured AVAR: iterating with model-based weights can lock
// into a fit that overshoots where it gives itself little weight). Exact NNLS by enumerating the
// supports (at most 2^5 of them).
NnlsResult weighted_nnls(const Eigen::MatrixXd& F, const Eigen::VectorXd& avar, const Eigen::VectorXd& edf) {
  const int n = static_cast<int>(F.rows()), p = static_cast<int>(F.cols());
  NnlsResult best;
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) w(i) = std::sqrt(edf(i) / 2.0) / avar(i);
  const Eigen::MatrixXd A = w.asDiagonal() * F;
  const Eigen::VectorXd b = w.asDiagonal() * avar;
  Eigen::VectorXd scale(p);
  for (int j = 0; j < p; ++j) scale(j) = std::max(A.col(j).norm(), 1e-300);
  const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
  double best_cost = std::numeric_limits<double>::infinity();
  for (int mask = 1; mask < (1 << p); ++mask) {
    std::vector<int> cols;
    for (int j = 0; j < p; ++j)
      if (mask & (1 << j)) cols.push_back(j);
    if (static_cast<int>(cols.size()) > n) continue;
    Eigen::MatrixXd S(n, static_cast<int>(cols.size()));
    for (std::size_t k = 0; k < cols.size(); ++k) S.col(static_cast<int>(k)) = As.col(cols[k]);
    const Eigen::VectorXd x = S.colPivHouseholderQr().solve(b);
    if (!x.allFinite() || (x.array() < 0).any()) continue;
    const double cost = (S * x - b).squaredNorm();
    if (cost < best_cost) {
      best_cost = cost;
      best.c = Eigen::VectorXd::Zero(p);
      best.cov = Eigen::MatrixXd::Zero(p, p);
      for (std::size_t k = 0; k < cols.size(); ++k) best.c(cols[k]) = x(static_cast<int>(k)) / scale(cols[k]);
      const Eigen::MatrixXd inv = (S.transpose() * S).inverse();
      for (std::size_t k = 0; k < cols.size(); ++k)
        for (std::size_t l = 0; l < cols.size(); ++l)
          best.cov(cols[k], cols[l]) = inv(static_cast<int>(k), static_cast<int>(l)) /
                                       (scale(cols[k]) * scale(cols[l]));
      best.chi2 = cost;
      best.ok = true;
    }
  }
  return best;
}

// Term from a coefficient c of the AVAR basis: value = √(c/k), se by the delta method.
AllanTerm term_from(const NnlsResult& r, int j, double k) {
  AllanTerm t;
  const double c = r.c(j);
  if (c > 0) {
    t.present = true;
    t.value = std::sqrt(c / k);
    t.se = std::sqrt(std::max(r.cov(j, j), 0.0)) / (2.0 * std::sqrt(c * k));
  }
  return t;
}

}  // namespace

AllanFit fit_allan(const std::vector<AllanPoint>& pts_in) {
  AllanFit f;
  std::vector<AllanPoint> pts;
  for (const auto& p : pts_in)
    if (p.edf >= 1.0 && p.adev > 0 && std::isfinite(p.adev)) pts.push_back(p);
  f.points = pts.size();
  if (pts.size() < 3) return f;
  const int n = static_cast<int>(pts.size());
  Eigen::VectorXd avar(n), edf(n);
  for (int i = 0; i < n; ++i) {
    avar(i) = pts[static_cast<std::size_t>(i)].adev * pts[static_cast<std::size_t>(i)].adev;
    edf(i) = pts[static_cast<std::size_t>(i)].edf;
  }
  // Unit-coefficient basis: AVAR = c_Q·(1/τ²) + c_N·(1/τ) + c_B·1 + c_K·τ + c_R·τ².
  Eigen::MatrixXd F(n, 5);
  for (int i = 0; i < n; ++i) {
    const double t = pts[static_cast<std::size_t>(i)].tau;
    F.row(i) << 1.0 / (t * t), 1.0 / t, 1.0, t, t * t;
  }
  const NnlsResult r = weighted_nnls(F, avar, edf);
  if (r.ok) {
    f.Q = term_from(r, 0, 3.0);
    f.N = term_from(r, 1, 1.0);
    f.B = term_from(r, 2, 2.0 * std::numbers::ln2 / std::numbers::pi);
    f.K = term_from(r, 3, 1.0 / 3.0);
    f.R = term_from(r, 4, 0.5);
    f.chi2 = r.chi2;
  }
  // Gauss–Markov alternative: grid over T (log-spaced across the τ range and beyond).
  const double t_lo = pts.front().tau, t_hi = pts.back().tau;
  double best = std::numeric_limits<double>::infinity();
  for (int g = 0; g <= 80; ++g) {
    const double T = t_lo * std::pow(t_hi * 10.0 / t_lo, g / 80.0);
    Eigen::MatrixXd Fg = F;
    for (int i = 0; i < n; ++i) Fg(i, 2) = avar_gauss_markov(1.0, T, pts[static_cast<std::size_t>(i)].tau);
    const NnlsResult rg = weighted_nnls(Fg, avar, edf);
    if (rg.ok && rg.chi2 < best) {
      best = rg.chi2;
      f.gm_chi2 = rg.chi2;
      f.gm_present = rg.c(2) > 0;
      f.gm_sigma = std::sqrt(std::max(rg.c(2), 0.0));
      f.gm_T = T;
      f.gm_N = term_from(rg, 1, 1.0);
      f.gm_K = term_from(rg, 3, 1.0 / 3.0);
    }
  }
  auto it = std::min_element(pts.begin(), pts.end(), [](auto& a, auto& b) { return a.adev < b.adev; });
  f.adev_min = it->adev;
  f.tau_min = it->tau;
  f.B_from_min = it->adev / std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi);
  f.N_at_1s = f.N.value;
  return f;
}

}  // namespace calbench::identification
