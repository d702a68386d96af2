#include "devices/adis16488a.hpp"

#include <cmath>
#include <cstdio>

namespace calbench::devices {
namespace {
int bcd(unsigned v) { return static_cast<int>((v >> 4 & 0xF) * 10 + (v & 0xF)); }
std::int32_t to_i32(std::uint16_t hi, std::uint16_t lo) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(hi) << 16 | lo);
}
constexpr double kScaleLsb = 1.0 / 32768.0;
const double kGyroLsb = adis::reg("XG_BIAS").scale;
const double kAccelLsb = adis::reg("XA_BIAS").scale;

std::int16_t quant16(double v) { return static_cast<std::int16_t>(std::clamp(std::lround(v), -32768L, 32767L)); }
std::int32_t quant32(double v) {
  return static_cast<std::int32_t>(std::clamp<double>(std::round(v), -2147483648.0, 2147483647.0));
}

void triad_to_regs(const TriadErrors& t, double lsb, std::array<std::int16_t, 3>& scale,
                   std::array<std::int32_t, 3>& bias) {
  for (int i = 0; i < 3; ++i) {
    // (1 + s)(1 + m) = 1 cancels the scale error; B = −(1 + s)·b cancels the bias.
    scale[i] = quant16((1.0 / (1.0 + t.M(i, i)) - 1.0) / kScaleLsb);
    const double s = scale[i] * kScaleLsb;
    bias[i] = quant32(-(1.0 + s) * t.bias[i] / lsb);
  }
}
TriadErrors regs_to_triad(const std::array<std::int16_t, 3>& scale, const std::array<std::int32_t, 3>& bias, double lsb) {
  TriadErrors t;
  for (int i = 0; i < 3; ++i) {
    const double s = scale[i] * kScaleLsb;
    t.M(i, i) = 1.0 / (1.0 + s) - 1.0;
    t.bias[i] = -bias[i] * lsb / (1.0 + s);
  }
  return t;
}
TriadErrors residual(const TriadErrors& e, const std::array<std::int16_t, 3>& scale,
                     const std::array<std::int32_t, 3>& bias, double lsb) {
  TriadErrors r = e;
  Mat3 D = Mat3::Zero();
  Vec3 B;
  for (int i = 0; i < 3; ++i) {
    D(i, i) = 1.0 + scale[i] * kScaleLsb;
    B[i] = bias[i] * lsb;
  }
  r.M = D * (Mat3::Identity() + e.M) - Mat3::Identity();
  r.bias = D * e.bias + B;
  return r;
}
}  // namespace

UserCal user_cal_from_errors(const SensorErrors& e) {
  UserCal c;
  triad_to_regs(e.gyro, kGyroLsb, c.gyro_scale, c.gyro_bias);
  triad_to_regs(e.accel, kAccelLsb, c.accel_scale, c.accel_bias);
  return c;
}
SensorErrors errors_from_user_cal(const UserCal& r) {
  SensorErrors e;
  e.gyro = regs_to_triad(r.gyro_scale, r.gyro_bias, kGyroLsb);
  e.accel = regs_to_triad(r.accel_scale, r.accel_bias, kAccelLsb);
  return e;
}
SensorErrors residual_after_user_cal(const SensorErrors& e, const UserCal& r) {
  SensorErrors out;
  out.gyro = residual(e.gyro, r.gyro_scale, r.gyro_bias, kGyroLsb);
  out.accel = residual(e.accel, r.accel_scale, r.accel_bias, kAccelLsb);
  return out;
}

std::string ImuIdentity::firmware() const {
  char b[48];
  std::snprintf(b, sizeof b, "%x.%02x (%04x-%02x-%02x)", firm_rev >> 8, firm_rev & 0xFF, firm_y, firm_dm >> 8,
                firm_dm & 0xFF);
  (void)bcd;
  return b;
}
std::string ImuIdentity::serial_string() const {
  char b[16];
  std::snprintf(b, sizeof b, "%u", serial);
  return b;
}

