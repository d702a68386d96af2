// Benchmarks of the spine (issue 2): recording write/read throughput (rows/s), streaming memory
// on a 1-hour 2460 Hz recording, and the bench fit of the factory plan at 2460 Hz.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

#include "bench/bench_recording.hpp"
#include "bench/io/plan_toml.hpp"
#include "bench/io/recording.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"

namespace calbench {
namespace {

fs::path temp_dir(const char* name) {
  fs::path p = fs::temp_directory_path() / ("calbench-perf-" + std::to_string(::getpid()) + "-" + name);
  fs::create_directories(p);
  return p;
}

long rss_kb() {
  std::ifstream f("/proc/self/statm");
  long pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

void write_recording(const fs::path& dir, std::size_t rows) {
  RecordingMeta m;
  m.kind = RecordingKind::bench;
  m.device = {"ADIS16488A", "PERF"};
  m.site = Site{55.75, 37.62, 150};
  m.imu_rate_hz = 2460;
  RecordingWriter w(dir, m, ImuForm::rates, true, false);
  ImuRecord r;
  BenchRefRow b;
  for (std::size_t k = 0; k < rows; ++k) {
    const double t = k / 2460.0;
    r.t = t;
    r.gyro = Vec3(1e-3 * std::sin(t), 2.5e-3, -0.123456789 + 1e-9 * k);
    r.accel = Vec3(0.0123, -0.0456, -9.80665 + 1e-7 * k);
    r.temp_c = 25.0 + 1e-5 * k;
    w.imu(r);
    b.t = t;
    b.w = Vec3(1e-5, 2e-5, 3e-5);
    b.f = Vec3(0, 0, -9.81);
    b.step = static_cast<int>(k / 24600);
    b.angle_deg = 0;
    w.bench_ref(b);
  }
  w.finish();
}

void BM_Recording_Write(benchmark::State& st) {
  const std::size_t rows = static_cast<std::size_t>(st.range(0));
  const fs::path d = temp_dir("write");
  for (auto _ : st) write_recording(d, rows);
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations() * rows));  // imu + reference rows together
  st.counters["MB_written"] = (fs::file_size(d / "imu.csv") + fs::file_size(d / "reference.csv")) / 1e6;
  fs::remove_all(d);
}
BENCHMARK(BM_Recording_Write)->Arg(500000)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

void BM_Recording_ReadImu(benchmark::State& st) {
  const std::size_t rows = static_cast<std::size_t>(st.range(0));
  const fs::path d = temp_dir("read");
  write_recording(d, rows);
  for (auto _ : st) {
    ImuReader r(d / "imu.csv", 2460);
    ImuRecord rec;
    double sum = 0;
    while (r.next(rec)) sum += rec.gyro(0);
    benchmark::DoNotOptimize(sum);
  }
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations() * rows));
  fs::remove_all(d);
}
BENCHMARK(BM_Recording_ReadImu)->Arg(500000)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

// One hour at 2460 Hz = 8.856 M rows, streamed: the resident memory must not grow with the file.
void BM_Recording_ReadOneHourStreaming(benchmark::State& st) {
  const std::size_t rows = 3600 * 2460;
  const fs::path d = temp_dir("hour");
  write_recording(d, rows);
  long growth = 0;
  for (auto _ : st) {
    const long before = rss_kb();
    long peak = before;
    ImuReader r(d / "imu.csv", 2460);
    ImuRecord rec;
    std::size_t n = 0;
    while (r.next(rec))
      if ((++n & 0xFFFFF) == 0) peak = std::max(peak, rss_kb());
    growth = std::max(growth, peak - before);
    if (n != rows) st.SkipWithError("row count mismatch");
  }
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations() * rows));
  st.counters["file_MB"] = fs::file_size(d / "imu.csv") / 1e6;
  st.counters["rss_growth_MB"] = growth / 1024.0;
  fs::remove_all(d);
}
BENCHMARK(BM_Recording_ReadOneHourStreaming)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(1);

// The factory plan (bench/plans/factory.toml) at 2460 Hz: simulated once, then fitted.
struct FactoryData {
  BenchPlan plan;
  std::vector<BenchBlock> blocks;
  fs::path dir;
  std::size_t rows = 0;
  FactoryData() {
    plan = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml");
    dir = temp_dir("factory");
    RecordingMeta m;
    m.kind = RecordingKind::bench;
    m.device = {"ADIS16488A", "PERF"};
    m.site = plan.site;
    m.imu_rate_hz = 2460;
    RecordingWriter w(dir, m);
    BenchBlockBuilder bb(1.0);
    BenchSimOptions so;
    simulate_bench(plan, plan.site, draw_random_unit(1), so, [&](const BenchSample& s) {
      write_bench_sample(w, s);
      bb.add(s.t, 1.0 / 2460, s.gyro, s.accel, s.w_ref, s.f_ref, s.step);
      ++rows;
    });
    w.finish();
    blocks = bb.finish();
  }
  ~FactoryData() { fs::remove_all(dir); }
};
FactoryData& factory() {
  static FactoryData d;
  return d;
}

void BM_BenchFit_Factory_FromBlocks(benchmark::State& st) {
  auto& d = factory();
  BenchFitOptions o;
  o.table = d.plan.table;
  o.method = st.range(0) == 0 ? BenchMethod::lsq : BenchMethod::ekf;
  st.SetLabel(st.range(0) == 0 ? "lsq" : "ekf");
  for (auto _ : st) benchmark::DoNotOptimize(fit_bench(d.blocks, o));
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations() * d.rows));
}
BENCHMARK(BM_BenchFit_Factory_FromBlocks)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// What `calbench fit bench` does: read both CSV files, aggregate, fit.
void BM_BenchFit_Factory_FromRecording(benchmark::State& st) {
  auto& d = factory();
  BenchFitOptions o;
  o.table = d.plan.table;
  for (auto _ : st) {
    const auto data = load_bench_blocks(d.dir);
    benchmark::DoNotOptimize(fit_bench(data.blocks, o));
  }
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations() * d.rows));
}
BENCHMARK(BM_BenchFit_Factory_FromRecording)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

}  // namespace
}  // namespace calbench

