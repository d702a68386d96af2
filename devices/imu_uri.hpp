// Where an IMU is: THE parser of IMU URIs (the station's --imu and fixture slots, provision's
// --to-device); devices/imu_open.hpp opens what it names.
//   KIND[:SERIAL][#csN]   or   KIND://[SERIAL][#csN]
// KIND: ft232h | mcp2210; SERIAL: the bridge's USB serial number (empty: the only one attached);
// N: the chip-select line of the bridge the unit sits on (default 0, the bridge's own CS pin).
// Units on one bridge with different chip selects share the bridge's time (docs/devices.md
// "Fixtures").
//   emu://SERIAL_NUM[?prod_id=N&flash_fails=1]
// an emulated ADIS16488A in this process, at rest (provision's tests and demos), with SERIAL_NUM
// (decimal or 0x…) and, optionally, the faults of its configuration (devices/adis16488a_emulator.hpp).
#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace calbench::devices {

struct ImuUri {
  std::string kind;    // "ft232h" | "mcp2210" | "emu"
  std::string serial;  // may be empty (a bridge); emu: SERIAL_NUM as written
  int cs = 0;          // chip-select index on the bridge
  // kind "emu": the unit's SERIAL_NUM and injected faults.
  std::uint16_t emu_serial = 0;
  std::optional<std::uint16_t> emu_prod_id;
  bool emu_flash_fails = false;
  bool emulated() const { return kind == "emu"; }
  std::string bridge() const { return kind + ":" + serial; }  // one physical bridge
  std::string text() const;                                    // canonical KIND:SERIAL[#csN]
};

// Number of chip-select lines a bridge kind offers (FT232H: ADBUS3, ADBUS4, ADBUS6, ADBUS7 — ADBUS5 is
// the data-ready input; MCP2210: GP0–GP8; an emulated unit: one).
int chip_selects(const std::string& kind);

// std::invalid_argument with the reason for anything else.
ImuUri parse_imu_uri(const std::string& uri);

}  // namespace calbench::devices
