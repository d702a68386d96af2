// IMU URIs (devices/imu_uri.hpp): the bridge kind, its serial number and the chip select, in the
// station's form KIND[:SERIAL][#csN] and provision's KIND://SERIAL; anything else refused with why.
#include <gtest/gtest.h>

#include "devices/imu_uri.hpp"

namespace calbench::devices {
namespace {

TEST(ImuUri, ParsesKindSerialAndChipSelect) {
  ImuUri u = parse_imu_uri("mcp2210");
  EXPECT_EQ(u.kind, "mcp2210");
  EXPECT_EQ(u.serial, "");
  EXPECT_EQ(u.cs, 0);
  u = parse_imu_uri("ft232h:FT7XK2#cs3");
  EXPECT_EQ(u.kind, "ft232h");
  EXPECT_EQ(u.serial, "FT7XK2");
  EXPECT_EQ(u.cs, 3);
  EXPECT_EQ(u.bridge(), "ft232h:FT7XK2");
  EXPECT_EQ(u.text(), "ft232h:FT7XK2#cs3");
  u = parse_imu_uri("mcp2210://0001234501");  // provision's form
  EXPECT_EQ(u.serial, "0001234501");
  EXPECT_EQ(u.text(), "mcp2210:0001234501");
  EXPECT_EQ(parse_imu_uri("mcp2210:A#cs8").cs, 8);
}

// Provision's emulated unit goes through the same parser (issue 35: one parser, one opener).
TEST(ImuUri, ParsesAnEmulatedUnitWithItsFaults) {
  ImuUri u = parse_imu_uri("emu://4660");
  EXPECT_TRUE(u.emulated());
  EXPECT_EQ(u.emu_serial, 4660);
  EXPECT_FALSE(u.emu_prod_id);
  EXPECT_FALSE(u.emu_flash_fails);
  u = parse_imu_uri("emu://0x1234?prod_id=0x4060&flash_fails=1");
  EXPECT_EQ(u.emu_serial, 0x1234);
  EXPECT_EQ(u.emu_prod_id.value_or(0), 0x4060);
  EXPECT_TRUE(u.emu_flash_fails);
  EXPECT_EQ(parse_imu_uri("ft232h://FT1#cs2").text(), "ft232h:FT1#cs2");
  for (const char* bad : {"emu://70000", "emu://x", "emu://-1", "emu://3?speed=2", "emu://3?prod_id=0x10000",
                          "emu://3#cs1", "mcp2210:A?prod_id=1", "usb://1", "emu:3"})
    EXPECT_THROW(parse_imu_uri(bad), std::invalid_argument) << bad;
}

TEST(ImuUri, RefusesWhatIsNotAnImuAddress) {
  for (const char* bad : {"", "spi0", "ft232h:bad serial", "ft232h#cs4", "mcp2210#cs9", "mcp2210#cs", "mcp2210#x1",
                          "mcp2210#cs-1", "mcp2210#cs1x", "usb:123"})
    EXPECT_THROW(parse_imu_uri(bad), std::invalid_argument) << bad;
  try {
    parse_imu_uri("ft232h#cs4");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cs0 to cs3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace calbench::devices
