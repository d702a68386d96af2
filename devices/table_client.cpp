#include "devices/table_client.hpp"

#include <modbus.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

namespace calbench::devices {
namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;

std::string query_value(const std::string& q, const std::string& key) {
  std::size_t pos = 0;
  while (pos < q.size()) {
    std::size_t amp = q.find('&', pos);
    if (amp == std::string::npos) amp = q.size();
    const std::string kv = q.substr(pos, amp - pos);
    const auto eq = kv.find('=');
    if (eq != std::string::npos && kv.substr(0, eq) == key) return kv.substr(eq + 1);
    pos = amp + 1;
  }
  return "";
}
int to_int(const std::string& s, const std::string& what, const std::string& uri) {
  try {
    std::size_t n = 0;
    const int v = std::stoi(s, &n);
    if (n != s.size()) throw std::invalid_argument("");
    return v;
  } catch (...) {
    throw std::invalid_argument("table URI '" + uri + "': " + what + " '" + s + "' is not an integer");
  }
}
}  // namespace

TableUri parse_table_uri(const std::string& uri) {
  TableUri u;
  u.text = uri;
  std::string rest, query;
  const auto qpos = uri.find('?');
  const std::string head = uri.substr(0, qpos);
  if (qpos != std::string::npos) query = uri.substr(qpos + 1);
  if (head.rfind("modbus-tcp://", 0) == 0) {
    u.tcp = true;
    rest = head.substr(13);
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || colon == 0)
      throw std::invalid_argument("table URI '" + uri + "': expected modbus-tcp://HOST:PORT");
    u.host = rest.substr(0, colon);
    u.port = to_int(rest.substr(colon + 1), "port", uri);
    if (u.port <= 0 || u.port > 65535) throw std::invalid_argument("table URI '" + uri + "': port out of range");
  } else if (head.rfind("modbus-rtu:", 0) == 0) {
    u.tcp = false;
    u.device = head.substr(11);
    if (u.device.empty()) throw std::invalid_argument("table URI '" + uri + "': expected modbus-rtu:/dev/ttyX");
    if (auto b = query_value(query, "baud"); !b.empty()) u.baud = to_int(b, "baud", uri);
    if (auto p = query_value(query, "parity"); !p.empty()) {
      if (p != "N" && p != "E" && p != "O") throw std::invalid_argument("table URI '" + uri + "': parity must be N, E or O");
      u.parity = p[0];
    }
    if (auto d = query_value(query, "data"); !d.empty()) u.data_bits = to_int(d, "data", uri);
    if (auto s = query_value(query, "stop"); !s.empty()) u.stop_bits = to_int(s, "stop", uri);
  } else {
    throw std::invalid_argument("table URI '" + uri + "': must start with modbus-tcp:// or modbus-rtu:");
  }
  if (auto s = query_value(query, "slave"); !s.empty()) u.slave = to_int(s, "slave", uri);
  if (auto o = query_value(query, "order"); !o.empty()) {
    try {
      u.order = table::parse_word_order(o);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("table URI '" + uri + "': " + e.what());
    }
  }
  return u;
}

TableClient::TableClient(TableUri uri, TableClientOptions opt) : uri_(std::move(uri)), opt_(opt) {}

TableClient::~TableClient() {
  stop_heartbeat();
  close();
}

void TableClient::open_locked() {
  if (ctx_) {
    modbus_close(ctx_);
    modbus_free(ctx_);
    ctx_ = nullptr;
  }
  connected_ = false;
  ctx_ = uri_.tcp ? modbus_new_tcp(uri_.host.c_str(), uri_.port)
                  : modbus_new_rtu(uri_.device.c_str(), uri_.baud, uri_.parity, uri_.data_bits, uri_.stop_bits);
  if (!ctx_) throw TableError(uri_.text + ": cannot create Modbus context: " + modbus_strerror(errno));
  modbus_set_slave(ctx_, uri_.slave);
  const double t = std::max(opt_.response_timeout_s, 1e-3);
  modbus_set_response_timeout(ctx_, static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(std::fmod(t, 1.0) * 1e6));
  modbus_set_byte_timeout(ctx_, static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(std::fmod(t, 1.0) * 1e6));
  if (modbus_connect(ctx_) == -1) throw TableError(uri_.text + ": cannot connect: " + modbus_strerror(errno));
  connected_ = true;
}

void TableClient::connect() {
  std::lock_guard lk(mu_);
  open_locked();
}

void TableClient::close() {
  std::lock_guard lk(mu_);
  if (ctx_) {
    modbus_close(ctx_);
    modbus_free(ctx_);
    ctx_ = nullptr;
  }
  connected_ = false;
}

template <class F>
auto TableClient::with_retry(const char* what, F&& f) -> decltype(f(static_cast<modbus_t*>(nullptr))) {
  std::lock_guard lk(mu_);
  std::string last;
  for (int attempt = 0; attempt <= opt_.retries; ++attempt) {
    if (attempt > 0) {
      ++retries_used_;
      std::this_thread::sleep_for(std::chrono::duration<double>(opt_.reconnect_backoff_s));
    }
    try {
      if (!connected_) {
        if (attempt > 0 || ctx_) ++reconnects_;
        open_locked();
      }
    } catch (const TableError& e) {
      last = e.what();
      continue;
    }
    errno = 0;
    if (auto r = f(ctx_); r.ok) return r;
    const int err = errno;
    last = uri_.text + ": " + what + ": " + modbus_strerror(err);
    if (err > MODBUS_ENOBASE && err < MODBUS_ENOBASE + 12) throw TableError(last);  // exception reply: no retry
    if (ctx_) modbus_close(ctx_);
    connected_ = false;
  }
  throw TableError(last + " (after " + std::to_string(opt_.retries + 1) + " attempts)");
}

