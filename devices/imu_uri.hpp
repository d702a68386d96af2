// Where an IMU is: the USB-SPI bridge that reaches it and the chip select on that bridge.
//   KIND[:SERIAL][#csN]   or provision's form   KIND://[SERIAL][#csN]
// KIND: ft232h | mcp2210; SERIAL: the bridge's USB serial number (empty: the only one attached);
// N: the chip-select line of the bridge the unit sits on (default 0, the bridge's own CS pin).
// Units on one bridge with different chip selects share the bridge's time (docs/devices.md
// "Fixtures").
#pragma once
#include <string>

namespace calbench::devices {

struct ImuUri {
  std::string kind;    // "ft232h" | "mcp2210"
  std::string serial;  // may be empty
  int cs = 0;          // chip-select index on the bridge
  std::string bridge() const { return kind + ":" + serial; }  // one physical bridge
  std::string text() const;                                    // canonical KIND:SERIAL[#csN]
};

// Number of chip-select lines a bridge kind offers (FT232H: ADBUS3, ADBUS4, ADBUS6, ADBUS7 — ADBUS5 is
// the data-ready input; MCP2210: GP0–GP8).
int chip_selects(const std::string& kind);

// std::invalid_argument with the reason for anything else.
ImuUri parse_imu_uri(const std::string& uri);

}  // namespace calbench::devices
