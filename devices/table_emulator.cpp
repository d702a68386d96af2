#include "devices/table_emulator.hpp"

#include <arpa/inet.h>
#include <modbus.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace calbench::devices {

namespace {
// Does this request write MODE_OF_OPERATION = rate on an axis? (Function codes 0x06 write single
// register, 0x10 write multiple, 0x17 write/read multiple; big-endian on the wire.)
bool selects_rate_mode(const std::uint8_t* q, int h, int len) {
  auto u16 = [&](int at) { return at + 1 < len ? static_cast<int>(q[at] << 8 | q[at + 1]) : -1; };
  int addr = -1, qty = 0, values = 0;
  switch (q[h]) {
    case 0x06: addr = u16(h + 1), qty = 1, values = h + 3; break;
    case 0x10: addr = u16(h + 1), qty = u16(h + 3), values = h + 6; break;
    case 0x17: addr = u16(h + 5), qty = u16(h + 7), values = h + 10; break;
    default: return false;
  }
  const int rate = static_cast<std::uint16_t>(static_cast<std::int16_t>(table::Mode::rate));
  for (int a = 0; a < table::kAxes; ++a) {
    const int k = table::address(a, table::reg("MODE_OF_OPERATION")) - addr;
    if (addr >= 0 && k >= 0 && k < qty && u16(values + 2 * k) == rate) return true;
  }
  return false;
}
}  // namespace

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kTwoPi = 6.283185307179586;
double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

TableEmulator::TableEmulator(TableEmulatorConfig cfg, std::shared_ptr<EmuClock> clock)
    : cfg_(std::move(cfg)), clock_(std::move(clock)) {
  for (auto& a : ax_) {
    a.acc_lim = cfg_.default_accel;
    a.rate_lim = cfg_.default_rate_limit;
  }
  t_ = clock_->now();
  last_hb_t_ = t_;
}

TableEmulator::~TableEmulator() { stop(); }

std::string TableEmulator::uri() const {
  return "modbus-tcp://" + cfg_.bind + ":" + std::to_string(port_) +
         (cfg_.order == table::WordOrder::cdab ? "?order=cdab" : "?order=abcd");
}

void TableEmulator::start() {
  modbus_t* ctx = modbus_new_tcp(cfg_.bind.c_str(), cfg_.port);
  if (!ctx) throw std::runtime_error("table emulator: modbus_new_tcp failed: " + std::string(modbus_strerror(errno)));
  modbus_mapping_t* map = modbus_mapping_new(0, 0, table::kAxisBase[1] + table::kBlockSize, 0);
  if (!map) {
    modbus_free(ctx);
    throw std::runtime_error("table emulator: cannot allocate the register map");
  }
  const int fd = modbus_tcp_listen(ctx, 4);
  if (fd < 0) {
    const std::string err = modbus_strerror(errno);
    modbus_mapping_free(map);
    modbus_free(ctx);
    throw std::runtime_error("table emulator: cannot listen on " + cfg_.bind + ":" + std::to_string(cfg_.port) + ": " + err);
  }
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  ctx_ = ctx;
  map_ = map;
  listen_fd_ = fd;
  {
    std::lock_guard lk(mu_);
    for (int i = 0; i < table::kAxes; ++i) {  // the limits as registers, so a client can read them back
      auto* regs = map->tab_registers;
      table::put_f32(static_cast<float>(ax_[i].acc_lim / kDeg), cfg_.order,
                     regs + table::address(i, table::reg("ACCEL_LIMIT")));
      table::put_f32(static_cast<float>(ax_[i].rate_lim / kDeg), cfg_.order,
                     regs + table::address(i, table::reg("RATE_LIMIT")));
    }
    publish_locked(t_);
  }
  run_ = true;
  thread_ = std::thread([this] { run(); });
}

