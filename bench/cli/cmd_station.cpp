// calbench station run --plan PLAN [--table URI] [--imu URI] [--emulated] [--db PATH] [--out DIR] [--json]
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iostream>

#include "bench/cli/operator_option.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "db/store.hpp"
#include "common/input_error.hpp"
#include "bench/station/station.hpp"
#include "db/connection.hpp"

namespace calbench::cli {
namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

struct StationArgs {
  station::Options o;
  std::string plan, out = "station-out";
  std::vector<std::string> inject;
  bool json = false, force = false;
};

std::uint16_t parse_u16(const std::string& v, const std::string& key) {
  try {
    std::size_t n = 0;
    const unsigned long x = std::stoul(v, &n, 0);
    if (n != v.size() || x > 0xFFFF) throw 0;
    return static_cast<std::uint16_t>(x);
  } catch (...) {
    throw InputError("--inject", 0, key, "'" + v + "' is not a 16-bit number");
  }
}

void apply_inject(const std::string& kv, station::Injections& in) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) throw InputError("--inject", 0, kv, "expected KEY=VALUE");
  const std::string k = kv.substr(0, eq), v = kv.substr(eq + 1);
  try {
    // Whole decimal numbers in range: "nan", "-5" or "3abc" were taken and the fault silently never came.
    if (k == "table-kill-at") {
      double x = 0;
      const auto r = std::from_chars(v.data(), v.data() + v.size(), x, std::chars_format::general);
      if (r.ec != std::errc() || r.ptr != v.data() + v.size() || !std::isfinite(x) || x < 0)
        throw InputError("--inject", 0, k, "expected a finite time >= 0 s, got '" + v + "'");
      in.table_kill_at_s = x;
    } else if (k == "imu-prod-id") in.imu_prod_id = parse_u16(v, k);
    else if (k == "imu-flags") in.imu_sys_e_flag = parse_u16(v, k);
    else if (k == "imu-skip-every") {
      int n = 0;
      const auto r = std::from_chars(v.data(), v.data() + v.size(), n);
      if (r.ec != std::errc() || r.ptr != v.data() + v.size() || n < 1)
        throw InputError("--inject", 0, k, "expected a whole number >= 1, got '" + v + "'");
      in.imu_skip_every = n;
    }
    else if (k == "imu-self-test") in.imu_self_test_diag = parse_u16(v, k);
    else throw InputError("--inject", 0, k, "unknown; one of table-kill-at, imu-prod-id, imu-flags, imu-skip-every, imu-self-test");
  } catch (const InputError&) {
    throw;
  } catch (...) {
    throw InputError("--inject", 0, k, "bad value '" + v + "'");
  }
}

