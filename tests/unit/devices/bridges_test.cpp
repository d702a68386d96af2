// Byte-level tests of the USB-SPI bridges against fakes of their USB endpoints: the exact reports /
// MPSSE byte streams for a register read, a write and a page switch, and the decoding of replies
// and of the bridges' error statuses.
#include <gtest/gtest.h>

#include <deque>

#include "devices/adis16488a.hpp"
#include "devices/ft232h.hpp"
#include "devices/mcp2210.hpp"

using namespace calbench::devices;

namespace {

struct FakeHid : HidEndpoint {
  std::vector<Bytes>* written;
  std::deque<Bytes>* replies;
  FakeHid(std::vector<Bytes>* w, std::deque<Bytes>* r) : written(w), replies(r) {}
  void write(const Bytes& report) override { written->push_back(report); }
  Bytes read(int) override {
    if (replies->empty()) return {};
    Bytes r = replies->front();
    replies->pop_front();
    return r;
  }
};

Bytes hid_reply(std::uint8_t cmd, std::uint8_t status, std::uint8_t engine, Bytes data) {
  Bytes r(64, 0);
  r[0] = cmd;
  r[1] = status;
  r[2] = static_cast<std::uint8_t>(data.size());
  r[3] = engine;
  for (std::size_t i = 0; i < data.size(); ++i) r[4 + i] = data[i];
  return r;
}

Bytes xfer(std::uint8_t hi, std::uint8_t lo) {
  Bytes r(64, 0);
  r[0] = 0x42;
  r[1] = 2;
  r[4] = hi;
  r[5] = lo;
  return r;
}

struct Mcp : ::testing::Test {
  std::vector<Bytes> written;
  std::deque<Bytes> replies;
  Mcp2210Bus bus{std::make_unique<FakeHid>(&written, &replies)};
};

TEST_F(Mcp, SpiSettingsReportIsExact) {
  Bytes r = bus.spi_settings_report();
  ASSERT_EQ(r.size(), 64u);
  EXPECT_EQ(r[0], 0x40);
  // 3 000 000 bps little-endian = 0x002DC6C0
  EXPECT_EQ(r[4], 0xC0); EXPECT_EQ(r[5], 0xC6); EXPECT_EQ(r[6], 0x2D); EXPECT_EQ(r[7], 0x00);
  EXPECT_EQ(r[8], 0xFF); EXPECT_EQ(r[9], 0x01);    // idle CS all high
  EXPECT_EQ(r[10], 0xFE); EXPECT_EQ(r[11], 0x01);  // GP0 low when active
  EXPECT_EQ(r[18], 2); EXPECT_EQ(r[19], 0);        // 2 bytes per CS frame
  EXPECT_EQ(r[20], 3);                             // mode 3
  Bytes c = bus.chip_settings_report();
  EXPECT_EQ(c[0], 0x21);
  EXPECT_EQ(c[4], 0x01);       // GP0 chip select
  EXPECT_EQ(c[10], 0x02);      // GP6 event counter
  EXPECT_EQ(c[17], 2 << 1);    // rising edges
}

TEST_F(Mcp, RegisterReadIsPageSwitchThenPipelinedFrames) {
  Adis16488a imu(bus);
  replies = {hid_reply(0x42, 0, 0x10, {0x00, 0x00}),   // page switch frame
             hid_reply(0x42, 0, 0x10, {0x12, 0x34}),   // request PROD_ID (reply belongs to nothing)
             hid_reply(0x42, 0, 0x10, {0x40, 0x68})};  // dummy frame carries PROD_ID
  EXPECT_EQ(imu.read16(calbench::devices::adis::reg("PROD_ID")), 0x4068);
  ASSERT_EQ(written.size(), 3u);
  EXPECT_EQ(written[0], xfer(0x80, 0x00));  // PAGE_ID ← 0
  EXPECT_EQ(written[1], xfer(0x7E, 0x00));  // read 0x7E
  EXPECT_EQ(written[2], xfer(0x00, 0x00));  // dummy read of PAGE_ID
  // Cached page: a second read on page 0 sends no page frame.
  written.clear();
  replies = {hid_reply(0x42, 0, 0x10, {0, 0}), hid_reply(0x42, 0, 0x10, {0x00, 0x2A})};
  EXPECT_EQ(imu.read16(calbench::devices::adis::reg("SEQ_CNT")), 0x002A);
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(written[0], xfer(0x06, 0x00));
}

TEST_F(Mcp, WriteIsTwoByteFramesAfterPageSwitch) {
  Adis16488a imu(bus);
  for (int i = 0; i < 3; ++i) replies.push_back(hid_reply(0x42, 0, 0x10, {0, 0}));
  imu.write16(calbench::devices::adis::reg("DEC_RATE"), 0x0103);
  ASSERT_EQ(written.size(), 3u);
  EXPECT_EQ(written[0], xfer(0x80, 0x03));  // page 3
  EXPECT_EQ(written[1], xfer(0x8C, 0x03));  // low byte to 0x0C
  EXPECT_EQ(written[2], xfer(0x8D, 0x01));  // high byte to 0x0D
  EXPECT_EQ(imu.cached_page(), 3);
}

TEST_F(Mcp, EngineNotFinishedIsPolledWithEmptyTransfers) {
  replies = {hid_reply(0x42, 0, 0x20, {}), hid_reply(0x42, 0, 0x30, {0xAB}), hid_reply(0x42, 0, 0x10, {0xCD})};
  auto rx = bus.transfer({0x1234});
  ASSERT_EQ(rx.size(), 1u);
  EXPECT_EQ(rx[0], 0xABCD);
  ASSERT_EQ(written.size(), 3u);
  EXPECT_EQ(written[0], xfer(0x12, 0x34));
  Bytes empty(64, 0);
  empty[0] = 0x42;
  EXPECT_EQ(written[1], empty);
  EXPECT_EQ(written[2], empty);
}

TEST_F(Mcp, ErrorStatusesAreDecoded) {
  replies = {hid_reply(0x42, 0xF7, 0, {})};
  try {
    bus.transfer({0x0000});
    FAIL() << "no exception";
  } catch (const SpiError& e) {
    EXPECT_NE(std::string(e.what()).find("SPI bus not available"), std::string::npos) << e.what();
  }
  replies = {hid_reply(0x40, 0xFC, 0, {}), hid_reply(0x40, 0, 0, {})};
  replies.front()[0] = 0x21;
  EXPECT_THROW(bus.configure(), SpiError);
  // No reply at all: a timeout error naming the command.
  replies.clear();
  try {
    bus.transfer({0x0000});
    FAIL();
  } catch (const SpiError& e) {
    EXPECT_NE(std::string(e.what()).find("0x42"), std::string::npos) << e.what();
  }
  // Wrong echo.
  replies = {hid_reply(0x41, 0, 0x10, {0, 0})};
  EXPECT_THROW(bus.transfer({0x0000}), SpiError);
  EXPECT_EQ(mcp2210::status_text(0xF8), "USB/SPI transfer in progress (0xF8)");
}

TEST_F(Mcp, DataReadyFromEventCounterCountsMissedEdges) {
  Bytes r = hid_reply(0x12, 0, 0, {});
  r[4] = 3;  // three rising edges since the last look: two missed
  replies = {hid_reply(0x12, 0, 0, {}), r};
  EXPECT_TRUE(bus.wait_data_ready(1.0));
  EXPECT_EQ(bus.missed_edges(), 2u);
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(written[0][0], 0x12);
  EXPECT_EQ(written[0][1], 0x00);  // read and reset
}

struct FakeFtdi : FtdiEndpoint {
  std::vector<Bytes>* written;
  std::deque<Bytes>* replies;
  int* purges;
  FakeFtdi(std::vector<Bytes>* w, std::deque<Bytes>* r, int* p) : written(w), replies(r), purges(p) {}
  void write(const Bytes& b) override { written->push_back(b); }
  Bytes read(std::size_t n, int) override {
    if (replies->empty()) return {};
    Bytes r = replies->front();
    replies->pop_front();
    if (r.size() > n) r.resize(n);
    return r;
  }
  void purge() override { ++*purges; }
};

struct Ftdi : ::testing::Test {
  std::vector<Bytes> written;
  std::deque<Bytes> replies;
  int purges = 0;
  Ft232hBus bus{std::make_unique<FakeFtdi>(&written, &replies, &purges)};
};

// One CS frame: CS low, clock 2 bytes out/in (mode 3, MSB first), CS high.
Bytes frame(std::uint8_t hi, std::uint8_t lo) { return {0x80, 0x01, 0x0B, 0x31, 0x01, 0x00, hi, lo, 0x80, 0x09, 0x0B}; }
const Bytes kStall = {0x8F, 0x05, 0x00, 0x8E, 0x01};  // 5 µs at 10 MHz = 50 clocks = 6 bytes + 2 bits

TEST_F(Ftdi, ConfigureBytesAreExact) {
  EXPECT_EQ(bus.divisor(), 2);  // 30 MHz/(1+2) = 10 MHz
  bus.configure();
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0], (Bytes{0x8A, 0x97, 0x8D, 0x85, 0x86, 0x02, 0x00, 0x80, 0x09, 0x0B}));
}

