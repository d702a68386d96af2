// Every path out of a station run that did not complete commands the table to stop (issue 35: keep and
// verify it). The station runs against a real table emulator on loopback (its own thread, real
// time) whose watchdog is long, so that only the station's stop — not the watchdog — can disable the
// axes; the IMU is the emulated one, following the table.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <sstream>

#include "bench/station/station.hpp"
#include "devices/table_emulator.hpp"
#include "tests/support/temp_dir.hpp"

namespace calbench::station {
namespace {

struct AbortRig {
  test::TempDir dir;
  devices::TableEmulator table{[] {
    devices::TableEmulatorConfig c;
    c.watchdog_s = 600;  // never within a test: a disabled axis was disabled by the station
    return c;
  }()};
  Options o;
  std::ostringstream log;
  AbortRig() {
    table.start();
    const auto plan = dir.path() / "plan.toml";
    std::ofstream(plan) << "[plan]\nname = \"one\"\n[site]\nlat_deg = 52.0\nlon_deg = 13.0\nh_m = 40.0\n"
                           "[table]\nsettle_s = 0.1\n[[step]]\nkind = \"static\"\nmount = \"z\"\n"
                           "outer_deg = 0.0\ninner_deg = 0.0\ndwell_s = 0.5\n";
    o.plan_file = plan;
    o.table_uri = table.uri();
    o.emulated = true;
    o.out_dir = dir.path() / "out";
  }
  ~AbortRig() { table.stop(); }
  void expect_stopped(const Result& r) {
    EXPECT_EQ(r.exit_code, 1) << r.message << "\n" << log.str();
    EXPECT_TRUE(r.summary.value("table_stopped", false)) << r.message;
    EXPECT_NE(r.message.find("table stopped and disabled"), std::string::npos) << r.message;
    EXPECT_FALSE(table.enabled(0));
    EXPECT_FALSE(table.enabled(1));
  }
};

TEST(StationAbort, InterruptedRunStopsTheTable) {
  AbortRig rig;
  const std::atomic<bool> stop{true};  // Ctrl-C before the first step: the axes are enabled by then
  const Result r = run(rig.o, rig.log, stop);
  EXPECT_NE(r.message.find("interrupted"), std::string::npos) << r.message;
  rig.expect_stopped(r);
}

TEST(StationAbort, AStepThatFailsItsCheckStopsTheTable) {
  AbortRig rig;
  rig.o.max_repeats = 0;
  rig.o.inject.imu.sys_e_flag = 0x0008;  // every sample flagged once the unit runs
  const std::atomic<bool> stop{false};
  const Result r = run(rig.o, rig.log, stop);
  EXPECT_NE(r.message.find("failed 1 times"), std::string::npos) << r.message;
  rig.expect_stopped(r);
}

// A unit that fails its self-test ends the run before the axes are enabled (connected, told to stop).
TEST(StationAbort, AFailedSelfTestEndsTheRunBeforeTheTableIsEnabled) {
  AbortRig rig;
  rig.o.inject.imu.self_test_diag = 0x0001;
  const std::atomic<bool> stop{false};
  const Result r = run(rig.o, rig.log, stop);
  EXPECT_NE(r.message.find("self-test failed"), std::string::npos) << r.message;
  rig.expect_stopped(r);
  EXPECT_EQ(rig.log.str().find("[step"), std::string::npos) << rig.log.str();  // no step began
}

}  // namespace
}  // namespace calbench::station
