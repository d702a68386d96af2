// Prior 1σ of the constant parameters of the in-motion filter — the sensor blocks of the state
// (bias, scale and skew of both triads, state_layout.hpp) and the mounting — and where they come
// from (issue 16):
//   * raw data (no coefficient set): the data-sheet class of the device, datasheet_priors();
//   * data corrected by a coefficient set: per parameter, the set's σ combined with the stability
//     allowance of the device class — how far that parameter can move between the calibration that
//     produced the set and the drive (turn-on repeatability, ageing, mounting stress, temperature):
//       σ_prior = hypot(σ_set, allowance).
//     The filter then estimates the correction to the set; its posterior σ is the σ of the fused
//     (combined) set, and can never exceed σ_prior (a Kalman update only removes variance from
//     constant states). A parameter the drive does not inform keeps the set's value with σ_prior.
// The device classes and the source of each figure: bench/imu_classes/*.toml, docs/in-motion.md
// ("Priors", "Device classes").
#pragma once
#include <string>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench::inmotion {

struct ParameterPriors {
  Vec3 gyro_bias = Vec3::Zero();   // rad/s
  Vec3 accel_bias = Vec3::Zero();  // m/s²
  Mat3 gyro_M = Mat3::Zero();      // dimensionless (scale on the diagonal, skews off it)
  Mat3 accel_M = Mat3::Zero();
  Vec3 mount = Vec3::Zero();       // rad, per axis of the mounting misalignment δμ
};

// The σ of a coefficient set in this layout (bias and M of both triads) with the mounting's σ.
ParameterPriors sigma_of(const SensorErrors& e, const Vec3& mount_sigma = Vec3::Zero());

// Data-sheet class of a raw ADIS16488A (no calibration applied): initial bias 0.5 °/s and 30 mg
// (2.5× and 1.9× the data sheet's ±0.2 °/s and ±16 mg initial bias error), scale 1 %, skew 0.2 %,
// mounting 1° per axis (the installation tolerance of a vehicle bracket). The library's default
// (InMotionConfig); `fit drive` takes the priors of the recording's device class instead
// (bench/imu_classes/*.toml [priors]; adis16488a.toml holds these figures, pinned by a test).
ParameterPriors datasheet_priors();

// How far each constant parameter can move between a calibration and a drive, 1σ. One per device
// class (bench/imu_classes/*.toml [allowance], read into calibration/imu_class.hpp).
struct StabilityAllowance {
  std::string device_class;
  double gyro_bias = 0;    // rad/s
  double accel_bias = 0;   // m/s²
  double gyro_scale = 0;   // dimensionless
  double gyro_skew = 0;
  double accel_scale = 0;
  double accel_skew = 0;
  double mount = 0;        // rad per axis (only where the input carries a mounting estimate)
};

// Where a prior came from, per parameter.
enum class PriorSource {
  datasheet,    // no set, or the set's σ is unknown (null): data-sheet class
  set_and_allowance,  // hypot(set σ, allowance)
  option,       // overridden by a command-line option
};

struct PriorReport {
  // The filter's priors, in the frame of the data it sees (corrected by the set: the correction δ
  // with (I + M_set)(I + δ) = I + M, so row i of δ and b is the raw-frame spread over (1 + M_set,ii)).
  ParameterPriors sigma;
  // The same in raw-data coefficients, hypot(set σ, allowance): what the combined set's σ is bounded by.
  ParameterPriors sigma_raw;
  // Per parameter in the order of prior_parameter_names(): source, the set's σ (NaN: none/unknown)
  // and the allowance (NaN: none).
  std::vector<PriorSource> source;
  std::vector<double> set_sigma, allowance;
};

// Names of the 27 constant parameters in a fixed order: gyro.bias.x … gyro.M.zz (12), accel.bias.x …
// accel.M.zz (12) — the coefficient names of the store — then mount.x, mount.y, mount.z.
const std::vector<std::string>& prior_parameter_names();
double prior_value(const ParameterPriors& p, std::size_t k);  // the k-th σ in that order
void set_prior_value(ParameterPriors& p, std::size_t k, double sigma);

// The 1σ per axis of the mounting misalignment δμ (reference body axes, Ĉ = (I − δμ×)C) for a
// mounting given as roll, pitch, yaw (rad) with 1σ per angle: Σ_δμ = J⁻¹ diag(σ²) J⁻ᵀ with
// J = ∂rpy/∂δμ at that mounting (for a yawed mounting the axes of roll/pitch and δμ differ).
Vec3 mounting_sigma_from_rpy(const Vec3& rpy, const Vec3& sigma_rpy);

// Priors for raw data: the data-sheet class everywhere.
PriorReport priors_datasheet(const ParameterPriors& datasheet = datasheet_priors());
// Priors for data corrected by `set`: hypot(set σ, allowance) where the set's σ is finite, the
// data-sheet class where it is unknown (+inf). `mount_sigma` is the σ of a mounting the input
// carries (rad; +inf or NaN: none — then the data-sheet mounting prior).
PriorReport priors_from_set(const SensorErrors& set, const StabilityAllowance& a, const Vec3& mount_sigma,
                            const ParameterPriors& datasheet = datasheet_priors());

}  // namespace calbench::inmotion