TEST_F(Ftdi, RegisterReadIsOneUsbWritePerTransfer) {
  Adis16488a imu(bus);
  replies = {{0x00, 0x00}, {0x12, 0x34, 0x40, 0x68}};
  EXPECT_EQ(imu.read16(calbench::devices::adis::reg("PROD_ID")), 0x4068);
  ASSERT_EQ(written.size(), 2u);
  Bytes page = frame(0x80, 0x00);
  page.push_back(0x87);
  EXPECT_EQ(written[0], page);
  Bytes read = frame(0x7E, 0x00);
  read.insert(read.end(), kStall.begin(), kStall.end());
  Bytes dummy = frame(0x00, 0x00);
  read.insert(read.end(), dummy.begin(), dummy.end());
  read.push_back(0x87);
  EXPECT_EQ(written[1], read);
}

TEST_F(Ftdi, WriteAndPageSwitch) {
  Adis16488a imu(bus);
  replies = {{0, 0}, {0, 0, 0, 0}};
  imu.write16(calbench::devices::adis::reg("X_GYRO_SCALE"), 0xFF80);
  Bytes page = frame(0x80, 0x02);
  page.push_back(0x87);
  EXPECT_EQ(written[0], page);
  Bytes w = frame(0x84, 0x80);
  w.insert(w.end(), kStall.begin(), kStall.end());
  Bytes h = frame(0x85, 0xFF);
  w.insert(w.end(), h.begin(), h.end());
  w.push_back(0x87);
  EXPECT_EQ(written[1], w);
}

