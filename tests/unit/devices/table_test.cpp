// The rate-table Modbus client against the table emulator on loopback (ephemeral ports, bounded
// loops, explicit timeouts): float encoding, URIs, rate and position moves, settling, watchdog,
// E-stop, reconnection, stalls, a vanished server, fault injection, word order.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "devices/table_client.hpp"
#include "devices/table_emulator.hpp"

using namespace calbench::devices;
using Clock = std::chrono::steady_clock;

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;

TEST(TableMap, FloatEncodingBothWordOrdersRoundTrip) {
  std::uint16_t w[2];
  table::put_f32(123456.0f, table::WordOrder::abcd, w);
  EXPECT_EQ(w[0], 0x47F1);
  EXPECT_EQ(w[1], 0x2000);
  table::put_f32(123456.0f, table::WordOrder::cdab, w);
  EXPECT_EQ(w[0], 0x2000);
  EXPECT_EQ(w[1], 0x47F1);
  for (auto o : {table::WordOrder::abcd, table::WordOrder::cdab})
    for (float v : {0.0f, -0.0f, 1.0f, -360.5f, 3.14159265f, 1e-30f, -7.25e12f, 0.001f}) {
      table::put_f32(v, o, w);
      const float back = table::get_f32(w, o);
      EXPECT_EQ(std::memcmp(&back, &v, 4), 0) << v;
    }
  table::put_u32(0x12345678u, table::WordOrder::cdab, w);
  EXPECT_EQ(w[0], 0x5678);
  EXPECT_EQ(table::get_u32(w, table::WordOrder::cdab), 0x12345678u);
  EXPECT_THROW(table::parse_word_order("badc"), std::invalid_argument);
}

TEST(TableMap, UriParsing) {
  auto t = parse_table_uri("modbus-tcp://127.0.0.1:1502?order=cdab&slave=3");
  EXPECT_TRUE(t.tcp);
  EXPECT_EQ(t.host, "127.0.0.1");
  EXPECT_EQ(t.port, 1502);
  EXPECT_EQ(t.slave, 3);
  EXPECT_EQ(t.order, table::WordOrder::cdab);
  auto r = parse_table_uri("modbus-rtu:/dev/ttyUSB0?baud=38400&parity=E");
  EXPECT_FALSE(r.tcp);
  EXPECT_EQ(r.device, "/dev/ttyUSB0");
  EXPECT_EQ(r.baud, 38400);
  EXPECT_EQ(r.parity, 'E');
  EXPECT_THROW(parse_table_uri("modbus-tcp://host"), std::invalid_argument);
  EXPECT_THROW(parse_table_uri("modbus-tcp://host:99999"), std::invalid_argument);
  EXPECT_THROW(parse_table_uri("http://x:1"), std::invalid_argument);
  EXPECT_THROW(parse_table_uri("modbus-rtu:/dev/x?parity=Q"), std::invalid_argument);
  EXPECT_THROW(parse_table_uri("modbus-tcp://h:1?order=xyz"), std::invalid_argument);
}

// Emulator at 10× real time so moves and the watchdog take tens of milliseconds.
struct Table : ::testing::Test {
  TableEmulatorConfig cfg = [] {
    TableEmulatorConfig c;
    c.watchdog_s = 0.5;
    return c;
  }();
  std::unique_ptr<TableEmulator> emu;
  std::unique_ptr<TableClient> cli;
  void SetUp() override { start(); }
  void start(table::WordOrder order = table::WordOrder::abcd) {
    cfg.order = order;
    emu = std::make_unique<TableEmulator>(cfg, std::make_shared<WallClock>(10.0));
    emu->start();
    TableClientOptions o;
    o.response_timeout_s = 0.1;
    o.retries = 2;
    o.reconnect_backoff_s = 0.01;
    cli = std::make_unique<TableClient>(parse_table_uri(emu->uri()), o);
    cli->connect();
  }
  void TearDown() override {
    cli.reset();
    emu.reset();
  }
  // Poll until pred(status) or `wall_s` passes.
  template <class P>
  bool wait_for(int axis, P pred, double wall_s, AxisStatus* last = nullptr) {
    const auto end = Clock::now() + std::chrono::duration<double>(wall_s);
    while (Clock::now() < end) {
      auto s = cli->status(axis);
      if (last) *last = s;
      if (pred(s)) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
  }
};

TEST_F(Table, RateModeReachesTheRateAndSettles) {
  EXPECT_GT(emu->port(), 0);
  cli->start_heartbeat(0.01);
  cli->set_limits(1, 100 * kDeg, 200 * kDeg);
  cli->set_mode(1, table::Mode::rate);
  cli->command_rate(1, 30 * kDeg);
  cli->enable(1);
  AxisStatus s;
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.settled(); }, 3.0, &s));
  EXPECT_TRUE(s.enabled());
  EXPECT_NEAR(s.rate, 30 * kDeg, 1e-3 * kDeg);  // encoder-derived, quantised
  const auto st = emu->axis_state(1, emu->clock().now());
  EXPECT_NEAR(st.rate, 30 * kDeg, 30 * kDeg * 1e-5);  // true rate incl. ripple
  EXPECT_NEAR(st.accel, 0.0, 1e-9);
  // A rate above the limit is clamped and flagged.
  cli->command_rate(1, 500 * kDeg);
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.statusword & table::sw::limit_active; }, 2.0, &s));
  cli->stop_heartbeat();
}

