// ADIS16488A emulator behind the SpiBus interface: answers the register protocol word by word
// (pipelined replies in the next frame, PAGE_ID paging, byte writes, GLOB_CMD self-test / flash
// update / factory restore / reset with their busy times on the emulated clock, flash-backed page 2
// and 3 registers), produces data-ready at 2460 Hz/(DEC_RATE+1) on an EmuClock, with physics from a
// callback (true w_ib_b, f_b at time t) and sensor errors from ImuErrorSimulator. Its outputs go
// through the user calibration registers as the real part's do (model: docs/devices.md).
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <mutex>

#include "common/imu_error_sim.hpp"
#include "devices/adis16488a_regs.hpp"
#include "devices/emu_clock.hpp"
#include "devices/spi_bus.hpp"

namespace calbench::devices {

struct EmuTruth {
  Vec3 w_ib_b = Vec3::Zero();  // rad/s
  Vec3 f_b = Vec3::Zero();     // m/s²
};
using EmuPhysics = std::function<EmuTruth(double t)>;

// Injected faults (tests, demos, `station run --emulated --inject`): part of the configuration, and
// changeable while the unit runs (faults()).
struct EmuFaults {
  std::uint16_t prod_id = adis::kProdId;  // anything else: wrong part
  std::uint16_t sys_e_flag = 0;           // bits OR-ed into SYS_E_FLAG of every sample while set
  std::uint16_t self_test_diag = 0;       // DIAG_STS after a self-test (non-zero = failure)
  bool flash_update_fails = false;
  int skip_every = 0;                     // > 0: every n-th internal sample raises no data-ready
  // A unit that fails in service: sys_e_flag and skip_every act only once it has run its first
  // self-test (it is identified and self-tested as a good one), sys_e_flag moreover only from
  // flags_from_s (emulated s) on when that is ≥ 0.
  bool after_self_test = false;
  double flags_from_s = -1;
};

struct Adis16488aEmulatorConfig {
  std::uint16_t serial = 0x1234;
  double sck_hz = 10e6;       // SPI clock the frames take on the emulated clock
  double temperature_c = 31.5;
  std::uint64_t seed = 1;
  EmuFaults faults;
};

class Adis16488aEmulator : public SpiBus {
 public:
  Adis16488aEmulator(std::shared_ptr<EmuClock> clock, EmuPhysics physics, const SensorErrors& truth,
                     const NoiseSpec& noise, Adis16488aEmulatorConfig cfg = {});

  std::vector<std::uint16_t> transfer(const std::vector<std::uint16_t>& words) override;
  bool wait_data_ready(double timeout_s) override;
  double now() const override { return clock_->now(); }
  void delay(double seconds) override { clock_->wait_until(clock_->now() + seconds); }
  std::string describe() const override { return "emulated ADIS16488A"; }

  EmuFaults& faults() { return faults_; }
  void power_cycle();  // RAM ← flash, page 0, outputs cleared

  // Bookkeeping for tests and benchmarks (device side; the driver never sees these).
  std::uint64_t samples_produced() const { return produced_; }
  std::uint64_t samples_overwritten() const { return overwritten_; }  // latched but never read
  std::uint64_t busy_violations() const { return busy_violations_; }   // frames sent while busy
  std::uint64_t frames() const { return frames_; }
  std::uint64_t write_frames() const { return write_frames_; }  // register writes taken (PAGE_ID excluded)
  std::uint32_t flash_count() const { return flash_count_; }
  std::uint16_t peek(std::uint8_t page, std::uint8_t offset) const { return ram_[index(page, offset)]; }
  const ImuErrorSimulator& simulator() const { return sim_; }

 private:
  static std::size_t index(std::uint8_t page, std::uint8_t offset) { return page * 64u + (offset & 0x7E) / 2u; }
  double period() const { return (ram_[index(3, 0x0C)] + 1) / adis::kInternalRateHz; }
  void reset_registers(bool from_flash);
  void advance_to(double t);      // produce every internal sample up to t
  void produce(double t);         // latch one output sample
  std::uint16_t frame(std::uint16_t w);
  void write_byte(std::uint8_t offset, std::uint8_t byte);
  void command(std::uint8_t bits);
  void set32(std::uint8_t page, std::uint8_t offset, std::int64_t v);

  std::shared_ptr<EmuClock> clock_;
  EmuPhysics physics_;
  ImuErrorSimulator sim_;
  Adis16488aEmulatorConfig cfg_;
  EmuFaults faults_;
  std::array<std::uint16_t, 13 * 64> ram_{}, flash_{};
  std::uint8_t page_ = 0;
  std::uint16_t pending_ = 0;      // reply clocked out in the next frame
  double busy_until_ = -1;
  double next_tick_ = 0;           // next internal sample time
  std::uint64_t tick_ = 0;         // internal samples so far
  std::uint16_t seq_ = 0;
  bool unread_ = false;
  double last_dr_ = -1;            // time of the last data-ready edge
  double consumed_dr_ = -1;        // last edge a waiter has been given
  std::uint64_t produced_ = 0, overwritten_ = 0, busy_violations_ = 0, frames_ = 0, write_frames_ = 0;
  std::uint32_t flash_count_ = 0;
  std::uint16_t sticky_flags_ = 0;  // SYS_E_FLAG bits latched by self-test / flash failures
  bool self_tested_ = false;        // a self-test has run (EmuFaults::after_self_test)
  bool in_service() const { return !faults_.after_self_test || self_tested_; }
  std::uint16_t fault_flags(double t) const;  // EmuFaults::sys_e_flag as it acts at time t
  int skip_every() const { return in_service() ? faults_.skip_every : 0; }
};

}  // namespace calbench::devices
