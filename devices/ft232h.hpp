// FTDI FT232H in MPSSE mode (libftdi1) as an SpiBus: the bridge that can stream 2460 Hz.
// A whole sample — wait for data-ready (GPIOL1 rising edge), then every word in its own CS frame with
// the stall clocked out as dummy clocks while CS is high — is queued in ONE USB write, and the
// replies come back in one read. Protocol facts: hardware-notes §2.3; docs/devices.md "FT232H".
// Pins: ADBUS0 SCK, ADBUS1 MOSI, ADBUS2 MISO, ADBUS3 CS (active low), ADBUS5 = GPIOL1 ← ADIS DR.
#pragma once
#include <memory>

#include "devices/spi_bus.hpp"
#include "devices/usb_transport.hpp"

namespace calbench::devices {

namespace mpsse {
inline constexpr std::uint16_t kVid = 0x0403, kPid = 0x6014;
inline constexpr std::uint8_t kSetLowBits = 0x80, kWriteReadBytesMode3 = 0x31, kSendImmediate = 0x87,
                              kWaitIoHigh = 0x88, kWaitIoLow = 0x89, kDisableDiv5 = 0x8A,
                              kDisable3Phase = 0x8D, kClockBits = 0x8E, kClockBytes = 0x8F,
                              kSetDivisor = 0x86, kLoopbackOff = 0x85, kDisableAdaptive = 0x97,
                              kBadCommand = 0xFA;
inline constexpr std::uint8_t kPinSck = 0x01, kPinMosi = 0x02, kPinCs = 0x08;
inline constexpr std::uint8_t kDirection = kPinSck | kPinMosi | kPinCs;  // MISO, GPIOL1 inputs
}  // namespace mpsse

struct Ft232hConfig {
  double sck_hz = 10e6;    // ADIS16488A max 15 MHz; 60 MHz/((1+div)·2)
  int timeout_ms = 200;    // for replies (and data-ready when waiting in the MPSSE)
};

class Ft232hBus : public SpiBus {
 public:
  Ft232hBus(std::unique_ptr<FtdiEndpoint> ep, Ft232hConfig cfg = {});
  void configure();  // clock divisor, pins idle (SCK high for mode 3, CS high)

  std::vector<std::uint16_t> transfer(const std::vector<std::uint16_t>& words) override;
  bool wait_data_ready(double timeout_s) override;
  std::optional<std::vector<std::uint16_t>> transfer_on_data_ready(const std::vector<std::uint16_t>& words,
                                                                   double timeout_s) override;
  std::string describe() const override { return "ft232h"; }

  // The exact byte stream (public for the byte-level tests).
  Bytes configure_bytes() const;
  Bytes frames_bytes(const std::vector<std::uint16_t>& words, bool wait_dr) const;
  int divisor() const;
  double actual_sck_hz() const { return 30e6 / (1 + divisor()); }

 private:
  std::vector<std::uint16_t> exchange(const Bytes& cmd, std::size_t nwords, int timeout_ms, bool* timed_out);
  std::unique_ptr<FtdiEndpoint> ep_;
  Ft232hConfig cfg_;
};

}  // namespace calbench::devices