Adis16488a::Adis16488a(SpiBus& bus, Adis16488aOptions opt) : bus_(bus), opt_(opt) {
  for (const char* n : {"SEQ_CNT", "SYS_E_FLAG", "DIAG_STS", "TEMP_OUT"}) sample_offsets_.push_back(adis::reg(n).offset);
  for (const char* n : {"X_GYRO", "Y_GYRO", "Z_GYRO", "X_ACCL", "Y_ACCL", "Z_ACCL"}) {
    const auto& r = adis::reg(n);
    sample_offsets_.push_back(static_cast<std::uint8_t>(r.offset + 2));  // OUT (high) first
    sample_offsets_.push_back(r.offset);                                   // then LOW
  }
}

void Adis16488a::select_page(std::uint8_t page) {
  if (page_ == page) return;
  bus_.transfer({adis::page_frame(page)});
  page_ = page;
}

std::vector<std::uint16_t> Adis16488a::read_words(std::uint8_t page, const std::vector<std::uint8_t>& offsets) {
  if (offsets.empty()) return {};
  select_page(page);
  std::vector<std::uint16_t> tx;
  tx.reserve(offsets.size() + 1);
  for (auto o : offsets) tx.push_back(adis::read_frame(o));
  tx.push_back(adis::read_frame(0x00));  // the extra frame that clocks out the last reply (reads PAGE_ID)
  auto rx = bus_.transfer(tx);
  if (rx.size() != tx.size()) throw SpiError("ADIS16488A: bus returned " + std::to_string(rx.size()) + " words for " +
                                             std::to_string(tx.size()) + " frames");
  return {rx.begin() + 1, rx.end()};  // reply to request k arrives in frame k+1
}

std::uint16_t Adis16488a::read16(const adis::Reg& r) { return read_words(r.page, {r.offset})[0]; }

std::uint32_t Adis16488a::read32(const adis::Reg& r) {
  auto w = read_words(r.page, {static_cast<std::uint8_t>(r.offset + 2), r.offset});
  return static_cast<std::uint32_t>(w[0]) << 16 | w[1];
}

void Adis16488a::write16(const adis::Reg& r, std::uint16_t v) {
  select_page(r.page);
  bus_.transfer({adis::write_frame(r.offset, v & 0xFF), adis::write_frame(static_cast<std::uint8_t>(r.offset + 1), v >> 8)});
}

void Adis16488a::write32(const adis::Reg& r, std::uint32_t v) {
  select_page(r.page);
  const auto o = r.offset;
  bus_.transfer({adis::write_frame(o, v & 0xFF), adis::write_frame(static_cast<std::uint8_t>(o + 1), v >> 8 & 0xFF),
                 adis::write_frame(static_cast<std::uint8_t>(o + 2), v >> 16 & 0xFF),
                 adis::write_frame(static_cast<std::uint8_t>(o + 3), v >> 24 & 0xFF)});
}

ImuIdentity Adis16488a::connect() {
  invalidate_page();  // unknown after power-up or a previous session
  ImuIdentity id;
  id.prod_id = read16(adis::reg("PROD_ID"));
  if (opt_.check_prod_id && id.prod_id != adis::kProdId) {
    char b[200];
    std::snprintf(b, sizeof b,
                  "ADIS16488A not found on %s: PROD_ID reads 0x%04X (%u), expected 0x4068 (16488). "
                  "Wrong part, wiring, SPI mode or no power.",
                  bus_.describe().c_str(), id.prod_id, id.prod_id);
    throw DeviceError(b);
  }
  auto p3 = read_words(3, {adis::reg("FIRM_REV").offset, adis::reg("FIRM_DM").offset, adis::reg("FIRM_Y").offset,
                           adis::reg("DEC_RATE").offset});
  id.firm_rev = p3[0];
  id.firm_dm = p3[1];
  id.firm_y = p3[2];
  id.dec_rate = p3[3];
  id.serial = read16(adis::reg("SERIAL_NUM"));
  id.output_rate_hz = adis::kInternalRateHz / (id.dec_rate + 1);
  period_ = 1.0 / id.output_rate_hz;
  id_ = id;
  have_last_ = false;
  return id;
}

