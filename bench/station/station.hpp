// The calibration station (issue 3, "bench/: the station"): connect the table and the IMU, identify
// and self-test the unit, run each plan step (command, settle, record, check, repeat a failed step),
// write the recording as it goes, fit, store the coefficients. Safety: any abort commands the table
// to stop and disable. docs/devices.md "Station".
// Several units at once (issue 21): a fixture's slots (bench/station/fixture.hpp) run one table cycle
// together, one recording and one coefficient set each, tied by a run id; a unit that fails is
// marked failed and the others go on. docs/devices.md "Fixtures".
#pragma once
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "calibration/bench_plan.hpp"
#include "devices/adis16488a_emulator.hpp"

namespace calbench::station {

// Fault injection for the emulated devices (tests, demos): the emulators' own configuration
// (devices/adis16488a_emulator.hpp EmuFaults, devices/table_emulator.hpp kill_at_s), passed on as is.
struct Injections {
  double table_kill_at_s = -1;                     // the in-process table controller dies at this emulated time
  devices::EmuFaults imu;                          // every unit's
  std::map<std::string, devices::EmuFaults> slot;  // one slot's (by name), instead of `imu`
};

struct Options {
  std::filesystem::path plan_file;
  std::string table_uri;       // empty with --emulated: in-process emulator on an ephemeral port
  std::string imu_uri;         // ft232h[:serial] | mcp2210[:serial]; empty with --emulated
  std::filesystem::path fixture_file;  // several units (else the plan's [plan] fixture, else one unit)
  int units = 0;               // > 0 with --emulated: an emulated fixture of this many units
  bool emulated = false;
  std::filesystem::path out_dir = "station-out";
  std::string db;              // also store run + draft set here (COEFFS.json is always written): a SQLite
                               // file, or a PostgreSQL URI (then via the journal below, forwarded at once
                               // when the server answers, else by `calbench db sync`)
  std::string journal;         // with a PostgreSQL db: the local journal (empty: $CALBENCH_JOURNAL, else
                               // ./calbench-journal.db)
  std::string operator_name;   // who runs the station (recorded; empty: $CALBENCH_OPERATOR, else the OS user)
  std::uint64_t seed = 1;      // emulated unit (slot k of a fixture: seed + k)
  int max_repeats = 2;         // per step
  double heartbeat_s = 0.1;    // bus-clock period of heartbeat + status poll
  bool progress_tty = false;
  double pace = 0;             // > 0, emulated time of the in-process table: at most pace x real time
  Injections inject;
};

struct Result {
  int exit_code = 0;
  std::string message;
  nlohmann::json summary;
};

// Code: this file's station.cpp (setup, fit and store, the abort path), step_runner.* (the plan's
// steps), run_summary.* (the message and --json summary), unit.hpp (one unit), fixture.* (the slots,
// checked); devices/imu_open.hpp opens the IMUs.
// Runs the whole station. Never throws for device/link problems: they end in Result with exit code
// 1 after the table was told to stop. `stop` is polled (Ctrl-C).
Result run(const Options& opt, std::ostream& log, const std::atomic<bool>& stop);

}  // namespace calbench::station
