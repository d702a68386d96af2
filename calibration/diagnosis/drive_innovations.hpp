// Innovation statistics of the in-motion filter on a drive (docs/diagnosis.md, "Drives"): the
// second evidence source of `calbench diagnose` on a drive, next to the predicted-output
// comparison. Per observation type (position, velocity, attitude; eqs 13–15):
//   * NIS/dof: mean of νᵀS⁻¹ν / 3 over the epochs the filter used (1 for a consistent filter),
//     and the counts of rejected (gated) and forced epochs;
//   * whiteness: Ljung–Box (10 lags) of each normalised component ν_i/√S_ii over all epochs
//     (a consistent filter's innovations are white); the smallest p of the three is the verdict;
//   * where: the 20 s windows with the largest NIS/dof;
//   * under which conditions: the correlation, over the ~1 s blocks of the drive diagnosis, of the
//     block mean of √(NIS/3) (normalised innovation magnitude) with each drive condition and the
//     magnitude of the signed ones (|w_x|, …).
// Pure mathematics: the caller runs the filter and hands over its innovations.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/diagnosis/drive_data.hpp"
#include "calibration/diagnosis/greedy_search.hpp"

namespace calbench {

struct InnovationSample {
  double t = 0;
  Vec3 nu = Vec3::Zero();
  Mat3 S = Mat3::Identity();
  double nis = 0;
  int status = 0;  // 0 used, 1 rejected, 2 forced (inmotion::InnovationRecord::Status)
  // The filter's motion at the epoch (inmotion::InnovationRecord): horizontal speed m/s, turn rate
  // about the vertical rad/s, horizontal acceleration m/s² (innovation_conditions.hpp).
  double speed = 0, turn_rate = 0, accel = 0;
};

struct InnovationWindow {
  double t0 = 0, t1 = 0;
  double nis_per_dof = 0;
  int epochs = 0;
};

struct InnovationStats {
  long epochs = 0, used = 0, rejected = 0, forced = 0;
  double nis_per_dof = 0;          // mean NIS/3 over used epochs
  double median_nis_per_dof = 0;   // over all epochs (robust to the gated ones)
  double fraction_within_95 = 0;   // used epochs with NIS ≤ χ²₃(0.95)
  double ljung_box_p[3] = {1, 1, 1};  // per component, normalised innovation
  double ljung_box_p_min = 1;
  double lag1_autocorr[3] = {0, 0, 0};
  std::vector<InnovationWindow> worst_windows;   // largest NIS/dof first
  std::vector<ConditionCorrelation> correlations;  // largest |r| first (n_correlations; < 0: all)
  int correlation_blocks = 0;                      // blocks with an epoch (n of the correlations)
};

// data: the drive diagnosis blocks (conditions); nullptr → no correlations.
InnovationStats innovation_stats(const std::vector<InnovationSample>& x, const DriveDiagData* data,
                                 double window_s = 20.0, int n_worst = 3, int n_correlations = -1);

// −2 ln L of the innovations up to a constant (Gaussian, ν ~ N(0, S)): Σ νᵀS⁻¹ν + ln det S over the
// epochs with a finite NIS, the gated ones included, so that two filter runs over the same fixes are
// compared over the same epochs (a run that gates an epoch pays for it).
double innovation_deviance(const std::vector<InnovationSample>& x);
// The same for two runs over the epochs both have (matched by time to 1 µs; each in time order):
// runs whose filters started at different times (a heading chosen later) or took different fixes
// are compared on what they share. shared: the number of such epochs.
std::pair<double, double> paired_deviance(const std::vector<InnovationSample>& a, const std::vector<InnovationSample>& b,
                                          long* shared = nullptr);

// The evidence of a drive without a reference INS (GNSS-only, docs/diagnosis.md "GNSS-only
// drives"): no predicted MEMS output exists without a reference attitude, so each candidate effect
// is a hypothesis of the aided in-motion filter (an extra state block, or a scale allowed to move),
// judged by the innovations against the fixes. The generalised likelihood ratio of the runs with and
// without it, Δχ² = deviance(without) − deviance(with), takes the same rules as the catalogue search
// (greedy_search.hpp): greedy by Δχ², at least policy.min_delta_chi2 and positive ΔBIC with the
// penalty greedy_term_penalty(k, rows); afterwards each accepted candidate is checked backwards in the
// final model (removing it must still cost min_delta_chi2, else it is withdrawn, WithdrawnWhy::weak).
struct HypothesisStep {
  int candidate = 0;
  double dchi2 = 0, dbic = 0;
  double dchi2_final = 0;  // what removing it from the final model costs
};
struct HypothesisSearchResult {
  std::vector<int> model;              // accepted candidates, in the order accepted
  std::vector<HypothesisStep> steps;   // per accepted candidate (same order)
  std::vector<HypothesisStep> withdrawn;
  std::vector<double> first_round_dchi2;  // Δχ² of each candidate against the base (round 1)
  double base_deviance = 0, final_deviance = 0;
  int evaluations = 0;  // filter runs (distinct models)
};
// Overdispersion φ ≥ 1 of one observation type's innovations (quasi-likelihood, as the catalogue
// search's WithdrawnWhy::overdispersed): NIS/dof above 1 scales every Δχ² up by it, and correlated
// innovations carry fewer independent observations than epochs — an AR(1) sequence with lag-1
// autocorrelation ρ has the variance of its sum inflated by (1 + ρ)/(1 − ρ). φ = max(1, NIS/dof) ·
// max(1, (1 + ρ)/(1 − ρ)), ρ the largest component lag-1 autocorrelation (capped at 0.95).
double innovation_overdispersion(const InnovationStats& s);

// A candidate without a filter state (an effect the estimators compensate on the IMU samples, e.g.
// g_sensitivity): its deviance profiled over its parameters θ. The innovations are linear in θ to
// first order, so D(θ) = D₀ + gᵀθ + ½θᵀHθ; g and H from runs at 0, ±h·e_i and h·(e_i + e_j) (i < j),
// θ̂ = −H⁻¹g, cov θ̂ = 2H⁻¹ (D = −2 ln L); then Newton steps (the quadratic again around θ̂, steps of
// its σ, at most 4 rounds) until the move is below σ/10. ok = false when H is not positive definite
// (the drive does not determine θ).
struct ProfileFit {
  Eigen::VectorXd theta, sigma;
  bool ok = false;
};
// deviance_at(θ): the filter run with the effect compensated at θ (θ = 0: the model without it).
ProfileFit profile_quadratic(int p, double h, const std::function<double(const Eigen::VectorXd&)>& deviance_at);

// nparams: parameters per candidate; rows: scalar observations (the penalty's N); deviance(model):
// the filter over the drive with these candidates (indices, sorted) → innovation_deviance.
HypothesisSearchResult hypothesis_search(const std::vector<int>& nparams, long rows, const GreedyPolicy& policy,
                                         const std::function<double(const std::vector<int>&)>& deviance);

}  // namespace calbench
