// THE opener of an IMU's bus from its URI (devices/imu_uri.hpp), for the station and for provision:
// the bridge (FT232H via libftdi1, MCP2210 via hidapi) configured for the unit's chip select, or an
// emulated unit at rest (emu://, with the faults its URI names).
#pragma once
#include <memory>
#include <string>

#include "devices/imu_uri.hpp"
#include "devices/spi_bus.hpp"

namespace calbench::devices {

// Why this opener cannot drive the unit the URI names ("" when it can): checked, with the URI alone,
// before anything is opened or moved (a fixture's slots are checked with it before any run).
std::string cannot_open(const ImuUri& u);

// The unit's bus, configured. std::invalid_argument for what cannot_open() names; SpiError /
// std::runtime_error when the bridge is absent or refuses.
std::unique_ptr<SpiBus> open_imu(const ImuUri& u);

}  // namespace calbench::devices
