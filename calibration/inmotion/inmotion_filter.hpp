// In-motion calibration of a MEMS IMU against a reference inertial-satellite system (paper
// section IV): an error-state extended Kalman filter with feedback around a strapdown INS
// (calibration/ins/strapdown.hpp) driven by the MEMS increments. State: state_layout.hpp.
// Dynamics: error_model.hpp (covariance propagated every `cov_dt` seconds with the transition
// integrated over the IMU samples in between). Observations: observation.hpp (eqs 13–15).
// After each update the estimated errors are fed back into the INS and the sensor model and the
// error state is reset to zero.
#pragma once
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calibration/inmotion/adaptive_noise.hpp"
#include "calibration/inmotion/error_model.hpp"
#include "calibration/inmotion/observation.hpp"
#include "calibration/inmotion/priors.hpp"
#include "calibration/inmotion/standstill.hpp"
#include "calibration/inmotion/velocity_latency.hpp"
#include "common/noise_spec.hpp"
#include "common/sensor_model.hpp"

namespace calbench::inmotion {

// In-run drift model of one axis: first-order (eq 22; σ and correlation time) or, with
// exp_cosine, the exponential-cosine model K(τ) = σ² e^{−|τ|/τ_s} cos βτ (eq 32) carried as two
// augmented states (eqs 35–36, drift_expcos.cpp; the augmented layout, 48 states).
struct DriftPrior {
  double sigma = 0;
  double tau_s = 300;
  bool exp_cosine = false;
  double beta = 0;  // rad/s (exp_cosine only)
};

struct InMotionConfig {
  NoiseSpec noise = adis16488a_noise();  // white-noise densities (process noise)
  // σ of the IMU stamps about the sensor's clock, s (identification/sample_timing.hpp): process
  // noise σ²·|Δm|² per step on velocity and attitude, Δm the step's change of mean rate. 0: none.
  double sample_time_sigma = 0;
  // GNSS fixes: their velocity describes the motion this long before their stamp, s
  // (velocity_latency.hpp; identification/gnss_velocity_latency.hpp measures it). 0: at the stamp.
  double gnss_vel_latency_s = 0;
  // In-run drift models per axis; defaults from `noise` (identified models may replace them).
  std::optional<std::array<DriftPrior, 3>> gyro_drift, accel_drift;
  // Prior 1σ of the constant parameters, relative to the data the filter sees (priors.hpp): the
  // data-sheet class of a raw unit by default; for data corrected by a coefficient set,
  // priors_from_set() (the set's σ combined with the device class's stability allowance).
  ParameterPriors prior = datasheet_priors();
  double sigma_vel0 = 0.1;                        // m/s, initial velocity beyond the reference's
  // Observations.
  bool obs_pos = true, obs_vel = true, obs_att = true;
  double obs_rate_hz = 10;     // at most this many reference epochs per second are used
  double cov_dt = 0.1;         // covariance propagation interval, s
  // Reference accuracy when reference.csv has no sigma columns.
  double ref_sigma_pos = 0.1, ref_sigma_vel = 0.02, ref_sigma_att = 0.01 * units::kDeg;
  double gate_nis = 50;        // innovation gate (3 dof); larger NIS is rejected and counted
  // Adaptive process noise (adaptive_noise.hpp): the navigation states' white-noise densities
  // scaled by covariance matching of the innovations when these are inconsistent with the model.
  AdaptiveNoiseConfig adaptive;
  // When one observation type has been rejected for this long without a break, the filter has
  // lost track (its navigation covariance is too optimistic, e.g. a heading error grown beyond
  // the linear range before the first manoeuvre): the next epoch is used anyway after the
  // position, velocity and attitude rows and columns of P are scaled so that its NIS equals the
  // gate (the parameters keep what they learnt), and counted as `forced`.
  double gate_recover_s = 10;
  bool store_for_smoother = false;
  // Vehicle constraints (docs/in-motion.md, "Vehicle constraints"), applied from the IMU stream at
  // the covariance propagation steps, at most constraint_rate_hz times a second; off by default
  // (a handheld or pedestrian carrier does not obey the non-holonomic constraint).
  //   ZUPT (obs_zupt.cpp) while standing: standstill = the IMU quiet over standstill_window_s
  //     (StandstillDetector, spread ≤ standstill_factor × white noise) and the INS speed and the
  //     last fix's horizontal speed (where fixes carry velocity) below standstill_max_speed; with
  //     zupt_zero_rate the zero angular rate too (a gyro-bias observation).
  //   NHC (obs_nhc.cpp) while moving: no standstill, INS horizontal speed ≥ nhc_min_speed, and the
  //     vehicle not turning faster than nhc_max_turn_rate nor with a lateral acceleration (speed ×
  //     yaw rate) above nhc_max_lateral_accel, where a car's tyres slip and its sideslip exceeds σ.
  bool obs_nhc = false, obs_zupt = false, zupt_zero_rate = true;
  double constraint_rate_hz = 10;
  double nhc_sigma = 0.1;    // m/s, lateral and vertical (a car's departure from the constraint)
  double zupt_sigma = 0.01;  // m/s per axis
  double nhc_min_speed = 1.0;
  double nhc_max_turn_rate = 15 * units::kDeg;  // rad/s
  double nhc_max_lateral_accel = 3.0;           // m/s²
  double standstill_window_s = 1.0, standstill_factor = 3.0, standstill_max_speed = 0.5;
  // Heading from the course over ground (docs/in-motion.md, "GNSS-only drives"). Without attitude
  // observations the heading is observable only through the vehicle's accelerations; after a
  // standstill, or without any reference attitude at the start, its error can lie far outside the
  // linear range. The course over ground then gives the reference body's heading (forward motion,
  // no sideslip beyond `align_sideslip`; MEMS heading through the current mounting estimate):
  //   * GNSS fixes without attitude at the start: level from the mean specific force over the
  //     first `align_level_s` (an opening standstill is assumed), heading unknown; epochs are used
  //     while standing, skipped while moving until the course gives the heading;
  //   * without attitude observations: at the start of motion (after a standstill, or the start of
  //     the data) when the heading σ exceeds `align_heading_sigma` and the course is at least twice
  //     as good, and when the gate has lost track (instead of only widening P) while moving;
  // each is a re-alignment: heading replaced, horizontal navigation covariance rotated with it,
  // heading row/column re-initialised (course σ ⊕ mounting), position reset to the fix, velocity
  // rotated (or the fix's). Never with attitude observations (the default filter is unchanged).
  bool realign_heading = true;
  double align_level_s = 10;                  // s of data for levelling (GNSS-only start)
  double align_min_speed = 3;                 // m/s: course from the fix velocity
  // Course from the fix positions: a chord long enough that the fixes' noise (√2·σ_h/L) is below the
  // sideslip σ, at least align_min_chord_m, at most align_min_baseline_m (fixes of 0.37 m and worse).
  double align_min_baseline_m = 30;
  double align_min_chord_m = 5;
  double align_window_s = 20;                 // s of fixes kept for the chord
  double align_max_turn = 10 * units::kDeg;   // largest heading change (INS) along the chord
  double align_sideslip = 1.0 * units::kDeg;  // 1σ of the body's course-heading difference
  double align_heading_sigma = 5 * units::kDeg;
  // Heading hypotheses (GNSS-only start, when motion has gone on for align_bank_wait_s without a
  // course over ground: slow or winding motion, a handheld unit): a Gaussian sum (Alspach &
  // Sorenson 1972) of align_hypotheses copies of the filter, headings evenly spaced round the
  // circle, each in its linear range; each takes the fixes, and the copy whose innovations are the
  // most likely (Σ −½(NIS + ln det S)) becomes the filter once it leads the next by
  // align_bank_select (a likelihood ratio of e^select), at the latest align_bank_max_s after the
  // start. Needs no forward motion and no mounting. 0 or 1 hypotheses: off (skip until a course).
  int align_hypotheses = 12;
  double align_bank_wait_s = 5;
  double align_bank_min_s = 10;
  double align_bank_max_s = 60;
  double align_bank_select = 20;
  // Course updates: while the heading σ exceeds course_update_sigma (the yaw-gyro drift not yet
  // learnt, typically the first minutes of a GNSS-only drive on raw data), the course over ground
  // is also a heading observation (forward motion, sideslip as above), at most every
  // course_update_s (a chord of fix positions is then mostly new fixes). 0 s: off.
  double course_update_s = 10;
  double course_update_sigma = 1.0 * units::kDeg;
  // GNSS-only start: at the first heading alignment, forget what the standstill with the
  // placeholder heading taught the sensor-error states (values and covariance back to the end of
  // levelling). With the heading unknown the filter's model of that standstill is wrong (the Earth
  // rate in the wrong axes, linearised 100°+ from the truth), so what it learnt is not information.
  bool restart_at_heading = true;
  // GNSS-only start: the gyro bias from the levelling standstill (the zero-rate observation of
  // obs_zupt.cpp with the heading unknown: the mean rate less the Earth rate's down component, its
  // horizontal part as noise), where the IMU was quiet over the window by the standstill rule
  // (standstill.hpp, standstill_factor). It is what a filter started from a known attitude gets
  // from its opening standstill; without it the yaw-gyro bias starts at its raw prior (0.5 °/s on
  // an ADIS16488A) and only position fixes in motion, through the heading, can tell it.
  bool level_gyro_bias = true;
  // Optional blocks (state_blocks.hpp): the mounting misalignment (off: the nominal mounting is
  // taken as exact), and blocks declared outside the filter's files, appended to the layout.
  bool mounting = true;
  std::vector<BlockSpec> extra_blocks;
  // The common rotation of both triads against the mounting and the MEMS attitude, which in-motion
  // data cannot tell (gauge.hpp): its conditional covariance carried along at every feedback, so
  // that the filter never learns it beyond its priors (on), or the plain EKF's covariance (off).
  bool hold_unobservable_rotation = true;
  // The antenna blocks (antenna_blocks.cpp; docs/in-motion.md, "Lever arm and time offset"): the
  // GNSS antenna's lever-arm correction (3 states, prior σ lever_arm_sigma per axis, m) and the
  // IMU–GNSS time offset (1 state, prior σ time_offset_sigma, s). Off: the nominal lever arm and
  // time stamps are taken as exact.
  bool estimate_lever_arm = false, estimate_time_offset = false;
  double lever_arm_sigma = 0.1, time_offset_sigma = 0.02;
  // Covariance arithmetic (docs/in-motion.md, "Covariance arithmetic"). structured (default): the
  // propagation touches only the rows that move (the navigation and drift-shaping states; the
  // constant parameters have identity transitions and no process noise, so their block of P stays
  // as it is) and sums each product in the dense path's order, the update is the dense path's:
  // the results are bit for bit those of dense. joseph: the same propagation, the Joseph-form update
  // (positive semi-definite for any gain; differs from dense at the rounding floor). dense: the
  // full N×N ΦPΦᵀ of every step, the former path, kept as the reference the others are proven against.
  enum class Covariance { structured, joseph, dense };
  Covariance covariance = Covariance::structured;
};

// How the filter got (and kept) its heading: for RESULT.json and the summary.
struct AlignmentReport {
  std::string mode = "reference";  // "reference": the first reference epoch's attitude; "gnss": levelled + course
  double level_t0 = 0, level_t1 = 0;
  Vec3 level_rpy = Vec3::Zero();   // MEMS roll, pitch (rad) from the levelling; yaw undefined
  double level_accel_std = 0;      // m/s², std of the specific-force norm over the levelling window
  double level_gyro_mean = 0;      // rad/s, |mean rate| over the window (turn-on bias + Earth rate at rest)
  bool level_quiet = false;        // the window was a standstill by the standstill rule
  bool level_gyro_bias = false;    // the gyro bias was observed on it (InMotionConfig::level_gyro_bias)
  double heading_t = -1;           // first heading from the course (−1: none)
  int heading_hypotheses = 0;      // > 0: the first heading chosen among this many hypotheses (not the course)
  double heading_lead = 0;         // the chosen hypothesis's log-likelihood lead over the next
  long skipped_unaligned = 0;      // epochs skipped while moving before the heading was known
  long course_updates = 0, course_rejected = 0;  // course over ground used as a heading observation
};

struct Recovery {
  double t = 0;
  std::string reason, action;
};

// The observation types of consistency(): the reference's (eqs 13–15) and the vehicle constraints.
enum ObsType { kObsPosition = 0, kObsVelocity = 1, kObsAttitude = 2, kObsNhc = 3, kObsZupt = 4, kObsZeroRate = 5, kObsTypes = 6 };

// A standstill found by the detector (InMotionConfig, vehicle constraints), s.
struct Standstill {
  double t0 = 0, t1 = 0;
};

struct ConsistencyStats {
  long used = 0, rejected = 0, within95 = 0, forced = 0;
  double rejected_since = -1;  // time of the first rejection of the current streak, s (−1: none)
  double nis_sum = 0;
  double mean_nis() const { return used ? nis_sum / static_cast<double>(used) : 0.0; }
};

// The innovation of one observation type at the last reference epoch the filter took: ν = z − H·δx
// (before this type's update), its covariance S = H·P·Hᵀ + R, NIS = νᵀS⁻¹ν (before any widening),
// and what became of it. For innovation diagnostics (docs/diagnosis.md, Drives); read-only.
struct InnovationRecord {
  enum Status { used = 0, rejected = 1, forced = 2 };
  double t = -1;  // reference epoch time, s (−1: none yet)
  Vec3 nu = Vec3::Zero();
  Mat3 S = Mat3::Zero();
  double nis = 0;
  Status status = used;
  // The motion at the epoch (for locating where innovations grow; issue 53 item 5): horizontal speed
  // (m/s) now; turn rate about the vertical (rad/s) and horizontal acceleration magnitude (m/s²), each
  // the mean over the interval since the previous reference epoch.
  double speed = 0, turn_rate = 0, accel = 0;
};

// True when some axis carries an exponential-cosine model: the layout then has the aux blocks.
bool needs_augmented_layout(const InMotionConfig& cfg);

// In-run drift models of the six axes (0–2 gyro, 3–5 accel): first-order rate α and σ, or the
// exponential-cosine shaping filter (with its discretisation cached per step length).
struct DriftModels {
  Vec3 alpha_g = Vec3::Zero(), alpha_a = Vec3::Zero(), sig_g = Vec3::Zero(), sig_a = Vec3::Zero();
  bool expcos[6] = {false, false, false, false, false, false};
  identification::ShapingFilter sf[6];
  const identification::DiscreteShapingFilter& discrete(int k, double T) const;

