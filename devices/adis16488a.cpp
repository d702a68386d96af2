#include "devices/adis16488a.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace calbench::devices {
namespace {
int bcd(unsigned v) { return static_cast<int>((v >> 4 & 0xF) * 10 + (v & 0xF)); }
std::int32_t to_i32(std::uint16_t hi, std::uint16_t lo) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(hi) << 16 | lo);
}
constexpr double kScaleLsb = 1.0 / 32768.0;
const double kGyroLsb = adis::reg("XG_BIAS").scale;
const double kAccelLsb = adis::reg("XA_BIAS").scale;
// Register values that can cancel an error. SCALE = −32768 is a gain of 0: it would cancel no
// scale error, only silence the axis, so the usable range stops at −32767.
constexpr std::int64_t kScaleMin = -32767, kScaleMax = 32767;
constexpr std::int64_t kBiasMin = -2147483648LL, kBiasMax = 2147483647LL;
// Float rounding allowed on top of half an LSB in check_user_cal(), in LSBs and relative.
constexpr double kLsbSlack = 1e-6, kRelSlack = 4 * std::numeric_limits<double>::epsilon();

// std::lround(v) lies in [lo, hi] (lo < 0 < hi; halves round away from zero).
bool rounds_into(double v, std::int64_t lo, std::int64_t hi) {
  return std::isfinite(v) && v > static_cast<double>(lo) - 0.5 && v < static_cast<double>(hi) + 0.5;
}
// The SCALE register value, unrounded, that cancels scale error m: (1 + s)(1 + m) = 1.
double scale_lsb(double m) { return (1.0 / (1.0 + m) - 1.0) / kScaleLsb; }
// The BIAS register value, unrounded, that cancels b behind gain 1 + s: B = −(1 + s)·b.
double bias_lsb(double s, double b, double lsb) { return -(1.0 + s) * b / lsb; }

std::string scale_reg(bool gyro, int i) { return std::string(1, "XYZ"[i]) + (gyro ? "_GYRO_SCALE" : "_ACCL_SCALE"); }
std::string bias_reg(bool gyro, int i) { return std::string(1, "XYZ"[i]) + (gyro ? "G_BIAS" : "A_BIAS"); }
std::string m_name(bool gyro, int i, int j) {
  return std::string(gyro ? "gyro" : "accel") + " M[" + std::to_string(i) + "][" + std::to_string(j) + "]";
}
std::string b_name(bool gyro, int i) { return std::string(gyro ? "gyro" : "accel") + " bias[" + std::to_string(i) + "]"; }

std::int16_t quant16(double v) { return static_cast<std::int16_t>(std::lround(v)); }
std::int32_t quant32(double v) { return static_cast<std::int32_t>(std::llround(v)); }

void triad_misfits(const TriadErrors& t, bool gyro, double lsb, std::vector<RegisterMisfit>& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < 3; ++i) {
    const double m = t.M(i, i);
    const double v = std::isfinite(m) && 1.0 + m > 0 ? scale_lsb(m) : nan;
    // Open interval of M_ii whose register rounds into kScaleMin..kScaleMax.
    const double m_lo = 1.0 / (1.0 + (kScaleMax + 0.5) * kScaleLsb) - 1.0;
    const double m_hi = 1.0 / (1.0 + (kScaleMin - 0.5) * kScaleLsb) - 1.0;
    if (!rounds_into(v, kScaleMin, kScaleMax))
      out.push_back({m_name(gyro, i, i), scale_reg(gyro, i), m, v, kScaleMin, kScaleMax, m_lo, m_hi});
    if (!std::isfinite(v)) continue;  // no gain cancels it: the bias has no register value either
    const double s = rounds_into(v, kScaleMin, kScaleMax) ? std::lround(v) * kScaleLsb : v * kScaleLsb;
    const double vb = bias_lsb(s, t.bias[i], lsb);
    if (!rounds_into(vb, kBiasMin, kBiasMax))
      out.push_back({b_name(gyro, i), bias_reg(gyro, i), t.bias[i], std::isfinite(vb) ? vb : nan, kBiasMin, kBiasMax,
                     -(kBiasMax + 0.5) * lsb / (1.0 + s), -(kBiasMin - 0.5) * lsb / (1.0 + s)});
  }
}

