// Two-axis rate-table emulator: a real Modbus TCP server (libmodbus) on its own thread, with the
// register map of devices/table_map.hpp and axis dynamics: acceleration and rate limits, trapezoidal
// position moves, settling time before "target reached", encoder quantisation, rate ripple. It stops
// by itself on watchdog expiry (heartbeat unchanged) and on E-stop, and can inject faults: dropped
// connections, a stalled server, a following error. Binds 127.0.0.1 unless told otherwise; port 0 =
// ephemeral (see port()).
#pragma once
#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "common/table_motion.hpp"
#include "devices/emu_clock.hpp"
#include "devices/table_map.hpp"

namespace calbench::devices {

struct TableEmulatorConfig {
  std::string bind = "127.0.0.1";
  int port = 0;
  int slave = 1;                        // answered unit id (TCP: 0xFF and any id accepted)
  table::WordOrder order = table::WordOrder::abcd;
  double watchdog_s = 0.5;              // emulated-clock seconds without a heartbeat change
  double default_accel = 100 * 0.017453292519943295;  // rad/s² until the client sets limits
  double default_rate_limit = 200 * 0.017453292519943295;
  double max_rate = 1000 * 0.017453292519943295;      // hard limit (over-speed)
  double estop_decel = 500 * 0.017453292519943295;    // rad/s²
  double settle_s = 0.2;                // condition must hold this long for "target reached"
  double position_tolerance = 0.001 * 0.017453292519943295;  // rad
  double rate_tolerance = 0.001 * 0.017453292519943295;      // rad/s
  std::int64_t encoder_counts_per_rev = 1 << 24;
  double ripple_rel = 2e-6;             // relative rate ripple amplitude (true motion)
  double ripple_hz = 3.0;
  double step_s = 1e-3;                 // integration step of the dynamics
  // Injected fault (tests, demos, `station run --emulated --inject table-kill-at=S`): the controller
  // dies at this emulated time (≥ 0): the first request from then on goes unanswered, every
  // connection is closed and no new one is accepted.
  double kill_at_s = -1;
  // Capability: a position-only fixture (a positioner or indexing head without rate mode). A write
  // that selects rate mode (MODE_OF_OPERATION = rate, either axis) is refused with the Modbus
  // exception ILLEGAL DATA VALUE and changes nothing (`calbench emulate table --position-only`).
  bool position_only = false;
};

class TableEmulator {
 public:
  explicit TableEmulator(TableEmulatorConfig cfg = {}, std::shared_ptr<EmuClock> clock = std::make_shared<WallClock>());
  ~TableEmulator();
  void start();  // bind, listen, start the server thread; throws std::runtime_error
  void stop();
  int port() const { return port_; }
  std::string uri() const;  // modbus-tcp://HOST:PORT?order=...

  // True axis state at emulated time t (advances the dynamics to t): the IMU emulator's physics.
  AxisState axis_state(int axis, double t);
  std::array<AxisState, 2> axis_states(double t);
  bool enabled(int axis);
  std::uint16_t fault_code(int axis);
  EmuClock& clock() { return *clock_; }

  // Fault injection.
  void drop_connections();          // close every client socket now
  void stall_for(double wall_s);    // answer nothing for this long (wall time)
  void inject_following_error(int axis);
  std::uint64_t requests() const { return requests_; }

 private:
  struct Axis {
    double angle = 0, rate = 0, accel = 0;
    std::uint16_t cw = 0, prev_cw = 0, watchdog = 0, fault = 0;
    bool enabled = false, estop = false, following = false, limit = false;
    std::int16_t mode = 0;
    double cmd_rate = 0, cmd_pos = 0, acc_lim = 0, rate_lim = 0;
    double settled_since = -1;
    bool reached = false;
  };
  void run();
  void advance_locked(double t);
  void step_axis(Axis& a, double dt);
  void read_commands_locked();     // mapping → axes (after a client write)
  void publish_locked(double t);   // axes → mapping
  void stop_axis_locked(Axis& a, std::uint16_t fault);
  AxisState true_state(const Axis& a, double t) const;

  TableEmulatorConfig cfg_;
  std::shared_ptr<EmuClock> clock_;
  std::mutex mu_;
  std::array<Axis, 2> ax_;
  double t_ = 0;                  // dynamics advanced to here
  double last_hb_t_ = 0;
  void* ctx_ = nullptr;           // modbus_t*
  void* map_ = nullptr;           // modbus_mapping_t*
  int listen_fd_ = -1;
  int port_ = 0;
  std::thread thread_;
  std::atomic<bool> run_{false}, drop_{false};
  std::atomic<double> stall_until_{0};
  std::atomic<std::uint64_t> requests_{0};
};

}  // namespace calbench::devices
