// Throughput of several units (issue 21):
//   BM_Station_Fixture/N: `station run --emulated --units N` on bench/plans/factory.toml, in process
//     (the table emulator on loopback Modbus TCP, N emulated ADIS16488As at 2460 Hz, N fits): units
//     per hour of table time (the emulated plan duration = what the table needs on hardware), wall
//     and process CPU seconds per unit on this machine, samples lost.
//   BM_FitDrive_Units/4, BM_FitDrive_Separate/4: four MEMS units on 10 minutes of the default route at
//     2460 Hz (simulate drive --units 4, written once to a temporary folder): one multi-unit fit
//     (reference parsed once, units side by side on the machine's cores) against four separate fits
//     of the unit folders one after the other (each parsing the reference itself);
//     BM_FitDrive_Units/units:4/workers:1 shares the reference without running units side by side.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <atomic>
#include <filesystem>
#include <sstream>

#include "bench/drive/drive_units.hpp"
#include "bench/drive/fit_drive.hpp"
#include "bench/drive/simulate_drive.hpp"
#include "bench/station/station.hpp"

namespace calbench {
namespace {
namespace fs = std::filesystem;

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

fs::path temp_folder(const char* name) {
  const fs::path d = fs::temp_directory_path() / (std::string("calbench-perf-") + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

void BM_Station_Fixture(benchmark::State& state) {
  const int units = static_cast<int>(state.range(0));
  double emulated_s = 0, lost = 0, cpu = 0, wall = 0;
  for (auto _ : state) {
    const fs::path out = temp_folder("station");
    station::Options o;
    o.plan_file = fs::path(CALBENCH_SOURCE_DIR) / "bench/plans/factory.toml";
    o.emulated = true;
    o.units = units;
    o.out_dir = out;
    std::ostringstream log;
    std::atomic<bool> stop{false};
    const double c0 = process_cpu_s();
    const auto w0 = std::chrono::steady_clock::now();
    const station::Result r = station::run(o, log, stop);
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    cpu = process_cpu_s() - c0;
    fs::remove_all(out);
    if (r.exit_code != 0) {
      state.SkipWithError(r.message.c_str());
      return;
    }
    emulated_s = r.summary["emulated_s"].get<double>();
    lost = r.summary["samples_lost"].get<double>();
  }
  state.counters["units"] = units;
  state.counters["table_cycle_s"] = emulated_s;
  state.counters["units_per_hour"] = units * 3600.0 / emulated_s;
  state.counters["wall_s_per_unit"] = wall / units;
  state.counters["cpu_s_per_unit"] = cpu / units;
  state.counters["samples_lost"] = lost;
}
BENCHMARK(BM_Station_Fixture)->Arg(1)->Arg(4)->Arg(8)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1)->Repetitions(3);

// Four units on 10 minutes of the default route at 2460 Hz, written once per process.
const fs::path& four_unit_drive() {
  static const fs::path dir = [] {
    const fs::path d = temp_folder("drive4");
    SimulateDriveArgs a;
    a.route = (fs::path(CALBENCH_SOURCE_DIR) / "bench/routes/default.toml").string();
    a.truth = "random";
    a.out = d.string();
    a.seed = 7;
    a.units = 4;
    a.until_s = 600;
    simulate_drive_recording(a);
    std::atexit([] { std::error_code ec; fs::remove_all(four_unit_drive(), ec); });
    return d;
  }();
  return dir;
}

FitDriveArgs fit_args(const fs::path& out) {
  FitDriveArgs a;
  a.dir = four_unit_drive().string();
  a.out = out.string();
  a.window = "0:450";  // the rest for the out-of-sample QC, as a test engineer would
  return a;
}

void BM_FitDrive_Units(benchmark::State& state) {
  four_unit_drive();  // written before the timed loop
  const unsigned threads = static_cast<unsigned>(state.range(1));
  for (auto _ : state) {
    const fs::path out = temp_folder("fit4");
    const auto fits = fit_drive_units(fit_args(out), threads);
    for (const auto& f : fits)
      if (!f.error.empty()) state.SkipWithError(f.error.c_str());
    fs::remove_all(out);
  }
  state.counters["units"] = 4;
  state.counters["imu_rows_per_unit"] = 600 * 2460 + 1;
}
BENCHMARK(BM_FitDrive_Units)
    ->Args({4, 0})
    ->Args({4, 1})
    ->ArgNames({"units", "workers"})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(5);

void BM_FitDrive_Separate(benchmark::State& state) {
  const fs::path& drive = four_unit_drive();
  for (auto _ : state) {
    const fs::path out = temp_folder("fitsep");
    fs::create_directories(out);
    for (const char* slot : {"1", "2", "3", "4"}) {
      FitDriveArgs a = fit_args(out / (std::string(slot) + ".json"));
      a.dir = (drive / slot).string();
      benchmark::DoNotOptimize(fit_drive(a));
    }
    fs::remove_all(out);
  }
  state.counters["units"] = 4;
}
BENCHMARK(BM_FitDrive_Separate)->Arg(4)->ArgName("units")->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1)->Repetitions(5);

}  // namespace
}  // namespace calbench