void run_station(StationArgs& a) {
  a.o.plan_file = a.plan;
  a.o.out_dir = a.out;
  // A rerun must not silently replace an earlier run's recording and coefficients.
  if (!a.force && (std::filesystem::exists(a.o.out_dir / "COEFFS.json") || std::filesystem::exists(a.o.out_dir / "recording" / "meta.json")))
    throw InputError(a.out, 0, "", "already holds a station run (recording/, COEFFS.json): give another --out, or --force to replace it");
  for (const auto& kv : a.inject) apply_inject(kv, a.o.inject);
  if (!a.inject.empty() && !a.o.emulated) throw InputError("--inject", 0, "", "fault injection needs --emulated");
  // A bad operator name is bad input, refused before anything moves.
  (void)db::Actor::from_environment(a.o.operator_name);
  if (a.o.emulated && !a.o.imu_uri.empty())  // was silently ignored: the emulated IMU ran instead
    throw InputError("--imu", 0, "", "not used with --emulated (the IMU is emulated; --table may name an external table)");
  a.o.progress_tty = ::isatty(STDERR_FILENO) && !a.json;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const station::Result r = station::run(a.o, std::cerr, g_stop);
  if (a.json) print_json(r.summary.dump(2));
  std::cerr << (r.exit_code == 0 ? "" : "calbench: ") << r.message << std::endl;
  if (r.exit_code != 0) throw Exit{r.exit_code};
  // The next step of the workflow, to type.
  const std::string shown = db::redact_uri(a.o.db);  // never a password on the screen
  if (r.summary.contains("db") && r.summary["db"].contains("central")) {
    const auto& c = r.summary["db"]["central"];
    // The approval is QC's: the same database as a QC login.
    std::string qc = shown;
    if (const auto s = qc.find("://"), at = qc.find('@'); s != std::string::npos && at != std::string::npos && at > s)
      qc.replace(s + 3, at - s - 3, "QC_USER");
    if (c.contains("set"))
      std::cerr << "next: calbench db approve " << c["set"].get<long long>() << " --db " << qc
                << " --operator NAME   (as a member of calbench_qc, signed by someone other than the station's operator)"
                << std::endl;
    else
      std::cerr << "next: calbench db sync --db " << shown << (a.o.journal.empty() ? "" : " --journal " + a.o.journal)
                << "   (the run waits in the journal until the central store answers)" << std::endl;
  } else if (r.summary.contains("db") && r.summary["db"].contains("set"))
    std::cerr << "next: calbench db approve " << r.summary["db"]["set"].get<long long>() << " --db " << shown
              << " --operator NAME   (signed by a QC engineer other than the station's operator; QC thresholds; "
                 "then calbench provision SERIAL --to-device URI)" << std::endl;
  else if (r.summary.contains("coefficients"))
    std::cerr << "next: calbench db store-bench --coeffs " << r.summary["coefficients"].get<std::string>()
              << " --recording " << (a.o.out_dir / "recording").string() << " --db DB   (or rerun with --db)" << std::endl;
}

const bool registered = add_command(20, [](CLI::App& app) {
  auto* st = app.add_subcommand("station", "Run the calibration station: rate table + ADIS16488A, plan to coefficients");
  st->require_subcommand(1);
  auto a = std::make_shared<StationArgs>();
  auto* run = st->add_subcommand("run", "Run a plan: identify, self-test, command/settle/record/check each step, fit, store");
  run->add_option("--plan", a->plan, "bench plan (TOML), e.g. bench/plans/factory.toml")->required()->check(CLI::ExistingFile);
  run->add_option("--table", a->o.table_uri, "modbus-tcp://HOST:PORT[?order=abcd|cdab] or modbus-rtu:/dev/ttyX?baud=...");
  run->add_option("--imu", a->o.imu_uri, "ft232h[:SERIAL] or mcp2210[:SERIAL]");
  run->add_flag("--emulated", a->o.emulated,
                "in-process table emulator (real Modbus TCP on an ephemeral loopback port) and IMU emulator, "
                "emulated clock faster than real time");
  run->add_option("--db", a->o.db,
                  "also store the bench run and its coefficient set (draft) in this database: a SQLite file or a "
                  "postgresql:// URI (central store; written to --journal first, forwarded when the server answers)");
  run->add_option("--journal", a->o.journal,
                  "with a PostgreSQL --db: the station's local journal (default: $CALBENCH_JOURNAL, else ./calbench-journal.db)");
  run->add_option("--out", a->out, "output folder: recording/, COEFFS.json (an existing run there is refused without --force)")
      ->capture_default_str();
  run->add_flag("--force", a->force, "replace an earlier run in --out");
  add_operator_option(run, a->o.operator_name,
                  "who runs the station, recorded with the run and the set (default: $CALBENCH_OPERATOR, else the OS user)");
  run->add_option("--seed", a->o.seed, "emulated unit (random errors drawn from this seed)")
      ->capture_default_str()
      ->check(whole_number(0, std::numeric_limits<std::uint64_t>::max()));
  run->add_option("--max-repeats", a->o.max_repeats, "repeats of a step that fails its data check")
      ->capture_default_str()
      ->check(whole_number(0, 100));
  run->add_option("--inject", a->inject,
                  "emulated faults KEY=VALUE: table-kill-at=S (emulated s), imu-prod-id=0x4060, imu-flags=0x0008, "
                  "imu-skip-every=N, imu-self-test=0x0001");
  run->add_flag("--json", a->json, "print a JSON summary on stdout");
  run->callback([a] { run_station(*a); });
});

}  // namespace
}  // namespace calbench::cli
