// Observations of the in-motion filter against the reference inertial-satellite system
// (paper eqs 13–15), one file per equation: obs_position.cpp (13), obs_velocity.cpp (14),
// obs_attitude.cpp (15); and the vehicle constraints, taken from the IMU stream (no reference
// epoch needed): obs_nhc.cpp (non-holonomic: no lateral or vertical velocity of the vehicle) and
// obs_zupt.cpp (zero velocity, zero angular rate w.r.t. the Earth at a standstill). Each forms the reference quantity predicted from the MEMS INS through
// the mounting (C_mb, MEMS → reference body) and the lever arm r (MEMS origin in reference body
// axes), subtracts the reference's reading, and gives the Jacobian H w.r.t. the error state:
//   z = predicted − reference = H·δx + noise.
#pragma once
#include "calibration/inmotion/error_model.hpp"
#include "calibration/inmotion/state_layout.hpp"
#include "calibration/ins/strapdown.hpp"

namespace calbench::inmotion {

// One reference epoch (reference body origin), SI: lat/lon rad, attitude rad.
struct RefObs {
  double t = 0;
  double lat = 0, lon = 0, h = 0;
  Vec3 v_ned = Vec3::Zero();
  Vec3 rpy = Vec3::Zero();
  double sigma_pos = 0, sigma_vel = 0, sigma_att = 0;  // 1σ used for R
  // A GNSS fix (gnss.csv) carries no attitude, a velocity only where the file has one with a
  // finite σ, and a vertical position σ of its own (0: sigma_pos for all three axes).
  bool has_att = true, has_vel = true;
  double sigma_pos_v = 0;
};

// A GNSS fix of the antenna (taken as the reference body origin) as an observation: position with
// horizontal and vertical σ, velocity only where given and its σ is not 1e3 m/s or more (an
// importer's 1e6 means unknown), no attitude. σ ≤ 0 or NaN: the filter's defaults.
RefObs gnss_fix_obs(double t, double lat, double lon, double h, const Vec3* v_ned, double sigma_h, double sigma_v,
                    double sigma_vel);

struct ObsContext {
  const ins::NavState* mems = nullptr;  // nominal MEMS INS state at the epoch
  Mat3 C_mb = Mat3::Identity();         // current mounting estimate
  Vec3 lever = Vec3::Zero();
  Vec3 w_eb_b = Vec3::Zero();           // body rate w.r.t. Earth, reference body axes (set_body_rate)
  // ∂ω̂_eb^b/∂δx (3 × the layout's size): how the estimated body rate moves with the
  // attitude, the mounting and the gyro's sensor model (set_body_rate).
  Eigen::Matrix<double, 3, Eigen::Dynamic> w_eb_jac;
  Vec3 a_ned = Vec3::Zero();            // acceleration (NED) over the last IMU interval (the time-offset block)
  // The filter's layout (set_layout): its size and where the blocks the observations read are
  // (−1: not in the layout): the navigation blocks, the mounting (−1: not estimated), and the gyro
  // blocks (the zero-rate observation reads the gyro's sensor model): bias, in-run drift, M.
  int n_states = 0;
  int pos = -1, vel = -1, att = -1, mount = -1;
  int gyro_bias = -1, gyro_drift = -1, gyro_M = -1;
  void set_layout(const StateLayout& s) {
    n_states = s.size();
    pos = s.offset(Block::pos);
    vel = s.offset(Block::vel);
    att = s.offset(Block::att);
    mount = s.offset(Block::mount);
    gyro_bias = s.offset(Block::bg);
    gyro_drift = s.offset(Block::dg);
    gyro_M = s.offset(Block::Mg);
  }
};

template <int M>
struct ObservationM {
  Eigen::Matrix<double, M, 1> z = Eigen::Matrix<double, M, 1>::Zero();
  Eigen::Matrix<double, M, Eigen::Dynamic> H;  // M × the layout's size
  Eigen::Matrix<double, M, M> R = Eigen::Matrix<double, M, M>::Identity();
};
using Observation = ObservationM<3>;

Observation position_observation(const ObsContext& c, const RefObs& r);  // eq 13
Observation velocity_observation(const ObsContext& c, const RefObs& r);  // eq 14
Observation attitude_observation(const ObsContext& c, const RefObs& r);  // eq 15

// Non-holonomic constraint (obs_nhc.cpp): the vehicle (= reference body) moves along its x axis;
// z = (lateral, vertical) velocity of the reference body origin in its own axes, σ per axis.
ObservationM<2> nhc_observation(const ObsContext& c, double sigma);
// Zero-velocity update (obs_zupt.cpp): at a standstill z = the MEMS velocity (NED), σ per axis.
Observation zupt_observation(const ObsContext& c, double sigma);
// Zero angular rate w.r.t. the Earth at a standstill (obs_zupt.cpp), an observation of the gyro's
// sensor model: z = Â_g·(ȳ − b̂_g − d̂_g) − Ĉ_mn·ω_ie^n, ȳ the mean raw gyro rate of the data
// over the interval, σ per axis (the white noise of that mean). heading_known false: the heading is a
// placeholder (GNSS-only levelling): the Earth rate's horizontal part is noise, no attitude columns.
Observation zero_rate_observation(const ObsContext& c, const Nominal& n, const Vec3& y_mean, double sigma,
                                  bool heading_known = true);

// The MEMS INS state at a reference epoch, transferred through the mounting C_mb and the lever
// arm (initial alignment from the reference system, paper section III). Used to start the
// in-motion filter and every inertial-only QC run.
ins::NavState mems_state_from_reference(const RefObs& r, const Mat3& C_mb, const Vec3& lever);

// Reference body attitude predicted from the MEMS INS: C_nb = C_nm·C_mbᵀ.
inline Mat3 predicted_body_attitude(const ObsContext& c) { return c.mems->C_nb() * c.C_mb.transpose(); }

// The reference body's rate w.r.t. the Earth, reference body axes, from the corrected MEMS rate ω_m
// (MEMS axes, corrected by `corr`, the filter's sensor model): ω_eb^b = C_mb·(ω_m − C_mn·ω_ie^n), and its
// Jacobian w.r.t. the error state. With Ĉ_mb = (I − δμ×)·C_mb, Ĉ_mn = C_mn·(I + φ×) and the gyro
// blocks' part of ω̂_m (their own transition columns, BlockSpec::accumulate: F_φx = −C_nm·∂ω̂_m/∂x):
//   δω_eb^b = C_bn·(ω_ie^n×)·φ + (ω_eb^b×)·δμ + C_mb·∂ω̂_m/∂x·δx_gyro.
// The lever-arm velocity r × ω_eb^b of eq 14 and the NHC moves with all three: the mounting's and
// the gyro M's parts are as large as the mounting's term through Ĉ_nb (|ω|·|r|·|δμ|), and a
// common rotation of both triads is a mounting rotation only when both are there (issue 34).
void set_body_rate(ObsContext& c, const StateLayout& L, const SensorCorrection& corr, const Vec3& w_m);

// ∂(r × ω̂_eb^b)/∂δx = (r×)·ObsContext::w_eb_jac (3 × the layout's size). A context built without
// set_body_rate is a programming error (std::logic_error), not a zero: its terms would be lost silently.
Eigen::Matrix<double, 3, Eigen::Dynamic> lever_rate_jacobian(const ObsContext& c, const Vec3& lever);

}  // namespace calbench::inmotion
