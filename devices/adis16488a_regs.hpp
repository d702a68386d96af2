// ADIS16488A register map as data: every register the driver and the emulator use, with page,
// offset, width, scale to SI and access. Sources: ../shared/reference/hardware-notes.md §1
// (Linux adis16480.c, Makani adis16488 driver, ADI register tables). docs/devices.md lists it.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace calbench::devices::adis {

enum class Access { r, rw, w };
enum class Unit { none, rad_s, m_s2, celsius, rad, m_s, gauss, bar, count };

struct Reg {
  std::string_view name;
  std::uint8_t page;
  std::uint8_t offset;   // byte offset within the page (even). For 32-bit: the LOW word's offset.
  std::uint8_t width;    // 16 or 32 bits (32: LOW at offset, OUT/HIGH at offset+2)
  bool is_signed;
  double scale;          // SI per LSB of the full-width raw value (0 if not a physical quantity)
  Unit unit;
  Access access;
  bool flash_backed;     // saved by GLOB_CMD flash update, restored at reset
  std::uint16_t reset_value;  // of the (OUT/HIGH) word at power-up (factory default)
};

inline constexpr std::uint16_t kProdId = 0x4068;  // 16488
inline constexpr double kInternalRateHz = 2460.0;

std::span<const Reg> registers();
const Reg& reg(std::string_view name);  // throws std::out_of_range for an unknown name
std::optional<Reg> find(std::uint8_t page, std::uint8_t offset);  // register containing that byte

// Frames (hardware-notes §1.3). Reads are pipelined: the reply comes in the NEXT frame.
constexpr std::uint16_t read_frame(std::uint8_t offset) { return static_cast<std::uint16_t>((offset & 0x7E) << 8); }
constexpr std::uint16_t write_frame(std::uint8_t offset, std::uint8_t byte) {
  return static_cast<std::uint16_t>(0x8000 | (offset & 0x7F) << 8 | byte);
}
constexpr std::uint16_t page_frame(std::uint8_t page) { return write_frame(0x00, page); }

// SYS_E_FLAG and DIAG_STS decoded into words a person can act on.
std::string decode_sys_e_flag(std::uint16_t v);  // "" when no error bit is set
std::string decode_diag_sts(std::uint16_t v);
// Error bits of SYS_E_FLAG (everything except the new-mag/new-baro data flags 8, 9).
inline constexpr std::uint16_t kSysErrorMask = 0x80F9;
namespace sys_e {
inline constexpr std::uint16_t alarm = 1 << 0, spi_error = 1 << 3, over_range = 1 << 4, self_test = 1 << 5,
                               flash_update = 1 << 6, overrun = 1 << 7, new_mag = 1 << 8, new_baro = 1 << 9,
                               watchdog = 1 << 15;
}
namespace glob_cmd {
inline constexpr std::uint16_t bias_null = 1 << 0, self_test = 1 << 1, flash_test = 1 << 2,
                               flash_update = 1 << 3, factory_restore = 1 << 6, software_reset = 1 << 7;
// Minimum wait after each command before the next SPI access, seconds (hardware-notes §1.8).
inline constexpr double kSelfTestS = 0.012, kFlashTestS = 0.050, kFlashUpdateS = 0.375,
                        kFactoryRestoreS = 0.075, kResetS = 0.120;
}  // namespace glob_cmd

}  // namespace calbench::devices::adis
