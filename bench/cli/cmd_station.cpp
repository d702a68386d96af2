// calbench station run --plan PLAN [--table URI] [--imu URI | --fixture FILE | --emulated --units N] [--emulated] [--db PATH] [--out DIR] [--json]
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iostream>

#include "common/number_parse.hpp"
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

// [SLOT:]KEY=VALUE: a fault of every emulated unit, or of one slot of the fixture.
void apply_inject(const std::string& spec, station::Injections& in) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos) throw InputError("--inject", 0, spec, "expected [SLOT:]KEY=VALUE");
  const auto colon = spec.substr(0, eq).find(':');
  const std::string slot = colon == std::string::npos ? "" : spec.substr(0, colon);
  const std::string kv = colon == std::string::npos ? spec : spec.substr(colon + 1);
  const std::string k = kv.substr(0, kv.find('=')), v = kv.substr(kv.find('=') + 1);
  if (colon != std::string::npos && slot.empty()) throw InputError("--inject", 0, spec, "empty slot name before ':'");
  devices::EmuFaults& imu = slot.empty() ? in.imu : in.slot[slot];
  auto seconds = [&] {
    double x = 0;
    if (!parse_finite_number(v, x) || x < 0)
      throw InputError("--inject", 0, k, "expected a finite time >= 0 s, got '" + v + "'");
    return x;
  };
  try {
    // Whole decimal numbers in range: "nan", "-5" or "3abc" were taken and the fault silently never came.
    if (k == "table-kill-at") {
      if (!slot.empty()) throw InputError("--inject", 0, k, "a fault of the table, not of one slot ('" + slot + ":')");
      in.table_kill_at_s = seconds();
    } else if (k == "imu-prod-id") imu.prod_id = parse_u16(v, k);
    else if (k == "imu-flags") imu.sys_e_flag = parse_u16(v, k);
    else if (k == "imu-flags-from") imu.flags_from_s = seconds();
    else if (k == "imu-skip-every") {
      int n = 0;
      const auto r = std::from_chars(v.data(), v.data() + v.size(), n);
      if (r.ec != std::errc() || r.ptr != v.data() + v.size() || n < 1)
        throw InputError("--inject", 0, k, "expected a whole number >= 1, got '" + v + "'");
      imu.skip_every = n;
    }
    else if (k == "imu-self-test") imu.self_test_diag = parse_u16(v, k);
    else throw InputError("--inject", 0, k, "unknown; one of table-kill-at, imu-prod-id, imu-flags, imu-flags-from, "
                                            "imu-skip-every, imu-self-test");
  } catch (const InputError&) {
    throw;
  } catch (...) {
    throw InputError("--inject", 0, k, "bad value '" + v + "'");
  }
}

// A rerun must not silently replace an earlier run's recording and coefficients (one unit: in --out;
// a fixture: in --out/SLOT).
bool holds_run(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  auto run_in = [](const fs::path& d) { return fs::exists(d / "COEFFS.json") || fs::exists(d / "recording" / "meta.json"); };
  if (run_in(dir)) return true;
  std::error_code ec;
  if (fs::is_directory(dir, ec))
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.is_directory(ec) && run_in(e.path())) return true;
  return false;
}

// The approval is QC's: the central store's URI with a QC login in place of the station's (whose
// login the database refuses an approval), e.g. postgresql://QC_LOGIN@host:5432/calbench.
std::string qc_login_uri(const std::string& shown) {
  std::string qc = shown;
  if (const auto s = qc.find("://"), at = qc.find('@'); s != std::string::npos && at != std::string::npos && at > s)
    qc.replace(s + 3, at - s - 3, "QC_LOGIN");
  return qc;
}

