// Physics discovery on a bench recording (issue 7): predict the sensor output from the reference
// through the current coefficients, locate where the residual is systematic, name the missing
// physics from the catalogue (calibration/diagnosis/catalogue.hpp) by evidence, fit it, and show
// the improvement.
//
// Statistical model per sensor axis (gyro x..accel z), z = measured − reference − carried terms:
//   z = b + M_i·ref + Σ_terms regressor·θ + drift + bench error + white noise
// judged on two levels that share the parameters:
//   * ~1 s parent blocks by generalised least squares with the full covariance (white/n +
//     first-order Gauss–Markov drift + per-step bench error), as the bench fit does;
//   * 0.05 s sub-blocks as deviations from their parent's mean (drift and bench error cancel,
//     only white noise remains): this is where within-revolution effects show.
// Candidates are added greedily by Δχ² (= −2Δlog-likelihood) with a BIC-type penalty and a
// held-out check (fit on even steps, predict odd ones and vice versa); the loop stops when no
// candidate passes. correlated_drift is a candidate on the noise side (a larger drift σ chosen by
// maximum likelihood).
#pragma once
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "calibration/bench_plan.hpp"
#include "calibration/diagnosis/catalogue.hpp"
#include "common/noise_spec.hpp"

namespace calbench {

struct DiagnoseOptions {
  NoiseSpec noise = adis16488a_noise();  // data-sheet drift prior
  TableSpec table;                       // bench errors
  double penalty_per_param = 0;          // extra Δχ² per parameter on top of ln N (0 = default)
  double min_delta_chi2 = 40;            // smallest Δχ² that can count as a finding
  int max_findings = 6;
  // A candidate that, put in a finding's place in the final model, fits within this Δχ² of it is
  // reported as an alternative the recording cannot tell apart (likelihood ratio < e^5); so is one
  // whose regressor correlates with the finding's at ≥ ambiguity_correlation on this recording
  // (DiagAlternative::regressor_correlation), however large the Δχ².
  double ambiguity_chi2 = 10;
  double ambiguity_correlation = 0.99;
  // Issue 36, explained fraction: a finding is established only when the accepted model cuts the
  // systematic residual of the axis it is reported on by at least this fraction (amplitude,
  // 1 − rms_after/rms_before, the sweep's own "cut ≥ 80 %" criterion) and that axis's remainder is
  // consistent with its noise model; otherwise it is "partial" (docs/diagnosis.md, "Decision rules").
  double established_cut = 0.8;
  // Issue 36, the smallest inputs (DiagLowInput): test whether the gyros' output follows their
  // smallest rate inputs, the search redone with them taken as not sensed.
  bool low_input_check = true;
};

struct AxisStats {
  double chi2_dof = 0;       // whitened parent-level χ²/dof
  double high_chi2_dof = 0;  // sub-block deviations χ²/dof
  double ljung_box_q = 0, ljung_box_p = 1;
  double systematic_rms = 0; // RMS of per-step means and within-step low-passed residual, noise removed
  double step_rms = 0, within_rms = 0;
  double systematic_floor = 0; // drives: noise level of systematic_rms (below it, not told from zero)
  // Bench: rotating steps' sub-block residuals binned by table angle (12 bins per step) and summed
  // over the steps into a profile: its most significant bin (index, its z and its mean residual).
  int worst_angle_bin = -1;
  double worst_angle_bin_z = 0, worst_angle_bin_mean = 0;
  double angle_profile_p = 1;  // χ² test of the 12-bin angle profile against white noise
  // Bench (issue 36, the remainder's power): a generalised-least-squares test of one offset per
  // plan step in the whitened parent residual (the noise model's drift and bench errors in the
  // whitening). The step indicators are whitened by the same factor and projected off the axis's
  // model columns; Q = ‖projection of the whitened residual on what is left‖² is χ² with step_dof
  // = the rank of what is left. A remainder that moves from step to step (a dead band, a memory
  // of the last rotation, a clipped output) concentrates there, where the parent-level χ²/dof
  // spreads it over every block. Three families: all steps, the static steps and the rotating
  // steps (an effect of low rates or of gravity sits in the statics, one of the rate in the
  // rotations, and a family's test has fewer degrees of freedom to spread it over); step_p is the
  // smallest family p times 3 (Bonferroni: the axis's false-alarm rate stays at the level),
  // step_q and step_dof are that family's, step_family names it.
  double step_q = 0, step_p = 1;
  int step_dof = 0;
  const char* step_family = "all";
  double bic = 0;
};

struct ConditionCorrelation {
  std::string condition;
  double r = 0;
};

// Another catalogue term that explains the same residual about as well (e.g. a temperature bias
// and thermal lag on a warm-up alone, where T − T_end ∝ dT/dt).
struct DiagAlternative {
  Term term;
  std::vector<double> value;  // fitted in the finding's place, SI
  std::string unit;
  double chi2_worse = 0;      // χ² of that model minus the chosen one's (< ambiguity_chi2)
  // √(Δχ² it explains in the finding's place / Δχ² the finding explains): the regressors'
  // correlation on this recording as the residual shows it (1: the same shape here).
  double regressor_correlation = 0;
};

// Profile-likelihood intervals of a correlated_drift finding: σ, τ and the random-walk density
// K = σ·√(2/τ) with −2 ln L within 1 (1σ) and within 4 (2σ) of its minimum. NaN: the record
// leaves that side open (τ, and with it σ, not resolved). K is what a record only a few τ long
// determines (the drift's spectrum above 1/τ is K²/ω²); it stays bounded when τ is open towards
// long correlation times and is open above only when τ is open towards short ones.
struct DriftInterval {
  static constexpr double kOpen = std::numeric_limits<double>::quiet_NaN();
  double sigma_lo = kOpen, sigma_hi = kOpen, tau_lo = kOpen, tau_hi = kOpen;         // 1σ
  double sigma_lo2 = kOpen, sigma_hi2 = kOpen, tau_lo2 = kOpen, tau_hi2 = kOpen;     // 2σ
  double rw_lo = kOpen, rw_hi = kOpen, rw_lo2 = kOpen, rw_hi2 = kOpen;               // K, 1σ and 2σ
  // Is σ = s inside the 2σ interval (an open side unbounded)?
  bool sigma_within_2sigma(double s) const { return !(s < sigma_lo2) && !(s > sigma_hi2); }
};

struct DiagFinding {
  Term term;
  std::vector<double> value, sigma;  // SI
  std::string unit;
  int report_axis = -1;              // axis the finding is reported on (−1 = all)
  int report_sensor = 0;             // 0 gyro, 1 accel, 2 reference
  double delta_chi2 = 0, delta_bic = 0, heldout_delta_chi2 = 0;
  // GNSS-only drives: what removing it from the final model costs, the figure the overdispersion
  // check divides by φ (delta_chi2 is the gain when it was accepted).
  double delta_chi2_final = 0;
  std::string condition;             // the condition that reveals it
  double condition_r = 0;
  double rms_before = 0, rms_after = 0;  // systematic residual of the reported sensor axis (or all touched)
  double noise_tau_s = 0;                // correlated_drift only
  DriftInterval noise_interval;          // correlated_drift only: profile intervals of σ, τ and K
  std::vector<DiagAlternative> alternatives;  // best first; empty = the effect is told apart
  // Issue 36: the fraction of its axis's systematic residual the accepted model removes
  // (1 − rms_after/rms_before; 1 when nothing systematic was measurable before), whether that
  // axis's remainder is consistent with noise, and the status these give: "established",
  // "partial" (cut below DiagnoseOptions::established_cut or the axis left unexplained) or
  // "not told apart" (an alternative explains it as well).
  double explained_fraction = 1;
  bool remainder_is_noise = true;
  const char* status = "established";
  // A temperature-driven term against a correlated drift of its triad (the search redone with the
  // triad's temperature terms banned, the drift free to grow): that model's penalised −2 ln L minus
  // this one's (> 0: the temperature term explains the record better), and the drift it needed.
  struct VersusDrift {
    bool tested = false;
    double delta_score = 0, drift_sigma = 0, drift_tau_s = 0;
    const char* verdict = "";  // "temperature", "drift" or "cannot tell" (|Δ| < ambiguity_chi2)
  } versus_drift;
  // The record with the gyros' smallest inputs taken as not sensed (DiagLowInput) fits within
  // ambiguity_chi2 of this model and does without this finding: not told apart from it.
  bool low_input_alternative = false;
  // Told apart from every alternative (another term, or the smallest inputs not sensed): only then
  // does the finding carry a σ in the text and the JSON.
  bool told_apart() const { return alternatives.empty() && !low_input_alternative; }
};

// Why an accepted term was given up.
enum class WithdrawnWhy {
  weak,           // in the final model it explains less than min_delta_chi2 (backward check)
  drift_recheck,  // correlated_drift: the search redone without it scores better
  overdispersed,  // its Δχ², scaled by the unexplained remainder's χ²/dof (φ), fails the threshold
  leaves_unexplained,  // correlated_drift: an axis of its triad stays unexplained with it
  follows_condition,   // correlated_drift (drive): the wander it took follows a motion condition
};

// A term the greedy search accepted and then gave up (why: WithdrawnWhy): not a finding.
struct DiagWithdrawn {
  Term term;
  double delta_chi2_when_accepted = 0;
  // weak / overdispersed: what removing it from the final model costs (overdispersed: Σ Δχ²_a/φ_a).
  // correlated_drift: the change of the penalised −2 ln L from the model with it to the one redone
  // without (< 0 for drift_recheck).
  double delta_chi2_final = 0;
  WithdrawnWhy why = WithdrawnWhy::weak;
  // follows_condition: the condition, the axis and the correlation of the drift's smoothed path with
  // it, and its Fisher z over the record's independent stretches (length / 2τ).
  std::string condition;
  int axis = -1;
  double condition_r = 0, condition_z = 0;
  // Or (condition_dchi2 > 0): the condition's GLS Δχ² under the class's drift on that axis, the
  // triad's sum of them reaching the drift's own gain (drift_gain, −2 ln L).
  double condition_dchi2 = 0, drift_gain = 0;
};

struct DiagUnexplained {
  int sensor = 0, axis = 0;
  double chi2_dof = 0, high_chi2_dof = 0, ljung_box_p = 1, systematic_rms = 0;
  double step_p = 1;  // bench: the step-offset test (AxisStats::step_p, step_family)
  const char* step_family = "all";
  // Drives: the motion condition whose GLS test against the residual (the noise model's drift
  // included) reaches the acceptance threshold, its Δχ² and plain correlation; empty if none.
  std::string condition_test;
  double condition_dchi2 = 0, condition_r = 0;
  std::vector<int> worst_steps;
  std::vector<ConditionCorrelation> correlations;  // strongest first
  double angle_harmonic_amp = 0;
  int angle_harmonic = 0;
  // Where in the table angle (bench): the 30° bin whose mean residual stands out most (its z ≥ 4;
  // else NaN), over the rotating steps; and the strongest periodic component in time (the
  // sub-block residual's periodogram, 0.02–5 Hz; amplitude in SI).
  double angle_bin_deg[2] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  double angle_bin_mean = 0, angle_bin_z = 0;
  double period_hz = 0, period_amp = 0;
};

// Issue 36, a plateau at the highest inputs: an axis whose output stays frozen (its scatter inside
// the sub-blocks below kFrozenScatter of its white noise) at the largest outputs of the recording
// has left its measurement range. Those plan steps are left out of the diagnosis: a clipped output
// says nothing about the sensor model, and fitted by polynomial terms it would name them.
struct DiagSaturation {
  int sensor = 0, axis = 0;
  double level_pos = std::numeric_limits<double>::quiet_NaN();  // plateau output, positive side (SI)
  double level_neg = std::numeric_limits<double>::quiet_NaN();  // negative side
  double reference_max = 0;  // largest |reference input| about the axis on those steps
  double frozen_fraction = 0;  // share of those steps' sub-blocks that are frozen
  std::vector<int> steps;    // plan steps left out
  double excluded_s = 0;     // data left out (all axes: the steps are removed whole)
};
// Sub-block scatter below this fraction of (n − 1)·white variance counts as frozen.
constexpr double kFrozenScatter = 0.01;
// Finds the plateaus (empty if none) from the sub-blocks' scatter and the white noise per axis.
std::vector<DiagSaturation> find_saturation(const DiagData& d, const double (&white_var)[6]);
// The recording without those steps (parents and sub-blocks renumbered).
DiagData without_steps(const DiagData& d, const std::vector<int>& steps);

// Issue 36, the smallest inputs: a gyro whose output does not follow its smallest rate inputs (a
// dead band or a threshold: no term of the catalogue, whose terms are smooth in the input). On
// statics the input is the Earth rate, whose vertical part is exactly what an isotropic
// g-sensitivity of −Ω·sin L/g gives, and a larger drift absorbs short low-rate steps: the catalogue
// names those when the Earth rate is not sensed. The input an axis receives is row a of (I + M)·ω
// with the tested M (a turn about another axis reaches it through the misalignment). Screen per
// gyro axis: the base model's GLS fit at the parent level (the class's drift) with the sub-blocks
// whose received rate lies below a width on the grid Ω·{1.25, 2.5, 5, 10, 20} taken as not sensed
// (measured + received rate there); the width with the largest gain, kept when the gain reaches
// min_delta_chi2. Then the whole diagnosis is redone on the record so corrected, and the two
// compare by the penalised −2 ln L of their final models (DiagnoseResult::score), the hypothesis
// charged one parameter per axis; after a joint win each axis must earn its place (dropped, one at
// a time, when leaving it out costs less than ambiguity_chi2):
//   corrected better by ≥ ambiguity_chi2: "not sensed": that diagnosis is the result (this record
//     attached), and what the catalogue alone would have named is listed;
//   within ambiguity_chi2: "cannot tell": this record's diagnosis; its gyro findings that the
//     corrected one does without, or gives a value beyond 2σ of theirs, are not told apart from the
//     hypothesis (DiagFinding::low_input_alternative);
//   worse by ≥ ambiguity_chi2: "sensed" (JSON only).
struct DiagLowInput {
  struct Axis {
    int axis = 0;             // gyro axis
    double width = 0;         // the grid width (rad/s): inputs below it taken as not sensed
    double below_max = 0;     // largest |input| among them on this record (rad/s)
    double above_min = 0;     // smallest |input| above the width on this record (rad/s; 0: none)
    int blocks = 0;           // sub-blocks taken as not sensed
    double screen_gain = 0;   // the screen's Δχ² (base model)
    double penalty = 0;       // its charge: one parameter, ln(rows) (the width's choice among 5 is not charged)
  };
  std::vector<Axis> axes;     // empty: no axis passed the screen, not tested
  double delta_score = 0;     // −2 ln L (penalised) of the record as is minus the corrected one's, less the penalty
  const char* verdict = "";   // "not sensed", "cannot tell", "sensed"
  std::vector<std::string> competing;  // findings of the record as is that the corrected one does without
  // The record as is: its gyro axes' final statistics and those it left unexplained.
  AxisStats catalogue_after[3];
  std::vector<int> catalogue_unexplained;
  bool tested() const { return !axes.empty(); }
  // The hypothesis's charge: Σ of the axes'.
  static double penalty_of(const std::vector<Axis>& axes) {
    double p = 0;
    for (const auto& x : axes) p += x.penalty;
    return p;
  }
  double penalty() const { return penalty_of(axes); }
  // The verdict the text and the report state ("sensed" is in the JSON only).
  bool stated() const { return std::strcmp(verdict, "not sensed") == 0 || std::strcmp(verdict, "cannot tell") == 0; }
};

// Issue 36, drift against the class's stability: on an axis with no finding of its own and not
// unexplained, the drift the class's noise model absorbed (its smoothed path in the final residual).
// When it moved the bias by more than kDriftExcessFactor × the class's in-run bias stability over
// the run and stands kDriftExcessZ standard deviations above what that noise model gives on this
// recording (a drawn null), or the catalogue's temperature bias of the axis, though below the
// acceptance threshold (Δχ² ≥ kDriftTemperatureChi2), gives such a change, it is reported, never
// established: "temperature or drift, not told apart" when the temperature accounts for it
// (temperature_or_drift()), else "a drift beyond the data sheet or an effect outside the
// catalogue". Beside it, the best larger drift of that axis alone on the drift
// grid and its likelihood gain (which a short record leaves small: a warm-up is a likely path of the
// class's drift there, only an unusually large one).
struct DiagDriftExcess {
  int sensor = 0, axis = 0;
  double gain = 0;                 // −2 ln L of the class's drift minus that of the best larger one (≤ 0: none better)
  double sigma = 0, tau_s = 0;     // that drift (SI)
  double change = 0;               // max − min of its smoothed path over the run (SI)
  double stability = 0;            // the class's in-run bias stability (its drift σ, SI)
  // The change against its distribution under the class's noise model (kDriftExcessDraws draws of
  // the parent residual through the same smoother): mean, standard deviation, z.
  double null_mean = 0, null_sd = 0, z = 0;
  int null_exceed_count = -1;      // how many of the kDriftExcessDraws draws reach it (−1: not drawn)
  // The share of the draws reaching the change (NaN: not drawn).
  double null_exceed() const;
  bool has_temperature = false;
  double temperature_change = 0;   // max − min of the recorded temperature over the blocks (°C)
  double temperature_r = 0;        // correlation of the path with the temperature
  double per_degree = 0;           // the path's least-squares slope on the temperature (SI per °C)
  bool follows_temperature = false;  // |r| ≥ kDriftTemperatureR and temperature_change ≥ 1 °C
  // The catalogue's temperature_bias of this axis added to the final model: Δχ², value, 1σ (SI per K).
  double temperature_dchi2 = 0, temperature_coef = 0, temperature_coef_sigma = 0;
  // |coefficient| × the temperature change: the change over the run the temperature term gives.
  double temperature_change_total() const { return std::abs(temperature_coef) * temperature_change; }
  // Read as "temperature or drift, not told apart": the path follows the temperature, or the
  // temperature term reaches kDriftTemperatureChi2 (the text and the JSON status both ask this).
  bool temperature_or_drift() const;
};
constexpr double kDriftExcessFactor = 2.0;  // the change must exceed 2× the class's stability
constexpr double kDriftExcessZ = 4.0;       // and stand 4 standard deviations above its null mean
constexpr int kDriftExcessDraws = 400;
constexpr double kDriftTemperatureR = 0.8;  // |r| of the path with the temperature that "follows" it
// or: the temperature term, though below the acceptance threshold, at Δχ² ≥ 13.8 (χ²₁ p = 2·10⁻⁴)
// giving a change > 2× the stability. At Δχ² ≥ 4 a quarter of clean simulated units were reported
// (their own drift, following the self-heating of the plan, looks the same).
constexpr double kDriftTemperatureChi2 = 13.8;
// The report rule: (change > kDriftExcessFactor·stability and z ≥ kDriftExcessZ) or (the temperature
// term's Δχ² ≥ kDriftTemperatureChi2 and its change over the run > kDriftExcessFactor·stability).
bool drift_excess_reported(const DiagDriftExcess& x);
// A note, not a finding (issue 36: "never nothing" on a bias that moved): not reported, but the drift
// model absorbed a change beyond kDriftExcessFactor × the stability that the class's own drift
// reaches in at most kDriftNoteTail of the null draws. By design the class's drift does this on about
// that share of a clean unit's axes; the note gives the share and says what it cannot tell apart
// (the temperature term, when it fits at Δχ² ≥ kDriftNoteChi2 or the path follows the temperature,
// makes it "temperature or drift"). Without the tail condition, 2× the stability alone noted the
// accelerometers of 2 in 5 clean units (the class's own drift moves an ADIS16488A accelerometer 1.7×
// its stability over the 4-minute plan on average, 22–27 % of draws beyond 2×); a temperature term
// at Δχ² ≥ 4 alone fires on a quarter of clean units (their drift follows the plan's self-heating).
constexpr double kDriftNoteChi2 = 4.0;
constexpr double kDriftNoteTail = 0.05;
bool drift_excess_noted(const DiagDriftExcess& x);
// The note reads "temperature or drift": the path follows the temperature or the temperature term
// fits it at Δχ² ≥ kDriftNoteChi2.
inline bool drift_note_temperature(const DiagDriftExcess& x) {
  return x.follows_temperature || (x.has_temperature && x.temperature_dchi2 >= kDriftNoteChi2);
}
inline double DiagDriftExcess::null_exceed() const {
  return null_exceed_count < 0 ? std::numeric_limits<double>::quiet_NaN()
                               : static_cast<double>(null_exceed_count) / kDriftExcessDraws;
}
inline bool DiagDriftExcess::temperature_or_drift() const {
  return follows_temperature || (has_temperature && temperature_dchi2 >= kDriftTemperatureChi2);
}

// Per-sub-block residual of one sensor axis, for plots.
struct ResidualSeries {
  std::vector<double> before, after;  // rad/s or m/s²
};

// A catalogue term this recording cannot excite: even with white noise alone its best-determined
// parameter's 1σ exceeds a third of the largest value plausible for the unit class (the spec's
// prior), so it is not a candidate here (docs/diagnosis.md, "Which recording excites what").
struct NotExcited {
  Term term;
  double sigma_ratio = 0;  // min over parameters of 1σ / plausible value
};

struct DiagnoseResult {
  std::vector<DiagFinding> findings;
  std::vector<NotExcited> not_excited;
  std::vector<DiagUnexplained> unexplained;
  std::vector<DiagWithdrawn> withdrawn;
  std::vector<DiagSaturation> saturation;        // steps left out (rule: plateau at the top inputs)
  std::vector<DiagDriftExcess> drift_excess;     // drift beyond the class's stability, not established
  std::vector<DiagDriftExcess> drift_noted;      // a bias change beyond 2× the stability within the class's drift: a note
  // What the drift model absorbed, for every axis checked (no finding, not unexplained, the class's
  // drift kept): the reported ones and the rest, so that a reader sees the margin (JSON axes.*.drift).
  std::vector<DiagDriftExcess> drift_checked;
  DiagLowInput low_input;                        // the smallest inputs' test (tested: it ran)
  double score = 0;                              // penalised −2 ln L of the final model (its own record)
  AxisStats before[6], after[6];                 // gyro x,y,z, accel x,y,z
  std::vector<ConditionCorrelation> correlations_before[6];
  SensorErrors base_before;                      // coefficients used for "before"
  SensorErrors improved;                         // refit b, M with the new terms
  EffectTerms improved_terms;                    // carried + new terms
  EffectTerms terms_sigma;                       // 1σ of improved_terms (same layout)
  double drift_sigma[2] = {0, 0}, drift_tau[2] = {0, 0};  // noise model after (per triad)
  ResidualSeries residual[6];
  double white_sigma[6] = {0, 0, 0, 0, 0, 0};    // per-sample white noise
  int parents = 0, subs = 0;
  double data_s = 0;
};

// Issue 36's explained-fraction rule: fills f.explained_fraction, f.remainder_is_noise and f.status
// from its systematic residual before/after and the result's unexplained axes.
void finding_status(DiagFinding& f, const DiagnoseResult& res, const DiagnoseOptions& opt);

// `current`: coefficients to test (b, M) and the extra terms they already carry.
DiagnoseResult diagnose_bench(const DiagData& data, const SensorErrors& current, const EffectTerms& carried,
                              const DiagnoseOptions& opt);

// Value of a condition for a sub-block (used for correlations and plots). Names:
// "rate", "w_x".."w_z", "f_x".."f_z", "temperature", "dT/dt", "time", "angle".
// The finding of a drift larger or slower than the prior on one triad (0 gyro, 1 accel):
// first-order σ and τ with their profile intervals (the finding's σ is half the 1σ interval of σ,
// NaN when it is open), systematic residual as the RMS over the triad's axes.
DiagFinding correlated_drift_finding(int triad, double sigma, double tau_s, const DriftInterval& interval,
                                     double delta_chi2, double delta_bic, const AxisStats (&before)[6],
                                     const AxisStats (&after)[6]);

std::vector<std::string> condition_names();
double condition_value(const DiagData& d, const SubBlock& s, const std::string& name);
// A plot-axis label for a condition of condition_value() or drive_condition_value(), with the unit
// of the value those return (SI; angle in degrees): "time (s)", "w_z (rad/s)", "temperature (°C)".
std::string condition_axis_label(const std::string& name);

// Ljung–Box Q over `lags` lags and its p-value (χ² with `lags` dof, Wilson–Hilferty).
void ljung_box(const std::vector<double>& x, int lags, double& q, double& p);
// Upper tail P(χ²_dof > q) (Wilson–Hilferty).
double chi2_upper_p(double q, double dof);

}  // namespace calbench
