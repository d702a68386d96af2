// Drift-model identification from K̂: the paper's log-linear estimates (eqs 28–31, 38 and the α
// formula after it) and nonlinear least squares of eqs 24 and 37 (see the header).
#include "calibration/identification/correlation_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "calibration/identification/correlation.hpp"

namespace calbench::identification {

namespace {

// Leading run of positive K̂: the largest J ≤ max_lag with K̂(1 … J) > 0 (0 if K̂(1) ≤ 0).
std::size_t leading_positive_run(std::span<const double> K, std::size_t max_lag) {
  const std::size_t last = std::min(max_lag, K.size() - 1);
  std::size_t j = 0;
  while (j + 1 <= last && K[j + 1] > 0) ++j;
  return j;
}

// First zero of K̂ by linear interpolation between the lags around the first sign change; 0 if none.
double first_zero(std::span<const double> K, double dt, std::size_t max_lag) {
  const std::size_t last = std::min(max_lag, K.size() - 1);
  for (std::size_t j = 1; j <= last; ++j)
    if (K[j] <= 0) {
      const double a = K[j - 1], b = K[j];
      const double frac = a > b ? a / (a - b) : 0.0;
      return (static_cast<double>(j - 1) + frac) * dt;
    }
  return 0;
}

}  // namespace

PaperExponential paper_exponential(std::span<const double> K, double dt, std::size_t max_lag) {
  PaperExponential p;
  if (K.empty() || !(K[0] > 0)) return p;
  p.sigma = std::sqrt(K[0]);  // eq 28
  const std::size_t J = leading_positive_run(K, max_lag);
  p.lags_used = J;
  if (J == 0) return p;
  double sum_ln = 0, sum_tau = 0;  // eq 31 (j = 0 contributes ln 1 = 0 and τ = 0)
  for (std::size_t j = 1; j <= J; ++j) {
    sum_ln += std::log(K[j] / K[0]);  // eq 29
    sum_tau += static_cast<double>(j) * dt;
  }
  p.alpha = -sum_ln / sum_tau;
  p.valid = p.alpha > 0 && std::isfinite(p.alpha);
  return p;
}

PaperExpCosine paper_exp_cosine(std::span<const double> K, double dt, std::size_t max_lag) {
  PaperExpCosine p;
  if (K.empty() || !(K[0] > 0)) return p;
  p.sigma = std::sqrt(K[0]);  // eq 38
  p.tau_beta = first_zero(K, dt, max_lag);
  const std::size_t J = leading_positive_run(K, max_lag);
  p.lags_used = J;
  if (p.tau_beta <= 0 || J == 0) return p;
  p.beta = 0.5 * std::numbers::pi / p.tau_beta;  // eq 38
  double num = 0, sum_tau = 0;
  for (std::size_t j = 1; j <= J; ++j) {
    const double tau = static_cast<double>(j) * dt;
    const double c = std::cos(p.beta * tau);
    if (!(c > 0)) break;  // cannot happen for τ < τ_β; guards rounding at the zero itself
    num += std::log(c) - std::log(K[j] / K[0]);
    sum_tau += tau;
  }
  if (sum_tau > 0) p.alpha = num / sum_tau;
  p.valid = p.alpha > 0 && std::isfinite(p.alpha);
  return p;
}

namespace {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

// Model K(τ) = s e^{−ατ} cos βτ in normalised units, parameters θ = (s, ln α[, β]).
struct Problem {
  std::vector<double> tau;  // lags fitted, s
  std::vector<double> y;    // K̂/K̂(0) at those lags
  bool cosine = false;
  int p() const { return cosine ? 3 : 2; }
  void eval(const Vec& th, Vec& r, Mat* J) const {
    const std::size_t n = tau.size();
    r.resize(static_cast<Eigen::Index>(n));
    if (J) J->resize(static_cast<Eigen::Index>(n), p());
    const double s = th(0), a = std::exp(th(1)), b = cosine ? th(2) : 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Index ii = static_cast<Eigen::Index>(i);
      const double e = std::exp(-a * tau[i]);
      const double c = std::cos(b * tau[i]);
      r(ii) = s * e * c - y[i];
      if (J) {
        (*J)(ii, 0) = e * c;
        (*J)(ii, 1) = -s * tau[i] * a * e * c;
        if (cosine) (*J)(ii, 2) = -s * tau[i] * e * std::sin(b * tau[i]);
      }
    }
  }
};

struct LmResult {
  Vec th;
  double cost = 0;
  bool converged = false;
  int iterations = 0;
};

// Levenberg–Marquardt with Marquardt's diagonal scaling.
LmResult levenberg_marquardt(const Problem& pr, Vec th) {
  LmResult res;
  Vec r, r_new;
  Mat J;
  pr.eval(th, r, &J);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  for (int it = 0; it < 300; ++it) {
    res.iterations = it + 1;
    const Mat A = J.transpose() * J;
    const Vec g = J.transpose() * r;
    Mat Ad = A;
    for (int k = 0; k < A.rows(); ++k) Ad(k, k) += lambda * std::max(A(k, k), 1e-30);
    const Vec delta = Ad.ldlt().solve(-g);
    if (!delta.allFinite()) {
      lambda *= 10;
      if (lambda > 1e15) break;
      continue;
    }
    const Vec th_new = th + delta;
    pr.eval(th_new, r_new, nullptr);
    const double cost_new = r_new.squaredNorm();
    if (std::isfinite(cost_new) && cost_new <= cost) {
      const double decrease = cost - cost_new;
      th = th_new;
      cost = cost_new;
      pr.eval(th, r, &J);
      lambda = std::max(lambda / 3.0, 1e-12);
      if (decrease <= 1e-14 * std::max(cost, 1e-300) ||
          delta.norm() <= 1e-10 * (th.norm() + 1e-10)) {
        res.converged = true;
        break;
      }
    } else {
      lambda *= 4.0;
      if (lambda > 1e15) {
        // No downhill step even with a tiny trust region: at a minimum if the gradient vanishes.
        res.converged = g.norm() <= 1e-8 * (std::sqrt(A.diagonal().sum()) * std::sqrt(cost) + 1e-300);
        break;
      }
    }
  }
  res.th = th;
  res.cost = cost;
  return res;
}

// Bartlett: C(d) = Σ_m k_m k_{m+d}, d = 0 … 2L+2, of the two-sided model sequence (normalised
// units) with the empirical (white-noise-carrying) lag 0; cov(K̂(a), K̂(b)) = (C(|a−b|) + C(a+b))/N.
std::vector<double> bartlett_C(const DriftModel& m_norm, double k0_norm, double dt, std::size_t L) {
  const double decay = m_norm.alpha > 0 ? 25.0 / (m_norm.alpha * dt) : 1e7;
  const std::size_t M = std::min<std::size_t>(
      std::max<std::size_t>(2 * L + 2, static_cast<std::size_t>(std::min(decay, 4e6))), 8000000);
  std::vector<double> k(2 * M + 1);
  for (std::size_t m = 0; m <= M; ++m) {
    const double v = m == 0 ? k0_norm : m_norm.correlation(static_cast<double>(m) * dt);
    k[M + m] = v;
    k[M - m] = v;
  }
  return lagged_sums(k, 2 * L + 2);
}

// Jᵀ Σ J with Σ the Bartlett covariance of the normalised K̂ at the fitted lags.
Mat bartlett_jt_sigma_j(const Problem& pr, const Mat& J, const std::vector<double>& C, double dt,
                        std::size_t n_samples) {
  auto Cd = [&](std::size_t d) { return d < C.size() ? C[d] : 0.0; };
  const std::size_t n = pr.tau.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + 1999) / 2000);
  std::vector<std::size_t> lag(n);
  for (std::size_t i = 0; i < n; ++i) lag[i] = static_cast<std::size_t>(std::lround(pr.tau[i] / dt));
  const int p = static_cast<int>(J.cols());
  Mat out = Mat::Zero(p, p);
  for (std::size_t i = 0; i < n; i += stride)
    for (std::size_t j = 0; j < n; j += stride) {
      const std::size_t a = lag[i], b = lag[j];
      const double s = (Cd(a > b ? a - b : b - a) + Cd(a + b)) / static_cast<double>(n_samples);
      out.noalias() += s * J.row(static_cast<Eigen::Index>(i)).transpose() *
                       J.row(static_cast<Eigen::Index>(j));
    }
  return out * static_cast<double>(stride * stride);
}

