// The in-motion stage at the speed of the hardware (issue 22), on 1 h of the gnss_1h route
// simulated once per process at 200 Hz and at the ADIS16488A's 2460 Hz, written as CSV and
// converted to HDF5 (`calbench convert`) in a temporary folder:
//   BM_Read_Imu/<rate>/<form>, BM_Read_Reference/<form>: the recording readers alone (rows/s,
//     MB/s of the file read, i.e. of imu.csv or of the HDF5 datasets' bytes).
//   BM_FitDrive/<rate>/<obs>/<form>: `calbench fit drive DIR --obs OBS --out RESULT.json` end to end
//     from files (QC and digests included), the executable run on one core (taskset -c 0) as a
//     user runs it: wall seconds, ns per IMU epoch, the child's peak RSS.
//   BM_Read_Imu_OneRowChunks/<rows>: the IMU reader on a recording.h5 whose imu dataset has one
//     row per chunk (h5py's chunks=(1, n)), as issue 35's mutation run made it (75,807 rows took
//     79 s in `fit bench`: one chunk-index walk per chunk); such a dataset is read in one walk since.
//   With CALBENCH_BASELINE=/path/to/an/older/calbench, BM_FitDrive_Baseline/... runs that binary
//     on the CSV recording side by side (before -> after on the same machine).
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <hdf5.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "bench/drive/simulate_drive.hpp"
#include "bench/io/convert_recording.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"

extern char** environ;

