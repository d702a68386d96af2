// The two-axis rate table's Modbus holding-register map, as data (docs/devices.md "Rate table").
// Modelled on CiA 402 (hardware-notes §3.3). One block per axis: axis 0 = outer (along north) at
// 0x0000, axis 1 = inner (rate axis) at 0x0100. Angles in degrees and deg/s on the wire (the edge);
// SI (rad, rad/s) in the client's API. 32-bit values take two registers in a configurable word order.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace calbench::devices::table {

enum class Type { u16, i16, f32, i32, u32 };
enum class WordOrder { abcd, cdab };  // abcd: high word at the lower address; cdab: low word first

struct Reg {
  std::string_view name;
  std::uint16_t offset;  // from the axis base
  Type type;
  bool writable;
  std::string_view unit;
  std::string_view meaning;
};

inline constexpr std::uint16_t kAxisBase[2] = {0x0000, 0x0100};
inline constexpr std::uint16_t kBlockSize = 30;  // registers B+0 .. B+29, all readable in one FC03
inline constexpr int kAxes = 2;

std::span<const Reg> registers();
const Reg& reg(std::string_view name);  // throws std::out_of_range
inline std::uint16_t address(int axis, const Reg& r) { return static_cast<std::uint16_t>(kAxisBase[axis] + r.offset); }
inline int words(Type t) { return (t == Type::f32 || t == Type::i32 || t == Type::u32) ? 2 : 1; }

// CiA 402-style controlword / statusword bits, modes and fault codes.
namespace cw {
inline constexpr std::uint16_t switch_on = 1 << 0, enable_voltage = 1 << 1, quick_stop_n = 1 << 2,
                               enable_operation = 1 << 3, new_setpoint = 1 << 4, fault_reset = 1 << 7, halt = 1 << 8;
inline constexpr std::uint16_t kShutdown = 0x0006, kSwitchOn = 0x0007, kEnable = 0x000F, kDisable = 0x0006;
}  // namespace cw
namespace sw {
inline constexpr std::uint16_t ready = 1 << 0, switched_on = 1 << 1, operation_enabled = 1 << 2, fault = 1 << 3,
                               voltage_enabled = 1 << 4, quick_stop_n = 1 << 5, switch_on_disabled = 1 << 6,
                               warning = 1 << 7, remote = 1 << 9, target_reached = 1 << 10, limit_active = 1 << 11,
                               following_error = 1 << 13, estop = 1 << 14, interlock_open = 1 << 15;
}  // namespace sw
enum class Mode : std::int16_t { off = 0, position = 1, rate = 3 };
namespace fault {
inline constexpr std::uint16_t none = 0, over_speed = 1, encoder = 2, following_error = 3, estop = 4, comm_loss = 5;
}
inline constexpr std::uint16_t kEstopMagic = 0xA5A5;
std::string fault_text(std::uint16_t code);
std::string status_text(std::uint16_t statusword);

// 32-bit encodings done here (Debian's libmodbus 3.1.6 modbus_set_float_* are wrong, hardware-notes §4.2).
void put_u32(std::uint32_t v, WordOrder o, std::uint16_t* regs);
std::uint32_t get_u32(const std::uint16_t* regs, WordOrder o);
void put_f32(float v, WordOrder o, std::uint16_t* regs);
float get_f32(const std::uint16_t* regs, WordOrder o);
WordOrder parse_word_order(std::string_view s);  // "abcd" | "cdab"; throws std::invalid_argument

}  // namespace calbench::devices::table
