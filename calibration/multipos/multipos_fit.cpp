// Multi-position calibration (multipos_fit.hpp; the method, thresholds and observability rule are
// explained in docs/multipos.md).
#include "calibration/multipos/multipos_fit.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "common/units.hpp"

namespace calbench::multipos {
namespace {

using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

// Standard normal quantile (Acklam's rational approximation, relative error < 1.2e-9).
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01,  -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  const double pl = 0.02425;
  if (p < pl) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - pl) return -normal_quantile(1 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

// χ²_k(p)/k by the Wilson–Hilferty approximation (accurate to < 1 % for k ≥ 10).
double chi2_quantile_per_dof(double p, double k) {
  const double z = normal_quantile(p);
  const double h = 2.0 / (9.0 * k);
  const double c = 1 - h + z * std::sqrt(h);
  return c * c * c;
}

const char* axis_name(int i) { return i == 0 ? "x" : i == 1 ? "y" : "z"; }

// Levenberg–Marquardt on weighted residuals r(p) (already divided by their σ) with Jacobian J(p).
struct LmResult {
  VecX p;
  MatX JtJ;
  double chi2 = 0;
  int iterations = 0;
};
LmResult levenberg_marquardt(VecX p, const std::function<void(const VecX&, VecX&, MatX*)>& eval, int max_iter = 100) {
  VecX r;
  MatX J;
  eval(p, r, &J);
  double chi2 = r.squaredNorm(), lambda = 1e-3;
  int it = 0;
  for (; it < max_iter; ++it) {
    const MatX A = J.transpose() * J;
    const VecX g = J.transpose() * r;
    bool improved = false;
    for (int k = 0; k < 30 && !improved; ++k) {
      MatX Ad = A;
      for (int i = 0; i < Ad.rows(); ++i) Ad(i, i) += lambda * std::max(A(i, i), 1e-30);
      const VecX step = Ad.ldlt().solve(-g);
      const VecX pn = p + step;
      VecX rn;
      eval(pn, rn, nullptr);
      const double cn = rn.squaredNorm();
      if (std::isfinite(cn) && cn <= chi2) {
        const bool converged = chi2 - cn <= 1e-12 * std::max(chi2, 1.0) || step.norm() <= 1e-14 * (1 + p.norm());
        p = pn;
        chi2 = cn;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
        eval(p, r, &J);
        if (converged) return {p, J.transpose() * J, chi2, it + 1};
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;  // no step lowers χ²: at the minimum within numerical precision
  }
  return {p, J.transpose() * J, chi2, it};
}

// The fit's covariance, scaled by χ²/dof when above 1 (Birge ratio); a singular normal matrix is a
// refusal with `why`.
MatX covariance_or_refuse(const LmResult& r, double chi2_dof, const std::string& why) {
  Eigen::JacobiSVD<MatX> svd(r.JtJ);
  const auto& sv = svd.singularValues();
  if (!(sv(sv.size() - 1) > 1e-12 * sv(0))) throw MultiposRefusal(why);
  return r.JtJ.inverse() * std::max(1.0, chi2_dof);
}

// Accelerometer parameters: b (3), then M00, M11, M22, M10, M20, M21 (lower triangle).
constexpr int kAccelParams = 9;
TriadErrors accel_from(const VecX& p) {
  TriadErrors e;
  e.bias = p.head<3>();
  e.M(0, 0) = p(3);
  e.M(1, 1) = p(4);
  e.M(2, 2) = p(5);
  e.M(1, 0) = p(6);
  e.M(2, 0) = p(7);
  e.M(2, 1) = p(8);
  return e;
}
void accel_sigmas(const MatX& C, TriadErrors& e) {
  for (int i = 0; i < 3; ++i) e.sigma_bias(i) = std::sqrt(C(i, i));
  e.sigma_M.setZero();  // M01, M02, M12: zero by the frame's definition (no σ: not estimated)
  e.sigma_M(0, 0) = std::sqrt(C(3, 3));
  e.sigma_M(1, 1) = std::sqrt(C(4, 4));
  e.sigma_M(2, 2) = std::sqrt(C(5, 5));
  e.sigma_M(1, 0) = std::sqrt(C(6, 6));
  e.sigma_M(2, 0) = std::sqrt(C(7, 7));
  e.sigma_M(2, 1) = std::sqrt(C(8, 8));
}

// Gyro parameters: b (3), then M row-major (9).
constexpr int kGyroParams = 12;
TriadErrors gyro_from(const VecX& p) {
  TriadErrors e;
  e.bias = p.head<3>();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e.M(i, j) = p(3 + 3 * i + j);
  return e;
}

Eigen::Quaterniond exp_q(const Vec3& phi) {
  const double a = phi.norm();
  if (a < 1e-12) return Eigen::Quaterniond(1, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, phi / a));
}

double sample_dt(const MultiposInput& in, std::size_t j) {
  if (j > 0) return in.t[j] - in.t[j - 1];
  return 1.0 / in.rate_hz;
}

// Rotation body(end) → body(start) over samples [i0, i1) with the rates corrected by `g`.
Eigen::Matrix3d integrate(const MultiposInput& in, const TriadErrors& g, std::size_t i0, std::size_t i1) {
  const TriadCorrector corr(g);
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (std::size_t j = i0; j < i1; ++j) q = (q * exp_q(corr(in.gyro[j]) * sample_dt(in, j))).normalized();
  return q.toRotationMatrix();
}

}  // namespace

Vec3 rotate_up(const MultiposInput& in, const TriadErrors& gyro, std::size_t i0, std::size_t i1, const Vec3& up_start) {
  return integrate(in, gyro, i0, i1).transpose() * up_start;
}

std::vector<StaticInterval> detect_statics(const MultiposInput& in, const MultiposOptions& opt, NoiseLevel* gyro_noise,
                                           NoiseLevel* accel_noise, double* threshold_factor, std::size_t* window) {
  const std::size_t n = in.t.size();
  if (in.gyro.size() != n || in.accel.size() != n) throw std::invalid_argument("multipos: series of unequal length");
  if (!(in.rate_hz > 0)) throw std::invalid_argument("multipos: the sample rate must be positive");
  const std::size_t h = std::max<std::size_t>(5, static_cast<std::size_t>(std::lround(0.5 * opt.window_s * in.rate_hz)));
  const std::size_t w = 2 * h + 1;
  if (n < 4 * w) throw MultiposRefusal("the recording is too short for the static detector: " + std::to_string(n) +
                                       " samples, at least " + std::to_string(4 * w) + " needed");
  // Prefix sums of the 6 channels (minus their overall mean, for precision) and their squares.
  Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean.head<3>() += in.gyro[i];
    mean.tail<3>() += in.accel[i];
  }
  mean /= static_cast<double>(n);
  std::vector<Eigen::Matrix<double, 6, 1>> s1(n + 1), s2(n + 1);
  s1[0].setZero();
  s2[0].setZero();
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Matrix<double, 6, 1> x;
    x << in.gyro[i], in.accel[i];
    x -= mean;
    s1[i + 1] = s1[i] + x;
    s2[i + 1] = s2[i] + x.cwiseProduct(x);
  }
  auto window_var = [&](std::size_t c) {  // centred at c, needs h ≤ c < n − h
    const auto a = s1[c + h + 1] - s1[c - h];
    const auto b = s2[c + h + 1] - s2[c - h];
    return Eigen::Matrix<double, 6, 1>((b - a.cwiseProduct(a) / double(w)) / double(w - 1));
  };
  // Noise per sample measured on the quiet windows: the 25th percentile of the window variances,
  // divided by the χ² distribution's own 25th percentile (valid while statics fill ≥ 25 % of the time).
  const double q25 = chi2_quantile_per_dof(0.25, double(w - 1));
  double measured[2] = {0, 0};
  for (int triad = 0; triad < 2; ++triad)
    for (int ax = 0; ax < 3; ++ax) {
      std::vector<double> v;
      for (std::size_t c = h; c + h < n; c += h) v.push_back(window_var(c)(3 * triad + ax));
      std::nth_element(v.begin(), v.begin() + v.size() / 4, v.end());
      measured[triad] = std::max(measured[triad], std::sqrt(std::max(v[v.size() / 4], 0.0) / q25));
    }
  NoiseLevel lv[2];
  const double density[2] = {in.gyro_density, in.accel_density};
  for (int triad = 0; triad < 2; ++triad) {
    lv[triad].class_sigma = density[triad] * std::sqrt(in.rate_hz);
    lv[triad].measured_sigma = measured[triad];
    lv[triad].differs = lv[triad].class_sigma > 0 && (measured[triad] > 2 * lv[triad].class_sigma ||
                                                      measured[triad] < 0.5 * lv[triad].class_sigma);
    lv[triad].used_sigma = (lv[triad].class_sigma > 0 && !lv[triad].differs) ? lv[triad].class_sigma : measured[triad];
    if (!(lv[triad].used_sigma > 0))
      throw MultiposRefusal(std::string("the ") + (triad ? "accelerometer" : "gyro") +
                            " output does not vary at all on a quarter of the recording: no noise to set the static threshold from");
  }
  const double factor = chi2_quantile_per_dof(1 - opt.alpha, double(w - 1));
  Eigen::Matrix<double, 6, 1> limit;
  limit << Vec3::Constant(lv[0].used_sigma * lv[0].used_sigma * factor),
      Vec3::Constant(lv[1].used_sigma * lv[1].used_sigma * factor);
  std::vector<char> quiet(n, 0);
  for (std::size_t c = h; c + h < n; ++c) quiet[c] = (window_var(c).array() <= limit.array()).all();
  // A steady rotation (a table slewing at constant rate) has a quiet variance too: a still window's
  // mean rate must also be the gyro bias — the median over the quiet windows — within 5σ of a
  // window mean plus 3× the class's in-run bias stability (floor 0.05 °/s).
  {
    auto window_mean = [&](std::size_t c) {
      return Vec3((s1[c + h + 1] - s1[c - h]).head<3>() / double(w) + mean.head<3>());
    };
    std::vector<double> m[3];
    for (std::size_t c = h; c + h < n; c += h)
      if (quiet[c]) {
        const Vec3 v = window_mean(c);
        for (int i = 0; i < 3; ++i) m[i].push_back(v(i));
      }
    if (!m[0].empty()) {
      Vec3 bias;
      for (int i = 0; i < 3; ++i) {
        std::nth_element(m[i].begin(), m[i].begin() + m[i].size() / 2, m[i].end());
        bias(i) = m[i][m[i].size() / 2];
      }
      const double tol = std::max(5 * lv[0].used_sigma / std::sqrt(double(w)) + 3 * in.gyro_bias_stability, 0.05 * units::kDeg);
      for (std::size_t c = h; c + h < n; ++c)
        if (quiet[c] && (window_mean(c) - bias).cwiseAbs().maxCoeff() > tol) quiet[c] = 0;
    }
  }
  const std::size_t min_len = std::max<std::size_t>(w, static_cast<std::size_t>(std::lround(opt.min_static_s * in.rate_hz)));
  std::vector<StaticInterval> out;
  for (std::size_t i = 0; i < n;) {
    if (!quiet[i]) { ++i; continue; }
    std::size_t j = i;
    while (j < n && quiet[j]) ++j;
    if (j - i >= min_len) {
      StaticInterval s;
      s.i0 = i;
      s.i1 = j;
      s.t0 = in.t[i];
      s.t1 = in.t[j - 1];
      Vec3 fs = Vec3::Zero(), ws = Vec3::Zero(), f2 = Vec3::Zero(), w2 = Vec3::Zero();
      for (std::size_t k = i; k < j; ++k) {
        fs += in.accel[k];
        ws += in.gyro[k];
      }
      const double m = double(j - i);
      s.f_mean = fs / m;
      s.w_mean = ws / m;
      for (std::size_t k = i; k < j; ++k) {
        f2 += (in.accel[k] - s.f_mean).cwiseAbs2();
        w2 += (in.gyro[k] - s.w_mean).cwiseAbs2();
      }
      s.f_std = (f2 / (m - 1)).cwiseSqrt();
      s.w_std = (w2 / (m - 1)).cwiseSqrt();
      s.g_residual_raw = s.f_mean.norm() - in.gravity;
      out.push_back(s);
    }
    i = j;
  }
  if (gyro_noise) *gyro_noise = lv[0];
  if (accel_noise) *accel_noise = lv[1];
  if (threshold_factor) *threshold_factor = factor;
  if (window) *window = w;
  return out;
}

