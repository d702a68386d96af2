#include "devices/mcp2210.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

namespace calbench::devices {

std::string mcp2210::status_text(std::uint8_t s) {
  switch (s) {
    case kOk: return "completed";
    case kBusNotAvailable: return "SPI bus not available (0xF7: external master owns the bus)";
    case kTransferInProgress: return "USB/SPI transfer in progress (0xF8)";
    case kUnknownCommand: return "unknown command (0xF9)";
    case kEepromWriteFailure: return "EEPROM write failure (0xFA)";
    case kBlocked: return "access blocked / password protected (0xFB)";
    case kRejected: return "access rejected (0xFC)";
    case kWrongPassword: return "wrong password (0xFD)";
    default: {
      char b[48];
      std::snprintf(b, sizeof b, "unknown status 0x%02X", s);
      return b;
    }
  }
}

Mcp2210Bus::Mcp2210Bus(std::unique_ptr<HidEndpoint> ep, Mcp2210Config cfg) : ep_(std::move(ep)), cfg_(cfg) {}

Bytes Mcp2210Bus::spi_settings_report() const {
  Bytes r(64, 0);
  r[0] = mcp2210::kSetSpiSettings;
  for (int i = 0; i < 4; ++i) r[4 + i] = static_cast<std::uint8_t>(cfg_.bit_rate >> (8 * i));  // LE
  const std::uint16_t cs = static_cast<std::uint16_t>(1u << cfg_.cs_pin);
  const std::uint16_t idle = 0x01FF, active = static_cast<std::uint16_t>(idle & ~cs);
  r[8] = idle & 0xFF;   r[9] = idle >> 8;       // idle CS values (all high)
  r[10] = active & 0xFF; r[11] = active >> 8;   // active CS values (our CS low)
  // CS→data, data→CS and inter-byte delays: 100 µs quanta. The inter-word stall is the CS-high
  // time between two 0x42 commands (≥ one USB round trip ≈ 1 ms ≫ 5 µs); 0 here.
  r[12] = r[13] = r[14] = r[15] = r[16] = r[17] = 0;
  r[18] = 2; r[19] = 0;  // bytes per SPI transaction: one 16-bit word per CS frame
  r[20] = 3;             // SPI mode 3
  return r;
}

Bytes Mcp2210Bus::chip_settings_report() const {
  Bytes r(64, 0);
  r[0] = mcp2210::kSetChipSettings;
  for (int gp = 0; gp < 9; ++gp) r[4 + gp] = 0x00;  // GPIO
  r[4 + cfg_.cs_pin] = 0x01;                           // chip select
  if (cfg_.event_counter_dr) r[4 + 6] = 0x02;          // GP6 dedicated function: event counter
  r[13] = 0xFF; r[14] = 0x01;                          // default outputs high
  r[15] = 0xFF; r[16] = 0x01;                          // default directions: inputs
  r[17] = cfg_.event_counter_dr ? static_cast<std::uint8_t>(2 << 1) : 0;  // interrupt mode: rising edges
  return r;
}

Bytes Mcp2210Bus::transfer_report(const Bytes& data) {
  if (data.size() > 60) throw SpiError("mcp2210: more than 60 bytes in one transfer command");
  Bytes r(64, 0);
  r[0] = mcp2210::kTransferSpi;
  r[1] = static_cast<std::uint8_t>(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) r[4 + i] = data[i];
  return r;
}

Bytes Mcp2210Bus::command(const Bytes& report) {
  ep_->write(report);
  Bytes rsp = ep_->read(cfg_.timeout_ms);
  if (rsp.empty()) {
    char b[80];
    std::snprintf(b, sizeof b, "mcp2210: no response to command 0x%02X within %d ms", report[0], cfg_.timeout_ms);
    throw SpiError(b);
  }
  if (rsp.size() < 4 || rsp[0] != report[0]) {
    char b[80];
    std::snprintf(b, sizeof b, "mcp2210: bad response to command 0x%02X (echo 0x%02X)", report[0],
                  rsp.empty() ? 0 : rsp[0]);
    throw SpiError(b);
  }
  return rsp;
}

void Mcp2210Bus::configure() {
  for (const Bytes& r : {chip_settings_report(), spi_settings_report()}) {
    Bytes rsp = command(r);
    if (rsp[1] != mcp2210::kOk) throw SpiError("mcp2210: configuration rejected: " + mcp2210::status_text(rsp[1]));
  }
}

std::uint16_t Mcp2210Bus::transfer_word(std::uint16_t w) {
  Bytes data{static_cast<std::uint8_t>(w >> 8), static_cast<std::uint8_t>(w & 0xFF)};  // MSB first
  Bytes received;
  Bytes report = transfer_report(data);
  for (int poll = 0; poll <= cfg_.max_polls; ++poll) {
    Bytes rsp = command(report);
    if (rsp[1] == mcp2210::kTransferInProgress) {
      report = transfer_report({});  // engine busy: poll with no new data
      continue;
    }
    if (rsp[1] != mcp2210::kOk) throw SpiError("mcp2210: SPI transfer failed: " + mcp2210::status_text(rsp[1]));
    const std::size_t n = rsp[2];
    if (n > 60 || 4 + n > rsp.size()) throw SpiError("mcp2210: bad received-byte count");
    received.insert(received.end(), rsp.begin() + 4, rsp.begin() + 4 + static_cast<long>(n));
    if (rsp[3] == mcp2210::kEngineFinished) {
      if (received.size() != 2) throw SpiError("mcp2210: expected 2 received bytes, got " + std::to_string(received.size()));
      return static_cast<std::uint16_t>(received[0] << 8 | received[1]);
    }
    report = transfer_report({});  // 0x20 started / 0x30 partial: keep collecting
  }
  throw SpiError("mcp2210: SPI transfer did not finish after " + std::to_string(cfg_.max_polls) + " polls");
}

std::vector<std::uint16_t> Mcp2210Bus::transfer(const std::vector<std::uint16_t>& words) {
  std::vector<std::uint16_t> out;
  out.reserve(words.size());
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0 && stall_s_ > 1e-3) delay(stall_s_ - 1e-3);  // a USB round trip already gives ≥1 ms
    out.push_back(transfer_word(words[i]));
  }
  return out;
}

void Mcp2210Bus::set_stall(double seconds) { stall_s_ = seconds; }

bool Mcp2210Bus::wait_data_ready(double timeout_s) {
  if (!cfg_.event_counter_dr) throw SpiError("mcp2210: data-ready needs the GP6 event counter");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  do {
    Bytes r(64, 0);
    r[0] = mcp2210::kGetEventCount;
    r[1] = 0x00;  // reset the counter after reading it
    Bytes rsp = command(r);
    if (rsp[1] != mcp2210::kOk) throw SpiError("mcp2210: event count failed: " + mcp2210::status_text(rsp[1]));
    const unsigned count = static_cast<unsigned>(rsp[4] | rsp[5] << 8);
    if (count > 0) {
      missed_edges_ += count - 1;
      return true;
    }
  } while (std::chrono::steady_clock::now() < deadline);
  return false;
}

}  // namespace calbench::devices