void Adis16488a::set_dec_rate(int dec_rate) {
  if (dec_rate < 0 || dec_rate > 2047) throw std::invalid_argument("DEC_RATE must be 0..2047");
  write16(adis::reg("DEC_RATE"), static_cast<std::uint16_t>(dec_rate));
  const auto back = read16(adis::reg("DEC_RATE"));
  if (back != dec_rate) throw DeviceError("ADIS16488A: DEC_RATE reads back " + std::to_string(back) + " after writing " + std::to_string(dec_rate));
  id_.dec_rate = dec_rate;
  id_.output_rate_hz = adis::kInternalRateHz / (dec_rate + 1);
  period_ = 1.0 / id_.output_rate_hz;
  have_last_ = false;
}

void Adis16488a::glob_cmd(std::uint16_t bits, double wait_s) {
  // One low-byte write frame (all commands used are bits 0..7): a second frame for the high byte
  // would reach the part while it is already busy with the command.
  const auto& r = adis::reg("GLOB_CMD");
  select_page(r.page);
  bus_.transfer({adis::write_frame(r.offset, static_cast<std::uint8_t>(bits & 0xFF))});
  bus_.delay(wait_s);
}

SelfTestResult Adis16488a::self_test() {
  glob_cmd(adis::glob_cmd::self_test, adis::glob_cmd::kSelfTestS);
  auto w = read_words(0, {adis::reg("DIAG_STS").offset, adis::reg("SYS_E_FLAG").offset});
  SelfTestResult r;
  r.diag_sts = w[0];
  r.sys_e_flag = w[1];
  r.passed = (r.diag_sts & 0x003F) == 0 && !(r.sys_e_flag & adis::sys_e::self_test);
  if (!r.passed) {
    r.message = adis::decode_diag_sts(r.diag_sts);
    if (r.message.empty()) r.message = adis::decode_sys_e_flag(r.sys_e_flag);
  }
  return r;
}

void Adis16488a::software_reset() {
  glob_cmd(adis::glob_cmd::software_reset, adis::glob_cmd::kResetS);
  invalidate_page();
  have_last_ = false;
}

void Adis16488a::flash_update() {
  glob_cmd(adis::glob_cmd::flash_update, adis::glob_cmd::kFlashUpdateS);
  const auto f = read16(adis::reg("SYS_E_FLAG"));
  if (f & adis::sys_e::flash_update) throw DeviceError("ADIS16488A: flash update failed (SYS_E_FLAG bit 6)");
}

std::optional<ImuSample> Adis16488a::read_sample() {
  select_page(0);
  std::vector<std::uint16_t> tx;
  tx.reserve(sample_offsets_.size() + 1);
  for (auto o : sample_offsets_) tx.push_back(adis::read_frame(o));
  tx.push_back(adis::read_frame(0x00));
  auto rx = bus_.transfer_on_data_ready(tx, opt_.data_ready_timeout_s);
  if (!rx) return std::nullopt;
  if (rx->size() != tx.size()) throw SpiError("ADIS16488A: short transfer");
  const std::uint16_t* w = rx->data() + 1;
  ImuSample s;
  s.host_time = bus_.now();
  s.seq_cnt = w[0];
  s.sys_e_flag = w[1];
  s.diag_sts = w[2];
  s.temp_c = 25.0 + static_cast<std::int16_t>(w[3]) * adis::reg("TEMP_OUT").scale;
  const double gl = adis::reg("X_GYRO").scale, al = adis::reg("X_ACCL").scale;
  for (int i = 0; i < 3; ++i) {
    const auto g = to_i32(w[4 + 2 * i], w[5 + 2 * i]);
    const auto a = to_i32(w[10 + 2 * i], w[11 + 2 * i]);
    s.gyro[i] = g * gl;
    s.accel[i] = a * al;
    // Full scale: ±450 °/s ↔ ±22500·2¹⁶, ±18 g ↔ ±22500·2¹⁶ (hardware-notes §1.5).
    if (std::abs(static_cast<double>(g)) >= 22500.0 * 65536 || std::abs(static_cast<double>(a)) >= 22500.0 * 65536)
      s.saturated = true;
  }
  if (have_last_) {
    std::uint32_t steps;
    if (opt_.seq_cnt_loss_detection) {
      steps = static_cast<std::uint16_t>(s.seq_cnt - last_seq_);
    } else {
      steps = static_cast<std::uint32_t>(std::max(1L, std::lround((s.host_time - last_host_) / period_)));
    }
    if (steps == 0) steps = 1;  // same SEQ_CNT twice: the part repeated a sample; count time anyway
    s.lost_before = steps - 1;
    t_dev_ += steps * period_;
  } else {
    t_dev_ = 0;
  }
  s.t = t_dev_;
  have_last_ = true;
  last_seq_ = s.seq_cnt;
  last_host_ = s.host_time;
  ++samples_;
  lost_ += s.lost_before;
  if (s.error()) ++errors_;
  return s;
}

