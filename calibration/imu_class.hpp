// An IMU device class: the data-sheet figures of one IMU model, which the in-motion fit and the
// simulators take as prior knowledge of a unit of that model (issue 34). The figures live in one
// file per model, bench/imu_classes/<name>.toml (codec: bench/io/imu_class_toml.hpp); this is the
// plain struct they are read into, in SI. How to add a class: docs/in-motion.md, "Device classes".
#pragma once
#include <string>
#include <vector>

#include "calibration/inmotion/priors.hpp"
#include "common/imu_error_sim.hpp"
#include "common/noise_spec.hpp"

namespace calbench {

struct ImuClass {
  std::string name;                  // e.g. "ADIS16488A"
  std::vector<std::string> aliases;  // other meta.json device.model names of the same class
  std::string grade;                 // consumer, industrial, tactical (for reports)
  std::string source, url, revision; // the data sheet the figures come from
  std::string file;                  // where the class was read from
  // White noise (ARW, VRW), in-run bias stability as a first-order Gauss–Markov σ with its
  // correlation time, measurement ranges, output quantisation and output rate.
  NoiseSpec noise;
  // Spread of an uncalibrated part as the data sheet states it (1σ), drawn by the simulators.
  UnitSpread spread;
  // The fit's prior 1σ of a raw unit (initial bias, scale, skew and the mounting).
  inmotion::ParameterPriors priors;
  // How far a calibrated parameter can move between a calibration and a drive (device_class = name).
  inmotion::StabilityAllowance allowance;
};

// A model name as the classes are matched: lower case, without any white space.
std::string normalized_model_name(const std::string& model);
// True when `model` (meta.json device.model) names the class or one of its aliases.
bool imu_class_matches(const ImuClass& c, const std::string& model);

}  // namespace calbench
