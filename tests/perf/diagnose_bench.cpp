// One diagnosis each, timed (issue 19: the refactoring may not make them slower): the bench
// diagnosis of a simulated bench/plans/diagnose.toml run with a concealed g-sensitivity and lever
// arm, and the drive diagnosis (with its innovation part) of a simulated
// tests/data/drive_diag_route.toml drive with a concealed time offset and lever arm. The inputs are
// simulated once, outside the timed loop.
#include <benchmark/benchmark.h>

#include <string>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/io/plan_toml.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "calibration/gauss_markov_window.hpp"

namespace calbench {
namespace {

// One bench diagnosis of a simulated run of `plan` (seed 3) with `effects` concealed, timed.
void bench_diagnosis(benchmark::State& state, const char* plan_file, const EffectTerms& effects) {
  const BenchPlan plan = load_plan(std::string(CALBENCH_SOURCE_DIR) + plan_file);
  BenchSimOptions so;
  so.seed = 3;
  so.effects = effects;
  const DiagInput in = simulate_diag_input(plan, draw_random_unit(5003), so);
  std::size_t findings = 0;
  for (auto _ : state) {
    const DiagRun r = run_diagnosis(in, nullptr, plan.table);
    findings = r.result.findings.size();
    benchmark::DoNotOptimize(findings);
  }
  state.counters["findings"] = static_cast<double>(findings);
}

void BM_Diagnose_Bench(benchmark::State& state) {
  EffectTerms fx;
  effect_matrix(fx, EffectId::g_sensitivity)(0, 2) = 1.5e-4;
  effect_vector<3>(fx, EffectId::lever_arm)(1) = 0.02;
  bench_diagnosis(state, "/bench/plans/diagnose.toml", fx);
}
BENCHMARK(BM_Diagnose_Bench)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(5);

// The factory plan (~11 min of steps), clean: the diagnosis a station would run on every unit.
void BM_Diagnose_BenchFactory(benchmark::State& state) { bench_diagnosis(state, "/bench/plans/factory.toml", EffectTerms{}); }
BENCHMARK(BM_Diagnose_BenchFactory)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(5);

void BM_Diagnose_Drive(benchmark::State& state) {
  EffectTerms fx;
  effect_vector<1>(fx, EffectId::time_offset)(0) = 0.002;
  effect_vector<3>(fx, EffectId::lever_arm)(1) = -0.04;
  const DriveDiagInput in =
      simulate_drive_diag_input(std::string(CALBENCH_SOURCE_DIR) + "/tests/data/drive_diag_route.toml", 41, fx);
  std::size_t findings = 0;
  for (auto _ : state) {
    const DriveDiagRun r = run_drive_diagnosis(in, nullptr);
    findings = r.result.core.findings.size();
    benchmark::DoNotOptimize(findings);
  }
  state.counters["findings"] = static_cast<double>(findings);
}
BENCHMARK(BM_Diagnose_Drive)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(5);

}  // namespace
}  // namespace calbench
