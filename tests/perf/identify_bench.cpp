// Identification at scale (issue 6): the statistical correlation function (eq 25, by FFT) of 10⁷
// samples and the overlapping Allan deviation (octave τ, with intervals) of 10⁷ samples; plus the
// whole identify() (correlation, paper estimates, both NLS fits with Bartlett errors) on 10⁶.
#include <benchmark/benchmark.h>

#include <random>

#include "calibration/identification/sample_timing.hpp"

#include <random>
#include <vector>

#include "calibration/identification/allan.hpp"
#include "calibration/identification/correlation.hpp"
#include "calibration/identification/correlation_fit.hpp"
#include "calibration/identification/noise_processes.hpp"

namespace {
using namespace calbench::identification;

const std::vector<double>& series_1e7() {
  static const std::vector<double> x = [] {
    std::mt19937_64 rng(42);
    auto v = simulate_gauss_markov(10'000'000, 0.01, 1e-4, 300.0, rng);
    const auto w = simulate_white(v.size(), 0.01, 1e-4, rng);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] += w[i];
    return v;
  }();
  return x;
}

void BM_Identify_Correlation1e7(benchmark::State& state) {
  const auto& x = series_1e7();
  const auto max_lag = static_cast<std::size_t>(state.range(0));
  for (auto _ : state) {
    auto k = autocovariance(x, max_lag);
    benchmark::DoNotOptimize(k.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(x.size()));
}
BENCHMARK(BM_Identify_Correlation1e7)->Arg(100'000)->Arg(2'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Identify_Allan1e7(benchmark::State& state) {
  const auto& x = series_1e7();
  for (auto _ : state) {
    auto pts = allan_deviation(x, 0.01);
    auto fit = fit_allan(pts);
    benchmark::DoNotOptimize(fit.N.value);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(x.size()));
}
BENCHMARK(BM_Identify_Allan1e7)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Identify_Full1e6(benchmark::State& state) {
  std::mt19937_64 rng(7);
  const auto x = simulate_exp_cosine(1'000'000, 1.0, 1.0, 1.0 / 100.0, 2.0 / 100.0, rng);
  for (auto _ : state) {
    auto id = identify(x, 1.0);
    benchmark::DoNotOptimize(id.cos.beta);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(x.size()));
}
BENCHMARK(BM_Identify_Full1e6)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

// The logger's sample timing (issue 53) in fit drive's scan pass: rows per second the estimator
// takes on an hour-long 2460-Hz stream read 1.5 times per sample (one row in three repeats).
namespace calbench {
namespace {
void BM_SampleTiming_Scan(benchmark::State& state) {
  const std::size_t rows = 1 << 20;
  std::vector<double> t(rows);
  std::vector<Vec3> w(rows), f(rows);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  double tt = 0;
  for (std::size_t k = 0; k < rows; ++k) {
    const bool repeat = k % 3 == 2;
    t[k] = tt += 1.0 / 3690 + 1e-5 * n(rng);
    w[k] = repeat ? w[k - 1] : Vec3(n(rng), n(rng), n(rng));
    f[k] = repeat ? f[k - 1] : Vec3(n(rng), n(rng), n(rng));
  }
  for (auto _ : state) {
    identification::SampleTimingEstimator e;
    for (std::size_t k = 0; k < rows; ++k) e.add(t[k], w[k], f[k]);
    benchmark::DoNotOptimize(e.result().sigma_s);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * rows));
}
BENCHMARK(BM_SampleTiming_Scan)->Unit(benchmark::kMillisecond);
}  // namespace
}  // namespace calbench
