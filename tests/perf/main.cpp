// The one main() of calbench_perf: every tests/perf/*_bench.cpp only registers benchmarks.
#include <benchmark/benchmark.h>

BENCHMARK_MAIN();
