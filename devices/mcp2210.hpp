// Microchip MCP2210 USB-to-SPI bridge (HID, 64-byte reports) as an SpiBus.
// Protocol facts: ../shared/reference/hardware-notes.md §2.1; docs/devices.md "MCP2210".
// One 0x42 (transfer SPI data) command per 16-bit word, because the MCP2210 keeps CS asserted for
// the whole configured transaction: at ~1 ms per USB round trip this suits configuration, identity
// and provisioning, not 2460 Hz streaming (use the FT232H for that).
#pragma once
#include <memory>

#include "devices/spi_bus.hpp"
#include "devices/usb_transport.hpp"

namespace calbench::devices {

namespace mcp2210 {
inline constexpr std::uint16_t kVid = 0x04D8, kPid = 0x00DE;
inline constexpr std::uint8_t kGetEventCount = 0x12, kSetChipSettings = 0x21, kSetSpiSettings = 0x40,
                              kTransferSpi = 0x42, kCancelSpi = 0x11;
// Response status byte (byte 1).
inline constexpr std::uint8_t kOk = 0x00, kBusNotAvailable = 0xF7, kTransferInProgress = 0xF8,
                              kUnknownCommand = 0xF9, kEepromWriteFailure = 0xFA, kBlocked = 0xFB,
                              kRejected = 0xFC, kWrongPassword = 0xFD;
// SPI engine status (byte 3 of the 0x42 response).
inline constexpr std::uint8_t kEngineFinished = 0x10, kEngineStarted = 0x20, kEngineDataAvailable = 0x30;
std::string status_text(std::uint8_t status);
}  // namespace mcp2210

struct Mcp2210Config {
  std::uint32_t bit_rate = 3'000'000;  // bps (bridge maximum 12 MHz)
  int cs_pin = 0;                      // GP0..GP8 used as chip select (active low)
  bool event_counter_dr = true;        // ADIS data-ready wired to GP6 (event counter, rising edges)
  int timeout_ms = 100;                // per USB report
  int max_polls = 16;                  // 0x42 re-polls while the engine reports "not finished"
};

class Mcp2210Bus : public SpiBus {
 public:
  Mcp2210Bus(std::unique_ptr<HidEndpoint> ep, Mcp2210Config cfg = {});
  // Sends the chip settings (CS pin, GP6 event counter) and the SPI transfer settings.
  void configure();

  std::vector<std::uint16_t> transfer(const std::vector<std::uint16_t>& words) override;
  // Polls the GP6 event counter (0x12) until it is non-zero; resets it. Counts > 1 mean missed
  // data-ready pulses, reported by missed_edges().
  bool wait_data_ready(double timeout_s) override;
  void set_stall(double seconds) override;
  std::string describe() const override { return "mcp2210"; }
  std::uint64_t missed_edges() const { return missed_edges_; }

  // Exact 64-byte reports (public for the byte-level tests).
  Bytes spi_settings_report() const;
  Bytes chip_settings_report() const;
  static Bytes transfer_report(const Bytes& data);

 private:
  Bytes command(const Bytes& report);
  std::uint16_t transfer_word(std::uint16_t w);
  std::unique_ptr<HidEndpoint> ep_;
  Mcp2210Config cfg_;
  std::uint64_t missed_edges_ = 0;
};

}  // namespace calbench::devices
