// Quality control of a calibration by inertial-only navigation (paper section V): start the
// MEMS INS from the reference state at T0 (transferred through mounting and lever arm), correct
// the MEMS output with a coefficient set, navigate without any aiding and compare with the
// reference. The circular position error (eq 39)
//   ΔS = √(δφ² + δλ²),  δφ = (φ_INS − φ_ref)·R_M,  δλ = (λ_INS − λ_ref)·R_N·cos φ_ref
// uses the WGS-84 radii of curvature at the reference position (the paper's R).
#pragma once
#include "calibration/inmotion/observation.hpp"
#include "calibration/ins/strapdown.hpp"
#include "common/sensor_model.hpp"

namespace calbench::qc {

class InertialRun {
 public:
  // errors: the coefficient set (measured = (I+M)·true + b); C_mb: MEMS → reference body.
  InertialRun(const SensorErrors& errors, const Mat3& C_mb, const Vec3& lever, const inmotion::RefObs& start);
  // From a MEMS navigation state (an aided filter's at the start of a simulated GNSS outage,
  // outage_plan.hpp); ΔS is then measured against fixes of the antenna (the reference body origin).
  InertialRun(const SensorErrors& errors, const Mat3& C_mb, const Vec3& lever, const ins::NavState& start);
  // One IMU interval ending at t with raw increments.
  void imu(double t, const Vec3& dtheta, const Vec3& dv, double dt);
  // ΔS (m) against a reference epoch at (about) the current time.
  double cpe(const inmotion::RefObs& r) const;
  double time() const { return nav_.state().t; }
  const ins::NavState& nav() const { return nav_.state(); }

 private:
  TriadCorrector g_, a_;
  Mat3 C_mb_;
  Vec3 lever_;
  ins::Strapdown nav_;
};

}  // namespace calbench::qc