 private:
  mutable identification::DiscreteShapingFilter disc_[6];
};

// The drift models of a configuration (its gyro_drift/accel_drift, else the noise's first-order ones).
DriftModels drift_models(const InMotionConfig& cfg);

// The nominal state the error state is relative to: the MEMS INS, the sensor model, the mounting,
// the drift shaping states, and the values of blocks declared outside (at their layout offsets).
struct Nominal {
  // The navigation blocks' nominal values: the MEMS INS state (position, velocity, attitude).
  ins::NavState* nav = nullptr;
  // The mounting block's: a rotation (3 error states, 9 values), C_mb.
  Mat3 C_mb = Mat3::Identity();
  // Every other block's nominal value (sensor bias, drift, M row by row, exp-cosine first states,
  // antenna, extra blocks), laid out like the error state: the block's slice at its offset (the
  // filter sizes it by its layout, zero at the start). Blocks read their slice through the typed
  // views and write it by feedback (nominal ← nominal − dx, additive_feedback).
  Eigen::VectorXd x;
  Vec3 vec3(int off) const { return x.segment<3>(off); }
  Mat3 mat3(int off) const { return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(x.data() + off); }
};

// The feedback of an additive block of `size` states whose nominal value is its slice of
// Nominal::x: nominal ← nominal − dx (BlockSpec::feedback).
template <int size>
void additive_feedback(Nominal& n, int off, const VecCRef& dx) {
  n.x.segment<size>(off) -= dx.segment<size>(off);
}
// The series value (BlockSpec::total) of such a block: its slice.
template <int size>
void slice_total(const Nominal& n, int off, double* x) {
  for (int i = 0; i < size; ++i) x[i] = n.x(off + i);
}

// The nominal values between updates over T seconds: each block of layout s that moves its own
// (BlockSpec::predict: the drifts' and exp-cosine first states' x̂ ← Φ·x̂).
void propagate_drift(const DriftModels& drift, const StateLayout& s, Nominal& n, double T);

struct BlockInit {
  const InMotionConfig& cfg;
  const RefObs& first;
  const DriftModels& drift;
  Mat3 C_nb;              // reference body attitude at the first epoch
  double sp, sv, sa;      // the first epoch's position, velocity, attitude σ
};

struct BlockDynamics {
  const InMotionConfig& cfg;
  const FAccumulator& acc;
  const NavBlockInputs& nav;
  double T;
  const DriftModels& drift;
  double q_nav = 1;  // adaptive scale of the navigation states' white-noise variances (1: the model's)
};

struct BlockObsInput {
  const ObsContext& c;
  const RefObs& r;
};

// The in-motion filter. Its layout (state_blocks.hpp) follows the configuration: the paper's 42
// states, 48 with exp-cosine drift models, fewer without the mounting block, more with blocks
// declared in InMotionConfig::extra_blocks.
class InMotionFilter {
 public:
  using Vec = Eigen::VectorXd;
  using Mat = Eigen::MatrixXd;
  using Vec6 = Eigen::Matrix<double, 6, 1>;

