// calbench provision SERIAL [--set ID] (--to-device IMU-URI | --export FILE): put an approved
// coefficient set where it is used, and record the event (docs/database.md "Provisioning").
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "bench/cli/operator_option.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "common/input_error.hpp"
#include "db/input_errors.hpp"
#include "bench/io/json_util.hpp"
#include "common/noise_spec.hpp"
#include "bench/approval_thresholds.hpp"
#include "db/signed_approval.hpp"
#include "db/store.hpp"
#include "devices/adis16488a.hpp"
#include "devices/imu_open.hpp"

namespace calbench::cli {
namespace {
using nlohmann::json;
using namespace calbench::db;
using namespace calbench::devices;

struct ProvisionArgs {
  std::string db, serial, uri, out, op, thresholds;
  std::int64_t set = 0;
  bool json = false;
};

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

json unit_state(Adis16488a& drv) {  // reads only
  return {{"registers", regs_json(drv.read_user_cal())}, {"flash_count", drv.read32(adis::reg("FLSHCNT"))}};
}

json misfits_json(const std::vector<RegisterMisfit>& ms) {
  json out = json::array();
  for (const auto& m : ms)
    out.push_back({{"coefficient", m.coefficient}, {"register", m.reg}, {"value", m.value},
                   {"needed_lsb", std::isfinite(m.needed_lsb) ? json(std::round(m.needed_lsb)) : json(nullptr)},
                   {"register_range", {m.reg_min, m.reg_max}}, {"holds", {m.min, m.max}}, {"text", m.text()}});
  return out;
}

json checks_json(const std::vector<CoefficientCheck>& cs) {
  json out = json::array();
  for (const auto& c : cs)
    out.push_back({{"coefficient", c.coefficient}, {"register", c.reg.empty() ? json(nullptr) : json(c.reg)},
                   {"approved", c.approved}, {"unit", c.unit}, {"residual", c.residual}, {"tolerance", c.tolerance},
                   {"host_applied", c.host_applied}, {"ok", c.ok}});
  return out;
}

// Why the unit may not receive the set ("" when it may): its identity, then whether every
// coefficient fits the registers (checked before anything is written; the unit's registers and
// FLSHCNT are read before and after, into the report, to show that nothing was).
std::string refusal(Adis16488a& drv, const ImuIdentity& id, const CoefficientSetRecord& set, json& report) {
  if (id.prod_id != adis::kProdId) {
    char b[64];
    std::snprintf(b, sizeof b, "PROD_ID 0x%04X is not an ADIS16488A (0x%04X)", id.prod_id, adis::kProdId);
    return b;
  }
  if (!serial_matches(set.serial, id.serial)) return "the unit's SERIAL_NUM is " + id.serial_string() + ", not " + set.serial;
  report["unit_before"] = unit_state(drv);
  const auto misfits = user_cal_misfits(set.errors);
  if (misfits.empty()) return "";
  report["misfits"] = misfits_json(misfits);
  report["unit_after"] = unit_state(drv);
  return UserCalRangeError(misfits).what();
}

// The device half of `provision`: identity and fit (a refusal writes nothing and is recorded),
// then write, flash update, read back, and compare what the unit will apply with the approved set.
void provision_to_device(Store& s, const ProvisionArgs& a, const CoefficientSetRecord& set, SpiBus& bus) {
  Adis16488aOptions opt;
  opt.check_prod_id = false;  // checked below, so that a refusal is recorded
  Adis16488a drv(bus, opt);
  const ImuIdentity id = drv.connect();
  json report = {{"set", set.id}, {"target", a.uri}, {"prod_id", id.prod_id}, {"serial_num", id.serial},
                 {"firmware", id.firmware()}};
  if (const std::string refuse = refusal(drv, id, set, report); !refuse.empty()) {
    report["ok"] = false;
    report["message"] = "refused: " + refuse;
    s.record_provisioning(set.id, "device", a.uri, false, report.dump(), "refused: " + refuse);
    if (a.json) print_json(report.dump(2));
    std::cerr << "calbench: provision refused: " << refuse << "; nothing written to the device\n";
    throw Exit{1};
  }
  ProvisionResult r;
  try {
    r = drv.provision(set.errors);
  } catch (const std::exception& e) {
    r.ok = false;
    r.wrote = true;
    r.written = user_cal_from_errors(set.errors);
    r.message = e.what();
  }
  // From the registers read back: what the host still applies (the skews, and sub-LSB residue).
  const SensorErrors residual = residual_after_user_cal(set.errors, r.read_back);
  const auto skew = [](const Mat3& m) { return (m - Mat3(m.diagonal().asDiagonal())).cwiseAbs().maxCoeff(); };
  report["ok"] = r.ok;
  report["written"] = regs_json(r.written);
  report["read_back"] = regs_json(r.read_back);
  report["flash_count_before"] = r.flash_count_before;
  report["flash_count_after"] = r.flash_count_after;
  report["coefficients"] = checks_json(r.checks);
  report["message"] = r.message;
  // The part holds per-axis scale and bias only; the skews stay for the host to apply.
  report["host_residual_max_skew"] = std::max(skew(residual.gyro.M), skew(residual.accel.M));
  s.record_provisioning(set.id, "device", a.uri, r.ok, report.dump(),
                        r.ok ? "written, flash updated, read back equal, every coefficient applied as approved" : r.message);
  if (a.json) print_json(report.dump(2));
  if (!r.ok) {
    std::cerr << "calbench: provisioning FAILED: " << r.message << "\n";
    throw Exit{1};
  }
  if (!a.json)
    std::cout << "set " << set.id << " (" << set.serial << " v" << set.version << ") provisioned to " << a.uri
              << ": scale and bias registers written, flash updated (count " << r.flash_count_before << " -> "
              << r.flash_count_after << "), every register read back equal, and the correction they apply equals "
              << "the set's scale and bias within half a register LSB. Skews are not held by the device; "
              << "apply them on the host.\n";
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

// --to-device, parsed by THE IMU URI parser (devices/imu_uri.hpp): emu://SERIAL_NUM[?prod_id=N&flash_fails=1],
// mcp2210[:USB-SERIAL][#csN], ft232h[:USB-SERIAL] (or KIND://…), opened by the station's opener.
ImuUri imu_uri(const std::string& uri) {
  ImuUri u;
  try {
    u = parse_imu_uri(uri);
  } catch (const std::invalid_argument& e) {
    throw arg_error("--to-device", e.what());
  }
  if (const std::string why = cannot_open(u); !why.empty()) throw arg_error("--to-device", why);
  return u;
}

void run(const ProvisionArgs& a) {
  if (!a.uri.empty()) (void)imu_uri(a.uri);  // bad input before the database is opened
  if (!a.out.empty()) check_output_path(a.out);  // an export that cannot be written: bad input, before any check
  Store s(a.db.empty() ? Store::default_path() : a.db, OpenOptions{}, Actor::from_environment(a.op));
  const auto dev = s.find_device(a.serial);
  if (!dev) throw arg_error("SERIAL", "unknown device '" + a.serial + "' in " + s.connection().path());
  const CoefficientSetRecord set = choose_set(s, *dev, a.set);
  // A central store's role must be allowed to record the event before anything reaches a device
  // or a file: a device written without its record would be a unit nobody can trace.
  if (const std::string why = s.may_record_provisioning(); !why.empty()) throw PermissionError(0, why);
  s.check_signer("provisioning");  // PostgreSQL: --operator must be the login's person (db/signer.hpp)
  // The signed approval, the device's audit rows intact and the verdict in force now, before
  // anything reaches a unit or a file (PostgreSQL checks its part again in the server).
  if (const auto why = provisioning_refusals(s, set, approval_thresholds(a.thresholds, a.thresholds.empty() ? set.model : ""));
      !why.empty()) {
    std::string all;
    for (const auto& w : why) all += "\n  - " + w;
    // Approved with another thresholds file: say which, so that the provisioner can give it too.
    const SignedApproval sa = signed_approval(s, set);
    const auto t = sa.row.detail.find("thresholds: ");
    if (a.thresholds.empty() && sa.found && t != std::string::npos &&
        std::any_of(why.begin(), why.end(), [](const std::string& w) { return w.rfind("verdict now:", 0) == 0; }))
      all += "\n(the set was approved with " + sa.row.detail.substr(t) + "; give the same with --thresholds FILE if it "
             "still holds)";
    throw std::runtime_error("set " + std::to_string(set.id) + " is not provisioned; nothing was written:" + all);
  }

  if (!a.out.empty()) {
    write_text_atomic(a.out, set.payload_json + "\n");
    s.record_provisioning(set.id, "export", a.out, true, "{}", "coefficients.json written");
    if (a.json) print_json(json{{"set", set.id}, {"export", a.out}, {"ok", true}}.dump(2));
    else std::cout << "set " << set.id << " (" << set.serial << " v" << set.version << ") exported to " << a.out << "\n";
    return;
  }

  const std::unique_ptr<SpiBus> bus = open_imu(imu_uri(a.uri));
  provision_to_device(s, a, set, *bus);
}

const bool registered = add_command(80, [](CLI::App& app) {
  auto a = std::make_shared<ProvisionArgs>();
  auto* sub = app.add_subcommand("provision", "write an approved coefficient set to an IMU (or export it), recorded in the database");
  sub->add_option("SERIAL", a->serial, "device serial number")->required();
  sub->add_option("--set", a->set, "coefficient set id (default: the newest approved or provisioned set)")->check(set_id());
  auto* to = sub->add_option("--to-device", a->uri, "IMU: emu://SERIAL_NUM[?prod_id=N&flash_fails=1] (emulated), mcp2210[:USB-SERIAL][#csN] or ft232h[:USB-SERIAL] (as station run --imu; mcp2210://… and ft232h://… also work)");
  auto* ex = sub->add_option("--export", a->out, "write the set as coefficients.json instead");
  to->excludes(ex);
  ex->excludes(to);
  sub->add_option("--db", a->db, "database: a SQLite file or a postgresql:// URI (default: $CALBENCH_DB, else ./calbench.db)");
  sub->add_option("--thresholds", a->thresholds, "QC thresholds the set must still meet (default: its device class's, as db approve)");
  sub->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(sub, a->op, "who provisions, recorded with the event (default: $CALBENCH_OPERATOR, else the OS user)");
  sub->callback([a] {
    if (a->uri.empty() && a->out.empty()) throw arg_error("provision", "give --to-device IMU-URI or --export FILE");
    run(*a);
  });
});

}  // namespace
}  // namespace calbench::cli