TEST_F(Ftdi, DataReadyWaitIsQueuedInTheSameWrite) {
  replies = {{0xAA, 0xBB, 0xCC, 0xDD}};
  auto rx = bus.transfer_on_data_ready({0x0600, 0x0000}, 0.01);
  ASSERT_TRUE(rx.has_value());
  EXPECT_EQ((*rx)[0], 0xAABB);
  EXPECT_EQ((*rx)[1], 0xCCDD);
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0][0], 0x89);  // wait DR low
  EXPECT_EQ(written[0][1], 0x88);  // then high: a rising edge
  EXPECT_EQ(written[0][2], 0x80);
  // Timeout: nothing comes back → purge, re-configure, nullopt.
  written.clear();
  EXPECT_FALSE(bus.transfer_on_data_ready({0x0600}, 0.01).has_value());
  EXPECT_GE(purges, 1);
  EXPECT_EQ(written.back()[0], 0x8A);  // configuration re-sent
}

TEST_F(Ftdi, BadCommandEchoAndShortRepliesAreErrors) {
  replies = {{0xFA, 0x31}};
  try {
    bus.transfer({0x0000, 0x0000});
    FAIL();
  } catch (const SpiError& e) {
    EXPECT_NE(std::string(e.what()).find("0x31"), std::string::npos) << e.what();
  }
  replies = {{0x01}};
  EXPECT_THROW(bus.transfer({0x0000}), SpiError);
}

}  // namespace
