#include "devices/adis16488a_regs.hpp"

#include <array>
#include <cmath>
#include <stdexcept>

namespace calbench::devices::adis {
namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kG = 9.80665;
constexpr double kGyro32 = 0.02 / 65536.0 * kDeg;       // rad/s per LSB of OUT:LOW
constexpr double kAccel32 = 0.8e-3 / 65536.0 * kG;      // m/s² per LSB
constexpr double kDeltAng32 = 720.0 / 2147483648.0 * kDeg;  // rad
constexpr double kDeltVel32 = 200.0 / 2147483648.0;     // m/s
constexpr double kBaro32 = 40e-6 / 65536.0;             // bar
constexpr double kMag = 0.1e-3;                         // gauss
constexpr double kTemp = 0.00565;                       // °C per LSB, 0 = 25 °C
constexpr double kScaleLsb = 1.0 / 32768.0;             // user scale: dimensionless per LSB (assumed)

using A = Access;
using U = Unit;
// name, page, offset, width, signed, scale, unit, access, flash, reset value
constexpr std::array kRegs = {
    Reg{"PAGE_ID", 0, 0x00, 16, false, 0, U::none, A::rw, false, 0},
    Reg{"SEQ_CNT", 0, 0x06, 16, false, 0, U::count, A::r, false, 0},
    Reg{"SYS_E_FLAG", 0, 0x08, 16, false, 0, U::none, A::r, false, 0},
    Reg{"DIAG_STS", 0, 0x0A, 16, false, 0, U::none, A::r, false, 0},
    Reg{"ALM_STS", 0, 0x0C, 16, false, 0, U::none, A::r, false, 0},
    Reg{"TEMP_OUT", 0, 0x0E, 16, true, kTemp, U::celsius, A::r, false, 0},
    Reg{"X_GYRO", 0, 0x10, 32, true, kGyro32, U::rad_s, A::r, false, 0},
    Reg{"Y_GYRO", 0, 0x14, 32, true, kGyro32, U::rad_s, A::r, false, 0},
    Reg{"Z_GYRO", 0, 0x18, 32, true, kGyro32, U::rad_s, A::r, false, 0},
    Reg{"X_ACCL", 0, 0x1C, 32, true, kAccel32, U::m_s2, A::r, false, 0},
    Reg{"Y_ACCL", 0, 0x20, 32, true, kAccel32, U::m_s2, A::r, false, 0},
    Reg{"Z_ACCL", 0, 0x24, 32, true, kAccel32, U::m_s2, A::r, false, 0},
    Reg{"X_MAGN_OUT", 0, 0x28, 16, true, kMag, U::gauss, A::r, false, 0},
    Reg{"Y_MAGN_OUT", 0, 0x2A, 16, true, kMag, U::gauss, A::r, false, 0},
    Reg{"Z_MAGN_OUT", 0, 0x2C, 16, true, kMag, U::gauss, A::r, false, 0},
    Reg{"BAROM", 0, 0x2E, 32, true, kBaro32, U::bar, A::r, false, 0},
    Reg{"X_DELTANG", 0, 0x40, 32, true, kDeltAng32, U::rad, A::r, false, 0},
    Reg{"Y_DELTANG", 0, 0x44, 32, true, kDeltAng32, U::rad, A::r, false, 0},
    Reg{"Z_DELTANG", 0, 0x48, 32, true, kDeltAng32, U::rad, A::r, false, 0},
    Reg{"X_DELTVEL", 0, 0x4C, 32, true, kDeltVel32, U::m_s, A::r, false, 0},
    Reg{"Y_DELTVEL", 0, 0x50, 32, true, kDeltVel32, U::m_s, A::r, false, 0},
    Reg{"Z_DELTVEL", 0, 0x54, 32, true, kDeltVel32, U::m_s, A::r, false, 0},
    Reg{"PROD_ID", 0, 0x7E, 16, false, 0, U::none, A::r, false, kProdId},
    // Page 2: user calibration (flash-backed).
    Reg{"X_GYRO_SCALE", 2, 0x04, 16, true, kScaleLsb, U::none, A::rw, true, 0},
    Reg{"Y_GYRO_SCALE", 2, 0x06, 16, true, kScaleLsb, U::none, A::rw, true, 0},
    Reg{"Z_GYRO_SCALE", 2, 0x08, 16, true, kScaleLsb, U::none, A::rw, true, 0},
    Reg{"X_ACCL_SCALE", 2, 0x0A, 16, true, kScaleLsb, U::none, A::rw, true, 0},
    Reg{"Y_ACCL_SCALE", 2, 0x0C, 16, true, kScaleLsb, U::none, A::rw, true, 0},
    Reg{"Z_ACCL_SCALE", 2, 0x0E, 16, true, kScaleLsb, U::none, A::rw, true, 0},
    Reg{"XG_BIAS", 2, 0x10, 32, true, kGyro32, U::rad_s, A::rw, true, 0},
    Reg{"YG_BIAS", 2, 0x14, 32, true, kGyro32, U::rad_s, A::rw, true, 0},
    Reg{"ZG_BIAS", 2, 0x18, 32, true, kGyro32, U::rad_s, A::rw, true, 0},
    Reg{"XA_BIAS", 2, 0x1C, 32, true, kAccel32, U::m_s2, A::rw, true, 0},
    Reg{"YA_BIAS", 2, 0x20, 32, true, kAccel32, U::m_s2, A::rw, true, 0},
    Reg{"ZA_BIAS", 2, 0x24, 32, true, kAccel32, U::m_s2, A::rw, true, 0},
    Reg{"USER_SCR_1", 2, 0x74, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"USER_SCR_2", 2, 0x76, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"USER_SCR_3", 2, 0x78, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"USER_SCR_4", 2, 0x7A, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"FLSHCNT", 2, 0x7C, 32, false, 0, U::count, A::r, false, 0},
    // Page 3: control.
    Reg{"GLOB_CMD", 3, 0x02, 16, false, 0, U::none, A::w, false, 0},
    Reg{"FNCTIO_CTRL", 3, 0x06, 16, false, 0, U::none, A::rw, true, 0x000D},
    Reg{"GPIO_CTRL", 3, 0x08, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"CONFIG", 3, 0x0A, 16, false, 0, U::none, A::rw, true, 0x00C0},
    Reg{"DEC_RATE", 3, 0x0C, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"NULL_CNFG", 3, 0x0E, 16, false, 0, U::none, A::rw, true, 0x070A},
    Reg{"SLP_CNT", 3, 0x10, 16, false, 0, U::none, A::rw, false, 0},
    Reg{"FILTR_BNK_0", 3, 0x16, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"FILTR_BNK_1", 3, 0x18, 16, false, 0, U::none, A::rw, true, 0},
    Reg{"FIRM_REV", 3, 0x78, 16, false, 0, U::none, A::r, false, 0x0110},
    Reg{"FIRM_DM", 3, 0x7A, 16, false, 0, U::none, A::r, false, 0x0615},
    Reg{"FIRM_Y", 3, 0x7C, 16, false, 0, U::none, A::r, false, 0x2016},
    // Page 4.
    Reg{"SERIAL_NUM", 4, 0x20, 16, false, 0, U::none, A::r, false, 0},
};

std::string join_bits(std::uint16_t v, const std::array<const char*, 16>& names) {
  std::string s;
  for (int b = 0; b < 16; ++b) {
    if (!(v >> b & 1) || !names[b]) continue;
    if (!s.empty()) s += "; ";
    s += names[b];
  }
  return s;
}
}  // namespace