TEST_F(Table, PositionMoveSettlesOnTarget) {
  cli->start_heartbeat(0.01);
  cli->set_limits(0, 200 * kDeg, 90 * kDeg);
  cli->set_mode(0, table::Mode::position);
  cli->command_position(0, 90 * kDeg);
  cli->enable(0);
  AxisStatus s;
  ASSERT_TRUE(wait_for(0, [](const AxisStatus& x) { return x.settled(); }, 3.0, &s));
  EXPECT_NEAR(s.position, 90 * kDeg, 1e-4);
  EXPECT_NEAR(s.encoder, (1 << 24) / 4, 2);
  EXPECT_NEAR(s.pos_error, 0.0, 1e-4);
  EXPECT_GT(s.timestamp_ms, 0u);
  cli->stop_heartbeat();
}

TEST_F(Table, WatchdogStopsAndDisablesWithoutHeartbeat) {
  cli->set_mode(1, table::Mode::rate);
  cli->command_rate(1, 50 * kDeg);
  cli->enable(1);
  AxisStatus s;
  // 0.5 s emulated = 50 ms wall at 10×: well within the bound.
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.faulted(); }, 2.0, &s));
  EXPECT_EQ(s.fault_code, table::fault::comm_loss);
  EXPECT_FALSE(s.enabled());
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.rate == 0.0; }, 2.0, &s));
  EXPECT_EQ(table::fault_text(s.fault_code), "communication loss (watchdog expired)");
}

TEST_F(Table, EstopStopsEverythingUntilReset) {
  cli->start_heartbeat(0.01);
  cli->set_mode(1, table::Mode::rate);
  cli->command_rate(1, 100 * kDeg);
  cli->enable(1);
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.rate > 50 * kDeg; }, 2.0));
  cli->estop();
  AxisStatus s;
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.rate == 0.0 && x.faulted(); }, 2.0, &s));
  EXPECT_EQ(s.fault_code, table::fault::estop);
  EXPECT_TRUE(s.statusword & table::sw::estop);
  EXPECT_TRUE(cli->status(0).faulted());
  // Enable refuses while latched... enable() resets the fault (clearing ESTOP_CMD) first.
  cli->enable(1);
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.enabled() && !x.faulted(); }, 2.0, &s));
  cli->stop_heartbeat();
}

TEST_F(Table, ReconnectsAfterTheServerDropsTheConnection) {
  cli->status(0);
  emu->drop_connections();
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  const auto r0 = cli->reconnects();
  EXPECT_NO_THROW(cli->status(0));
  EXPECT_GE(cli->reconnects(), r0 + 1);
  EXPECT_GE(cli->retries_used(), 1u);
}

TEST_F(Table, StalledServerTimesOutThenRecovers) {
  emu->stall_for(0.8);
  const auto t0 = Clock::now();
  EXPECT_THROW(cli->status(0), TableError);
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_LT(dt, 0.7);  // 3 attempts × 0.1 s timeout + back-off
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_NO_THROW(cli->status(0));
}

TEST_F(Table, VanishedServerFailsFastAndStopAllReportsIt) {
  emu->stop();
  const auto t0 = Clock::now();
  try {
    cli->status(0);
    FAIL();
  } catch (const TableError& e) {
    EXPECT_NE(std::string(e.what()).find(emu->uri().substr(0, 20)), std::string::npos) << e.what();
  }
  EXPECT_FALSE(cli->stop_all());
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 1.5);
}