NlsFit finish_fit(const Problem& pr, const LmResult& lm, std::span<const double> K, double dt,
                  std::size_t n_samples) {
  NlsFit f;
  f.kind = pr.cosine ? DriftModelKind::exp_cosine : DriftModelKind::exponential;
  f.converged = lm.converged;
  f.iterations = lm.iterations;
  const double K0 = K[0];
  const double s = lm.th(0), a = std::exp(lm.th(1)), b = pr.cosine ? std::abs(lm.th(2)) : 0.0;
  f.sigma = std::sqrt(std::max(s, 0.0) * K0);
  f.alpha = a;
  f.beta = b;
  f.lags = pr.tau.size();
  f.rss = lm.cost * K0 * K0;
  f.white_var = K0 - f.sigma * f.sigma;
  const double n = static_cast<double>(f.lags);
  const int p = pr.p();
  const double rss_n = std::max(f.rss / n, std::numeric_limits<double>::min());
  f.aic = n * std::log(rss_n) + 2.0 * p;
  f.bic = n * std::log(rss_n) + p * std::log(n);
  if (!(s > 0)) {
    f.converged = false;
    return f;
  }
  Vec r;
  Mat J;
  Vec th = lm.th;
  if (pr.cosine) th(2) = b;
  pr.eval(th, r, &J);
  const Mat JtJ = J.transpose() * J;
  Eigen::FullPivLU<Mat> lu(JtJ);
  lu.setThreshold(1e-12);
  if (!lu.isInvertible()) {  // e.g. β = 0 exactly, where the β column vanishes
    f.se_sigma = f.se_alpha = f.se_beta = std::numeric_limits<double>::infinity();
    f.se_sigma_iid = f.se_alpha_iid = f.se_beta_iid = std::numeric_limits<double>::infinity();
    return f;
  }
  const Mat inv = lu.inverse();
  // Naive covariance (independent residuals).
  const double dof = std::max(1.0, n - p);
  const Mat cov_iid = inv * (lm.cost / dof);
  // Bartlett sandwich.
  const DriftModel m_norm{f.kind, std::sqrt(s), a, b};
  const std::size_t L = static_cast<std::size_t>(std::lround(pr.tau.back() / dt));
  const std::vector<double> C = bartlett_C(m_norm, 1.0, dt, L);
  const Mat cov = inv * bartlett_jt_sigma_j(pr, J, C, dt, n_samples) * inv;
  // Most negative value of the fitted curve within the lags, and the Bartlett 1-σ of K̂ there.
  for (std::size_t i = 0; i < pr.tau.size(); ++i) {
    const double v = m_norm.correlation(pr.tau[i]);
    if (v < f.min_model / K0) {
      const std::size_t j = static_cast<std::size_t>(std::lround(pr.tau[i] / dt));
      const double var = (C[0] + (2 * j < C.size() ? C[2 * j] : 0.0)) / static_cast<double>(n_samples);
      f.min_model = v * K0;
      f.min_model_se = std::sqrt(std::max(var, 0.0)) * K0;
    }
  }
  auto to_se = [&](const Mat& c, double& se_sigma, double& se_alpha, double& se_beta) {
    // σ = √(s K0): dσ = √K0 ds /(2√s);  α = e^{θ₁}: dα = α dθ₁.
    se_sigma = std::sqrt(std::max(c(0, 0), 0.0)) * std::sqrt(K0) / (2.0 * std::sqrt(s));
    se_alpha = a * std::sqrt(std::max(c(1, 1), 0.0));
    se_beta = pr.cosine ? std::sqrt(std::max(c(2, 2), 0.0)) : 0.0;
  };
  to_se(cov_iid, f.se_sigma_iid, f.se_alpha_iid, f.se_beta_iid);
  to_se(cov, f.se_sigma, f.se_alpha, f.se_beta);
  return f;
}

