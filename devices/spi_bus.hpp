// The SPI bus as the ADIS16488A sees it: a sequence of 16-bit words, each in its own chip-select
// frame (CS asserted for exactly one word, MSB first, SPI mode 3), with a stall (CS high) of at
// least `stall_s` between words, and a data-ready line the host can wait on.
//
// Implementations: Mcp2210Bus (hidapi), Ft232hBus (libftdi1 MPSSE), Adis16488aEmulator.
#pragma once
#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace calbench::devices {

// A bridge or bus failure (USB error, bridge status code, timeout). Message names the bridge.
class SpiError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class SpiBus {
 public:
  virtual ~SpiBus() = default;

  // Send each word in its own CS frame; returns the word clocked in on MISO during each frame
  // (same length as `words`). Throws SpiError.
  virtual std::vector<std::uint16_t> transfer(const std::vector<std::uint16_t>& words) = 0;

  // Wait for the next rising edge of data-ready (up to timeout_s on the bus clock).
  virtual bool wait_data_ready(double timeout_s) = 0;

  // Wait for data-ready, then transfer. Bridges that can queue both in one USB exchange
  // (FT232H: MPSSE wait-on-I/O) override this. Returns nullopt on timeout.
  virtual std::optional<std::vector<std::uint16_t>> transfer_on_data_ready(
      const std::vector<std::uint16_t>& words, double timeout_s) {
    if (!wait_data_ready(timeout_s)) return std::nullopt;
    return transfer(words);
  }

  // Time on the bus's clock, seconds (monotonic; the emulated clock for the emulator).
  virtual double now() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }
  // Wait on the bus's clock (command stalls: self-test, flash update, reset).
  virtual void delay(double seconds) {
    if (seconds > 0) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  }

  // Minimum CS-high time between two words.
  virtual void set_stall(double seconds) { stall_s_ = seconds; }
  double stall() const { return stall_s_; }

  virtual std::string describe() const = 0;

 protected:
  double stall_s_ = 5e-6;  // 5 µs: the Linux adis16480 driver's read/write delay (≥2 µs needed)
};

}  // namespace calbench::devices
