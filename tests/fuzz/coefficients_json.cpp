// Harness: the readers of a coefficients.json and of what rides in it or beside it: the
// coefficients (bench/io/coefficients_json.*), the catalogue terms of an IMPROVED.json
// (bench/diagnose/effects_json.*), MODELS.json drift models (bench/io/drift_models_json.*), and
// the --coeffs readers of `qc` and `diagnose` on drives (a coefficients.json or a RESULT.json).
// Input: the file. Each reader gets the same file; a set that is read is written back to text.
#include <cstdint>

#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/qc_drive.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/drift_models_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const auto file = fuzz::scratch() / "coeffs.json";
  const std::string f = file.string();
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  nlohmann::json j;
  try {
    j = read_json_file(file);
  } catch (const InputError&) {
    fds.verify();
    return 0;
  }
  try {
    const CoefficientSet c = read_coefficients(file);
    volatile std::size_t n = coefficients_to_json(c).dump(2).size();
    (void)n;
    const EffectTerms e = simulation_effects(c.extra, f, "", {});
    nlohmann::json out = coefficients_to_json(c);
    replace_effect_keys(e, out);
  } catch (const InputError&) {
  }
  try {
    EffectTerms sigma;
    const EffectTerms e = effects_from_json(j, f, &sigma);
    nlohmann::json out = nlohmann::json::object();
    effects_to_json(e, sigma, out);
  } catch (const InputError&) {
  }
  try {
    assign_drift_models(drift_models_from_json(j, f), f);
  } catch (const InputError&) {
  }
  try {
    load_qc_set(f);
  } catch (const InputError&) {
  }
  try {
    read_drive_coeffs(f);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