std::span<const Reg> registers() { return kRegs; }

const Reg& reg(std::string_view name) {
  for (const auto& r : kRegs)
    if (r.name == name) return r;
  throw std::out_of_range("ADIS16488A: no register named " + std::string(name));
}

std::optional<Reg> find(std::uint8_t page, std::uint8_t offset) {
  for (const auto& r : kRegs)
    if (r.page == page && offset >= r.offset && offset < r.offset + r.width / 8) return r;
  return std::nullopt;
}

std::string decode_sys_e_flag(std::uint16_t v) {
  static const std::array<const char*, 16> names = {
      "alarm (see ALM_STS)", nullptr, nullptr, "SPI communication error", "sensor over-range",
      "inertial self-test failure (see DIAG_STS)", "flash update failure", "processing overrun", nullptr,
      nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, "watchdog timer reset"};
  return join_bits(v & kSysErrorMask, names);
}

std::string decode_diag_sts(std::uint16_t v) {
  static const std::array<const char*, 16> names = {
      "X gyro self-test failed", "Y gyro self-test failed", "Z gyro self-test failed",
      "X accelerometer self-test failed", "Y accelerometer self-test failed", "Z accelerometer self-test failed",
      nullptr, nullptr, "X magnetometer self-test failed", "Y magnetometer self-test failed",
      "Z magnetometer self-test failed", "barometer self-test failed", nullptr, nullptr, nullptr, nullptr};
  return join_bits(v, names);
}

}  // namespace calbench::devices::adis
