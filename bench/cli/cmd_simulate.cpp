// calbench simulate bench --plan PLAN --truth TRUTH.json|random --out DIR [--seed N]
//   [--inject EFFECT:key=value,...]... [--effects EFFECTS.json]   (catalogue terms, docs/diagnosis.md)
#include <iostream>

#include "bench/bench_recording.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/coefficients_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/plan_toml.hpp"
#include "bench/io/recording.hpp"
#include "calibration/bench_sim.hpp"

namespace calbench::cli {
namespace {

struct SimBenchArgs {
  std::string plan, truth, out, serial, effects;
  std::vector<std::string> inject;
  std::uint64_t seed = 1;
  bool force = false;
};

void run_simulate_bench(const SimBenchArgs& a) {
  const BenchPlan plan = load_plan(a.plan);
  CoefficientSet truth;
  if (a.truth == "random") {
    truth.errors = draw_random_unit(a.seed);
    truth.device.serial = a.serial.empty() ? "SIM-" + std::to_string(a.seed) : a.serial;
    truth.extra["truth"] = {{"drawn_by", "calbench simulate --truth random"}, {"seed", a.seed}};
  } else {
    truth = read_coefficients(a.truth);
    if (!a.serial.empty()) truth.device.serial = a.serial;
  }
  // Physics beyond the spec's model: from the truth's own extra keys, an effects file, --inject.
  const EffectTerms effects = simulation_effects(truth.extra, a.truth, a.effects, a.inject);
  if (effects.any()) replace_effect_keys(effects, truth.extra);
  const fs::path out(a.out);
  if (fs::exists(out / "meta.json") && !a.force)
    throw InputError(a.out, 0, "", "already holds a recording (use --force to overwrite)");
  check_output_folder(out);
  RecordingMeta meta;
  meta.kind = RecordingKind::bench;
  meta.device = truth.device;
  meta.site = plan.site;
  meta.imu_rate_hz = adis16488a_noise().output_rate_hz;
  meta.notes = "simulated by calbench: plan '" + plan.name + "', seed " + std::to_string(a.seed);
  meta.extra["bench"] = {{"plan", plan.name}, {"table", table_spec_json(plan.table)}};
  fs::create_directories(out);
  write_coefficients(out / "truth.json", truth);
  RecordingWriter w(out, meta, ImuForm::rates, true, false, false);
  BenchSimOptions so;
  so.seed = a.seed;
  so.effects = effects;
  std::size_t n = 0, sat = 0;
  simulate_bench(plan, plan.site, truth.errors, so, [&](const BenchSample& s) {
    write_bench_sample(w, s);
    ++n;
    sat += s.saturated;
  });
  w.finish();
  std::cout << "simulated " << n << " samples (" << n / meta.imu_rate_hz << " s) of plan '" << plan.name << "' into "
            << a.out << " (truth in " << (out / "truth.json").string() << ")";
  if (sat) std::cout << "; " << sat << " saturated samples";
  std::cout << std::endl;
}

const bool registered = add_command(10, [](CLI::App& app) {
  auto* sim = app.add_subcommand("simulate", "Simulate recordings with known truth (bench; drive; multipos)");
  sim->require_subcommand(1);
  auto a = std::make_shared<SimBenchArgs>();
  auto* b = sim->add_subcommand("bench", "Simulate a bench run: the two-axis table executing PLAN with an ADIS16488A on it");
  b->add_option("--plan", a->plan, "plan file (TOML), e.g. bench/plans/factory.toml")->required()->check(CLI::ExistingFile);
  b->add_option("--truth", a->truth, "coefficients.json of the simulated unit, or 'random' to draw one")->required();
  b->add_option("--out", a->out, "recording folder to write (meta.json, imu.csv, reference.csv, truth.json)")->required()
      ->check(non_empty());
  b->add_option("--seed", a->seed, "random seed (noise, drift, and the unit for --truth random)")
      ->check(whole_number(0, std::numeric_limits<std::uint64_t>::max()));
  b->add_option("--serial", a->serial, "device serial to write (default: from the truth, or SIM-<seed>)");
  b->add_option("--inject", a->inject,
                 "inject a catalogue effect the nominal model lacks, SI units, repeatable: e.g. "
                 "g_sensitivity:axis=x,f=y,value=1.6e-4  temperature_bias:sensor=gyro,axis=z,value=2e-6  "
                 "time_offset:value=1e-3  lever_arm:x=0.01  table_wobble:sin=5e-5  (docs/diagnosis.md)");
  b->add_option("--effects", a->effects, "JSON file with catalogue keys (as in IMPROVED.json) to inject")
      ->check(CLI::ExistingFile);
  b->add_flag("--force", a->force, "overwrite an existing recording in --out");
  b->callback([a] { run_simulate_bench(*a); });
});

}  // namespace
}  // namespace calbench::cli