UserCal Adis16488a::read_user_cal() {
  std::vector<std::uint8_t> offs;
  for (const char* n : {"X_GYRO_SCALE", "Y_GYRO_SCALE", "Z_GYRO_SCALE", "X_ACCL_SCALE", "Y_ACCL_SCALE", "Z_ACCL_SCALE"})
    offs.push_back(adis::reg(n).offset);
  for (const char* n : {"XG_BIAS", "YG_BIAS", "ZG_BIAS", "XA_BIAS", "YA_BIAS", "ZA_BIAS"}) {
    offs.push_back(static_cast<std::uint8_t>(adis::reg(n).offset + 2));
    offs.push_back(adis::reg(n).offset);
  }
  auto w = read_words(2, offs);
  UserCal c;
  for (int i = 0; i < 3; ++i) {
    c.gyro_scale[i] = static_cast<std::int16_t>(w[i]);
    c.accel_scale[i] = static_cast<std::int16_t>(w[3 + i]);
    c.gyro_bias[i] = to_i32(w[6 + 2 * i], w[7 + 2 * i]);
    c.accel_bias[i] = to_i32(w[12 + 2 * i], w[13 + 2 * i]);
  }
  return c;
}

void Adis16488a::write_user_cal(const UserCal& c) {
  static const char* gs[] = {"X_GYRO_SCALE", "Y_GYRO_SCALE", "Z_GYRO_SCALE"};
  static const char* as[] = {"X_ACCL_SCALE", "Y_ACCL_SCALE", "Z_ACCL_SCALE"};
  static const char* gb[] = {"XG_BIAS", "YG_BIAS", "ZG_BIAS"};
  static const char* ab[] = {"XA_BIAS", "YA_BIAS", "ZA_BIAS"};
  for (int i = 0; i < 3; ++i) {
    write16(adis::reg(gs[i]), static_cast<std::uint16_t>(c.gyro_scale[i]));
    write16(adis::reg(as[i]), static_cast<std::uint16_t>(c.accel_scale[i]));
    write32(adis::reg(gb[i]), static_cast<std::uint32_t>(c.gyro_bias[i]));
    write32(adis::reg(ab[i]), static_cast<std::uint32_t>(c.accel_bias[i]));
  }
}

ProvisionResult Adis16488a::provision(const UserCal& c) {
  ProvisionResult r;
  r.written = c;
  r.flash_count_before = read32(adis::reg("FLSHCNT"));
  write_user_cal(c);
  flash_update();
  r.flash_count_after = read32(adis::reg("FLSHCNT"));
  r.read_back = read_user_cal();
  if (!(r.read_back == c)) {
    r.message = "user calibration registers read back different from what was written";
  } else if (r.flash_count_after <= r.flash_count_before) {
    r.message = "FLSHCNT did not increase: the flash update did not happen";
  } else {
    r.ok = true;
  }
  return r;
}

}  // namespace calbench::devices