Problem make_problem(std::span<const double> K, double dt, std::size_t first_lag,
                     std::size_t max_lag, bool cosine) {
  if (K.empty() || !(K[0] > 0)) throw std::invalid_argument("fit: K̂(0) must be positive");
  max_lag = std::min(max_lag, K.size() - 1);
  if (max_lag < first_lag + 3) throw std::invalid_argument("fit: need at least 4 lags");
  Problem pr;
  pr.cosine = cosine;
  for (std::size_t j = first_lag; j <= max_lag; ++j) {
    pr.tau.push_back(static_cast<double>(j) * dt);
    pr.y.push_back(K[j] / K[0]);
  }
  return pr;
}

// Starting α: the paper's estimate if usable, else 1/(first lag below K̂(1)/e).
double alpha_start(std::span<const double> K, double dt, std::size_t max_lag) {
  const PaperExponential pe = paper_exponential(K, dt, max_lag);
  if (pe.valid) return pe.alpha;
  const double ref = K.size() > 1 && K[1] > 0 ? K[1] : K[0];
  for (std::size_t j = 1; j <= std::min(max_lag, K.size() - 1); ++j)
    if (K[j] < ref / std::numbers::e) return 1.0 / (static_cast<double>(j) * dt);
  return 1.0 / (static_cast<double>(max_lag) * dt);
}

}  // namespace

