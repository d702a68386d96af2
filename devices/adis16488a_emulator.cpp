#include "devices/adis16488a_emulator.hpp"

#include <cmath>

namespace calbench::devices {
namespace {
const double kGyroLsb = adis::reg("X_GYRO").scale;
const double kAccelLsb = adis::reg("X_ACCL").scale;
const double kDeltAngLsb = adis::reg("X_DELTANG").scale;
const double kDeltVelLsb = adis::reg("X_DELTVEL").scale;
constexpr double kScaleLsb = 1.0 / 32768.0;
std::int64_t clamp32(double v) {
  return static_cast<std::int64_t>(std::clamp(std::round(v), -2147483648.0, 2147483647.0));
}
}  // namespace

Adis16488aEmulator::Adis16488aEmulator(std::shared_ptr<EmuClock> clock, EmuPhysics physics, const SensorErrors& truth,
                                       const NoiseSpec& noise, Adis16488aEmulatorConfig cfg)
    : clock_(std::move(clock)), physics_(std::move(physics)), sim_(truth, noise, cfg.seed), cfg_(cfg), faults_(cfg.faults) {
  reset_registers(false);
  for (const auto& r : adis::registers())
    if (r.flash_backed)
      for (int k = 0; k < r.width / 16; ++k) flash_[index(r.page, static_cast<std::uint8_t>(r.offset + 2 * k))] =
                                                 ram_[index(r.page, static_cast<std::uint8_t>(r.offset + 2 * k))];
  next_tick_ = clock_->now() + period();
}

void Adis16488aEmulator::set32(std::uint8_t page, std::uint8_t offset, std::int64_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  ram_[index(page, offset)] = static_cast<std::uint16_t>(u & 0xFFFF);
  ram_[index(page, static_cast<std::uint8_t>(offset + 2))] = static_cast<std::uint16_t>(u >> 16);
}

void Adis16488aEmulator::reset_registers(bool from_flash) {
  ram_.fill(0);
  for (const auto& r : adis::registers()) {
    const auto hi = index(r.page, static_cast<std::uint8_t>(r.offset + (r.width == 32 ? 2 : 0)));
    ram_[hi] = r.reset_value;
    if (from_flash && r.flash_backed)
      for (int k = 0; k < r.width / 16; ++k) {
        const auto i = index(r.page, static_cast<std::uint8_t>(r.offset + 2 * k));
        ram_[i] = flash_[i];
      }
  }
  ram_[index(4, adis::reg("SERIAL_NUM").offset)] = cfg_.serial;
  set32(2, adis::reg("FLSHCNT").offset, flash_count_);
  page_ = 0;
  pending_ = 0;
  sticky_flags_ = 0;
  unread_ = false;
}

void Adis16488aEmulator::power_cycle() {
  reset_registers(true);
  next_tick_ = clock_->now() + period();
}

void Adis16488aEmulator::produce(double t) {
  if (unread_) ++overwritten_;
  const EmuTruth truth = physics_(t);
  const auto out = sim_.sample(t, truth.w_ib_b, truth.f_b);
  const double dt = period();
  bool over = out.saturated;
  for (int i = 0; i < 3; ++i) {
    // User calibration path (ASSUMED model): y = (1 + SCALE/2¹⁵)·raw + BIAS, in output LSBs.
    const auto s_g = static_cast<std::int16_t>(ram_[index(2, static_cast<std::uint8_t>(0x04 + 2 * i))]);
    const auto s_a = static_cast<std::int16_t>(ram_[index(2, static_cast<std::uint8_t>(0x0A + 2 * i))]);
    const auto b_g = static_cast<std::int32_t>(static_cast<std::uint32_t>(ram_[index(2, static_cast<std::uint8_t>(0x12 + 4 * i))]) << 16 |
                                               ram_[index(2, static_cast<std::uint8_t>(0x10 + 4 * i))]);
    const auto b_a = static_cast<std::int32_t>(static_cast<std::uint32_t>(ram_[index(2, static_cast<std::uint8_t>(0x1E + 4 * i))]) << 16 |
                                               ram_[index(2, static_cast<std::uint8_t>(0x1C + 4 * i))]);
    const double g = (1.0 + s_g * kScaleLsb) * (out.gyro[i] / kGyroLsb) + b_g;
    const double a = (1.0 + s_a * kScaleLsb) * (out.accel[i] / kAccelLsb) + b_a;
    const auto gq = clamp32(g), aq = clamp32(a);
    set32(0, static_cast<std::uint8_t>(0x10 + 4 * i), gq);
    set32(0, static_cast<std::uint8_t>(0x1C + 4 * i), aq);
    set32(0, static_cast<std::uint8_t>(0x40 + 4 * i), clamp32(gq * kGyroLsb * dt / kDeltAngLsb));
    set32(0, static_cast<std::uint8_t>(0x4C + 4 * i), clamp32(aq * kAccelLsb * dt / kDeltVelLsb));
  }
  ram_[index(0, 0x0E)] = static_cast<std::uint16_t>(
      static_cast<std::int16_t>(std::lround((cfg_.temperature_c - 25.0) / adis::reg("TEMP_OUT").scale)));
  ++seq_;
  ram_[index(0, 0x06)] = seq_;
  ram_[index(0, 0x08)] = static_cast<std::uint16_t>(fault_flags(t) | sticky_flags_ | (over ? adis::sys_e::over_range : 0));
  unread_ = true;
  last_dr_ = t;
  ++produced_;
}

void Adis16488aEmulator::advance_to(double t) {
  while (next_tick_ <= t) {
    ++tick_;
    const double tt = next_tick_;
    next_tick_ += period();
    if (tt < busy_until_) continue;  // no output while a command runs
    if (skip_every() > 0 && tick_ % static_cast<std::uint64_t>(skip_every()) == 0) {
      ++seq_;  // the part counted the sample but raised no data-ready
      continue;
    }
    produce(tt);
  }
}

bool Adis16488aEmulator::wait_data_ready(double timeout_s) {
  const double start = clock_->now();
  advance_to(start);
  // The next edge after `start`.
  double te = next_tick_;
  std::uint64_t k = tick_ + 1;
  const double p = period();
  for (int guard = 0; guard < 1'000'000; ++guard, ++k, te += p) {
    if (te < busy_until_) continue;
    if (skip_every() > 0 && k % static_cast<std::uint64_t>(skip_every()) == 0) continue;
    break;
  }
  if (te > start + timeout_s) {
    clock_->wait_until(start + timeout_s);
    advance_to(clock_->now());
    return false;
  }
  clock_->wait_until(te);
  advance_to(clock_->now());
  return true;
}

std::vector<std::uint16_t> Adis16488aEmulator::transfer(const std::vector<std::uint16_t>& words) {
  std::vector<std::uint16_t> out(words.size());
  const double frame_s = 16.0 / cfg_.sck_hz + stall_s_;
  for (std::size_t i = 0; i < words.size(); ++i) {
    clock_->elapse(frame_s);
    advance_to(clock_->now());
    out[i] = frame(words[i]);
  }
  return out;
}

std::uint16_t Adis16488aEmulator::frame(std::uint16_t w) {
  ++frames_;
  const std::uint16_t reply = pending_;
  if (clock_->now() < busy_until_) {  // the part does not listen while a command runs
    ++busy_violations_;
    pending_ = 0;
    return 0;
  }
  if (w & 0x8000) {
    if ((w >> 8 & 0x7F) != 0x00) ++write_frames_;
    write_byte(static_cast<std::uint8_t>(w >> 8 & 0x7F), static_cast<std::uint8_t>(w & 0xFF));
    pending_ = 0;
    return reply;
  }
  const auto off = static_cast<std::uint8_t>(w >> 8 & 0x7E);
  if (off == 0x00) {
    pending_ = page_;
  } else if (page_ > 12) {
    pending_ = 0;
  } else if (page_ == 0 && off == 0x7E) {
    pending_ = faults_.prod_id;
  } else if (page_ == 3 && off == 0x02) {
    pending_ = 0;  // GLOB_CMD reads 0 when no command runs
  } else {
    pending_ = ram_[index(page_, off)];
    if (page_ == 0 && off >= 0x10 && off < 0x28) unread_ = false;
  }
  return reply;
}

void Adis16488aEmulator::write_byte(std::uint8_t off, std::uint8_t byte) {
  if (off == 0x00) {
    page_ = byte;
    return;
  }
  if (page_ > 12) return;
  const auto r = adis::find(page_, off);
  if (!r || r->access == adis::Access::r) return;  // read-only or unmapped: ignored, as the part does
  if (page_ == 3 && r->name == "GLOB_CMD") {
    if (off == 0x02) command(byte);
    return;
  }
  auto& word = ram_[index(page_, off)];
  word = (off & 1) ? static_cast<std::uint16_t>((word & 0x00FF) | byte << 8)
                   : static_cast<std::uint16_t>((word & 0xFF00) | byte);
  if (page_ == 3 && r->name == "DEC_RATE") {
    if (ram_[index(3, 0x0C)] > 2047) ram_[index(3, 0x0C)] = 2047;
    next_tick_ = std::max(clock_->now(), last_dr_) + period();
  }
}

std::uint16_t Adis16488aEmulator::fault_flags(double t) const {
  if (!in_service() || (faults_.flags_from_s >= 0 && t < faults_.flags_from_s)) return 0;
  return faults_.sys_e_flag;
}

void Adis16488aEmulator::command(std::uint8_t bits) {
  const double t = clock_->now();
  double busy = 0;
  if (bits & adis::glob_cmd::software_reset) {
    reset_registers(true);
    busy = adis::glob_cmd::kResetS;
  }
  if (bits & adis::glob_cmd::factory_restore) {
    for (std::uint8_t o = 0x04; o < 0x28; o += 2) ram_[index(2, o)] = 0;
    busy = std::max(busy, adis::glob_cmd::kFactoryRestoreS);
  }
  if (bits & adis::glob_cmd::self_test) {
    ram_[index(0, 0x0A)] = faults_.self_test_diag;
    if (faults_.self_test_diag) sticky_flags_ |= adis::sys_e::self_test;
    else sticky_flags_ &= static_cast<std::uint16_t>(~adis::sys_e::self_test);
    ram_[index(0, 0x08)] = static_cast<std::uint16_t>(fault_flags(t) | sticky_flags_);
    self_tested_ = true;
    busy = std::max(busy, adis::glob_cmd::kSelfTestS);
  }
  if (bits & adis::glob_cmd::flash_update) {
    if (faults_.flash_update_fails) {
      sticky_flags_ |= adis::sys_e::flash_update;
    } else {
      for (const auto& r : adis::registers())
        if (r.flash_backed)
          for (int k = 0; k < r.width / 16; ++k) {
            const auto i = index(r.page, static_cast<std::uint8_t>(r.offset + 2 * k));
            flash_[i] = ram_[i];
          }
      ++flash_count_;
      set32(2, adis::reg("FLSHCNT").offset, flash_count_);
      sticky_flags_ &= static_cast<std::uint16_t>(~adis::sys_e::flash_update);
    }
    ram_[index(0, 0x08)] = static_cast<std::uint16_t>(fault_flags(t) | sticky_flags_);
    busy = std::max(busy, adis::glob_cmd::kFlashUpdateS);
  }
  if (busy > 0) busy_until_ = t + busy;
}

}  // namespace calbench::devices
