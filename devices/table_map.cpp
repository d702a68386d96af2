#include "devices/table_map.hpp"

#include <array>
#include <cstring>
#include <stdexcept>

namespace calbench::devices::table {
namespace {
using T = Type;
constexpr std::array kRegs = {
    Reg{"CONTROLWORD", 0, T::u16, true, "", "CiA402 bits: 0 switch on, 1 enable voltage, 2 quick stop (0 = stop), 3 enable operation, 7 fault reset (rising edge), 8 halt"},
    Reg{"MODE_OF_OPERATION", 1, T::i16, true, "", "0 off, 1 position, 3 rate"},
    Reg{"CMD_RATE", 2, T::f32, true, "deg/s", "commanded rate (rate mode)"},
    Reg{"CMD_POSITION", 4, T::f32, true, "deg", "commanded position (position mode), unwrapped"},
    Reg{"ACCEL_LIMIT", 6, T::f32, true, "deg/s^2", "acceleration limit"},
    Reg{"RATE_LIMIT", 8, T::f32, true, "deg/s", "rate limit (also the slew rate of position moves)"},
    Reg{"WATCHDOG", 10, T::u16, true, "", "heartbeat: the client changes it; unchanged for longer than the watchdog period while enabled -> stop, disable, fault 5"},
    Reg{"ESTOP_CMD", 11, T::u16, true, "", "0x0000 run; 0xA5A5 software E-stop of the whole table (latched until fault reset with ESTOP_CMD cleared)"},
    Reg{"STATUSWORD", 16, T::u16, false, "", "CiA402 bits 0-7; 10 target reached (in position / at rate, settled); 11 limit active; 13 following error; 14 E-stop active"},
    Reg{"MODE_DISPLAY", 17, T::i16, false, "", "active mode"},
    Reg{"FAULT_CODE", 18, T::u16, false, "", "0 none, 1 over-speed, 2 encoder, 3 following error, 4 E-stop, 5 communication loss (watchdog)"},
    Reg{"ACT_POSITION", 20, T::f32, false, "deg", "actual position (encoder), unwrapped"},
    Reg{"ACT_RATE", 22, T::f32, false, "deg/s", "actual rate (encoder)"},
    Reg{"POS_ERROR", 24, T::f32, false, "deg", "commanded minus actual position (position mode)"},
    Reg{"ENCODER_COUNTS", 26, T::i32, false, "counts", "raw encoder count"},
    Reg{"TIMESTAMP_MS", 28, T::u32, false, "ms", "controller time of this status"},
};
}  // namespace

std::span<const Reg> registers() { return kRegs; }
const Reg& reg(std::string_view name) {
  for (const auto& r : kRegs)
    if (r.name == name) return r;
  throw std::out_of_range("rate table: no register named " + std::string(name));
}

std::string fault_text(std::uint16_t code) {
  switch (code) {
    case fault::none: return "no fault";
    case fault::over_speed: return "over-speed";
    case fault::encoder: return "encoder fault";
    case fault::following_error: return "following error";
    case fault::estop: return "E-stop";
    case fault::comm_loss: return "communication loss (watchdog expired)";
    default: return "vendor fault " + std::to_string(code);
  }
}

std::string status_text(std::uint16_t s) {
  std::string t;
  auto add = [&](const char* x) { t += t.empty() ? x : std::string(", ") + x; };
  if (s & sw::fault) add("fault");
  if (s & sw::estop) add("E-stop");
  if (s & sw::following_error) add("following error");
  add((s & sw::operation_enabled) ? "enabled" : "disabled");
  if (s & sw::target_reached) add("target reached");
  if (s & sw::limit_active) add("limit active");
  return t;
}

void put_u32(std::uint32_t v, WordOrder o, std::uint16_t* regs) {
  const auto hi = static_cast<std::uint16_t>(v >> 16), lo = static_cast<std::uint16_t>(v & 0xFFFF);
  regs[0] = o == WordOrder::abcd ? hi : lo;
  regs[1] = o == WordOrder::abcd ? lo : hi;
}
std::uint32_t get_u32(const std::uint16_t* regs, WordOrder o) {
  const std::uint32_t a = regs[0], b = regs[1];
  return o == WordOrder::abcd ? (a << 16 | b) : (b << 16 | a);
}
void put_f32(float v, WordOrder o, std::uint16_t* regs) {
  std::uint32_t u;
  std::memcpy(&u, &v, 4);
  put_u32(u, o, regs);
}
float get_f32(const std::uint16_t* regs, WordOrder o) {
  const std::uint32_t u = get_u32(regs, o);
  float v;
  std::memcpy(&v, &u, 4);
  return v;
}
WordOrder parse_word_order(std::string_view s) {
  if (s == "abcd" || s == "ABCD") return WordOrder::abcd;
  if (s == "cdab" || s == "CDAB") return WordOrder::cdab;
  throw std::invalid_argument("word order must be abcd or cdab, not '" + std::string(s) + "'");
}

}  // namespace calbench::devices::table