TEST_F(Table, FollowingErrorInjection) {
  cli->start_heartbeat(0.01);
  cli->set_mode(0, table::Mode::rate);
  cli->command_rate(0, 10 * kDeg);
  cli->enable(0);
  ASSERT_TRUE(wait_for(0, [](const AxisStatus& x) { return x.enabled(); }, 2.0));
  emu->inject_following_error(0);
  AxisStatus s;
  ASSERT_TRUE(wait_for(0, [](const AxisStatus& x) { return x.faulted(); }, 2.0, &s));
  EXPECT_EQ(s.fault_code, table::fault::following_error);
  EXPECT_TRUE(s.statusword & table::sw::following_error);
  cli->stop_heartbeat();
}

TEST_F(Table, ExceptionRepliesAreNotRetried) {
  const auto r0 = cli->retries_used();
  try {
    cli->read_registers(0x0200, 4);
    FAIL();
  } catch (const TableError& e) {
    EXPECT_NE(std::string(e.what()).find("Illegal data address"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cli->retries_used(), r0);
}

// A position-only fixture (capability position_only): selecting rate mode is refused with an
// exception reply that changes nothing; position moves work as on a rate table.
TEST_F(Table, PositionOnlyTableRefusesRateModeAndStillPositions) {
  cfg.position_only = true;
  start();
  cli->start_heartbeat(0.01);
  cli->set_limits(1, 100 * kDeg, 30 * kDeg);
  cli->set_mode(1, table::Mode::position);
  cli->command_position(1, 0.0);
  cli->enable(1);
  const auto r0 = cli->retries_used();
  for (int axis : {0, 1}) {
    try {
      cli->set_mode(axis, table::Mode::rate);
      FAIL() << "rate mode accepted on axis " << axis;
    } catch (const TableError& e) {
      EXPECT_NE(std::string(e.what()).find("Illegal data value"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(cli->retries_used(), r0);  // an exception reply: not retried
  cli->command_rate(1, 50 * kDeg);     // a rate set-point alone selects nothing
  cli->command_position(1, 20 * kDeg);
  AxisStatus s;
  ASSERT_TRUE(wait_for(1, [](const AxisStatus& x) { return x.settled() && std::abs(x.position - 20 * kDeg) < 1e-3 * kDeg; },
                       3.0, &s));
  EXPECT_EQ(s.mode, table::Mode::position);
  EXPECT_NEAR(emu->axis_state(1, emu->clock().now()).rate, 0.0, 1e-9);
  cli->stop_heartbeat();
}

TEST_F(Table, WordOrderIsConfigurable) {
  TearDown();
  start(table::WordOrder::cdab);
  cli->command_rate(1, 123456.0 * kDeg);
  auto w = cli->read_registers(table::address(1, table::reg("CMD_RATE")), 2);
  EXPECT_EQ(w[0], 0x2000);  // low word first on the wire
  EXPECT_EQ(w[1], 0x47F1);
  cli->set_limits(1, 1000 * kDeg, 45 * kDeg);
  w = cli->read_registers(table::address(1, table::reg("RATE_LIMIT")), 2);
  EXPECT_FLOAT_EQ(table::get_f32(w.data(), table::WordOrder::cdab), 45.0f);
}

}  // namespace

namespace {
// Issue 35: the controller's death is the emulator's own configuration (kill_at_s), not the station's:
// it answers until the emulated time reaches kill_at_s, then the next request fails and nothing
// reconnects.
TEST(TableEmulatorFaults, KillAtDiesAtItsEmulatedTime) {
  auto clock = std::make_shared<VirtualClock>();
  TableEmulatorConfig cfg;
  cfg.kill_at_s = 5.0;
  TableEmulator emu(cfg, clock);
  emu.start();
  TableClientOptions o;
  o.response_timeout_s = 0.1;
  o.retries = 2;
  o.reconnect_backoff_s = 0.01;
  TableClient cli(parse_table_uri(emu.uri()), o);
  cli.connect();
  clock->wait_until(4.9);
  EXPECT_NO_THROW(cli.status(0));  // alive before its time
  clock->wait_until(5.0);
  EXPECT_THROW(cli.status(0), TableError);
  EXPECT_FALSE(cli.stop_all());
  emu.stop();
}
}  // namespace