  // Starts at the first reference epoch, transferring its state to the MEMS IMU through the
  // nominal mounting (rotation C_mb, MEMS → reference body) and lever arm.
  InMotionFilter(const InMotionConfig& cfg, const Mat3& C_mb_nominal, const Vec3& lever, const RefObs& first);

  // One IMU interval ending at t: increments of the data as given (Δθ rad, Δv m/s).
  void imu(double t, const Vec3& dtheta, const Vec3& dv, double dt);
  // One reference epoch (t not after the last IMU time). Returns true if it was used.
  bool reference(const RefObs& r);

  double time() const { return nav_.state().t; }
  const ins::NavState& nav() const { return nav_.state(); }
  const Mat& P() const { return P_; }
  const StateLayout& layout() const { return layout_; }
  int offset(Block b) const { return layout_.offset(b); }  // −1: not in this layout
  // The nominal value of the extra blocks' states (at their layout offsets).
  const Eigen::VectorXd& extra_values() const { return n_.x; }
  // Current estimates of the sensor model of the data the filter saw (constant part) with σ.
  SensorErrors estimate() const;
  // 1σ of the total gyro drift b + d (constant plus in-run part) now, rad/s; the two parts are
  // separable only over many correlation times, their sum is what navigation needs.
  Vec3 gyro_total_drift_sigma() const;
  Vec3 gyro_drift() const { return n_.vec3(off(Block::dg)); }
  Vec3 accel_drift() const { return n_.vec3(off(Block::da)); }
  const Mat3& mounting() const { return n_.C_mb; }
  // Mounting as roll, pitch, yaw (rad) and their 1σ (through the Jacobian of the angles).
  void mounting_rpy(Vec3& rpy, Vec3& sigma) const;
  // 0 pos, 1 vel, 2 att, 3 nhc, 4 zupt, 5 zero rate (ObsType)
  const ConsistencyStats& consistency(int type) const { return type < 3 ? stats_[type] : cstats_[type - 3]; }
  // Standstills found (vehicle constraints on), in time order; the last may be open (t1 = now).
  std::vector<Standstill> standstills() const;
  const InnovationRecord& last_innovation(int type) const { return innov_[type]; }
  const AlignmentReport& alignment() const { return align_; }
  // The conditional σ (rad) of the triads' common rotation ε in the current covariance (gauge.hpp);
  // zeros when the layout lacks the blocks it moves.
  Vec3 unobservable_rotation_sigma() const;
  // The same in the initial covariance (the priors').
  Vec3 unobservable_rotation_sigma_prior() const { return rot_sigma_prior_; }
  // The adaptive process noise: its scale now, the largest it reached, how often it was raised.
  const AdaptiveNoise& adaptive_noise() const { return adapt_; }
  // Re-alignments and forced recoveries, in time order.
  const std::vector<Recovery>& recoveries() const { return recoveries_; }
  // True while the filter has no heading yet (GNSS-only start before the first course).
  bool heading_known() const { return phase_ == Phase::aligned; }
  // Series column names of the layout's states (block declarations), in state order.
  std::vector<std::string> column_names() const;
  // Every state's nominal value (estimate, not error) and 1σ, SI, in layout order (position as
  // latitude/longitude in rad and height; attitude and mounting as Euler angles, the mounting σ
  // through the angles' Jacobian). Series units only at the output: series_display().
  void state_si(Vec& x, Vec& sigma) const;
  // Total drift per axis, constant part + in-run shaping-filter state (b + d: gyro rad/s, accel
  // m/s²; what `calbench identify` identifies), and its 1σ (with the b–d correlation).
  void total_drift_si(Vec6& x, Vec6& sigma) const;

