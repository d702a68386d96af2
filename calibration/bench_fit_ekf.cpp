// Bench fit by the paper's sequential modification of the EKF (section II, after eq 5): the
// observations are processed block by block and component by component as scalar updates, so
// no matrix is inverted, and the random errors of the rotary bench enter as a state that is
// reset at every plan step (constant during the step, independent between steps).
//
// State of one triad, blocks in this order (offsets computed from the sizes, the same rule as
// the in-motion filter's blocks, calibration/filter/block_layout.hpp):
//   bias  b (3)        constant part of the drift / bias
//   M     M (9)        row-major: M[i][j] at M + 3i + j (scale on the diagonal, skews off it)
//   drift d (3)        in-run drift, first-order Gauss–Markov (data-sheet σ, τ)
//   bench e (3)        bench error during the current step
// Observation of axis i (eq 4 generalised): z_i = b_i + Σ_j M_ij ref_j + d_i + e_i + v_i.
#include <cmath>

#include "calibration/bench_fit.hpp"
#include "calibration/filter/block_layout.hpp"

namespace calbench {
namespace {

enum BenchState { kBiasBlock, kMBlock, kDriftBlock, kBenchBlock, kBlockCount };
constexpr std::array<int, kBlockCount> kSizes = {3, 9, 3, 3};
constexpr auto kOffsets = filter::offsets_from_sizes(kSizes);
constexpr int kBias = kOffsets[kBiasBlock];
constexpr int kM = kOffsets[kMBlock];
constexpr int kDrift = kOffsets[kDriftBlock];
constexpr int kBench = kOffsets[kBenchBlock];
constexpr int kStates = kOffsets[kBlockCount];
static_assert(kStates == 18, "b, M, d, e of one triad");
using StateVec = Eigen::Matrix<double, kStates, 1>;
using StateMat = Eigen::Matrix<double, kStates, kStates>;

// Jacobian row of the observation of axis i w.r.t. the state (each block's part in its place).
StateVec observation_row(const Vec3& ref, int i) {
  StateVec h = StateVec::Zero();
  h(kBias + i) = 1.0;                                            // ∂z_i/∂b_i
  for (int j = 0; j < 3; ++j) h(kM + 3 * i + j) = ref(j);        // ∂z_i/∂M_ij = ref_j
  h(kDrift + i) = 1.0;                                           // ∂z_i/∂d_i
  h(kBench + i) = 1.0;                                           // ∂z_i/∂e_i
  return h;
}

// Scalar Kalman update in Joseph form (numerically symmetric and positive).
void scalar_update(StateVec& x, StateMat& P, const StateVec& h, double z, double r) {
  const StateVec Ph = P * h;
  const double s = h.dot(Ph) + r;
  const StateVec k = Ph / s;
  x += k * (z - h.dot(x));
  const StateMat A = StateMat::Identity() - k * h.transpose();
  P = A * P * A.transpose() + r * k * k.transpose();
}

}  // namespace

using bench_fit_detail::AxisProblem;

BenchFitResult fit_bench_ekf(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt,
                             const std::vector<AxisProblem>& problems, BenchFitResult r) {
  using namespace bench_fit_detail;
  for (TriadId triad : {TriadId::gyro, TriadId::accel}) {
    const AxisProblem* ax[3];
    for (const auto& p : problems)
      if (p.triad == triad) ax[p.axis] = &p;
    // Initial uncertainty: far wider than any ADIS16488A-class unit (effectively diffuse);
    // coefficients that are not estimated get zero variance and stay at 0.
    const double b0 = triad == TriadId::gyro ? 0.1 : 1.0;  // rad/s, m/s²
    const double m0 = 0.05;
    StateVec x = StateVec::Zero();
    StateMat P = StateMat::Zero();
    for (int i = 0; i < 3; ++i) {
      P(kBias + i, kBias + i) = ax[i]->estimated[kParBias] ? b0 * b0 : 0.0;
      for (int j = 0; j < 3; ++j) P(kM + 3 * i + j, kM + 3 * i + j) = ax[i]->estimated[kParM0 + j] ? m0 * m0 : 0.0;
      P(kDrift + i, kDrift + i) = ax[i]->drift_sigma * ax[i]->drift_sigma;
    }
    int step = -2;
    double t_prev = blocks.front().t_mid;
    for (const auto& b : blocks) {
      // Propagation: b, M constant; d Gauss–Markov (exact discretisation); e reset per step.
      const double dt = b.t_mid - t_prev;
      t_prev = b.t_mid;
      for (int i = 0; i < 3; ++i) {
        const double phi = std::exp(-dt / ax[i]->drift_tau);
        const int s = kDrift + i;
        P.row(s) *= phi;
        P.col(s) *= phi;
        P(s, s) += ax[i]->drift_sigma * ax[i]->drift_sigma * (1.0 - phi * phi);
        x(s) *= phi;
      }
      if (b.step != step) {
        step = b.step;
        for (int i = 0; i < 3; ++i) {
          const int s = kBench + i;
          x(s) = 0;
          P.row(s).setZero();
          P.col(s).setZero();
          P(s, s) = std::pow(bench_error_sigma(b, triad, i, opt.table), 2);
        }
      }
      const Vec3& ref = triad == TriadId::gyro ? b.w : b.f;
      for (int i = 0; i < 3; ++i)
        scalar_update(x, P, observation_row(ref, i), observation(b, triad, i), ax[i]->white_var / b.n);
    }
    TriadErrors& te = triad == TriadId::gyro ? r.estimate.gyro : r.estimate.accel;
    for (int i = 0; i < 3; ++i) {
      const bool eb = ax[i]->estimated[kParBias];
      te.bias(i) = eb ? x(kBias + i) : 0.0;
      te.sigma_bias(i) = eb ? std::sqrt(P(kBias + i, kBias + i)) : kUnknownSigma;
      for (int j = 0; j < 3; ++j) {
        const bool em = ax[i]->estimated[kParM0 + j];
        const int s = kM + 3 * i + j;
        te.M(i, j) = em ? x(s) : 0.0;
        te.sigma_M(i, j) = em ? std::sqrt(P(s, s)) : kUnknownSigma;
      }
    }
  }
  return r;
}

}  // namespace calbench