namespace calbench {
namespace {
namespace fs = std::filesystem;

// 1 h of the gnss_1h route at `rate` Hz, CSV and HDF5, made once per process.
struct Drive {
  fs::path csv, h5;
};
const Drive& drive(int rate) {
  static std::map<int, Drive> made;
  auto it = made.find(rate);
  if (it != made.end()) return it->second;
  const fs::path base = fs::temp_directory_path() / ("calbench-perf-io-" + std::to_string(::getpid()));
  fs::create_directories(base);
  std::ifstream in(fs::path(CALBENCH_SOURCE_DIR) / "bench/routes/gnss_1h.toml");
  std::stringstream route;
  route << in.rdbuf();
  std::string text = route.str();
  const std::string from = "[imu]\nrate_hz = 200.0";
  const auto p = text.find(from);
  if (p != std::string::npos) text.replace(p, from.size(), "[imu]\nrate_hz = " + std::to_string(rate) + ".0");
  const fs::path route_file = base / ("route" + std::to_string(rate) + ".toml");
  std::ofstream(route_file) << text;
  SimulateDriveArgs a;
  a.route = route_file.string();
  a.truth = "random";
  a.seed = 1;
  a.until_s = 3600;
  a.out = (base / ("drive" + std::to_string(rate))).string();
  simulate_drive_recording(a);
  Drive d{a.out, base / ("drive" + std::to_string(rate) + "-h5")};
  convert_recording(d.csv, "h5", d.h5);
  return made[rate] = d;
}

double file_mb(const fs::path& dir, bool h5, const char* table) {
  return static_cast<double>(fs::file_size(h5 ? dir / kHdf5RecordingFile : dir / (std::string(table) + ".csv"))) / 1e6;
}

void BM_Read_Imu(benchmark::State& state) {
  const int rate = static_cast<int>(state.range(0));
  const bool h5 = state.range(1) != 0;
  const Drive& d = drive(rate);
  const fs::path dir = h5 ? d.h5 : d.csv;
  long rows = 0;
  for (auto _ : state) {
    ImuReader r(dir / "imu.csv", rate);
    ImuRecord rec;
    rows = 0;
    while (r.next(rec)) ++rows;
    benchmark::DoNotOptimize(rec);
  }
  const double mb = h5 ? static_cast<double>(rows) * 8 * 8 / 1e6 : file_mb(dir, false, "imu");
  state.SetLabel(h5 ? "imu dataset of recording.h5" : "imu.csv");
  state.counters["rows_per_s"] = benchmark::Counter(static_cast<double>(rows), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MB_per_s"] = benchmark::Counter(mb, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["rows"] = static_cast<double>(rows);
}
BENCHMARK(BM_Read_Imu)->ArgsProduct({{200, 2460}, {0, 1}})->ArgNames({"rate", "h5"})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(5);

void BM_Read_Reference(benchmark::State& state) {
  const bool h5 = state.range(0) != 0;
  const Drive& d = drive(200);
  const fs::path dir = h5 ? d.h5 : d.csv;
  long rows = 0;
  for (auto _ : state) {
    DriveRefReader r(dir / "reference.csv");
    DriveRefRow row;
    rows = 0;
    while (r.next(row)) ++rows;
    benchmark::DoNotOptimize(row);
  }
  const double mb = h5 ? static_cast<double>(rows) * 14 * 8 / 1e6 : file_mb(dir, false, "reference");
  state.counters["rows_per_s"] = benchmark::Counter(static_cast<double>(rows), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MB_per_s"] = benchmark::Counter(mb, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Read_Reference)->Arg(0)->Arg(1)->ArgNames({"h5"})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(5);

// DIR/recording.h5 with an imu dataset of `rows` rows in chunks of one row (rates form, synthetic
// values at 200 Hz), made once per process.
fs::path one_row_chunks(long rows) {
  static std::map<long, fs::path> made;
  if (made.count(rows)) return made[rows];
  const fs::path dir = fs::temp_directory_path() / ("calbench-perf-io-" + std::to_string(::getpid())) / ("chunks1-" + std::to_string(rows));
  fs::create_directories(dir);
  const std::vector<std::string> cols = {"t_s", "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"};
  const hsize_t ncol = cols.size(), dims[2] = {static_cast<hsize_t>(rows), ncol}, chunk[2] = {1, ncol};
  std::vector<double> v(static_cast<std::size_t>(rows) * ncol);
  for (long k = 0; k < rows; ++k) {
    double* r = &v[static_cast<std::size_t>(k) * ncol];
    r[0] = 0.005 * static_cast<double>(k);
    r[1] = 1e-4, r[2] = -2e-4, r[3] = 3e-4, r[4] = 0.01, r[5] = -0.02, r[6] = -9.8;
  }
  const hid_t f = H5Fcreate((dir / kHdf5RecordingFile).c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t sp = H5Screate_simple(2, dims, nullptr), pl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(pl, 2, chunk);
  const hid_t d = H5Dcreate2(f, "/imu", H5T_IEEE_F64LE, sp, H5P_DEFAULT, pl, H5P_DEFAULT);
  H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  std::size_t len = 0;
  for (const auto& c : cols) len = std::max(len, c.size());
  std::vector<char> names(len * ncol, '\0');
  for (std::size_t i = 0; i < ncol; ++i) std::copy(cols[i].begin(), cols[i].end(), names.begin() + static_cast<long>(i * len));
  const hid_t st = H5Tcopy(H5T_C_S1);
  H5Tset_size(st, len);
  const hid_t asp = H5Screate_simple(1, &ncol, nullptr), a = H5Acreate2(d, "columns", st, asp, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(a, st, names.data());
  H5Aclose(a);
  H5Sclose(asp);
  H5Tclose(st);
  H5Dclose(d);
  H5Pclose(pl);
  H5Sclose(sp);
  H5Fclose(f);
  return made[rows] = dir;
}

void BM_Read_Imu_OneRowChunks(benchmark::State& state) {
  const long want = state.range(0);
  const fs::path dir = one_row_chunks(want);
  long rows = 0;
  for (auto _ : state) {
    // A new modification time: the file's structure is surveyed again (not the process's cache).
    fs::last_write_time(dir / kHdf5RecordingFile, fs::file_time_type::clock::now());
    ImuReader r(dir / "imu.csv", 200);
    ImuRecord rec;
    rows = 0;
    while (r.next(rec)) ++rows;
    benchmark::DoNotOptimize(rec);
  }
  if (rows != want) state.SkipWithError("rows read differ from rows written");
  state.SetLabel("imu dataset of recording.h5, 1-row chunks");
  state.counters["rows_per_s"] = benchmark::Counter(static_cast<double>(rows), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["rows"] = static_cast<double>(rows);
}
BENCHMARK(BM_Read_Imu_OneRowChunks)->Arg(10000)->Arg(75807)->ArgNames({"rows"})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(3);

// Runs argv, returns wall seconds and the child's peak RSS (kB); -1 on failure.
double run_child(const std::vector<std::string>& args, long& rss_kb) {
  std::vector<char*> argv;
  for (const auto& s : args) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  const auto t0 = std::chrono::steady_clock::now();
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) return -1;
  posix_spawn_file_actions_destroy(&fa);
  int status = 0;
  rusage ru{};
  wait4(pid, &status, 0, &ru);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rss_kb = ru.ru_maxrss;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? wall : -1;
}

void fit_drive_row(benchmark::State& state, const std::string& binary, bool h5) {
  const int rate = static_cast<int>(state.range(0));
  const char* obs = state.range(1) == 0 ? "pos" : "pos,vel,att";
  const Drive& d = drive(rate);
  const fs::path dir = h5 ? d.h5 : d.csv;
  const fs::path out = dir.parent_path() / "result.json";
  long rss = 0;
  double wall = 0;
  for (auto _ : state) {
    wall = run_child({"taskset", "-c", "0", binary, "fit", "drive", dir.string(), "--obs", obs, "--out", out.string()}, rss);
    if (wall < 0) {
      state.SkipWithError(("fit drive failed: " + binary).c_str());
      return;
    }
    state.SetIterationTime(wall);
  }
  const double epochs = 3600.0 * rate;
  state.SetLabel(std::string(h5 ? "HDF5" : "CSV") + ", --obs " + obs);
  state.counters["ns_per_imu_epoch"] = wall / epochs * 1e9;
  state.counters["peak_rss_MB"] = static_cast<double>(rss) / 1024.0;
}

void BM_FitDrive(benchmark::State& state) { fit_drive_row(state, CALBENCH_BINARY, state.range(2) != 0); }
BENCHMARK(BM_FitDrive)
    ->ArgsProduct({{200, 2460}, {0, 1}, {0, 1}})
    ->ArgNames({"rate", "att", "h5"})
    ->Unit(benchmark::kSecond)
    ->UseManualTime()
    ->Iterations(1)
    ->Repetitions(5);

void BM_FitDrive_Baseline(benchmark::State& state) {
  const char* b = std::getenv("CALBENCH_BASELINE");
  if (!b || !*b) {
    state.SkipWithError("set CALBENCH_BASELINE=/path/to/an/older/calbench to time it side by side");
    return;
  }
  fit_drive_row(state, b, false);
}
BENCHMARK(BM_FitDrive_Baseline)
    ->ArgsProduct({{200, 2460}, {0, 1}})
    ->ArgNames({"rate", "att"})
    ->Unit(benchmark::kSecond)
    ->UseManualTime()
    ->Iterations(1)
    ->Repetitions(5);

}  // namespace
}  // namespace calbench
