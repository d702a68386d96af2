// Fixture files (bench/station/fixture.hpp): slots with IMU URIs and nominal poses; bad input named by
// file, line and key (duplicate slots, one chip select twice, a URI that does not parse, ...).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "bench/station/fixture.hpp"
#include "common/input_error.hpp"

namespace calbench::station {
namespace {

namespace fs = std::filesystem;

struct TempFile {
  fs::path path;
  explicit TempFile(const std::string& text) {
    path = fs::temp_directory_path() / ("calbench_fixture_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                        "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".toml");
    std::ofstream(path) << text;
  }
  ~TempFile() { fs::remove(path); }
};

InputError load_error(const std::string& text) {
  TempFile f(text);
  try {
    load_fixture(f.path);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), f.path.string());
    return e;
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return InputError("accepted");
}

TEST(Fixture, TheExampleFixtureReads) {
  const Fixture fx = load_fixture(fs::path(CALBENCH_SOURCE_DIR) / "bench/fixtures/quad-ft232h.toml");
  EXPECT_EQ(fx.name, "quad-ft232h");
  ASSERT_EQ(fx.slots.size(), 4u);
  EXPECT_EQ(fx.slots[1].name, "B");
  EXPECT_EQ(fx.slots[1].uri.kind, "ft232h");
  EXPECT_EQ(fx.slots[1].uri.serial, "FT4ZK1B");
  // Slot B: turned 90° about z (its x is the fixture's y), 80 mm along the fixture's y.
  EXPECT_LT((fx.slots[1].pose.C_f_s * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-12);
  EXPECT_LT((fx.slots[1].pose.r_f - Vec3(0, 0.08, 0)).norm(), 1e-15);
  EXPECT_GT(fx.slots[1].line, 1);
}

TEST(Fixture, BadInputNamesTheKey) {
  const std::string two = "[[slot]]\nname = \"a\"\nimu = \"mcp2210:S1\"\n[[slot]]\nname = \"%N\"\nimu = \"%U\"\n";
  auto with = [&](const std::string& name, const std::string& uri) {
    std::string t = two;
    t.replace(t.find("%N"), 2, name);
    t.replace(t.find("%U"), 2, uri);
    return t;
  };
  InputError e = load_error(with("a", "mcp2210:S2"));
  EXPECT_EQ(e.field(), "slot[2].name");
  EXPECT_NE(e.message().find("duplicate slot 'a'"), std::string::npos) << e.what();
  e = load_error(with("b", "mcp2210:S1"));  // the same bridge serial and chip select
  EXPECT_EQ(e.field(), "slot[2].imu");
  EXPECT_NE(e.message().find("two units on one chip select"), std::string::npos) << e.what();
  EXPECT_EQ(e.line(), 6u);
  e = load_error(with("b", "spi:/dev/spidev0.0"));
  EXPECT_EQ(e.field(), "slot[2].imu");
  e = load_error(with("b", "mcp2210"));  // one bridge named, one "the only one attached"
  EXPECT_EQ(e.field(), "slot[2].imu");
  e = load_error(with("b/c", "mcp2210:S2"));  // names a folder
  EXPECT_EQ(e.field(), "slot[2].name");
  e = load_error(two.substr(0, two.find("[[slot]]", 5)) + "offset_mm = [2000.0, 0.0, 0.0]\n");
  EXPECT_EQ(e.field(), "slot[1].offset_mm");
  e = load_error(two.substr(0, two.find("[[slot]]", 5)) + "offset = [1.0, 0.0, 0.0]\n");  // a typo
  EXPECT_NE(e.message().find("unknown key"), std::string::npos) << e.what();
  e = load_error(two.substr(0, two.find("[[slot]]", 5)) + "rotation_deg = [0.0, 0.0]\n");
  EXPECT_EQ(e.field(), "slot[1].rotation_deg");
  e = load_error("[fixture]\nname = \"empty\"\n");
  EXPECT_EQ(e.field(), "slot");
  e = load_error("[[slot]]\nname = \"a\"\n");
  EXPECT_EQ(e.field(), "slot[1].imu");
  e = load_error("[[slot]\n");
  EXPECT_GE(e.line(), 1u);
  std::string many;
  for (int k = 0; k < 17; ++k) many += "[[slot]]\nname = \"s" + std::to_string(k) + "\"\nimu = \"mcp2210:B" + std::to_string(k) + "\"\n";
  e = load_error(many);
  EXPECT_EQ(e.field(), "slot");
}

// Issue 35 item 4: what the hardware refuses is refused when the fixture is read, before any run
// (emulated or not): two units on one bridge (different chip selects), a chip select the FT232H
// bus cannot drive, an emulated unit as a slot; --imu alone the same.
TEST(Fixture, BridgeChecksAreTheFixturesForEveryRun) {
  const std::string two = "[[slot]]\nname = \"a\"\nimu = \"ft232h:FT4ZK1A#cs0\"\n[[slot]]\nname = \"b\"\nimu = \"%U\"\n";
  auto with = [&](const std::string& uri) {
    std::string t = two;
    t.replace(t.find("%U"), 2, uri);
    return t;
  };
  {
    TempFile ok(with("ft232h:FT4ZK1B"));  // each unit on its own bridge: read
    EXPECT_EQ(load_fixture(ok.path).slots.size(), 2u);
  }
  InputError e = load_error(with("ft232h:FT4ZK1A#cs1"));  // the fixture: one bridge, two chip selects
  EXPECT_EQ(e.field(), "slot[2].imu");
  EXPECT_NE(e.message().find("cs0 (ADBUS3) only"), std::string::npos) << e.what();
  e = load_error(with("ft232h:FT4ZK1B#cs2"));  // an FT232H of its own, but a chip select its bus cannot drive
  EXPECT_NE(e.message().find("cs0 (ADBUS3) only"), std::string::npos) << e.what();
  e = load_error("[[slot]]\nname = \"a\"\nimu = \"mcp2210:M1#cs0\"\n[[slot]]\nname = \"b\"\nimu = \"mcp2210:M1#cs1\"\n");
  EXPECT_EQ(e.field(), "imu");  // one MCP2210, two chip selects: one bridge per unit
  EXPECT_EQ(e.line(), 4u);
  EXPECT_NE(e.message().find("slots 'a' and 'b' share the bridge mcp2210:M1"), std::string::npos) << e.what();
  e = load_error(with("emu://5"));
  EXPECT_EQ(e.field(), "slot[2].imu");
  EXPECT_NE(e.message().find("--emulated"), std::string::npos) << e.what();
  for (const char* bad : {"ft232h#cs1", "emu://7"}) {
    try {
      single_unit_fixture(bad);
      ADD_FAILURE() << "--imu " << bad << " accepted";
    } catch (const InputError& x) {
      EXPECT_EQ(x.file(), "--imu") << x.what();
    }
  }
  EXPECT_EQ(single_unit_fixture("mcp2210:M1#cs3").slots.front().uri.cs, 3);
}

TEST(Fixture, EmulatedUnitsAreRoundTheCentreAndTurned) {
  const Fixture fx = emulated_fixture(8);
  ASSERT_EQ(fx.slots.size(), 8u);
  for (std::size_t k = 0; k < fx.slots.size(); ++k) {
    EXPECT_NEAR(fx.slots[k].pose.r_f.norm(), 0.08, 1e-12);
    EXPECT_NEAR(fx.slots[k].pose.C_f_s.determinant(), 1.0, 1e-12);
    EXPECT_EQ(fx.slots[k].name, std::to_string(k + 1));
  }
  EXPECT_LT((fx.slots[1].pose.C_f_s * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-12);
}

}  // namespace
}  // namespace calbench::station
