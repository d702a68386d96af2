// Estimator side of the physics catalogue (docs/diagnosis.md): the inverse of the sensor-side
// terms of effect_terms.hpp, applied to a stream of raw IMU samples before the strapdown INS, and
// the time-stamp correction of a time offset. Pure mathematics: no I/O.
//
// The simulators make  y = (I+M)·x + b + d(x)  (d = sensor_side_terms at the true input x) and
// stamp a sample t when it saw the motion at t − τ. The compensation returns the raw output
// without d, y' = y − d(x̂), with x̂ solved from y by two fixed-point steps
//   x̂₀ = (I+M)⁻¹(y − b),  x̂ₖ₊₁ = (I+M)⁻¹(y − b − d(x̂ₖ)),
// so that the usual correction (I+M)⁻¹(y' − b) afterwards gives x; and the corrected stamp t − τ.
// Terms used on a stream (drive): temperature_bias/_scale (only on samples with a temperature),
// g_sensitivity, scale_nonlinearity, scale_asymmetry, scale_factor, lever_arm (size effect: ω×(ω×r) + ω̇×r
// with ω̇ from successive samples — integrated over a sample it is (ω_k − ω_k−1)×r, which
// telescopes, so sample noise in ω̇ does not accumulate in velocity), time_offset.
// Not applicable to a stream: temperature_rate (needs dT/dt), the table terms (misalignment,
// table_wobble: bench geometry); correlated_drift is a noise-model term (the estimator's drift
// prior), not an output correction.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "calibration/effects/effect_terms.hpp"

namespace calbench {

// Which catalogue terms of a set a drive estimator applies, and why the others are not.
struct EffectUse {
  std::vector<std::string> applied;                              // catalogue keys
  std::vector<std::pair<std::string, std::string>> ignored;      // key, reason
};
// has_temperature: the recording's IMU samples carry a temperature.
EffectUse drive_effect_use(const EffectTerms& e, bool has_temperature);

class ImuEffectCompensator {
 public:
  ImuEffectCompensator() = default;
  // e: the catalogue terms; set: the coefficient set (b, M) the data are corrected with afterwards
  // (the true input the terms depend on is solved through it).
  ImuEffectCompensator(const EffectTerms& e, const SensorErrors& set);

  // True when some output term is non-zero (time offset aside).
  bool active() const { return active_; }
  double time_offset_s() const;
  // Corrected time stamp of a sample stamped t.
  double corrected_time(double t) const;

  // One raw rate sample (rad/s, m/s²) ending a sample interval dt; temp_c NaN when unknown.
  // Returns y − d(x̂) in place. Samples must come in time order (ω̇ from the previous one).
  void rates(Vec3& w, Vec3& f, double dt, double temp_c);
  // One raw increment sample over dt (rad, m/s): the mean rates over the interval are compensated.
  void increments(Vec3& dtheta, Vec3& dv, double dt, double temp_c);

  // The output terms d(x) at a true input (rate, specific force, ω̇, temperature): what is removed.
  void output_terms(const Vec3& w, const Vec3& f, const Vec3& dw, double temp_c, Vec3& dg, Vec3& da) const;
  long samples_with_temperature() const { return n_temp_; }

 private:
  EffectTerms e_;
  TriadCorrector cg_, ca_;
  bool active_ = false;
  bool have_prev_ = false;
  Vec3 w_prev_ = Vec3::Zero();
  long n_temp_ = 0;
};

}  // namespace calbench