void TableEmulator::stop() {
  if (!run_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  modbus_mapping_free(static_cast<modbus_mapping_t*>(map_));
  modbus_free(static_cast<modbus_t*>(ctx_));
  map_ = ctx_ = nullptr;
}

void TableEmulator::run() {
  auto* ctx = static_cast<modbus_t*>(ctx_);
  auto* map = static_cast<modbus_mapping_t*>(map_);
  std::vector<int> clients;
  std::vector<std::uint8_t> q(MODBUS_TCP_MAX_ADU_LENGTH);
  while (run_) {
    {
      std::lock_guard lk(mu_);
      advance_locked(clock_->now());
      publish_locked(t_);
    }
    if (drop_.exchange(false)) {
      for (int c : clients) ::close(c);
      clients.clear();
    }
    if (wall_now() < stall_until_.load()) {  // stalled: accept nothing, answer nothing
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    fd_set rd;
    FD_ZERO(&rd);
    FD_SET(listen_fd_, &rd);
    int maxfd = listen_fd_;
    for (int c : clients) {
      FD_SET(c, &rd);
      maxfd = std::max(maxfd, c);
    }
    timeval tv{0, 2000};
    const int n = select(maxfd + 1, &rd, nullptr, nullptr, &tv);
    if (n <= 0) continue;
    // A stall begun while select waited: a request sent after stall_for() returned must go
    // unanswered too (checked before select only, a loaded machine answered it).
    if (wall_now() < stall_until_.load()) continue;
    if (FD_ISSET(listen_fd_, &rd)) {
      const int s = ::accept(listen_fd_, nullptr, nullptr);
      if (s >= 0) clients.push_back(s);
    }
    for (auto it = clients.begin(); it != clients.end();) {
      if (!FD_ISSET(*it, &rd)) {
        ++it;
        continue;
      }
      modbus_set_socket(ctx, *it);
      const int rc = modbus_receive(ctx, q.data());
      if (rc > 0 && cfg_.kill_at_s >= 0 && clock_->now() >= cfg_.kill_at_s) {  // the controller dies
        for (int c : clients) ::close(c);
        ::close(listen_fd_);
        listen_fd_ = -1;
        return;
      }
      if (rc > 0 && cfg_.position_only && selects_rate_mode(q.data(), modbus_get_header_length(ctx), rc)) {
        modbus_reply_exception(ctx, q.data(), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
        ++requests_;
        ++it;
      } else if (rc > 0) {
        std::lock_guard lk(mu_);
        advance_locked(clock_->now());
        publish_locked(t_);
        modbus_reply(ctx, q.data(), rc, map);
        read_commands_locked();
        publish_locked(t_);
        ++requests_;
        ++it;
      } else if (rc == -1) {
        ::close(*it);
        it = clients.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (int c : clients) ::close(c);
}

void TableEmulator::stop_axis_locked(Axis& a, std::uint16_t fault) {
  if (a.fault == table::fault::none) a.fault = fault;
  a.enabled = false;
  if (fault == table::fault::estop) a.estop = true;
  if (fault == table::fault::following_error) a.following = true;
}

void TableEmulator::read_commands_locked() {
  auto* regs = static_cast<modbus_mapping_t*>(map_)->tab_registers;
  bool estop = false;
  for (int i = 0; i < table::kAxes; ++i) {
    Axis& a = ax_[i];
    auto at = [&](const char* n) { return regs + table::address(i, table::reg(n)); };
    if (*at("ESTOP_CMD") == table::kEstopMagic) estop = true;
    a.cw = *at("CONTROLWORD");
    if ((a.cw & table::cw::fault_reset) && !(a.prev_cw & table::cw::fault_reset) &&
        regs[table::address(0, table::reg("ESTOP_CMD"))] != table::kEstopMagic &&
        regs[table::address(1, table::reg("ESTOP_CMD"))] != table::kEstopMagic) {
      a.fault = table::fault::none;
      a.estop = a.following = false;
    }
    a.prev_cw = a.cw;
    const bool want = (a.cw & 0x000F) == 0x000F && !(a.cw & table::cw::halt);
    if (want && !a.enabled && a.fault == table::fault::none) {
      a.enabled = true;
      last_hb_t_ = t_;  // the watchdog period starts at enable
    } else if (!want) {
      a.enabled = false;
    }
    const auto mode = static_cast<std::int16_t>(*at("MODE_OF_OPERATION"));
    const double cmd_rate = table::get_f32(at("CMD_RATE"), cfg_.order) * kDeg;
    const double cmd_pos = table::get_f32(at("CMD_POSITION"), cfg_.order) * kDeg;
    if (mode != a.mode || cmd_rate != a.cmd_rate || cmd_pos != a.cmd_pos) {  // new set-point: not reached yet
      a.reached = false;
      a.settled_since = -1;
    }
    a.mode = mode;
    a.cmd_rate = cmd_rate;
    a.cmd_pos = cmd_pos;
    const double acc = table::get_f32(at("ACCEL_LIMIT"), cfg_.order) * kDeg;
    const double rl = table::get_f32(at("RATE_LIMIT"), cfg_.order) * kDeg;
    a.acc_lim = std::isfinite(acc) && acc > 0 ? acc : cfg_.default_accel;
    a.rate_lim = std::isfinite(rl) && rl > 0 ? std::min(rl, cfg_.max_rate) : cfg_.default_rate_limit;
    if (!std::isfinite(a.cmd_rate)) a.cmd_rate = 0;
    if (!std::isfinite(a.cmd_pos)) a.cmd_pos = a.angle;
    if (*at("WATCHDOG") != a.watchdog) {
      a.watchdog = *at("WATCHDOG");
      last_hb_t_ = t_;
    }
  }
  if (estop)
    for (auto& a : ax_) stop_axis_locked(a, table::fault::estop);
}

void TableEmulator::step_axis(Axis& a, double dt) {
  double target = 0, amax = a.acc_lim;
  bool pos_mode = false;
  a.limit = false;
  if (!a.enabled) {
    amax = a.estop ? cfg_.estop_decel : a.acc_lim;
  } else if (a.mode == static_cast<std::int16_t>(table::Mode::rate)) {
    target = std::clamp(a.cmd_rate, -a.rate_lim, a.rate_lim);
    a.limit = std::abs(a.cmd_rate) > a.rate_lim;
  } else if (a.mode == static_cast<std::int16_t>(table::Mode::position)) {
    pos_mode = true;
    const double e = a.cmd_pos - a.angle;
    target = std::copysign(std::min({a.rate_lim, std::sqrt(2 * amax * std::abs(e)), std::abs(e) / dt}), e);
  }
  const double acc = std::clamp((target - a.rate) / dt, -amax, amax);
  a.angle += a.rate * dt + 0.5 * acc * dt * dt;
  a.rate += acc * dt;
  a.accel = acc;
  if (pos_mode && std::abs(a.cmd_pos - a.angle) < 1e-9 && std::abs(a.rate) < amax * dt) {
    a.angle = a.cmd_pos;
    a.rate = 0;
  }
  if (std::abs(a.rate) > cfg_.max_rate * 1.05) stop_axis_locked(a, table::fault::over_speed);
  bool cond;
  if (!a.enabled) {
    cond = false;
  } else if (pos_mode) {
    cond = std::abs(a.cmd_pos - a.angle) < cfg_.position_tolerance && std::abs(a.rate) < cfg_.rate_tolerance;
  } else {
    cond = std::abs(a.rate - target) < cfg_.rate_tolerance && std::abs(a.accel) < 1e-12;
  }
  if (cond) {
    if (a.settled_since < 0) a.settled_since = t_;
    a.reached = t_ + dt - a.settled_since >= cfg_.settle_s;
  } else {
    a.settled_since = -1;
    a.reached = false;
  }
}

void TableEmulator::advance_locked(double t) {
  while (t_ < t) {
    const double dt = std::min(cfg_.step_s, t - t_);
    if (dt < 1e-12) {
      t_ = t;
      break;
    }
    for (auto& a : ax_) step_axis(a, dt);
    t_ += dt;
    const bool any = ax_[0].enabled || ax_[1].enabled;
    if (any && t_ - last_hb_t_ > cfg_.watchdog_s)
      for (auto& a : ax_)
        if (a.enabled) stop_axis_locked(a, table::fault::comm_loss);
  }
}

void TableEmulator::publish_locked(double t) {
  auto* regs = static_cast<modbus_mapping_t*>(map_)->tab_registers;
  for (int i = 0; i < table::kAxes; ++i) {
    const Axis& a = ax_[i];
    auto at = [&](const char* n) { return regs + table::address(i, table::reg(n)); };
    std::uint16_t s = table::sw::remote | table::sw::voltage_enabled;
    if (a.fault) {
      s |= table::sw::fault;
    } else {
      s |= table::sw::ready | table::sw::quick_stop_n;
      if ((a.cw & 0x0003) == 0x0003) s |= table::sw::switched_on;
    }
    if (a.enabled) s |= table::sw::operation_enabled | table::sw::switched_on;
    if (a.reached) s |= table::sw::target_reached;
    if (a.limit) s |= table::sw::limit_active;
    if (a.following) s |= table::sw::following_error;
    if (a.estop) s |= table::sw::estop;
    *at("STATUSWORD") = s;
    *at("MODE_DISPLAY") = static_cast<std::uint16_t>(a.enabled ? a.mode : 0);
    *at("FAULT_CODE") = a.fault;
    const AxisState ts = true_state(a, t);
    const double cpr = static_cast<double>(cfg_.encoder_counts_per_rev);
    const auto counts = static_cast<std::int64_t>(std::llround(ts.angle / kTwoPi * cpr));
    const double enc_angle = counts / cpr * kTwoPi;
    const double rate_res = kTwoPi / cpr / 0.01;  // encoder difference over 10 ms
    table::put_f32(static_cast<float>(enc_angle / kDeg), cfg_.order, at("ACT_POSITION"));
    table::put_f32(static_cast<float>(std::round(ts.rate / rate_res) * rate_res / kDeg), cfg_.order, at("ACT_RATE"));
    table::put_f32(static_cast<float>(a.mode == 1 ? (a.cmd_pos - enc_angle) / kDeg : 0.0), cfg_.order, at("POS_ERROR"));
    table::put_u32(static_cast<std::uint32_t>(counts), cfg_.order, at("ENCODER_COUNTS"));
    table::put_u32(static_cast<std::uint32_t>(std::llround(t * 1000.0)), cfg_.order, at("TIMESTAMP_MS"));
  }
}

AxisState TableEmulator::true_state(const Axis& a, double t) const {
  const double d = t - t_;  // |d| ≤ one step: the constant-acceleration segment extended
  AxisState s{a.angle + a.rate * d + 0.5 * a.accel * d * d, a.rate + a.accel * d, a.accel};
  if (cfg_.ripple_rel > 0 && cfg_.ripple_hz > 0) {
    const double w = kTwoPi * cfg_.ripple_hz;
    s.angle += -s.rate * cfg_.ripple_rel / w * std::cos(w * t);
    s.rate *= 1.0 + cfg_.ripple_rel * std::sin(w * t);
  }
  return s;
}

AxisState TableEmulator::axis_state(int axis, double t) {
  std::lock_guard lk(mu_);
  advance_locked(t);
  return true_state(ax_[axis], t);
}

std::array<AxisState, 2> TableEmulator::axis_states(double t) {
  std::lock_guard lk(mu_);
  advance_locked(t);
  return {true_state(ax_[0], t), true_state(ax_[1], t)};
}

bool TableEmulator::enabled(int axis) {
  std::lock_guard lk(mu_);
  advance_locked(clock_->now());
  return ax_[axis].enabled;
}

std::uint16_t TableEmulator::fault_code(int axis) {
  std::lock_guard lk(mu_);
  advance_locked(clock_->now());
  return ax_[axis].fault;
}

void TableEmulator::drop_connections() { drop_ = true; }
void TableEmulator::stall_for(double wall_s) { stall_until_ = wall_now() + wall_s; }
void TableEmulator::inject_following_error(int axis) {
  std::lock_guard lk(mu_);
  stop_axis_locked(ax_[axis], table::fault::following_error);
}

}  // namespace calbench::devices
