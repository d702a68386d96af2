#include "devices/imu_open.hpp"

#include <stdexcept>

#include "common/noise_spec.hpp"
#include "devices/adis16488a_emulator.hpp"
#include "devices/emu_clock.hpp"
#include "devices/ft232h.hpp"
#include "devices/mcp2210.hpp"
#include "devices/usb_transport.hpp"

namespace calbench::devices {

std::string cannot_open(const ImuUri& u) {
  if (u.kind == "ft232h" && u.cs != 0)  // the bus drives ADBUS3 only (devices/ft232h.hpp)
    return std::string("'").append(u.text()).append("': the FT232H bus drives chip select cs0 (ADBUS3) only");
  return "";
}

std::unique_ptr<SpiBus> open_imu(const ImuUri& u) {
  if (const std::string why = cannot_open(u); !why.empty()) throw std::invalid_argument(why);
  if (u.emulated()) {
    Adis16488aEmulatorConfig cfg;
    cfg.serial = u.emu_serial;
    if (u.emu_prod_id) cfg.faults.prod_id = *u.emu_prod_id;
    cfg.faults.flash_update_fails = u.emu_flash_fails;
    const EmuPhysics still = [](double) {
      EmuTruth t;
      t.f_b = Vec3(0, 0, -9.80665);
      return t;
    };
    return std::make_unique<Adis16488aEmulator>(std::make_shared<VirtualClock>(), still, SensorErrors{},
                                                adis16488a_noise(), cfg);
  }
  if (u.kind == "ft232h") {
    auto bus = std::make_unique<Ft232hBus>(open_libftdi(mpsse::kVid, mpsse::kPid, u.serial));
    bus->configure();
    return bus;
  }
  Mcp2210Config mc;
  mc.cs_pin = u.cs;
  auto bus = std::make_unique<Mcp2210Bus>(open_hidapi(mcp2210::kVid, mcp2210::kPid, u.serial), mc);
  bus->configure();
  return bus;
}

}  // namespace calbench::devices
