// A multi-unit fixture on the table's inner platform (issue 21): its slots, each an IMU reached through
// a USB-SPI bridge (devices/imu_uri.hpp) with its nominal pose on the fixture. The fixture takes the
// cube's place in the plan: a plan's mounts name fixture axes. Format: docs/devices.md "Fixtures".
// One slot with an identity pose at the centre is today's single-unit station.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "calibration/bench_kinematics.hpp"
#include "devices/imu_uri.hpp"

namespace calbench::station {

struct FixtureSlot {
  std::string name;           // letters, digits, '-', '_' (a folder of the run's output)
  std::string imu;            // as written; empty: emulated (no bridge)
  devices::ImuUri uri;        // parsed imu
  Vec3 rotation_deg = Vec3::Zero();  // roll, pitch, yaw (z-y-x) of slot axes → fixture axes, as written
  SlotPose pose;              // C_f_s and r_f (SI)
  int line = 0;               // in the fixture file
};

struct Fixture {
  std::string name;
  std::string file;           // empty for a fixture made from --units
  std::vector<FixtureSlot> slots;
  bool has_slot(const std::string& slot) const {
    for (const auto& s : slots)
      if (s.name == slot) return true;
    return false;
  }
  std::string slot_names() const {  // "1, 2, 3": for messages
    std::string names;
    for (const auto& s : slots) names += (names.empty() ? "" : ", ") + s.name;
    return names;
  }
};

// Reads and checks a fixture file: InputError (exit 2) naming the file, line and key for bad input
// (duplicate slot names, two slots on one bridge (one bridge per unit), an IMU URI that does not
// parse or that the opener (devices/imu_open.hpp) cannot drive, a bridge without serial number among
// several of its kind, ...). The one place fixtures are checked: the same for an emulated and a real
// run, before either starts.
Fixture load_fixture(const std::filesystem::path& file);

// N emulated units (`station run --emulated --units N`): slot names "1".."N", evenly round the
// centre of the platform at 80 mm, each turned by 90° about z from the one before (so that the units'
// own axes see every direction of the fixture), no bridges.
Fixture emulated_fixture(int units);

// The default single slot: today's station (IMU at the centre, axes of the cube); its --imu checked
// as a fixture slot's.
Fixture single_unit_fixture(const std::string& imu_uri);

}  // namespace calbench::station
