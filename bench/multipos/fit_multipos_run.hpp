// calbench fit multipos: a multipos recording (spec kind "multipos") → coefficients.json, with the
// static poses found, the rotations used, the noise levels and the fit's σ (docs/multipos.md).
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "calibration/multipos/multipos_fit.hpp"
#include "common/coefficients_codec.hpp"
#include "common/noise_spec.hpp"

namespace calbench {

struct FitMultiposArgs {
  std::string dir, out, plot, device_class;
  std::vector<int> exclude_poses, exclude_rotations;
  bool earth_rate = false;
  bool json = false;
};

// The recording read into the estimator's input (SI rates; increments divided by their interval),
// with the gravity and the class noise it is fitted with. InputError on a recording of another
// kind or malformed tables. A model no class knows is fitted without a class (noise measured).
struct MultiposRecording {
  multipos::MultiposInput input;
  std::string gravity_source;   // "meta.json gravity_m_s2", "site (WGS-84 normal gravity)", "standard gravity …"
  nlohmann::json device_class;  // what the report records of the class ("name" null: none)
  bool class_known = true;      // false: the model names no class and no --device-class was given
  NoiseSpec noise;              // the class noise (diagnose: the drift prior); no class: measured + wide
  DeviceId device;
};
MultiposRecording read_multipos_recording(const std::string& dir, const std::string& device_class_option);
// The class's name, or "none (noise measured on the recording)".
std::string class_name(const MultiposRecording& r);

// The fit of a multipos recording as a coefficient set (the spec's coefficients.json with a
// "multipos" key): what `fit multipos` writes and the station stores for a positions plan.
// InputError when the recording does not determine the coefficients (which poses to add).
struct MultiposSetResult {
  MultiposRecording rec;
  multipos::MultiposFit fit;
  CoefficientSet set;
};
MultiposSetResult fit_multipos_set(const FitMultiposArgs& a);

// Runs the fit and prints text (or --json); writes --out and --plot atomically. A recording that
// does not determine the coefficients is an InputError saying which poses or rotations to add.
void run_fit_multipos(const FitMultiposArgs& a, std::ostream& out);

}  // namespace calbench