void triad_to_regs(const TriadErrors& t, double lsb, std::array<std::int16_t, 3>& scale,
                   std::array<std::int32_t, 3>& bias) {
  for (int i = 0; i < 3; ++i) {
    // (1 + s)(1 + m) = 1 cancels the scale error; B = −(1 + s)·b cancels the bias. In range: checked.
    scale[i] = quant16(scale_lsb(t.M(i, i)));
    bias[i] = quant32(bias_lsb(scale[i] * kScaleLsb, t.bias[i], lsb));
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

void triad_checks(const TriadErrors& e, bool gyro, const std::array<std::int16_t, 3>& scale,
                  const std::array<std::int32_t, 3>& bias, double lsb, std::vector<CoefficientCheck>& out) {
  const TriadErrors unit = regs_to_triad(scale, bias, lsb);
  const TriadErrors res = residual(e, scale, bias, lsb);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      CoefficientCheck c;
      c.coefficient = m_name(gyro, i, j);
      c.approved = e.M(i, j);
      c.residual = res.M(i, j);
      if (i == j) {
        // Residual (1 + s)(1 + m) − 1 = δs·(1 + m): half an LSB of s, times 1 + m.
        c.reg = scale_reg(gyro, i);
        c.unit = unit.M(i, i);
        c.tolerance = (0.5 + kLsbSlack) * kScaleLsb * std::abs(1.0 + c.approved) + kRelSlack * (1.0 + std::abs(c.residual));
        c.ok = std::abs(c.residual) <= c.tolerance;
      } else {
        c.host_applied = true;  // the part holds no skews
        c.ok = true;
      }
      out.push_back(c);
    }
  for (int i = 0; i < 3; ++i) {
    CoefficientCheck c;
    c.coefficient = b_name(gyro, i);
    c.reg = bias_reg(gyro, i);
    c.approved = e.bias[i];
    c.unit = unit.bias[i];
    c.residual = res.bias[i];  // (1 + s)·b + B: half an LSB of B
    c.tolerance = (0.5 + kLsbSlack) * lsb + kRelSlack * std::abs((1.0 + scale[i] * kScaleLsb) * c.approved);
    c.ok = std::abs(c.residual) <= c.tolerance;
    out.push_back(c);
  }
}

std::string g6(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

std::string RegisterMisfit::text() const {
  const bool bias = coefficient.find("bias") != std::string::npos;
  const std::string unit = !bias ? "" : coefficient.rfind("gyro", 0) == 0 ? " rad/s" : " m/s²";
  std::string t = coefficient + " = " + g6(value) + unit + ": ";
  if (std::isnan(needed_lsb))
    t += "no " + reg + " value cancels it" + (bias ? "" : " (1 + " + coefficient.substr(coefficient.find('M')) + " must be finite and positive)");
  else
    t += reg + " would need " + g6(std::round(needed_lsb)) + " LSB, outside " + std::to_string(reg_min) + ".." + std::to_string(reg_max);
  return t + "; it holds " + g6(min) + " < " + coefficient + " < " + g6(max) + unit;
}

UserCalRangeError::UserCalRangeError(std::vector<RegisterMisfit> m)
    : std::invalid_argument([&] {
        std::string t = "the set does not fit the ADIS16488A's user calibration registers: ";
        for (std::size_t k = 0; k < m.size(); ++k) t += (k ? "; " : "") + m[k].text();
        return t;
      }()),
      misfits(std::move(m)) {}

std::vector<RegisterMisfit> user_cal_misfits(const SensorErrors& e) {
  std::vector<RegisterMisfit> out;
  triad_misfits(e.gyro, true, kGyroLsb, out);
  triad_misfits(e.accel, false, kAccelLsb, out);
  return out;
}

std::string CoefficientCheck::text() const {
  if (host_applied) return coefficient + ": applied by the host (" + g6(residual) + ")";
  return coefficient + ": the unit's " + reg + " cancels " + g6(unit) + ", the set's is " + g6(approved) + " (residual " +
         g6(residual) + ", allowed ±" + g6(tolerance) + ")";
}

std::vector<CoefficientCheck> check_user_cal(const SensorErrors& approved, const UserCal& r) {
  std::vector<CoefficientCheck> out;
  triad_checks(approved.gyro, true, r.gyro_scale, r.gyro_bias, kGyroLsb, out);
  triad_checks(approved.accel, false, r.accel_scale, r.accel_bias, kAccelLsb, out);
  return out;
}

UserCal user_cal_from_errors(const SensorErrors& e) {
  if (auto m = user_cal_misfits(e); !m.empty()) throw UserCalRangeError(std::move(m));
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
  r.wrote = true;
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

ProvisionResult Adis16488a::provision(const SensorErrors& approved) {
  if (auto misfits = user_cal_misfits(approved); !misfits.empty()) {
    ProvisionResult r;  // nothing sent to the unit
    r.message = UserCalRangeError(misfits).what();
    r.misfits = std::move(misfits);
    return r;
  }
  ProvisionResult r = provision(user_cal_from_errors(approved));
  // What the unit will apply, from the registers as read back, against the approved set.
  r.checks = check_user_cal(approved, r.read_back);
  std::string wrong;
  for (const auto& c : r.checks)
    if (!c.ok) wrong += (wrong.empty() ? "" : "; ") + c.text();
  if (!wrong.empty()) {
    r.message = "the unit would apply something other than the approved set: " + wrong +
                (r.message.empty() ? "" : " (and " + r.message + ")");
    r.ok = false;
  }
  return r;
}

}  // namespace calbench::devices