void run_station(StationArgs& a) {
  a.o.plan_file = a.plan;
  a.o.out_dir = a.out;
  // A rerun must not silently replace an earlier run's recording and coefficients.
  if (!a.force && holds_run(a.o.out_dir))
    throw InputError(a.out, 0, "", "already holds a station run (recording/, COEFFS.json): give another --out, or --force to replace it");
  for (const auto& kv : a.inject) apply_inject(kv, a.o.inject);
  // imu-flags-from without the flags would silently inject nothing.
  auto flags_need = [](const devices::EmuFaults& i, const std::string& who) {
    if (i.flags_from_s >= 0 && i.sys_e_flag == 0)
      throw InputError("--inject", 0, who + "imu-flags-from", "needs " + who + "imu-flags=BITS (which error flags to raise)");
  };
  flags_need(a.o.inject.imu, "");
  for (const auto& [slot, i] : a.o.inject.slot) flags_need(i, slot + ":");
  if (!a.inject.empty() && !a.o.emulated) throw InputError("--inject", 0, "", "fault injection needs --emulated");
  // A bad operator name is bad input, refused before anything moves.
  (void)db::Actor::from_environment(a.o.operator_name);
  if (a.o.emulated && !a.o.imu_uri.empty())  // was silently ignored: the emulated IMU ran instead
    throw InputError("--imu", 0, "", "not used with --emulated (the IMU is emulated; --table may name an external table)");
  a.o.progress_tty = ::isatty(STDERR_FILENO) && !a.json;
  if (a.o.pace > 0 && (!a.o.emulated || !a.o.table_uri.empty()))
    throw InputError("--pace", 0, "", "paces the in-process emulated table's time (--emulated without --table); a real or "
                                      "external table runs in real time already");
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const station::Result r = station::run(a.o, std::cerr, g_stop);
  if (a.json) print_json(r.summary.dump(2));
  std::cerr << (r.exit_code == 0 ? "" : "calbench: ") << r.message << std::endl;
  const std::string shown = db::redact_uri(a.o.db);  // never a password on the screen
  if (r.summary.contains("units")) {  // a fixture: the next step per calibrated unit
    for (const auto& u : r.summary["units"]) {
      if (!u.value("ok", false)) continue;
      const std::string slot = u["slot"].get<std::string>();
      if (u.contains("db") && u["db"].contains("central") && u["db"]["central"].contains("set"))
        std::cerr << "next (slot " << slot << "): calbench db approve " << u["db"]["central"]["set"].get<long long>()
                  << " --db " << qc_login_uri(shown) << "   (as a QC login, member of calbench_qc)" << std::endl;
      else if (u.contains("db") && u["db"].contains("set") && !db::is_postgres_uri(a.o.db))
        std::cerr << "next (slot " << slot << "): calbench db approve " << u["db"]["set"].get<long long>() << " --db "
                  << shown << " --operator NAME" << std::endl;
      else if (a.o.db.empty())
        std::cerr << "next (slot " << slot << "): calbench db store-bench --coeffs " << u["coefficients"].get<std::string>()
                  << " --recording " << u["recording"].get<std::string>() << " --db DB" << std::endl;
    }
    if (r.exit_code != 0) throw Exit{r.exit_code};
    return;
  }
  if (r.exit_code != 0) throw Exit{r.exit_code};
  // The next step of the workflow, to type.
  if (r.summary.contains("db") && r.summary["db"].contains("central")) {
    const auto& c = r.summary["db"]["central"];
    if (c.contains("set"))
      std::cerr << "next: calbench db approve " << c["set"].get<long long>() << " --db " << qc_login_uri(shown)
                << "   (as a QC login, member of calbench_qc: its person signs, not the station's login)" << std::endl;
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
  run->add_option("--imu", a->o.imu_uri, "one unit: ft232h[:SERIAL] or mcp2210[:SERIAL][#csN]");
  run->add_option("--fixture", a->o.fixture_file,
                  "several units: a fixture file (TOML; slots with IMU URIs and mountings, docs/devices.md "
                  "\"Fixtures\"); default: the plan's [plan] fixture, else one unit")
      ->check(CLI::ExistingFile);
  run->add_option("--units", a->o.units,
                  "with --emulated: a fixture of N emulated units (different truths, 80 mm round the centre; "
                  "results in --out/1 .. --out/N)")
      ->check(whole_number(1, 16));
  run->add_flag("--emulated", a->o.emulated,
                "in-process table emulator (real Modbus TCP on an ephemeral loopback port) and IMU emulator, "
                "emulated clock faster than real time");
  run->add_option("--db", a->o.db,
                  "also store the bench run and its coefficient set (draft) in this database: a SQLite file or a "
                  "postgresql:// URI (central store: its login, schema version and the role's privileges are checked before "
                  "the table moves, a refusal is exit 2; written to --journal first, forwarded when the server answers, "
                  "which it need not at start)");
  run->add_option("--journal", a->o.journal,
                  "with a PostgreSQL --db: the station's local journal (default: $CALBENCH_JOURNAL, else ./calbench-journal.db)");
  run->add_option("--out", a->out,
                  "output folder: recording/, COEFFS.json (a fixture: one folder per slot); an existing run there is "
                  "refused without --force")
      ->capture_default_str()
      ->check(non_empty());
  run->add_flag("--force", a->force, "replace an earlier run in --out");
  add_operator_option(run, a->o.operator_name,
                  "who runs the station, recorded with the run and the set (default: $CALBENCH_OPERATOR, else the OS user)");
  run->add_option("--seed", a->o.seed, "emulated unit (random errors drawn from this seed; a fixture's unit k: seed + k - 1)")
      ->capture_default_str()
      ->check(whole_number(0, std::numeric_limits<std::uint64_t>::max()));
  run->add_option("--max-repeats", a->o.max_repeats, "repeats of a step that fails its data check")
      ->capture_default_str()
      ->check(whole_number(0, 100));
  run->add_option("--inject", a->inject,
                  "emulated faults [SLOT:]KEY=VALUE (SLOT: of that slot only): table-kill-at=S (emulated s), "
                  "imu-prod-id=0x4060, imu-flags=0x0008, imu-flags-from=S (the flags from emulated time S on), "
                  "imu-skip-every=N, imu-self-test=0x0001");
  run->add_option("--pace", a->o.pace,
                  "emulated runs with the in-process table: at most PACE x real time (1: as long as on a real bench, "
                  "e.g. to watch the live view; default: as fast as the machine can)")
      ->check(finite_number(0.01, 1000));
  run->add_flag("--json", a->json, "print a JSON summary on stdout");
  run->callback([a] { run_station(*a); });
});

}  // namespace
}  // namespace calbench::cli