NlsFit fit_exponential(std::span<const double> K, double dt, std::size_t n_samples,
                       std::size_t first_lag, std::size_t max_lag) {
  const Problem pr = make_problem(K, dt, first_lag, max_lag, false);
  Vec th(2);
  const double a0 = alpha_start(K, dt, max_lag);
  th << std::max(pr.y.front() * std::exp(a0 * pr.tau.front()), 1e-6), std::log(a0);
  return finish_fit(pr, levenberg_marquardt(pr, th), K, dt, n_samples);
}

NlsFit fit_exp_cosine(std::span<const double> K, double dt, std::size_t n_samples,
                      std::size_t first_lag, std::size_t max_lag, double beta_start_hint,
                      const NlsFit* exponential_fit) {
  const Problem pr = make_problem(K, dt, first_lag, max_lag, true);
  double a0 = alpha_start(K, dt, max_lag);
  double s0 = std::max(pr.y.front() * std::exp(a0 * pr.tau.front()), 1e-6);
  if (exponential_fit && exponential_fit->converged && exponential_fit->alpha > 0) {
    a0 = exponential_fit->alpha;
    s0 = exponential_fit->sigma * exponential_fit->sigma / K[0];
  }
  // Multi-start in β (the cosine makes the cost multimodal); keep the lowest converged cost.
  std::vector<double> starts;
  if (beta_start_hint > 0) starts.push_back(beta_start_hint);
  for (double f : {0.1, 0.5, 1.0, 2.0}) starts.push_back(f * a0);
  starts.push_back(0.5 * std::numbers::pi / (pr.tau.back()));
  LmResult best;
  bool have = false;
  for (double b0 : starts) {
    Vec th(3);
    th << s0, std::log(a0), b0;
    const LmResult r = levenberg_marquardt(pr, th);
    if (!std::isfinite(r.cost)) continue;
    if (!have || (r.converged && !best.converged) ||
        (r.converged == best.converged && r.cost < best.cost)) {
      best = r;
      have = true;
    }
  }
  // β = 0 nests the exponential: never report a worse fit than the exponential one.
  if (exponential_fit && exponential_fit->converged &&
      (!have || best.cost * K[0] * K[0] > exponential_fit->rss)) {
    best.th = Vec(3);
    best.th << exponential_fit->sigma * exponential_fit->sigma / K[0], std::log(exponential_fit->alpha), 0.0;
    best.converged = true;
    Vec r;
    pr.eval(best.th, r, nullptr);
    best.cost = r.squaredNorm();
    have = true;
  }
  if (!have) {
    NlsFit f;
    f.kind = DriftModelKind::exp_cosine;
    return f;
  }
  return finish_fit(pr, best, K, dt, n_samples);
}