namespace {
struct Res {
  bool ok;
  std::vector<std::uint16_t> v;
};
}  // namespace

std::vector<std::uint16_t> TableClient::read_registers(std::uint16_t addr, int n) {
  return with_retry("read registers", [&](modbus_t* c) {
           Res r{false, std::vector<std::uint16_t>(static_cast<std::size_t>(n))};
           r.ok = modbus_read_registers(c, addr, n, r.v.data()) == n;
           return r;
         }).v;
}

void TableClient::write_registers(std::uint16_t addr, const std::vector<std::uint16_t>& v) {
  with_retry("write registers", [&](modbus_t* c) {
    return Res{modbus_write_registers(c, addr, static_cast<int>(v.size()), v.data()) == static_cast<int>(v.size()), {}};
  });
}

void TableClient::write_u16(int axis, const char* name, std::uint16_t v) {
  write_registers(table::address(axis, table::reg(name)), {v});
}
void TableClient::write_f32(int axis, const char* name, double v) {
  std::vector<std::uint16_t> w(2);
  table::put_f32(static_cast<float>(v), uri_.order, w.data());
  write_registers(table::address(axis, table::reg(name)), w);
}

AxisStatus TableClient::status(int axis) {
  const auto& sw = table::reg("STATUSWORD");
  auto r = read_registers(table::address(axis, sw), table::kBlockSize - sw.offset);
  auto at = [&](const char* n) { return r.data() + (table::reg(n).offset - sw.offset); };
  AxisStatus s;
  s.statusword = *at("STATUSWORD");
  s.mode = static_cast<table::Mode>(static_cast<std::int16_t>(*at("MODE_DISPLAY")));
  s.fault_code = *at("FAULT_CODE");
  s.position = table::get_f32(at("ACT_POSITION"), uri_.order) * kDeg;
  s.rate = table::get_f32(at("ACT_RATE"), uri_.order) * kDeg;
  s.pos_error = table::get_f32(at("POS_ERROR"), uri_.order) * kDeg;
  s.encoder = static_cast<std::int32_t>(table::get_u32(at("ENCODER_COUNTS"), uri_.order));
  s.timestamp_ms = table::get_u32(at("TIMESTAMP_MS"), uri_.order);
  return s;
}

void TableClient::reset_fault(int axis) {
  write_u16(0, "ESTOP_CMD", 0);
  write_u16(axis, "CONTROLWORD", 0);
  write_u16(axis, "CONTROLWORD", table::cw::fault_reset);
  write_u16(axis, "CONTROLWORD", 0);
}

void TableClient::enable(int axis) {
  if (status(axis).faulted()) reset_fault(axis);
  write_u16(axis, "CONTROLWORD", table::cw::kShutdown);
  write_u16(axis, "CONTROLWORD", table::cw::kSwitchOn);
  write_u16(axis, "CONTROLWORD", table::cw::kEnable);
}
void TableClient::disable(int axis) { write_u16(axis, "CONTROLWORD", table::cw::kDisable); }
void TableClient::set_mode(int axis, table::Mode m) {
  write_u16(axis, "MODE_OF_OPERATION", static_cast<std::uint16_t>(static_cast<std::int16_t>(m)));
}
void TableClient::command_rate(int axis, double rad_s) { write_f32(axis, "CMD_RATE", rad_s / kDeg); }
void TableClient::command_position(int axis, double rad) { write_f32(axis, "CMD_POSITION", rad / kDeg); }
void TableClient::set_limits(int axis, double accel, double rate) {
  write_f32(axis, "ACCEL_LIMIT", accel / kDeg);
  write_f32(axis, "RATE_LIMIT", rate / kDeg);
}
void TableClient::estop() { write_u16(0, "ESTOP_CMD", table::kEstopMagic); }

void TableClient::heartbeat() {
  std::lock_guard lk(mu_);
  ++hb_counter_;
  for (int a = 0; a < table::kAxes; ++a) write_u16(a, "WATCHDOG", hb_counter_);
}

void TableClient::start_heartbeat(double period_s) {
  stop_heartbeat();
  hb_run_ = true;
  hb_thread_ = std::thread([this, period_s] {
    while (hb_run_) {
      try {
        heartbeat();
      } catch (...) {
        ++hb_errors_;
      }
      const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(period_s);
      while (hb_run_ && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
}

void TableClient::stop_heartbeat() {
  hb_run_ = false;
  if (hb_thread_.joinable()) hb_thread_.join();
}

bool TableClient::stop_all() noexcept {
  // One attempt per write: on a dead link this must end quickly (the caller is aborting).
  std::lock_guard lk(mu_);
  const int saved = opt_.retries;
  opt_.retries = 0;
  bool ok = true;
  for (int a = 0; a < table::kAxes; ++a) {
    try {
      command_rate(a, 0.0);
    } catch (...) {
      ok = false;
    }
    try {
      disable(a);
    } catch (...) {
      ok = false;
    }
  }
  opt_.retries = saved;
  return ok;
}

}  // namespace calbench::devices
