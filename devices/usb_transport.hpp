// The USB endpoints behind each bridge, as tiny interfaces, so that the bridges' protocol code can
// be tested byte for byte against fakes (tests/unit/devices/bridges_test.cpp).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace calbench::devices {

using Bytes = std::vector<std::uint8_t>;

// A HID device with 64-byte reports (MCP2210). write() takes the 64-byte report without the
// report-ID byte; read() returns a 64-byte report, or an empty vector on timeout.
class HidEndpoint {
 public:
  virtual ~HidEndpoint() = default;
  virtual void write(const Bytes& report) = 0;
  virtual Bytes read(int timeout_ms) = 0;
};

// An FTDI MPSSE channel: a byte stream out and in (FT232H).
class FtdiEndpoint {
 public:
  virtual ~FtdiEndpoint() = default;
  virtual void write(const Bytes& bytes) = 0;
  // Read exactly n bytes or fewer if timeout_ms passes.
  virtual Bytes read(std::size_t n, int timeout_ms) = 0;
  // Drop whatever is queued in both directions (after a timeout).
  virtual void purge() = 0;
};

// Real endpoints. `serial` empty = first device found. Throw SpiError if the device is absent.
std::unique_ptr<HidEndpoint> open_hidapi(std::uint16_t vid, std::uint16_t pid, const std::string& serial);
std::unique_ptr<FtdiEndpoint> open_libftdi(std::uint16_t vid, std::uint16_t pid, const std::string& serial);

}  // namespace calbench::devices