  // Rauch–Tung–Striebel pass over the stored epochs (store_for_smoother); replaces the
  // constant-parameter estimates with the smoothed values at the first epoch and returns the
  // smoothed series (time, states as state_si with the sensor states smoothed, σ, total drift σ).
  struct SmoothedEpoch {
    double t;
    Vec x, sigma;        // SI
    Vec6 total_sigma;    // SI, as total_drift_si()
  };
  std::vector<SmoothedEpoch> smooth();

 private:
  void propagate();
  // The measurement update of one observation (rows of H, its R): dx += K·ν and P by the
  // configured covariance form; K = P·Hᵀ·S⁻¹ from the caller's PHt and factorised S.
  template <int M>
  void update(Vec& dx, const Eigen::Matrix<double, M, Eigen::Dynamic>& H, const Eigen::Matrix<double, M, M>& R,
              const Eigen::Matrix<double, Eigen::Dynamic, M>& PHt, const Eigen::Matrix<double, Eigen::Dynamic, M>& K,
              const Eigen::Matrix<double, M, 1>& nu);
  // P·Hᵀ: the dense product, or over the columns H touches (the same sums).
  template <int M>
  Eigen::Matrix<double, Eigen::Dynamic, M> pht(const Eigen::Matrix<double, M, Eigen::Dynamic>& H);
  void feedback(const Vec& dx);
  // After the nominal moved (feedback, levelling, the restart at the heading): the unobservable
  // rotation's conditional covariance moved from direction N_before to the current one; nothing when
  // N_before is empty or the direction did not move.
  void carry_rotation(const Mat& N_before);
  // The observation context at the current nominal state (reference epochs, vehicle constraints).
  ObsContext obs_context() const;
  // Vehicle constraints (vehicle_constraints.cpp): every IMU sample, the fix speed of every
  // reference epoch, and the updates after a propagation step.
  void constraint_sample(double t, const Vec3& dth_raw, const Vec3& dv_raw, double dt);
  void constraint_note_fix(const RefObs& r);
  void constrain();
  template <int M>
  bool constraint_update(Vec& dx, const ObservationM<M>& o, ConsistencyStats& st);
  void propagate_drift_nominal(double T);
  // The sensor correction from the blocks' nominal values, after each change of them.
  void refresh_correctors();
  int off(Block b) const { return layout_.offset(b); }
  // P's navigation rows, then its navigation columns (BlockSpec::navigation), times d.
  void scale_navigation(Mat& P, double d) const;
  // Heading from the course over ground (see InMotionConfig::realign_heading).
  struct Fix {
    double t, lat, lon, h, yaw_ins;  // yaw_ins: INS body yaw at the fix (its changes are what count)
    Vec3 v;
    bool has_vel;
    double sigma_h, sigma_vel;
  };
  bool course(double& cog, double& sigma, std::string& how) const;
  // Heading hypotheses (InMotionConfig::align_hypotheses).
  void start_bank(const RefObs& r);
  void rebind();  // after a copy or move: the pointers into this filter (nominal nav state, layout)
  bool bank_reference(const RefObs& r);
  bool moving() const;
  void realign(const RefObs& r, double cog, double sigma, const std::string& reason, const std::string& how);
  void finish_levelling(const RefObs& r);
  // The blocks' part of a MEMS position just set from a fix (BlockSpec::position_offset): returns
  // the NED offset to add; the position rows of P, uncorrelated with everything before the call,
  // become those of fix error + Σ A·δx.
  Vec3 position_offset_blocks(const Mat3& C_nb, const Vec3& v);

