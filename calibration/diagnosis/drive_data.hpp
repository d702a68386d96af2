// Data of a drive recording as `diagnose` needs it (docs/diagnosis.md, "Drives"): the MEMS output
// predicted from the reference trajectory, next to what the MEMS measured, per reference
// interval (a "sub-block"), grouped into ~1 s parent blocks.
//
// Per reference interval [t_k, t_k+1] (T = t_k+1 − t_k):
//   predicted rotation of the reference body w.r.t. inertial space
//     φ_b = log(C_nb(k)ᵀ · Rot(ζ) · C_nb(k+1)),  ζ = (ω_ie + ω_en)·T at the midpoint
//   (the strapdown relation q_nb(k+1) = q(−ζ) ⊗ q_nb(k) ⊗ q(φ) solved for φ), ω_b = φ_b/T;
//   predicted specific force  f_b = C_midᵀ [(v(k+1) − v(k))/T − g + (2ω_ie + ω_en)×v_mid],
//   C_mid = C_nb(k)·Rot(φ_b/2); at the MEMS (nominal mounting C_mb, lever arm r, body axes):
//     ω_m = C_mbᵀ ω_b,  f_m = C_mbᵀ (f_b + ω̇_b×r + ω_b×(ω_b×r)), ω̇_b by central differences.
//   measured: the MEMS increments over the same interval (split at the epoch times), composed
//   exactly (quaternion product, so no coning error) φ_m, Δv rotated into the mid-interval frame;
//   gyro = φ_m/T, accel = Δv_mid/T.
// SubBlock (calibration/diagnosis/diag_data.hpp) carries these: gyro/accel = measured means,
// w/f = predicted, dw/df = time derivatives of the *measured* means (central differences over
// neighbouring intervals: much less noisy than differentiating the reference twice; the time
// offset and tangential lever-arm regressors use them), step = held-out window index.
#pragma once
#include <limits>
#include <vector>

#include "calibration/diagnosis/diag_data.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

// One MEMS sample: increments over (t − dt, t] in MEMS axes.
struct DriveImuSample {
  double t = 0, dt = 0;
  Vec3 dtheta = Vec3::Zero(), dv = Vec3::Zero();
  double temp_c = std::numeric_limits<double>::quiet_NaN();
  // The rates as recorded, when the file holds rates (the increments are then integrated from
  // them): the white-noise estimate uses these.
  bool has_rates = false;
  Vec3 w_raw = Vec3::Zero(), f_raw = Vec3::Zero();
};

// One reference epoch: position (rad, rad, m), NED velocity (m/s), attitude roll/pitch/yaw (rad).
struct DriveRefEpoch {
  double t = 0;
  double lat = 0, lon = 0, h = 0;
  Vec3 v_ned = Vec3::Zero(), rpy = Vec3::Zero();
};

// Motion class of a parent block, for "where" (per-segment) statistics.
enum class MotionClass { stationary = 0, straight = 1, turning = 2, accelerating = 3 };
const char* motion_class_name(MotionClass c);

struct DriveParentInfo {
  double speed = 0;        // m/s, mean
  double turn_rate = 0;    // rad/s, rotation about the local vertical (yaw rate), signed
  double along_accel = 0;  // m/s², rate of change of speed
  double ang_accel = 0;    // rad/s², |ω̇| of the MEMS (predicted)
  MotionClass motion = MotionClass::straight;
};

struct DriveDiagData {
  std::vector<SubBlock> subs;         // one per reference interval (see above)
  std::vector<ParentBlock> parents;   // ~1 s
  std::vector<DriveParentInfo> info;  // per parent
  std::vector<double> sub_speed;      // per sub-block, m/s
  double imu_rate_hz = 0;
  double mean_sub_s = 0;
  // White noise of one IMU sample (from successive differences of the rates), per axis
  // gyro x..z, accel x..z; a floor for the noise model.
  double sample_white_var[6] = {0, 0, 0, 0, 0, 0};
  bool has_temperature = false;
  long skipped_intervals = 0;  // reference intervals without complete IMU coverage
  // The prediction in reference body axes (ω_b; f_b with the lever-arm terms), per sub-block, and
  // the MEMS → body rotation C_mb it was moved to the MEMS with (SubBlock::w = C_mbᵀ ω_b, …).
  std::vector<Vec3> sub_w_body, sub_f_body;
  Mat3 C_mb = Mat3::Identity();
};

// The same data with the prediction moved to the MEMS through another mounting C_mb (sub-block
// and parent w, f); the measured side is untouched.
void remount(DriveDiagData& d, const Mat3& C_mb);

class DriveDiagBuilder {
 public:
  // C_mb: MEMS → reference body rotation; lever: MEMS origin in reference body axes (m).
  DriveDiagBuilder(const Mat3& C_mb, const Vec3& lever, double parent_s = 1.0, double window_s = 20.0);
  // Feed in time order: a reference epoch after the IMU sample that reaches its time.
  void imu(const DriveImuSample& s);
  void reference(const DriveRefEpoch& r);
  DriveDiagData finish();

 private:
  struct Raw {
    double t0 = 0, t1 = 0;
    int n = 0;
    Vec3 gyro, accel, w_b, f_b;
    double speed = 0, temp = 0;
    int temp_n = 0;
    double turn = 0, along = 0;
  };
  void add_part(const Vec3& dth, const Vec3& dv, double frac_dt, const DriveImuSample& s, double frac);
  void close_interval(const DriveRefEpoch& r);

  Mat3 C_mb_;
  Vec3 lever_;
  double parent_s_, window_s_;
  bool have_ref_ = false, have_pending_ = false;
  DriveRefEpoch last_ref_;
  DriveImuSample pending_;
  // Accumulator of the open interval.
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  Vec3 dv_acc_ = Vec3::Zero();
  double covered_ = 0, temp_sum_ = 0;
  int n_ = 0, temp_n_ = 0;
  std::vector<Raw> raw_;
  // White-noise estimate.
  bool have_prev_rate_ = false;
  Vec3 prev_w_, prev_f_;
  double dsum_[6] = {0, 0, 0, 0, 0, 0};
  long dn_ = 0;
  double dt_sum_ = 0;
  long dt_n_ = 0;
  long skipped_ = 0;
};

}  // namespace calbench