Identification identify(std::span<const double> x, double dt, const IdentifyOptions& opt) {
  const std::size_t N = x.size();
  if (N < 20) throw std::invalid_argument("series too short: " + std::to_string(N) + " samples, need at least 20");
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("time step must be positive");
  long double sum = 0;
  for (double v : x) {
    if (!std::isfinite(v)) throw std::invalid_argument("series contains NaN or infinity");
    sum += v;
  }
  Identification id;
  id.n_samples = N;
  id.dt = dt;
  id.mean = static_cast<double>(sum / static_cast<long double>(N));
  const std::size_t cap = std::max<std::size_t>(std::min<std::size_t>(N / 5, N - 1), 10);
  std::size_t L = 0;
  std::vector<double> K;
  if (opt.max_lag_s > 0) {
    L = std::clamp<std::size_t>(static_cast<std::size_t>(std::llround(opt.max_lag_s / dt)), 5, N - 1);
    K = autocovariance(x, L);
  } else {
    K = autocovariance(x, cap);
  }
  if (!(K[0] > 0) || K[0] <= 1e-26 * (id.mean * id.mean))
    throw std::invalid_argument("series is constant (zero variance)");
  if (opt.max_lag_s <= 0) {
    const double ref = K[1] > 0 ? K[1] : K[0];
    std::size_t T0 = cap;
    for (std::size_t j = 1; j <= cap; ++j)
      if (K[j] < ref / std::numbers::e) {
        T0 = j;
        break;
      }
    std::size_t zero = 0;
    for (std::size_t j = 1; j <= std::min(cap, 3 * T0); ++j)
      if (K[j] <= 0) {
        zero = j;
        break;
      }
    L = std::max<std::size_t>(3 * T0, (5 * zero + 1) / 2);
    L = std::clamp<std::size_t>(L, std::min<std::size_t>(10, N - 1), cap);
    K.resize(L + 1);
  }
  id.max_lag = L;
  id.K = K;
  for (std::size_t j = 1; j <= L; ++j)
    if (K[j] < 0) id.sign_change = true;
  id.first_zero_s = first_zero(K, dt, L);
  id.paper_exp = paper_exponential(K, dt, L);
  id.paper_cos = paper_exp_cosine(K, dt, L);
  const std::size_t first = std::min<std::size_t>(opt.first_lag, L > 4 ? L - 4 : 0);
  id.exp = fit_exponential(K, dt, N, first, L);
  id.cos = fit_exp_cosine(K, dt, N, first, L, id.paper_cos.beta, &id.exp);

  std::ostringstream why;
  const double dbic = id.cos.bic - id.exp.bic;
  const double z = id.cos.se_beta > 0 && std::isfinite(id.cos.se_beta) ? id.cos.beta / id.cos.se_beta : 0.0;
  const double lobe_z = id.cos.min_model_se > 0 ? -id.cos.min_model / id.cos.min_model_se : 0.0;
  why << "BIC(exp_cosine) - BIC(exponential) = " << dbic << ", beta/se_beta = " << z
      << ", negative lobe depth/se = " << lobe_z
      << ", K changes sign: " << (id.sign_change ? "yes" : "no");
  // A fit is usable if it converged to a finite, resolvable correlation time with finite errors.
  const double t_rec = static_cast<double>(N) * dt;
  auto usable = [&](const NlsFit& f) {
    return f.converged && f.sigma > 0 && std::isfinite(f.se_alpha) && std::isfinite(f.se_sigma) &&
           f.alpha > 1e-3 / t_rec && f.alpha < 1e3 / dt;
  };
  id.exp.usable = usable(id.exp);
  id.cos.usable = usable(id.cos) && id.cos.beta > 0 && std::isfinite(id.cos.se_beta);
  if (!id.exp.usable && !id.cos.usable) {
    id.chosen = DriftModelKind::exponential;
    why << "; no usable fit (no resolvable correlation: white noise, too short, or a trend?)";
  } else if (!id.exp.usable && id.cos.usable) {
    id.chosen = DriftModelKind::exp_cosine;
    why << "; exponential fit did not converge";
  } else if (id.cos.usable && dbic < -opt.bic_margin && z > opt.beta_z &&
             lobe_z > opt.lobe_z) {
    id.chosen = DriftModelKind::exp_cosine;
    why << "; exp_cosine: BIC lower by more than " << opt.bic_margin << ", beta > " << opt.beta_z
        << " se and a negative lobe deeper than " << opt.lobe_z << " se of K";
  } else {
    id.chosen = DriftModelKind::exponential;
    why << "; exponential: exp_cosine not supported by the evidence (needs BIC lower by more than "
        << opt.bic_margin << ", beta > " << opt.beta_z << " se and a negative lobe deeper than "
        << opt.lobe_z << " se of K)";
  }
  id.reason = why.str();
  return id;
}

}  // namespace calbench::identification
