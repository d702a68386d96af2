#include "devices/ft232h.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace calbench::devices {

Ft232hBus::Ft232hBus(std::unique_ptr<FtdiEndpoint> ep, Ft232hConfig cfg) : ep_(std::move(ep)), cfg_(cfg) {}

int Ft232hBus::divisor() const {
  // SCK = 60 MHz / ((1 + div)·2) with the ÷5 prescaler off; the smallest div not exceeding sck_hz.
  const int d = static_cast<int>(std::ceil(30e6 / cfg_.sck_hz - 1.0 - 1e-9));
  return std::clamp(d, 0, 0xFFFF);
}

Bytes Ft232hBus::configure_bytes() const {
  using namespace mpsse;
  const int d = divisor();
  return {kDisableDiv5, kDisableAdaptive, kDisable3Phase, kLoopbackOff,
          kSetDivisor, static_cast<std::uint8_t>(d & 0xFF), static_cast<std::uint8_t>(d >> 8),
          kSetLowBits, kPinSck | kPinCs, kDirection};  // idle: SCK high (mode 3), CS high
}

void Ft232hBus::configure() { ep_->write(configure_bytes()); }

Bytes Ft232hBus::frames_bytes(const std::vector<std::uint16_t>& words, bool wait_dr) const {
  using namespace mpsse;
  Bytes b;
  b.reserve(words.size() * 16 + 4);
  if (wait_dr) {  // rising edge of DR on GPIOL1: wait low, then wait high
    b.push_back(kWaitIoLow);
    b.push_back(kWaitIoHigh);
  }
  // Stall as dummy clocks with CS high: 8 clocks per byte (0x8F n-1), remainder bits (0x8E n-1).
  const long clocks = std::lround(std::ceil(stall_s_ * actual_sck_hz() - 1e-9));
  const long nbytes = clocks / 8, nbits = clocks % 8;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0) {
      if (nbytes > 0) {
        b.push_back(kClockBytes);
        b.push_back(static_cast<std::uint8_t>((nbytes - 1) & 0xFF));
        b.push_back(static_cast<std::uint8_t>((nbytes - 1) >> 8));
      }
      if (nbits > 0) {
        b.push_back(kClockBits);
        b.push_back(static_cast<std::uint8_t>(nbits - 1));
      }
    }
    b.insert(b.end(), {kSetLowBits, kPinSck, kDirection});  // CS low
    b.insert(b.end(), {kWriteReadBytesMode3, 0x01, 0x00,    // 2 bytes, MSB first
                       static_cast<std::uint8_t>(words[i] >> 8), static_cast<std::uint8_t>(words[i] & 0xFF)});
    b.insert(b.end(), {kSetLowBits, kPinSck | kPinCs, kDirection});  // CS high
  }
  b.push_back(kSendImmediate);
  return b;
}

std::vector<std::uint16_t> Ft232hBus::exchange(const Bytes& cmd, std::size_t nwords, int timeout_ms,
                                               bool* timed_out) {
  ep_->write(cmd);
  Bytes rx = ep_->read(2 * nwords, timeout_ms);
  if (rx.size() >= 2 && rx[0] == mpsse::kBadCommand && rx.size() < 2 * nwords) {
    char b[80];
    std::snprintf(b, sizeof b, "ft232h: MPSSE rejected opcode 0x%02X (bad command)", rx[1]);
    ep_->purge();
    throw SpiError(b);
  }
  if (rx.size() != 2 * nwords) {
    ep_->purge();
    if (timed_out && rx.empty()) {
      *timed_out = true;
      return {};
    }
    throw SpiError("ft232h: expected " + std::to_string(2 * nwords) + " bytes, got " + std::to_string(rx.size()) +
                   " within " + std::to_string(timeout_ms) + " ms");
  }
  std::vector<std::uint16_t> out(nwords);
  for (std::size_t i = 0; i < nwords; ++i) out[i] = static_cast<std::uint16_t>(rx[2 * i] << 8 | rx[2 * i + 1]);
  return out;
}

std::vector<std::uint16_t> Ft232hBus::transfer(const std::vector<std::uint16_t>& words) {
  if (words.empty()) return {};
  return exchange(frames_bytes(words, false), words.size(), cfg_.timeout_ms, nullptr);
}

std::optional<std::vector<std::uint16_t>> Ft232hBus::transfer_on_data_ready(const std::vector<std::uint16_t>& words,
                                                                            double timeout_s) {
  bool timed_out = false;
  auto out = exchange(frames_bytes(words, true), words.size(), static_cast<int>(std::ceil(timeout_s * 1000)),
                      &timed_out);
  if (timed_out) {
    // The MPSSE is still waiting on GPIOL1: purge and re-send the configuration.
    ep_->purge();
    configure();
    return std::nullopt;
  }
  return out;
}

bool Ft232hBus::wait_data_ready(double timeout_s) {
  using namespace mpsse;
  // Wait for the edge, then read the pins once so there is a reply to wait for.
  bool timed_out = false;
  ep_->write({kWaitIoLow, kWaitIoHigh, 0x81, kSendImmediate});
  Bytes rx = ep_->read(1, static_cast<int>(std::ceil(timeout_s * 1000)));
  timed_out = rx.empty();
  if (timed_out) {
    ep_->purge();
    configure();
    return false;
  }
  return true;
}

}  // namespace calbench::devices
