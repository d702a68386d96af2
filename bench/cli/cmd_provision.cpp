// calbench provision SERIAL [--set ID] (--to-device IMU-URI | --export FILE): put an approved
// coefficient set where it is used, and record the event (docs/database.md "Provisioning").
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>
#include <nlohmann/json.hpp>

#include "bench/cli/operator_option.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "common/input_error.hpp"
#include "db/input_errors.hpp"
#include "bench/io/json_util.hpp"
#include "common/noise_spec.hpp"
#include "db/store.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"
#include "devices/emu_clock.hpp"
#include "devices/ft232h.hpp"
#include "devices/mcp2210.hpp"
#include "devices/usb_transport.hpp"

namespace calbench::cli {
namespace {
using nlohmann::json;
using namespace calbench::db;
using namespace calbench::devices;

struct ProvisionArgs {
  std::string db, serial, uri, out, op;
  std::int64_t set = 0;
  bool json = false;
};

// IMU URIs:
//   emu://SERIAL[?prod_id=N&flash_fails=1]  an emulated ADIS16488A with SERIAL_NUM = SERIAL (in this process)
//   mcp2210://[USB-SERIAL]                   MCP2210 bridge (04D8:00DE) via hidapi
//   ft232h://[USB-SERIAL]                    FT232H bridge (0403:6014) via libftdi1
struct OpenedImu {
  std::unique_ptr<SpiBus> bus;
};

long parse_int(const std::string& s, const std::string& what) {
  std::size_t used = 0;
  long v = 0;
  try {
    v = std::stol(s, &used, 0);
  } catch (...) {
    used = 0;
  }
  if (used != s.size() || s.empty()) throw arg_error("--to-device", what + ": '" + s + "' is not an integer");
  return v;
}

OpenedImu open_imu(const std::string& uri) {
  // SCHEME://REST, or the station's form SCHEME[:REST] (ft232h:SERIAL, mcp2210).
  const auto sep = uri.find("://");
  const auto colon = uri.find(':');
  const std::string scheme = sep != std::string::npos ? uri.substr(0, sep) : uri.substr(0, colon);
  if (scheme != "mcp2210" && scheme != "ft232h" && sep == std::string::npos)
    throw arg_error("--to-device", "expected emu://SERIAL, mcp2210[:USB-SERIAL] or ft232h[:USB-SERIAL], got '" + uri + "'");
  std::string rest = sep != std::string::npos ? uri.substr(sep + 3) : colon == std::string::npos ? "" : uri.substr(colon + 1),
              query;
  if (const auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  OpenedImu o;
  if (scheme == "emu") {
    Adis16488aEmulatorConfig cfg;
    const long serial = parse_int(rest, "emulated SERIAL_NUM");
    if (serial < 0 || serial > 0xFFFF) throw arg_error("--to-device", "SERIAL_NUM is 16-bit (0..65535)");
    cfg.serial = static_cast<std::uint16_t>(serial);
    EmuFaults faults;
    std::stringstream qs(query);
    for (std::string kv; std::getline(qs, kv, '&');) {
      const auto eq = kv.find('=');
      const std::string k = kv.substr(0, eq), v = eq == std::string::npos ? "" : kv.substr(eq + 1);
      if (k == "prod_id") faults.prod_id = static_cast<std::uint16_t>(parse_int(v, "prod_id"));
      else if (k == "flash_fails") faults.flash_update_fails = v == "1" || v == "true";
      else if (!k.empty()) throw arg_error("--to-device", "unknown emulator option '" + k + "'");
    }
    auto clock = std::make_shared<VirtualClock>();
    const EmuPhysics still = [](double) {
      EmuTruth t;
      t.f_b = Vec3(0, 0, -9.80665);
      return t;
    };
    auto emu = std::make_unique<Adis16488aEmulator>(clock, still, SensorErrors{}, adis16488a_noise(), cfg);
    emu->faults() = faults;
    o.bus = std::move(emu);
  } else if (scheme == "mcp2210") {
    o.bus = std::make_unique<Mcp2210Bus>(open_hidapi(0x04D8, 0x00DE, rest));
  } else if (scheme == "ft232h") {
    o.bus = std::make_unique<Ft232hBus>(open_libftdi(0x0403, 0x6014, rest));
  } else {
    throw arg_error("--to-device", "unknown IMU URI scheme '" + scheme + "' (emu, mcp2210, ft232h)");
  }
  return o;
}

// The database serial and the unit's 16-bit SERIAL_NUM agree when the serial is that number in
// decimal or hexadecimal (0x…), ignoring leading zeros.
bool serial_matches(const std::string& db_serial, std::uint16_t sn) {
  for (int base : {10, 16}) {
    std::string s = db_serial;
    if (base == 16) {
      if (s.rfind("0x", 0) == 0 || s.rfind("0X", 0) == 0) s = s.substr(2);
      else continue;
    }
    std::size_t used = 0;
    try {
      const unsigned long v = std::stoul(s, &used, base);
      if (used == s.size() && v == sn) return true;
    } catch (...) {
    }
  }
  return false;
}

json regs_json(const UserCal& c) {
  return {{"gyro_scale", c.gyro_scale}, {"gyro_bias", c.gyro_bias}, {"accel_scale", c.accel_scale},
          {"accel_bias", c.accel_bias}};
}

CoefficientSetRecord choose_set(Store& s, const Device& d, std::int64_t set_id) {
  if (set_id) {
    CoefficientSetRecord r = s.get_set(set_id);
    if (r.device_id != d.id) throw arg_error("--set", "set " + std::to_string(set_id) + " belongs to device " + r.serial);
    // Not eligible is a refusal (exit 1), not bad input.
    if (r.status != SetStatus::approved && r.status != SetStatus::provisioned)
      throw std::runtime_error("set " + std::to_string(set_id) + " is " + to_string(r.status) +
                               ": only approved sets are provisioned" +
                               (r.status == SetStatus::draft ? " (calbench db approve " + std::to_string(set_id) + ")" : ""));
    return r;
  }
  // The newest set that may go into a unit: approved, or provisioned before (writing the set a unit
  // already holds again — a replaced or re-flashed unit — is allowed).
  const auto sets = s.sets_of(d.id);
  for (auto it = sets.rbegin(); it != sets.rend(); ++it)
    if (it->status == SetStatus::approved || it->status == SetStatus::provisioned) return *it;
  if (sets.empty()) {
    // This login may not see drafts (PostgreSQL provisioning): say what waits, and for whom.
    const auto all = s.set_statuses(d.id);
    if (all.empty())
      throw std::runtime_error("device " + d.serial + " has no coefficient set (calbench station run, db store-bench)");
    const auto& newest = all.back();
    throw std::runtime_error(
        "device " + d.serial + " has no approved coefficient set: its newest, set " + std::to_string(newest.id) + " (v" +
        std::to_string(newest.version) + "), is " + to_string(newest.status) +
        (newest.status == SetStatus::draft
             ? ", awaiting approval: a QC login approves it (calbench db approve " + std::to_string(newest.id) +
                   " --db postgresql://QC_LOGIN@HOST/DB), then provision again"
             : ""));
  }
  const auto& newest = sets.back();
  throw std::runtime_error("device " + d.serial + " has no approved coefficient set: its newest, set " + std::to_string(newest.id) +
                           ", is " + to_string(newest.status) +
                           (newest.status == SetStatus::draft ? " (calbench db approve " + std::to_string(newest.id) + ")" : ""));
}

void run(const ProvisionArgs& a) {
  Store s(a.db.empty() ? Store::default_path() : a.db, OpenOptions{}, Actor::from_environment(a.op));
  const auto dev = s.find_device(a.serial);
  if (!dev) throw arg_error("SERIAL", "unknown device '" + a.serial + "' in " + s.connection().path());
  const CoefficientSetRecord set = choose_set(s, *dev, a.set);
  // A central store's role must be allowed to record the event before anything reaches a device
  // or a file: a device written without its record would be a unit nobody can trace.
  if (const std::string why = s.may_record_provisioning(); !why.empty()) throw PermissionError(0, why);
  s.check_signer();  // PostgreSQL: --operator must be the login's person (db/signer.hpp)

  if (!a.out.empty()) {
    write_text_atomic(a.out, set.payload_json + "\n");
    s.record_provisioning(set.id, "export", a.out, true, "{}", "coefficients.json written");
    if (a.json) print_json(json{{"set", set.id}, {"export", a.out}, {"ok", true}}.dump(2));
    else std::cout << "set " << set.id << " (" << set.serial << " v" << set.version << ") exported to " << a.out << "\n";
    return;
  }

  OpenedImu imu = open_imu(a.uri);
  Adis16488aOptions opt;
  opt.check_prod_id = false;  // checked below, so that a refusal is recorded
  Adis16488a drv(*imu.bus, opt);
  const ImuIdentity id = drv.connect();
  json report = {{"set", set.id}, {"target", a.uri}, {"prod_id", id.prod_id}, {"serial_num", id.serial},
                 {"firmware", id.firmware()}};
  std::string refuse;
  if (id.prod_id != adis::kProdId) {
    char b[64];
    std::snprintf(b, sizeof b, "PROD_ID 0x%04X is not an ADIS16488A (0x%04X)", id.prod_id, adis::kProdId);
    refuse = b;
  } else if (!serial_matches(set.serial, id.serial)) {
    refuse = "the unit's SERIAL_NUM is " + id.serial_string() + ", not " + set.serial;
  }
  if (!refuse.empty()) {
    report["ok"] = false;
    report["message"] = "refused: " + refuse;
    s.record_provisioning(set.id, "device", a.uri, false, report.dump(), "refused: " + refuse);
    if (a.json) print_json(report.dump(2));
    std::cerr << "calbench: provision refused: " << refuse << "; nothing written to the device\n";
    throw Exit{1};
  }
  const UserCal cal = user_cal_from_errors(set.errors);
  ProvisionResult r;
  try {
    r = drv.provision(cal);
  } catch (const std::exception& e) {
    r.ok = false;
    r.written = cal;
    r.message = e.what();
  }
  const SensorErrors residual = residual_after_user_cal(set.errors, cal);
  report["ok"] = r.ok;
  report["written"] = regs_json(r.written);
  report["read_back"] = regs_json(r.read_back);
  report["flash_count_before"] = r.flash_count_before;
  report["flash_count_after"] = r.flash_count_after;
  report["message"] = r.message;
  // The part holds per-axis scale and bias only; the skews stay for the host to apply.
  report["host_residual_max_skew"] = (residual.gyro.M - Mat3(residual.gyro.M.diagonal().asDiagonal())).cwiseAbs().maxCoeff();
  s.record_provisioning(set.id, "device", a.uri, r.ok, report.dump(), r.ok ? "written, flash updated, read back equal" : r.message);
  if (a.json) print_json(report.dump(2));
  if (!r.ok) {
    std::cerr << "calbench: provisioning FAILED: " << r.message << "\n";
    throw Exit{1};
  }
  if (!a.json)
    std::cout << "set " << set.id << " (" << set.serial << " v" << set.version << ") provisioned to " << a.uri
              << ": scale and bias registers written, flash updated (count " << r.flash_count_before << " -> "
              << r.flash_count_after << "), every register read back equal. Skews are not held by the device; "
              << "apply them on the host.\n";
}

const bool registered = add_command(80, [](CLI::App& app) {
  auto a = std::make_shared<ProvisionArgs>();
  auto* sub = app.add_subcommand("provision", "write an approved coefficient set to an IMU (or export it), recorded in the database");
  sub->add_option("SERIAL", a->serial, "device serial number")->required();
  sub->add_option("--set", a->set, "coefficient set id (default: the newest approved or provisioned set)")->check(set_id());
  auto* to = sub->add_option("--to-device", a->uri, "IMU: emu://SERIAL_NUM (emulated), mcp2210[:USB-SERIAL] or ft232h[:USB-SERIAL] (as station run --imu; mcp2210://… and ft232h://… also work)");
  auto* ex = sub->add_option("--export", a->out, "write the set as coefficients.json instead");
  to->excludes(ex);
  ex->excludes(to);
  sub->add_option("--db", a->db, "database: a SQLite file or a postgresql:// URI (default: $CALBENCH_DB, else ./calbench.db)");
  sub->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(sub, a->op, "who provisions, recorded with the event (default: $CALBENCH_OPERATOR, else the OS user)");
  sub->callback([a] {
    if (a->uri.empty() && a->out.empty()) throw arg_error("provision", "give --to-device IMU-URI or --export FILE");
    run(*a);
  });
});

}  // namespace
}  // namespace calbench::cli
