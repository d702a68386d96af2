// Multi-position calibration (multipos_fit.hpp; the method, thresholds and observability rule are
// explained in docs/multipos.md).
#include "calibration/multipos/multipos_fit.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "calibration/multipos/multipos_observability.hpp"
#include "common/units.hpp"

namespace calbench::multipos {
namespace {

using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

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

std::vector<int> used_poses(std::vector<StaticInterval>& st, const std::vector<int>& exclude) {
  for (int k : exclude) {
    if (k < 0 || k >= static_cast<int>(st.size()))
      throw std::invalid_argument("--exclude-pose " + std::to_string(k) + ": there are " + std::to_string(st.size()) +
                                  " static poses (0.." + std::to_string(int(st.size()) - 1) + ")");
    st[k].used = false;
  }
  std::vector<int> used;
  for (int k = 0; k < static_cast<int>(st.size()); ++k)
    if (st[k].used) used.push_back(k);
  return used;
}

// Gravity-magnitude residuals of `poses` (divided by their σ) and their Jacobian.
void accel_eval_on(const MultiposInput& in, const MultiposFit& fit, const std::vector<int>& poses, const VecX& p, VecX& r,
                   MatX* J) {
  const TriadErrors e = accel_from(p);
  const Mat3 Ainv = (Mat3::Identity() + e.M).inverse();
  r.resize(static_cast<Eigen::Index>(poses.size()));
  if (J) J->resize(r.size(), kAccelParams);
  for (std::size_t m = 0; m < poses.size(); ++m) {
    const auto& s = fit.statics[poses[m]];
    const double sigma = fit.accel_noise.used_sigma / std::sqrt(double(s.i1 - s.i0));
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
}

// Step 2: the accelerometer from the gravity magnitude, its in-sample and held-out residuals.
void fit_accel(const MultiposInput& in, const std::vector<int>& used, MultiposFit& fit) {
  auto& st = fit.statics;
  const auto ar = levenberg_marquardt(VecX::Zero(kAccelParams), [&](const VecX& p, VecX& r, MatX* J) {
    accel_eval_on(in, fit, used, p, r, J);
  });
  fit.accel_iterations = ar.iterations;
  fit.accel_dof = static_cast<int>(used.size()) - kAccelParams;
  fit.accel_chi2_dof = fit.accel_dof > 0 ? ar.chi2 / fit.accel_dof : 0;
  const MatX Ca = covariance_or_refuse(ar, fit.accel_chi2_dof,
                                       "the poses do not determine the accelerometer coefficients (the fit's normal "
                                       "matrix is singular): the poses lack axes tilted between up, level and down");
  fit.coeffs.accel = accel_from(ar.p);
  accel_sigmas(Ca, fit.coeffs.accel);
  refuse_undetermined(fit.coeffs.accel, 0.02, 0.05 * in.gravity, "accelerometer",
                      "the poses do not separate it: it needs poses tilted between the faces (on an edge or a corner)");
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
  double sl = 0;
  for (std::size_t m = 0; m < used.size(); ++m) {
    std::vector<int> rest = used;
    rest.erase(rest.begin() + static_cast<long>(m));
    const auto lr = levenberg_marquardt(ar.p, [&](const VecX& p, VecX& r, MatX* J) { accel_eval_on(in, fit, rest, p, r, J); });
    const double e = TriadCorrector(accel_from(lr.p))(st[used[m]].f_mean).norm() - in.gravity;
    sl += e * e;
  }
  fit.g_loo_rms = std::sqrt(sl / used.size());
}

void noise_notes(MultiposFit& fit) {
  auto note = [&](const NoiseLevel& n, const char* name, const char* unit) {
    if (!n.differs) return;
    std::ostringstream os;
    os << name << " white noise measured " << n.used_sigma << " " << unit << " per sample (" << n.source << "), "
       << n.used_sigma / n.class_sigma << "× the class's " << n.class_sigma
       << ": the measured level is used (the class is a cross-check)";
    fit.notes.push_back(os.str());
  };
  note(fit.accel_noise, "accelerometer", "m/s²");
  note(fit.gyro_noise, "gyro", "rad/s");
}

// The gyro bias from every static (excluded poses too: the bias needs no gravity), with its σ.
Vec3 static_gyro_bias(const MultiposInput& in, const MultiposOptions& opt, const std::vector<Vec3>& up, MultiposFit& fit,
                      double& sigma_b0) {
  const auto& st = fit.statics;
  if (opt.earth_rate && !in.lat_rad) throw MultiposRefusal("--earth-rate needs the site latitude (meta.json site.lat_deg)");
  const double sg = fit.gyro_noise.used_sigma, omega_e = units::kEarthRate;
  Vec3 b0 = Vec3::Zero();
  double n_static = 0;
  for (std::size_t k = 0; k < st.size(); ++k) {
    Vec3 w = st[k].w_mean;
    if (opt.earth_rate) w -= up[k] * omega_e * std::sin(*in.lat_rad);
    b0 += w * double(st[k].c1 - st[k].c0);
    n_static += double(st[k].c1 - st[k].c0);
  }
  b0 /= n_static;
  const double earth_h = opt.earth_rate ? omega_e * std::cos(*in.lat_rad) : omega_e;
  sigma_b0 = std::sqrt(sg * sg / n_static + earth_h * earth_h / 3.0);
  if (opt.earth_rate) {
    const double density = sg / std::sqrt(in.rate_hz);
    // Resolving the Earth rate needs the bias estimate well below it: σ_b0 from noise alone.
    if (sg / std::sqrt(n_static) > 0.3 * omega_e || density > 0.3 * omega_e * std::sqrt(60.0))
      throw MultiposRefusal("--earth-rate: this unit's gyro noise (" + std::to_string(density / units::kDeg * 60) +
                            " °/√h) does not resolve the Earth rate (15 °/h) on these statics; fit without it");
    fit.notes.push_back("vertical Earth rate removed from the static gyro means (latitude from meta.json)");
  }
  return b0;
}

// The rotations between consecutive poses (raw angles with the static bias removed); the used ones.
std::vector<int> build_rotations(const MultiposInput& in, const MultiposOptions& opt, const Vec3& b0, MultiposFit& fit) {
  const auto& st = fit.statics;
  for (int k = 1; k < static_cast<int>(st.size()); ++k) {
    RotationUse ru;
    ru.from = k - 1;
    ru.to = k;
    // From a window before the end of the first pose to a window after the start of the next (at most
    // their midpoints): a pose's edge may hold the last of the turn's slowest motion, which its
    // mean direction does not see but the rotation must.
    const auto& a = st[k - 1];
    const auto& b = st[k];
    ru.i0 = std::max((a.i0 + a.i1) / 2, a.i1 - std::min(a.i1 - a.i0, fit.window_samples));
    ru.i1 = std::min((b.i0 + b.i1) / 2, b.i0 + fit.window_samples);
    ru.t0 = in.t[ru.i0];
    ru.t1 = in.t[ru.i1 - 1];
    TriadErrors bias_only;
    bias_only.bias = b0;
    const Eigen::AngleAxisd aa(integrate(in, bias_only, ru.i0, ru.i1));
    ru.angle_raw = aa.angle() * aa.axis();
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
  return rused;
}

// The gravity direction after each rotation: its σ (white noise of the two poses' means and of the
// gyro over the turn).
double rotation_sigma(const MultiposInput& in, const MultiposFit& fit, const RotationUse& ru) {
  const auto& st = fit.statics;
  const double sa = fit.accel_noise.used_sigma, gd = fit.gyro_noise.used_sigma / std::sqrt(in.rate_hz);
  const double na = double(st[ru.from].i1 - st[ru.from].i0), nb = double(st[ru.to].i1 - st[ru.to].i0);
  const double acc = sa * sa * (1 / na + 1 / nb) / (in.gravity * in.gravity);
  return std::sqrt(acc + gd * gd * (ru.t1 - ru.t0));
}

// Step 3: gyro bias and M from the gravity direction after the rotations, the bias tied to b0.
void fit_gyro(const MultiposInput& in, const std::vector<Vec3>& up, const Vec3& b0, double sigma_b0,
              const std::vector<int>& rused, MultiposFit& fit) {
  const auto& st = fit.statics;
  auto residuals = [&](const VecX& p, VecX& r) {
    const TriadErrors e = gyro_from(p);
    r.resize(static_cast<Eigen::Index>(3 * rused.size() + 3));
    for (std::size_t m = 0; m < rused.size(); ++m) {
      const auto& ru = fit.rotations[rused[m]];
      r.segment<3>(3 * m) = (rotate_up(in, e, ru.i0, ru.i1, up[ru.from]) - up[ru.to]) / rotation_sigma(in, fit, ru);
    }
    r.tail<3>() = (e.bias - b0) / sigma_b0;
  };
  auto eval = [&](const VecX& p, VecX& r, MatX* J) {
    residuals(p, r);
    if (!J) return;
    J->resize(r.size(), kGyroParams);
    for (int q = 0; q < kGyroParams; ++q) {
      VecX pp = p, pm = p, rp, rm;
      pp(q) += 1e-6;
      pm(q) -= 1e-6;
      residuals(pp, rp);
      residuals(pm, rm);
      J->col(q) = (rp - rm) / 2e-6;
    }
  };
  VecX g0 = VecX::Zero(kGyroParams);
  g0.head<3>() = b0;
  const auto gr = levenberg_marquardt(g0, eval, 50);
  fit.gyro_iterations = gr.iterations;
  fit.gyro_dof = 2 * static_cast<int>(rused.size()) + 3 - kGyroParams;
  fit.gyro_chi2_dof = fit.gyro_dof > 0 ? gr.chi2 / fit.gyro_dof : 0;
  const MatX Cg = covariance_or_refuse(gr, fit.gyro_chi2_dof,
                                       "the rotations do not determine the gyro coefficients (the fit's normal matrix is "
                                       "singular): they lack turns about each of the unit's axes — or, with rotations "
                                       "enough, a gyro axis's sign or scale in the conversion is wrong "
                                       "(import imu-tk --gyro-scale, import csv --gyro-unit and its columns)");
  fit.coeffs.gyro = gyro_from(gr.p);
  for (int i = 0; i < 3; ++i) fit.coeffs.gyro.sigma_bias(i) = std::sqrt(Cg(i, i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) fit.coeffs.gyro.sigma_M(i, j) = std::sqrt(Cg(3 + 3 * i + j, 3 + 3 * i + j));
  refuse_undetermined(fit.coeffs.gyro, 0.05, units::kPi / 180, "gyro",
                      "the rotations do not separate it: it needs turns about each of the unit's axes, in both directions");
}

// The rotations' residuals after the fit, and the same under the class's whole noise (the fit weighs
// white noise only): the bias wander tilts the gravity direction measured at either end (the fitted
// accelerometer bias is the mean over all poses: each end keeps up to σ/g) and adds the gyro's drift
// over the turn. What the approval judges; ≈ 1 or below for a sound unit.
void rotation_scores(const MultiposInput& in, const std::vector<Vec3>& up, const std::vector<int>& rused, MultiposFit& fit) {
  const auto& st = fit.statics;
  double rr = 0, c2 = 0;
  const double tilt = (in.accel_bias_stability > 0 ? in.accel_bias_stability : kWideAccelBiasStability) / in.gravity;
  const double drift = in.gyro_bias_stability > 0 ? in.gyro_bias_stability : kWideGyroBiasStability;
  for (auto& ru : fit.rotations) {
    const Vec3 pred = rotate_up(in, fit.coeffs.gyro, ru.i0, ru.i1, up[ru.from]);
    ru.residual_rad = std::acos(std::clamp(pred.normalized().dot(up[ru.to]), -1.0, 1.0));
    if (!ru.used) continue;
    rr += ru.residual_rad * ru.residual_rad;
    const double gdrift = drift * (ru.t1 - ru.t0);
    c2 += (pred - up[ru.to]).squaredNorm() / (std::pow(rotation_sigma(in, fit, ru), 2) + 2 * tilt * tilt + gdrift * gdrift);
  }
  fit.rotation_rms_rad = std::sqrt(rr / rused.size());
  fit.gyro_chi2_dof_class = fit.gyro_dof > 0 ? c2 / fit.gyro_dof : 0;
}

}  // namespace

MultiposFit fit_multipos(const MultiposInput& in, const MultiposOptions& opt) {
  MultiposFit fit;
  fit.statics = detect_statics(in, opt, &fit.gyro_noise, &fit.accel_noise, &fit.threshold_factor, &fit.window_samples,
                               &fit.too_short_s);
  const std::vector<int> used = used_poses(fit.statics, opt.exclude_poses);
  if (fit.statics.empty()) refuse_no_poses(fit, opt);
  check_gravity_units(fit.statics, in.gravity);
  fit.distinct_directions = count_distinct_directions(fit.statics, used);
  check_accel_observability(fit, used, opt);
  fit_accel(in, used, fit);
  noise_notes(fit);
  const TriadCorrector acorr(fit.coeffs.accel);
  std::vector<Vec3> up(fit.statics.size());
  for (std::size_t k = 0; k < up.size(); ++k) up[k] = acorr(fit.statics[k].f_mean).normalized();
  double sigma_b0 = 0;
  const Vec3 b0 = static_gyro_bias(in, opt, up, fit, sigma_b0);
  const std::vector<int> rused = build_rotations(in, opt, b0, fit);
  check_gyro_units(in, fit, up, b0, rused);
  check_rotation_observability(fit, rused, opt);
  fit_gyro(in, up, b0, sigma_b0, rused, fit);
  rotation_scores(in, up, rused, fit);
  return fit;
}

}  // namespace calbench::multipos
