// Modbus TCP / RTU client (libmodbus) for the two-axis rate table (map: devices/table_map.hpp).
// Every operation has an explicit response timeout; a failed exchange (timeout, broken link) is
// retried after closing and re-opening the link, up to `retries` times, then TableError is thrown.
// Modbus exception replies (illegal address, …) are not retried. Thread-safe (one mutex), so a
// heartbeat thread can run beside the controlling thread.
#pragma once
#include <atomic>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "devices/table_map.hpp"

typedef struct _modbus modbus_t;

namespace calbench::devices {

class TableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// modbus-tcp://HOST:PORT[?slave=N&order=abcd|cdab]
// modbus-rtu:/dev/ttyUSB0[?baud=115200&parity=N&data=8&stop=1&slave=1&order=abcd]
struct TableUri {
  bool tcp = true;
  std::string host = "127.0.0.1";
  int port = 502;
  std::string device;
  int baud = 115200;
  char parity = 'N';
  int data_bits = 8, stop_bits = 1;
  int slave = 1;
  table::WordOrder order = table::WordOrder::abcd;
  std::string text;  // as given
};
TableUri parse_table_uri(const std::string& uri);  // throws std::invalid_argument naming the part

struct TableClientOptions {
  double response_timeout_s = 0.25;
  int retries = 2;                 // extra attempts after the first
  double reconnect_backoff_s = 0.05;
};

struct AxisStatus {
  std::uint16_t statusword = 0, fault_code = 0;
  table::Mode mode = table::Mode::off;
  double position = 0;   // rad (unwrapped)
  double rate = 0;       // rad/s
  double pos_error = 0;  // rad
  std::int32_t encoder = 0;
  std::uint32_t timestamp_ms = 0;
  bool enabled() const { return statusword & table::sw::operation_enabled; }
  bool settled() const { return statusword & table::sw::target_reached; }
  bool faulted() const { return statusword & table::sw::fault; }
};

class TableClient {
 public:
  explicit TableClient(TableUri uri, TableClientOptions opt = {});
  ~TableClient();
  TableClient(const TableClient&) = delete;
  TableClient& operator=(const TableClient&) = delete;

  void connect();
  void close();
  const TableUri& uri() const { return uri_; }

  AxisStatus status(int axis);
  void enable(int axis);   // fault reset if needed, then 0x06 → 0x07 → 0x0F
  void disable(int axis);
  void set_mode(int axis, table::Mode m);
  void command_rate(int axis, double rad_s);
  void command_position(int axis, double rad);
  void set_limits(int axis, double accel_rad_s2, double rate_rad_s);
  void reset_fault(int axis);
  void estop();
  void heartbeat();                 // changes WATCHDOG on both axes
  void start_heartbeat(double period_s);  // background thread; errors counted, not thrown
  void stop_heartbeat();
  // Best effort on every axis: rate 0, disable. Never throws; false if any write failed.
  bool stop_all() noexcept;

  std::uint64_t retries_used() const { return retries_used_; }
  std::uint64_t reconnects() const { return reconnects_; }
  std::uint64_t heartbeat_errors() const { return hb_errors_; }

  // Raw register access (tests, diagnostics).
  std::vector<std::uint16_t> read_registers(std::uint16_t addr, int n);
  void write_registers(std::uint16_t addr, const std::vector<std::uint16_t>& v);

 private:
  template <class F>
  auto with_retry(const char* what, F&& f) -> decltype(f(static_cast<modbus_t*>(nullptr)));
  void open_locked();
  void write_f32(int axis, const char* name, double v);
  void write_u16(int axis, const char* name, std::uint16_t v);

  TableUri uri_;
  TableClientOptions opt_;
  modbus_t* ctx_ = nullptr;
  bool connected_ = false;
  std::recursive_mutex mu_;
  std::uint16_t hb_counter_ = 0;
  std::atomic<bool> hb_run_{false};
  std::thread hb_thread_;
  std::atomic<std::uint64_t> retries_used_{0}, reconnects_{0}, hb_errors_{0};
};

}  // namespace calbench::devices
