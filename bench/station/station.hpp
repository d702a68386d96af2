// The calibration station (issue 3, "bench/: the station"): connect the table and the IMU, identify
// and self-test the unit, run each plan step (command, settle, record, check, repeat a failed step),
// write the recording as it goes, fit, store the coefficients. Safety: any abort commands the table
// to stop and disable. docs/devices.md "Station".
#pragma once
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "calibration/bench_plan.hpp"

namespace calbench::station {

struct Injections {                 // fault injection for the emulated devices (tests, demos)
  double table_kill_at_s = -1;      // stop the in-process table emulator at this emulated time
  std::optional<std::uint16_t> imu_prod_id;
  std::uint16_t imu_sys_e_flag = 0; // from the first recorded step on
  int imu_skip_every = 0;
  std::uint16_t imu_self_test_diag = 0;
};

struct Options {
  std::filesystem::path plan_file;
  std::string table_uri;       // empty with --emulated: in-process emulator on an ephemeral port
  std::string imu_uri;         // ft232h[:serial] | mcp2210[:serial]; empty with --emulated
  bool emulated = false;
  std::filesystem::path out_dir = "station-out";
  std::string db;              // also store run + draft set here (COEFFS.json is always written): a SQLite
                               // file, or a PostgreSQL URI (then via the journal below, forwarded at once
                               // when the server answers, else by `calbench db sync`)
  std::string journal;         // with a PostgreSQL db: the local journal (empty: $CALBENCH_JOURNAL, else
                               // ./calbench-journal.db)
  std::string operator_name;   // who runs the station (recorded; empty: $CALBENCH_OPERATOR, else the OS user)
  std::uint64_t seed = 1;      // emulated unit
  int max_repeats = 2;         // per step
  double heartbeat_s = 0.1;    // bus-clock period of heartbeat + status poll
  bool progress_tty = false;
  Injections inject;
};

struct Result {
  int exit_code = 0;
  std::string message;
  nlohmann::json summary;
};

// Runs the whole station. Never throws for device/link problems: they end in Result with exit code
// 1 after the table was told to stop. `stop` is polled (Ctrl-C).
Result run(const Options& opt, std::ostream& log, const std::atomic<bool>& stop);

}  // namespace calbench::station
