// calbench emulate table: the two-axis rate-table emulator as a standalone Modbus TCP server.
#include <arpa/inet.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <thread>

#include <nlohmann/json.hpp>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "devices/table_emulator.hpp"

namespace calbench::cli {
namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

struct EmulateArgs {
  std::string listen = "127.0.0.1:1502";
  double watchdog_s = 0.5;
  std::string order = "abcd";
  double speed = 1.0;
  std::string port_file;
  bool position_only = false;
  bool json = false;
};

void run_table(const EmulateArgs& a) {
  devices::TableEmulatorConfig cfg;
  const auto colon = a.listen.rfind(':');
  if (colon == std::string::npos || colon == 0) throw InputError("--listen", 0, "listen", "expected HOST:PORT, e.g. 127.0.0.1:1502");
  cfg.bind = a.listen.substr(0, colon);
  in_addr ip{};  // the Modbus library takes a numeric IPv4 address (a name ended in "modbus_new_tcp failed", exit 1)
  if (::inet_pton(AF_INET, cfg.bind.c_str(), &ip) != 1)
    throw InputError("--listen", 0, "listen", "HOST must be an IPv4 address such as 127.0.0.1, got '" + cfg.bind + "'");
  try {
    std::size_t n = 0;
    cfg.port = std::stoi(a.listen.substr(colon + 1), &n);
    if (n != a.listen.size() - colon - 1 || cfg.port < 0 || cfg.port > 65535) throw 0;
  } catch (...) {
    throw InputError("--listen", 0, "listen", "port must be 0..65535 (0 = any free port)");
  }
  try {
    cfg.order = devices::table::parse_word_order(a.order);
  } catch (const std::invalid_argument& e) {
    throw InputError("--order", 0, "order", e.what());
  }
  cfg.watchdog_s = a.watchdog_s;
  cfg.position_only = a.position_only;
  devices::TableEmulator emu(cfg, std::make_shared<devices::WallClock>(a.speed));
  emu.start();
  if (!a.port_file.empty()) write_text_atomic(a.port_file, std::to_string(emu.port()) + "\n");
  if (a.json) {
    nlohmann::json j{{"uri", emu.uri()}, {"port", emu.port()}, {"watchdog_s", cfg.watchdog_s}, {"speed", a.speed},
                     {"position_only", cfg.position_only}};
    print_json(j.dump());
  } else {
    std::cout << "table emulator listening on " << emu.uri() << " (watchdog " << cfg.watchdog_s
              << " s, speed " << a.speed << "x" << (cfg.position_only ? ", position only: rate mode refused" : "") << "); Ctrl-C to stop" << std::endl;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  while (!g_stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  emu.stop();
  if (!a.json) std::cout << "table emulator stopped after " << emu.requests() << " requests" << std::endl;
}

const bool registered = add_command(25, [](CLI::App& app) {
  auto* sub = app.add_subcommand("emulate", "Run a device emulator standalone (the rate table over Modbus TCP)");
  sub->require_subcommand(1);
  auto args = std::make_shared<EmulateArgs>();
  auto* t = sub->add_subcommand("table", "Two-axis rate-table emulator: Modbus TCP server (map in docs/devices.md)");
  t->add_option("--listen", args->listen, "HOST:PORT to bind (loopback unless told otherwise; port 0 = any free)")
      ->capture_default_str();
  t->add_option("--watchdog", args->watchdog_s, "seconds without a heartbeat change before the table stops")
      ->capture_default_str()
      ->check(finite_positive());
  t->add_option("--order", args->order, "32-bit word order on the wire: abcd (high word first) or cdab")
      ->capture_default_str();
  t->add_option("--speed", args->speed, "emulated clock speed relative to real time")->capture_default_str()->check(finite_positive());
  t->add_option("--port-file", args->port_file, "write the bound port number to this file");
  t->add_flag("--position-only", args->position_only,
              "a position-only fixture (positioner, indexing head): a write selecting rate mode is refused with the "
              "Modbus exception ILLEGAL DATA VALUE");
  t->add_flag("--json", args->json, "print the listening URI as JSON");
  t->callback([args] { run_table(*args); });
});

}  // namespace
}  // namespace calbench::cli