  InMotionConfig cfg_;
  StateLayout layout_;
  int N_ = 0;
  ins::Strapdown nav_;
  Vec3 lever_;
  Nominal n_;
  SensorCorrection corr_;  // the blocks' correction of the raw increments (refresh_correctors)
  DriftModels drift_;
  Mat P_;
  // Structured covariance: the rows of the last step that moved, and work matrices kept between
  // steps (no allocation per step).
  std::vector<int> moving_, work_k_;
  std::vector<double> work_a_;
  Mat F_, Q_, work_G_;
  bool p_symmetric_ = false;  // P_ known to equal its transpose bit for bit (set where that is so)
  FAccumulator acc_;
  Vec3 w_last_ = Vec3::Zero();
  Vec3 a_last_ = Vec3::Zero();  // NED acceleration of the MEMS over the last IMU interval
  // Motion since the last reference epoch, for InnovationRecord/AdaptiveSample (reporting only).
  double motion_yaw_ = 0, motion_T_ = 0;
  Vec3 motion_v0_ = Vec3::Zero();
  bool motion_have_v0_ = false;
  VelocityHistory vel_hist_;    // the INS's velocity changes, for a lagging GNSS velocity
  double last_obs_t_ = -1e300;
  ConsistencyStats stats_[3];
  // Vehicle constraints: stats of nhc, zupt, zero rate; the standstill detector and what it found;
  // the raw gyro increments since the last constraint step; the last fix's horizontal speed.
  ConsistencyStats cstats_[3];
  StandstillDetector still_;
  bool standing_ = false;
  std::vector<Standstill> standstills_;
  double last_still_eval_t_ = -1e300, last_constraint_t_ = -1e300;
  Vec3 c_dth_raw_ = Vec3::Zero();
  double c_T_ = 0;
  double fix_speed_ = 0, fix_speed_t_ = -1e300;
  InnovationRecord innov_[3];
  enum class Phase { levelling, heading_unknown, aligned };
  Phase phase_ = Phase::aligned;
  struct Snapshot {
    Mat P;
    Nominal n;  // nav unused
    ins::Quat q_nb = ins::Quat::Identity();  // the MEMS attitude then (the direction of the unobservable rotation)
  };
  Snapshot lvl_snap_;  // at the end of levelling (restart_at_heading)
  Vec3 rot_sigma_prior_ = Vec3::Zero();  // unobservable_rotation_sigma_prior()
  Vec3 lvl_dth_ = Vec3::Zero(), lvl_dv_ = Vec3::Zero();
  double lvl_T_ = 0, lvl_f2_ = 0;  // levelling sums: time, Σ|f|²·dt
  StandstillDetector lvl_still_;   // the levelling window's samples, for the standstill rule
  std::deque<Fix> fixes_;
  double moving_since_ = -1;  // start of the current motion without a heading (−1: standing)
  // The bank of heading hypotheses while it runs; a copy of the filter starts with an empty one.
  struct Bank {
    std::vector<std::unique_ptr<InMotionFilter>> f;
    double t0 = 0;
    Bank() = default;
    Bank(const Bank&) {}
    Bank& operator=(const Bank&) { return *this; }
    Bank(Bank&&) = default;
    Bank& operator=(Bank&&) = default;
  } bank_;
  bool in_bank_ = false;  // this filter is one hypothesis of a bank
  double loglik_ = 0;     // its innovations' log-likelihood since the bank started
  // This epoch's log-likelihood terms of the innovations this hypothesis rejected, per observation
  // type (NaN: not rejected): a fix every hypothesis rejects is an outlier, not evidence between them.
  double bank_rejected_[3] = {0, 0, 0};
  double last_realign_t_ = -1e300;
  bool motion_check_ = true;  // the heading σ is checked at the next start of motion
  double last_course_t_ = -1e300;
  AlignmentReport align_;
  std::vector<Recovery> recoveries_;
  AdaptiveNoise adapt_;

  // Smoother storage (float to halve memory): per propagation step k → k+1.
  struct Stored {
    double t;
    Eigen::MatrixXf P_post, Phi, P_prior_next;
    Eigen::VectorXf dx_next;  // update applied at the next epoch
    Eigen::VectorXd x_post;   // totals after the update at this epoch
  };
  std::vector<Stored> store_;
  Vec pending_dx_;
};

// The former layout-templated names, kept for callers written against them: one class now.
using InMotionFilterAug = InMotionFilter;

}  // namespace calbench::inmotion
