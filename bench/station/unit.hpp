// One unit of a station run (bench/station/station.hpp): its slot, devices, the step being recorded,
// its recording and its fate. Shared by the station (setup, fit, store), its step runner
// (bench/station/step_runner.hpp) and the run summary (bench/station/run_summary.hpp).
#pragma once
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/io/recording.hpp"
#include "bench/station/fixture.hpp"
#include "common/imu_error_sim.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"
#include "devices/emu_clock.hpp"

namespace calbench::station {

// The whole run ends (with one unit, or when no unit is left): the table is stopped, exit 1.
struct Aborted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Unit {
  FixtureSlot slot;
  bool at_centre = true;           // identity pose at the centre: the centre's kinematics as they are
  fs::path out, rec_dir;
  std::uint64_t seed = 1;
  devices::EmuFaults inj;          // emulated: its injected faults
  std::shared_ptr<devices::VirtualClock> clock;  // its own bus time (emulated, several units: one bridge each)
  std::unique_ptr<devices::SpiBus> bus;
  std::unique_ptr<devices::Adis16488a> imu;
  SensorErrors truth;
  std::unique_ptr<RecordingWriter> writer;
  // The step being recorded (rows are written once the step passes its data check).
  bool recording = false;
  double t0 = -1;
  std::vector<ImuRecord> imu_rows;
  std::vector<BenchRefRow> ref_rows;
  std::uint64_t step_lost = 0, step_errors = 0, step_saturated = 0;
  std::string err_text;
  int misses = 0;                  // data-ready timeouts in a row
  // Totals and fate.
  std::uint64_t samples = 0, lost = 0, error_samples = 0, repeats = 0;
  bool identified = false, failed = false;
  std::string why;                 // failed: the reason
  nlohmann::json steps = nlohmann::json::array(), summary = nlohmann::json::object();
  // Reader thread (real time): samples wait here for the station's thread.
  std::thread reader;
  std::mutex mu;
  std::deque<devices::ImuSample> queue;
  std::string reader_error;
  std::atomic<bool> reading{false};

  bool live() const { return !failed; }
  std::string label() const { return "slot " + slot.name; }
};

using Units = std::vector<std::unique_ptr<Unit>>;

inline std::size_t live_units(const Units& units) {
  std::size_t n = 0;
  for (const auto& u : units) n += u->live();
  return n;
}

inline std::uint64_t total(const Units& units, std::uint64_t Unit::*f) {
  std::uint64_t n = 0;
  for (const auto& u : units) n += (*u).*f;
  return n;
}

}  // namespace calbench::station
