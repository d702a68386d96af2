#include "bench/diagnose/diagnose_run.hpp"

#include "bench/bench_recording.hpp"
#include "bench/diagnose/diagnose_text.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "common/input_error.hpp"
#include "calibration/bench_fit_effects.hpp"
#include "common/units.hpp"

// `calbench diagnose` on a bench recording: the coefficients to test (given, or the bench fit
// first), the diagnosis, IMPROVED.json. Loading: diagnose_load.cpp; output: diagnose_json.cpp,
// diagnose_text.cpp, diagnose_html.cpp.

namespace calbench {

std::string diagnosis_noise_class(const std::string& device_class, const std::string& model,
                                  const std::filesystem::path& meta_file, NoiseSpec& noise) {
  try {
    const ImuClassChoice c = choose_imu_class(device_class, model, meta_file.string());
    noise = c.cls.noise;
    return c.cls.name + " (" + c.chosen_by + ")";
  } catch (const InputError&) {
    if (!device_class.empty()) throw;
    noise = adis16488a_noise();
    return "ADIS16488A, the default: meta.json device.model '" + model + "' is no known class (give --device-class)";
  }
}

DiagRun run_diagnosis(const DiagInput& in, const CoefficientSet* coeffs, const TableSpec& table,
                      const std::string& device_class) {
  DiagRun run;
  DiagnoseOptions opt;
  run.noise_class = diagnosis_noise_class(device_class, in.meta.device.model, in.dir / "meta.json", opt.noise);
  EffectTerms carried;
  if (coeffs) {
    run.current = *coeffs;
    carried = effects_from_json(coeffs->extra, "coefficients");
  } else {
    BenchFitOptions fo;
    fo.table = table;
    // Long runs (a thermal plan: thousands of 1 s blocks) are fitted on the diagnosis's parent blocks.
    const BenchFitResult r = in.blocks.size() > 2000 ? fit_bench(blocks_without_effects(in.data, EffectTerms{}), fo)
                                                     : fit_bench(in.blocks, fo);
    run.current = bench_result_to_coefficients(r, fo, in.meta, "");
    run.fitted_first = true;
  }
  // Unknown coefficients (σ = ∞) are tested at 0, as the spec says they are applied.
  SensorErrors cur = run.current.errors;
  opt.table = table;
  run.result = diagnose_bench(in.data, cur, carried, opt);

  using namespace units;
  CoefficientSet& c = run.improved;
  c.device = in.meta.device.serial.empty() ? run.current.device : in.meta.device;
  c.errors = run.result.improved;
  auto limit = [](TriadErrors& t, double lb, double lm) {
    for (int i = 0; i < 3; ++i) {
      if (!(t.sigma_bias(i) < lb)) {
        t.bias(i) = 0;
        t.sigma_bias(i) = kUnknownSigma;
      }
      for (int j = 0; j < 3; ++j)
        if (!(t.sigma_M(i, j) < lm)) {
          t.M(i, j) = 0;
          t.sigma_M(i, j) = kUnknownSigma;
        }
    }
  };
  limit(c.errors.gyro, 0.05 * kDeg, 1e-3);
  limit(c.errors.accel, 5 * kMilliG, 2e-3);
  c.extra = run.current.extra.is_object() ? run.current.extra : nlohmann::json::object();
  nlohmann::json eff = nlohmann::json::array();
  for (const auto& f : run.result.findings) eff.push_back(effect_name(f.term.effect));
  diagnose_out::improved_extra(
      c.extra, run.result,
      {{"source", "calbench diagnose"},
       {"effects_added", eff},
       {"note", "b and M refitted together with the extra terms; keys documented in docs/diagnosis.md"}});
  return run;
}

}  // namespace calbench