namespace {
// A fit that converged but leaves a coefficient with σ beyond any use (a scale or skew with σ above
// max_m, a bias above max_b) is refused naming the worst one: a near-singular normal matrix
// passes the singularity test with noise on it (six face poses: skew σ of 10⁶ ppm).
void refuse_undetermined(const TriadErrors& e, double max_m, double max_b, const char* triad, const char* advice) {
  double worst = 0;
  std::string what;
  for (int i = 0; i < 3; ++i) {
    if (e.sigma_bias(i) / max_b > worst) {
      worst = e.sigma_bias(i) / max_b;
      what = std::string("bias ") + "xyz"[i];
    }
    for (int j = 0; j < 3; ++j)
      if (e.sigma_M(i, j) / max_m > worst) {
        worst = e.sigma_M(i, j) / max_m;
        what = std::string("M[") + "xyz"[i] + "][" + "xyz"[j] + "]";
      }
  }
  if (!(worst <= 1)) {
    std::ostringstream os;
    os << "the " << triad << " coefficients are not determined: " << what << " has σ " << worst << "× the largest usable ("
       << (what[0] == 'b' ? max_b : max_m) << (what[0] == 'b' ? (triad[0] == 'g' ? " rad/s" : " m/s²") : "") << "); " << advice;
    throw MultiposRefusal(os.str());
  }
}
}  // namespace

