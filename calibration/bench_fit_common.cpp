// Shared parts of the bench fit: observation model (eq 4 generalised), bench error model,
// white-noise measurement, observability analysis, residual statistics.
#include <cmath>
#include <sstream>

#include "calibration/bench_fit.hpp"
#include "common/units.hpp"

namespace calbench {
namespace bench_fit_detail {

double observation(const BenchBlock& b, TriadId triad, int axis) {
  return triad == TriadId::gyro ? b.gyro(axis) - b.w(axis) : b.accel(axis) - b.f(axis);
}

Eigen::Matrix<double, 1, kAxisParams> design_row(const BenchBlock& b, TriadId triad) {
  const Vec3& ref = triad == TriadId::gyro ? b.w : b.f;
  Eigen::Matrix<double, 1, kAxisParams> h;
  h << 1.0, ref(0), ref(1), ref(2);
  return h;
}

double bench_error_sigma(const BenchBlock& b, TriadId triad, int axis, const TableSpec& t) {
  if (triad == TriadId::gyro) {
    const double wi = b.w(axis);
    const double perp2 = std::max(b.w.squaredNorm() - wi * wi, 0.0);
    const double tilt = std::max(t.axis_wobble, t.position_accuracy);
    return std::sqrt(std::pow(t.rate_accuracy_rel * wi, 2) + tilt * tilt * perp2);
  }
  const double fi = b.f(axis);
  const double perp2 = std::max(b.f.squaredNorm() - fi * fi, 0.0);
  return t.position_accuracy * std::sqrt(perp2);
}

namespace {

const char* axis_name(int i) { return i == 0 ? "x" : i == 1 ? "y" : "z"; }

std::string param_name(int k, int axis) {
  std::ostringstream s;
  if (k == kParBias) s << "bias[" << axis << "]";
  else s << "M[" << axis << "][" << (k - kParM0) << "]";
  return s.str();
}

// Why a parameter cannot be determined, in the plan's terms.
std::string reason_for(const std::vector<BenchBlock>& blocks, TriadId triad, int axis, int k, double sigma,
                       double limit) {
  std::ostringstream s;
  if (k >= kParM0) {
    const int j = k - kParM0;
    double max_ref = 0;
    for (const auto& b : blocks) max_ref = std::max(max_ref, std::abs(triad == TriadId::gyro ? b.w(j) : b.f(j)));
    if (triad == TriadId::gyro && max_ref < units::kDeg)
      s << "the plan has no rotation about IMU " << axis_name(j) << " (only Earth rate, "
        << units::deg(max_ref) * 3600 << " °/h, reaches it)";
    else if (triad == TriadId::accel && max_ref < 0.3 * units::kG0)
      s << "the plan never puts IMU " << axis_name(j) << " near the vertical (|f_" << axis_name(j)
        << "| ≤ " << max_ref / units::kG0 << " g)";
    else if (j == axis)
      s << "the reference along IMU " << axis_name(j)
        << " takes too few distinct values to separate scale factor from bias";
    else
      s << "too little excitation along IMU " << axis_name(j);
  } else {
    s << "bias cannot be separated from the other terms with this plan";
  }
  if (std::isfinite(sigma)) s << " (σ would be " << sigma << ", limit " << limit << ")";
  return s.str();
}

// Limits beyond which a coefficient counts as not determined by the data: worse than the
// data-sheet spread of the device class, i.e. the plan taught us nothing useful about it.
double sigma_limit(TriadId triad, int k) {
  using namespace units;
  if (triad == TriadId::gyro) return k == kParBias ? 0.05 * kDeg : 1e-3;
  return k == kParBias ? 5 * kMilliG : 2e-3;
}

}  // namespace

std::vector<AxisProblem> setup_problems(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt,
                                        BenchFitResult& result) {
  // White noise per sample, pooled from the scatter inside blocks.
  Vec3 gss = Vec3::Zero(), ass = Vec3::Zero();
  double dof = 0, rate_sum = 0;
  for (const auto& b : blocks) {
    gss += b.gyro_ss;
    ass += b.accel_ss;
    dof += b.n - 1;
    rate_sum += b.n / std::max(b.duration, 1e-9);
  }
  if (dof < 10) throw std::runtime_error("bench fit: too little data in plan steps (" + std::to_string(dof) + " dof)");
  const Vec3 gvar = gss / dof, avar = ass / dof;
  const double fs = rate_sum / static_cast<double>(blocks.size());
  result.gyro_white_density = (gvar / fs).cwiseSqrt();
  result.accel_white_density = (avar / fs).cwiseSqrt();

  std::vector<AxisProblem> out;
  for (TriadId triad : {TriadId::gyro, TriadId::accel}) {
    const TriadNoise& tn = triad == TriadId::gyro ? opt.noise.gyro : opt.noise.accel;
    const char* tname = triad == TriadId::gyro ? "gyro" : "accel";
    for (int i = 0; i < 3; ++i) {
      AxisProblem p;
      p.triad = triad;
      p.axis = i;
      p.white_var = std::max(triad == TriadId::gyro ? gvar(i) : avar(i), 1e-30);
      p.drift_sigma = tn.drift_sigma;
      p.drift_tau = tn.drift_tau_s;
      p.estimated.fill(true);
      if (triad == TriadId::gyro && opt.model == BenchModel::paper) {
        p.estimated[kParM0 + i] = false;
        result.not_estimated.push_back(std::string(tname) + "." + param_name(kParM0 + i, i));
      }
      // Observability: information with blocks treated as independent (white + drift + bench
      // variance each); greedy removal of the worst-determined coefficient, M before bias.
      while (true) {
        std::vector<int> idx;
        for (int k = 0; k < kAxisParams; ++k)
          if (p.estimated[k]) idx.push_back(k);
        Eigen::Matrix4d info = Eigen::Matrix4d::Zero();
        for (const auto& b : blocks) {
          const double var = p.white_var / b.n + p.drift_sigma * p.drift_sigma +
                             std::pow(bench_error_sigma(b, triad, i, opt.table), 2);
          const auto h = design_row(b, triad);
          info += h.transpose() * h / var;
        }
        const int m = static_cast<int>(idx.size());
        Eigen::MatrixXd I(m, m);
        for (int a = 0; a < m; ++a)
          for (int c = 0; c < m; ++c) I(a, c) = info(idx[a], idx[c]);
        // Scale to unit diagonal before judging singularity.
        Eigen::VectorXd d = I.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
        const Eigen::MatrixXd In = d.asDiagonal() * I * d.asDiagonal();
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(In);
        std::vector<double> sigma(m, kUnknownSigma);
        if (es.eigenvalues().minCoeff() > 1e-12) {
          const Eigen::MatrixXd C = d.asDiagonal() * In.inverse() * d.asDiagonal();  // m ≤ 4
          for (int a = 0; a < m; ++a) sigma[a] = std::sqrt(C(a, a));
        }
        int worst = -1;
        double worst_ratio = 1.0;
        for (int pass = 0; pass < 2 && worst < 0; ++pass) {  // M first, then bias
          for (int a = 0; a < m; ++a) {
            const bool is_m = idx[a] >= kParM0;
            if ((pass == 0) != is_m) continue;
            const double ratio = sigma[a] / sigma_limit(triad, idx[a]);
            if (ratio > worst_ratio) {
              worst_ratio = ratio;
              worst = a;
            }
          }
        }
        if (worst < 0) break;
        const int k = idx[worst];
        p.estimated[k] = false;
        result.unobservable.push_back({tname, param_name(k, i),
                                       reason_for(blocks, triad, i, k, sigma[worst], sigma_limit(triad, k))});
        if (m == 1) break;
      }
      out.push_back(p);
    }
  }
  return out;
}

}  // namespace bench_fit_detail

namespace {
void fill_residuals(const std::vector<BenchBlock>& blocks, BenchFitResult& r) {
  using namespace bench_fit_detail;
  std::vector<StepResidual> steps;
  for (const auto& b : blocks) {
    if (steps.empty() || steps.back().step != b.step) {
      StepResidual s;
      s.step = b.step;
      steps.push_back(s);
    }
    StepResidual& s = steps.back();
    const Vec3 rg = b.gyro - r.estimate.gyro.measure(b.w);
    const Vec3 ra = b.accel - r.estimate.accel.measure(b.f);
    const double n = static_cast<double>(s.samples + b.n);
    const double wgt = b.n / n;
    s.gyro_mean += wgt * (rg - s.gyro_mean);
    s.accel_mean += wgt * (ra - s.accel_mean);
    s.gyro_rms += rg.cwiseAbs2() * b.n;   // sums for now
    s.accel_rms += ra.cwiseAbs2() * b.n;
    s.rate_norm += b.w.norm() * b.n;
    s.f_mean += b.f * b.n;
    s.samples += b.n;
    s.duration_s += b.duration;
  }
  for (auto& s : steps) {
    s.gyro_rms = (s.gyro_rms / s.samples).cwiseSqrt();
    s.accel_rms = (s.accel_rms / s.samples).cwiseSqrt();
    s.rate_norm /= s.samples;
    s.f_mean /= s.samples;
    s.rotating = s.rate_norm > units::kDeg;
  }
  r.steps = std::move(steps);
}
}  // namespace

BenchFitResult fit_bench_lsq(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt,
                             const std::vector<bench_fit_detail::AxisProblem>& problems, BenchFitResult r);
BenchFitResult fit_bench_ekf(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt,
                             const std::vector<bench_fit_detail::AxisProblem>& problems, BenchFitResult r);

BenchFitResult fit_bench(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt) {
  if (blocks.size() < 8) throw std::runtime_error("bench fit: only " + std::to_string(blocks.size()) +
                                                  " data blocks in plan steps (is the step column all −1?)");
  BenchFitResult r;
  const auto problems = bench_fit_detail::setup_problems(blocks, opt, r);
  r = opt.method == BenchMethod::lsq ? fit_bench_lsq(blocks, opt, problems, std::move(r))
                                     : fit_bench_ekf(blocks, opt, problems, std::move(r));
  r.blocks = static_cast<int>(blocks.size());
  for (const auto& b : blocks) r.data_s += b.duration;
  fill_residuals(blocks, r);
  return r;
}

}  // namespace calbench