MultiposFit fit_multipos(const MultiposInput& in, const MultiposOptions& opt) {
  MultiposFit fit;
  fit.statics = detect_statics(in, opt, &fit.gyro_noise, &fit.accel_noise, &fit.threshold_factor, &fit.window_samples);
  auto& st = fit.statics;
  for (int k : opt.exclude_poses) {
    if (k < 0 || k >= static_cast<int>(st.size()))
      throw std::invalid_argument("--exclude-pose " + std::to_string(k) + ": there are " + std::to_string(st.size()) +
                                  " static poses (0.." + std::to_string(int(st.size()) - 1) + ")");
    st[k].used = false;
  }
  std::vector<int> used;
  for (int k = 0; k < static_cast<int>(st.size()); ++k)
    if (st[k].used) used.push_back(k);

  // --- Observability of the accelerometer fit: enough poses, every axis both up and down.
  std::vector<std::string> missing;
  if (st.empty()) {
    std::ostringstream os;
    os << "no static pose found (the unit never held still for " << opt.min_static_s
       << " s by the static test): check that the accelerometer and gyro files are not swapped and that the "
          "conversion to SI is right (import imu-tk --acc-scale/--gyro-scale, import csv --accel-unit/--gyro-unit)";
    for (const auto* n : {&fit.gyro_noise, &fit.accel_noise}) {
      const bool gyro = n == &fit.gyro_noise;
      os << "; " << (gyro ? "gyro" : "accelerometer") << " noise per sample used by the test " << n->used_sigma
         << (gyro ? " rad/s" : " m/s²");
      if (n->class_sigma > 0 && n->measured_sigma > 0)
        os << " (class " << n->class_sigma << ", measured on the recording's quietest windows " << n->measured_sigma << ")";
    }
    os << ". A device class whose noise is below the unit's (the measured level replaces it only beyond 2×) makes every "
          "window fail: check the class (meta.json device.model, --device-class)";
    throw MultiposRefusal(os.str());
  }
  {  // A still unit measures gravity: a median |f̄| far from g is a wrong conversion, not a calibration.
    std::vector<double> mags;
    for (const auto& s : st) mags.push_back(s.f_mean.norm());
    std::nth_element(mags.begin(), mags.begin() + mags.size() / 2, mags.end());
    const double ratio = mags[mags.size() / 2] / in.gravity;
    if (!(ratio > 0.5 && ratio < 2.0))
      throw MultiposRefusal("the static poses measure |f| = " + std::to_string(mags[mags.size() / 2]) +
                            " m/s² (median), " + std::to_string(ratio) + "× gravity (" + std::to_string(in.gravity) +
                            " m/s²): the accelerometer values are not in m/s² — check the conversion to SI "
                            "(import imu-tk --acc-offset / --acc-scale, import csv --accel-unit, and that the "
                            "accelerometer columns are the right ones)");
  }
  if (used.size() < opt.min_poses)
    missing.push_back(std::to_string(used.size()) + " static poses used (" + std::to_string(st.size()) + " found" +
                      (used.size() < st.size() ? ", " + std::to_string(st.size() - used.size()) + " left out" : std::string()) +
                      "), at least " + std::to_string(opt.min_poses) +
                      " needed (9 accelerometer parameters; 12 or more recommended)");
  {
    Vec3 up_max = Vec3::Constant(-2), up_min = Vec3::Constant(2);
    for (int k : used) {
      const Vec3 u = st[k].f_mean.normalized();
      up_max = up_max.cwiseMax(u);
      up_min = up_min.cwiseMin(u);
    }
    // Bias and scale of axis i separate only when its share of gravity takes clearly different
    // values over the poses: a spread of at least 1 (e.g. down and level, or ±30°).
    for (int i = 0; i < 3; ++i)
      if (up_max(i) - up_min(i) < 1.0) {
        std::ostringstream os;
        os << "the " << axis_name(i) << " axis's share of gravity spans only " << std::lround(100 * up_min(i)) << "…"
           << std::lround(100 * up_max(i)) << " % over the poses (at least 100 % apart needed): add poses with the "
           << axis_name(i) << " axis pointing " << (1 - up_min(i) >= up_max(i) + 1 ? "up" : "down");
        missing.push_back(os.str());
      }
  }
  {
    // The skews need tilted poses: poses at the six faces only give 6 distinct equations for 9
    // unknowns however often they are repeated. Directions within 10° count once.
    std::vector<Vec3> dirs;
    for (int k : used) {
      const Vec3 u = st[k].f_mean.normalized();
      bool seen = false;
      for (const Vec3& d : dirs) seen = seen || u.dot(d) > std::cos(10 * units::kDeg);
      if (!seen) dirs.push_back(u);
    }
    if (dirs.size() < static_cast<std::size_t>(kAccelParams))
      missing.push_back("only " + std::to_string(dirs.size()) +
                        " distinct gravity directions among the poses (poses within 10° of each other count once), at "
                        "least 9 needed: the skews need tilted poses — add poses resting on an edge (about 45°) or a "
                        "corner of the unit, not only on its faces");
  }
  if (!missing.empty()) {
    std::ostringstream os;
    os << "the poses do not determine the accelerometer coefficients:";
    for (const auto& m : missing) os << "\n  - " << m;
    os << "\n  add static poses (≥ " << opt.min_static_s << " s still each); best: every axis up and down at least once";
    throw MultiposRefusal(os.str());
  }

  // --- Accelerometer: gravity magnitude.
  const double sa = fit.accel_noise.used_sigma;
  auto accel_eval_on = [&](const std::vector<int>& poses, const VecX& p, VecX& r, MatX* J) {
    const TriadErrors e = accel_from(p);
    const Mat3 Ainv = (Mat3::Identity() + e.M).inverse();
    r.resize(static_cast<Eigen::Index>(poses.size()));
    if (J) J->resize(r.size(), kAccelParams);
    for (std::size_t m = 0; m < poses.size(); ++m) {
      const auto& s = st[poses[m]];
      const double sigma = sa / std::sqrt(double(s.i1 - s.i0));
      const Vec3 y = Ainv * (s.f_mean - e.bias);
      const double ny = y.norm();
      r(m) = (ny - in.gravity) / sigma;
      if (J) {
        const Eigen::RowVector3d gy = y.transpose() / ny / sigma;
        J->block<1, 3>(m, 0) = -gy * Ainv;
        const int ij[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 0}, {2, 0}, {2, 1}};
        for (int q = 0; q < 6; ++q) (*J)(m, 3 + q) = -(gy * Ainv.col(ij[q][0]))(0) * y(ij[q][1]);
      }
    }
  };
  auto accel_eval = [&](const VecX& p, VecX& r, MatX* J) { accel_eval_on(used, p, r, J); };
  auto ar = levenberg_marquardt(VecX::Zero(kAccelParams), accel_eval);
  fit.accel_iterations = ar.iterations;
  fit.accel_dof = static_cast<int>(used.size()) - kAccelParams;
  fit.accel_chi2_dof = fit.accel_dof > 0 ? ar.chi2 / fit.accel_dof : 0;
  const MatX Ca = covariance_or_refuse(ar, fit.accel_chi2_dof,
                                       "the poses do not determine the accelerometer coefficients (the fit's normal "
                                       "matrix is singular): add poses with each axis tilted between up, level and down");
  fit.coeffs.accel = accel_from(ar.p);
  accel_sigmas(Ca, fit.coeffs.accel);
  refuse_undetermined(fit.coeffs.accel, 0.02, 0.05 * in.gravity, "accelerometer",
                      "the poses do not separate it: add poses tilted between the faces (on an edge or a corner)");
  const TriadCorrector acorr(fit.coeffs.accel);
  double s_raw = 0, s_fit = 0;
  for (auto& s : st) s.g_residual = acorr(s.f_mean).norm() - in.gravity;
  for (int k : used) {
    s_raw += st[k].g_residual_raw * st[k].g_residual_raw;
    s_fit += st[k].g_residual * st[k].g_residual;
  }
  fit.g_spread_raw = std::sqrt(s_raw / used.size());
  fit.g_spread = std::sqrt(s_fit / used.size());
  // Held out: each pose's |f| − g from the accelerometer fitted without it (what a new pose of this
  // unit would show; the fit's own figure above is in-sample).
  {
    double sl = 0;
    for (std::size_t m = 0; m < used.size(); ++m) {
      std::vector<int> rest = used;
      rest.erase(rest.begin() + static_cast<long>(m));
      const auto lr = levenberg_marquardt(ar.p, [&](const VecX& p, VecX& r, MatX* J) { accel_eval_on(rest, p, r, J); });
      const double e = TriadCorrector(accel_from(lr.p))(st[used[m]].f_mean).norm() - in.gravity;
      sl += e * e;
    }
    fit.g_loo_rms = std::sqrt(sl / used.size());
  }
  if (fit.accel_noise.differs)
    fit.notes.push_back("accelerometer white noise measured " + std::to_string(fit.accel_noise.measured_sigma) +
                        " m/s² per sample, the class says " + std::to_string(fit.accel_noise.class_sigma) +
                        ": the measured level is used");
  if (fit.gyro_noise.differs)
    fit.notes.push_back("gyro white noise measured " + std::to_string(fit.gyro_noise.measured_sigma) +
                        " rad/s per sample, the class says " + std::to_string(fit.gyro_noise.class_sigma) +
                        ": the measured level is used");

  // --- Gyro: bias from the statics, then bias and M from the rotations between consecutive poses.
  const double sg = fit.gyro_noise.used_sigma;
  std::vector<Vec3> up(st.size());
  for (std::size_t k = 0; k < st.size(); ++k) up[k] = acorr(st[k].f_mean).normalized();
  Vec3 b0 = Vec3::Zero();
  double n_static = 0;
  const double omega_e = units::kEarthRate;
  for (const auto& s : st) {  // every static (excluded poses too: the bias needs no gravity)
    Vec3 w = s.w_mean;
    if (opt.earth_rate && in.lat_rad) w -= up[&s - st.data()] * omega_e * std::sin(*in.lat_rad);
    b0 += w * double(s.i1 - s.i0);
    n_static += double(s.i1 - s.i0);
  }
  b0 /= n_static;
  const double earth_h = opt.earth_rate && in.lat_rad ? omega_e * std::cos(*in.lat_rad) : omega_e;
  const double sigma_b0 = std::sqrt(sg * sg / n_static + earth_h * earth_h / 3.0);
  if (opt.earth_rate && !in.lat_rad)
    throw MultiposRefusal("--earth-rate needs the site latitude (meta.json site.lat_deg)");
  if (opt.earth_rate) {
    const double density = sg / std::sqrt(in.rate_hz);
    // Resolving the Earth rate needs the bias estimate well below it: σ_b0 from noise alone.
    if (sg / std::sqrt(n_static) > 0.3 * omega_e || density > 0.3 * omega_e * std::sqrt(60.0))
      throw MultiposRefusal("--earth-rate: this unit's gyro noise (" + std::to_string(density / units::kDeg * 60) +
                            " °/√h) does not resolve the Earth rate (15 °/h) on these statics; fit without it");
    fit.notes.push_back("vertical Earth rate removed from the static gyro means (latitude from meta.json)");
  }
  std::vector<int> rot_from;
  for (int k = 1; k < static_cast<int>(st.size()); ++k) {
    RotationUse ru;
    ru.from = k - 1;
    ru.to = k;
    ru.t0 = in.t[st[k - 1].i1 - 1];
    ru.t1 = in.t[st[k].i0];
    TriadErrors bias_only;
    bias_only.bias = b0;
    const Eigen::Matrix3d R = integrate(in, bias_only, st[k - 1].i1, st[k].i0);
    ru.angle_raw = Eigen::AngleAxisd(R).angle() * Eigen::AngleAxisd(R).axis();
    fit.rotations.push_back(ru);
  }
  for (int k : opt.exclude_rotations) {
    if (k < 0 || k >= static_cast<int>(fit.rotations.size()))
      throw std::invalid_argument("--exclude-rotation " + std::to_string(k) + ": there are " +
                                  std::to_string(fit.rotations.size()) + " rotations (0.." +
                                  std::to_string(int(fit.rotations.size()) - 1) + ")");
    fit.rotations[k].used = false;
  }
  std::vector<int> rused;
  for (int k = 0; k < static_cast<int>(fit.rotations.size()); ++k)
    if (fit.rotations[k].used) rused.push_back(k);
  {
    // The turn's path length ∫|ω − b|dt can never be shorter than the angle gravity turned through
    // in the body, and for a hand-turned unit it is seldom more than twice it: rates in the wrong
    // unit (deg/s read as rad/s: 57×) show here before they ruin the fit.
    std::vector<double> ratio;
    for (int k : rused) {
      const auto& ru = fit.rotations[k];
      const double alpha = std::acos(std::clamp(up[ru.from].dot(up[ru.to]), -1.0, 1.0));
      if (alpha < 30 * units::kDeg) continue;
      double path = 0;
      for (std::size_t i = st[ru.from].i1; i < st[ru.to].i0; ++i)
        path += (in.gyro[i] - b0).norm() * (i + 1 < in.t.size() ? in.t[i + 1] - in.t[i] : 1 / in.rate_hz);
      ratio.push_back(path / alpha);
    }
    if (ratio.size() >= 3) {
      std::nth_element(ratio.begin(), ratio.begin() + static_cast<long>(ratio.size() / 2), ratio.end());
      const double med = ratio[ratio.size() / 2];
      if (!(med > 0.7 && med < 5)) {
        std::ostringstream os;
        os << "the gyro rates integrate to " << med << "× the angle gravity turned through in the rotations (median over "
           << ratio.size() << " rotations of 30° or more; 1–2 for rates in rad/s): the gyro values are not in rad/s — "
           << "check the conversion to SI (import csv --gyro-unit, import imu-tk --gyro-scale) and the gyro columns";
        throw MultiposRefusal(os.str());
      }
    }
  }
  {
    std::vector<std::string> miss;
    if (rused.size() < opt.min_rotations)
      miss.push_back(std::to_string(rused.size()) + " rotations between static poses, at least " +
                     std::to_string(opt.min_rotations) + " needed (12 gyro parameters, 2 per rotation)");
    for (int i = 0; i < 3; ++i) {
      double best = 0;
      for (int k : rused) best = std::max(best, std::abs(fit.rotations[k].angle_raw(i)));
      if (best < units::kPi / 4)
        miss.push_back(std::string("no rotation of 45° or more about the ") + axis_name(i) + " axis (largest " +
                       std::to_string(static_cast<int>(std::lround(best / units::kDeg))) + "°)");
    }
    if (!miss.empty()) {
      std::ostringstream os;
      os << "the rotations do not determine the gyro coefficients:";
      for (const auto& m : miss) os << "\n  - " << m;
      os << "\n  turn the unit about each of its axes between two static poses";
      throw MultiposRefusal(os.str());
    }
  }
  const double gd = sg / std::sqrt(in.rate_hz);  // rad/s/√Hz
  auto rot_sigma = [&](const RotationUse& ru) {
    const double na = double(st[ru.from].i1 - st[ru.from].i0), nb = double(st[ru.to].i1 - st[ru.to].i0);
    const double acc = sa * sa * (1 / na + 1 / nb) / (in.gravity * in.gravity);
    return std::sqrt(acc + gd * gd * (ru.t1 - ru.t0));
  };
  auto gyro_residuals = [&](const VecX& p, VecX& r) {
    const TriadErrors e = gyro_from(p);
    r.resize(static_cast<Eigen::Index>(3 * rused.size() + 3));
    for (std::size_t m = 0; m < rused.size(); ++m) {
      const auto& ru = fit.rotations[rused[m]];
      const Vec3 pred = rotate_up(in, e, st[ru.from].i1, st[ru.to].i0, up[ru.from]);
      r.segment<3>(3 * m) = (pred - up[ru.to]) / rot_sigma(ru);
    }
    r.tail<3>() = (e.bias - b0) / sigma_b0;
  };
  auto gyro_eval = [&](const VecX& p, VecX& r, MatX* J) {
    gyro_residuals(p, r);
    if (!J) return;
    J->resize(r.size(), kGyroParams);
    for (int q = 0; q < kGyroParams; ++q) {
      const double d = q < 3 ? 1e-6 : 1e-6;
      VecX pp = p, pm = p, rp, rm;
      pp(q) += d;
      pm(q) -= d;
      gyro_residuals(pp, rp);
      gyro_residuals(pm, rm);
      J->col(q) = (rp - rm) / (2 * d);
    }
  };
  VecX g0 = VecX::Zero(kGyroParams);
  g0.head<3>() = b0;
  auto gr = levenberg_marquardt(g0, gyro_eval, 50);
  fit.gyro_iterations = gr.iterations;
  fit.gyro_dof = 2 * static_cast<int>(rused.size()) + 3 - kGyroParams;
  fit.gyro_chi2_dof = fit.gyro_dof > 0 ? gr.chi2 / fit.gyro_dof : 0;
  const MatX Cg = covariance_or_refuse(gr, fit.gyro_chi2_dof,
                                       "the rotations do not determine the gyro coefficients (the fit's normal matrix is "
                                       "singular): turn the unit about each of its axes between static poses — or, with "
                                       "rotations enough, a gyro axis's sign or scale in the conversion is wrong "
                                       "(import imu-tk --gyro-scale, import csv --gyro-unit and its columns)");
  fit.coeffs.gyro = gyro_from(gr.p);
  for (int i = 0; i < 3; ++i) fit.coeffs.gyro.sigma_bias(i) = std::sqrt(Cg(i, i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) fit.coeffs.gyro.sigma_M(i, j) = std::sqrt(Cg(3 + 3 * i + j, 3 + 3 * i + j));
  refuse_undetermined(fit.coeffs.gyro, 0.05, units::kPi / 180, "gyro",
                      "the rotations do not separate it: turn the unit about each of its axes, in both directions, "
                      "between static poses");
  double rr = 0;
  for (auto& ru : fit.rotations) {
    const Vec3 pred = rotate_up(in, fit.coeffs.gyro, st[ru.from].i1, st[ru.to].i0, up[ru.from]);
    ru.residual_rad = std::acos(std::clamp(pred.normalized().dot(up[ru.to]), -1.0, 1.0));
    if (ru.used) rr += ru.residual_rad * ru.residual_rad;
  }
  fit.rotation_rms_rad = std::sqrt(rr / rused.size());
  // The same residuals under the class's whole noise (the fit weighs white noise only): the bias
  // wander tilts the gravity direction measured at either end (the fitted accelerometer bias is the
  // mean over all poses: each end keeps up to σ/g) and adds the gyro's drift over the turn. What
  // the approval judges; ≈ 1 or below for a sound unit.
  {
    const double tilt = in.accel_bias_stability / in.gravity;
    double c2 = 0;
    for (int k : rused) {
      const auto& ru = fit.rotations[k];
      const Vec3 pred = rotate_up(in, fit.coeffs.gyro, st[ru.from].i1, st[ru.to].i0, up[ru.from]);
      const double gdrift = in.gyro_bias_stability * (ru.t1 - ru.t0);
      const double s2 = std::pow(rot_sigma(ru), 2) + 2 * tilt * tilt + gdrift * gdrift;
      c2 += (pred - up[ru.to]).squaredNorm() / s2;
    }
    fit.gyro_chi2_dof_class = fit.gyro_dof > 0 ? c2 / fit.gyro_dof : 0;
  }
  return fit;
}

}  // namespace calbench::multipos
