// calbench db import-inmotion, store-bench and sync: what brings runs and sets into the store
// (registered with the other db subcommands in bench/cli/cmd_db.cpp; docs/database.md).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bench/cli/db_args.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/io/recording_location.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"
#include "db/connection.hpp"
#include "db/input_errors.hpp"
#include "db/inmotion_import.hpp"
#include "db/journal.hpp"
#include "db/store.hpp"

namespace calbench::cli::dbcmd {
using nlohmann::json;
using namespace calbench::db;

namespace {
// A RESULT.json read and checked (nothing is written on bad input).
InMotionResult read_result(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, 0, "", "cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  const InMotionResult r = parse_inmotion_result(ss.str(), file);
  // Where the recording is at hand, it must still be the one the result was fitted on.
  // (imu.csv, or recording.h5 for an HDF5 recording: the file the fit's digest is of)
  const std::filesystem::path imu = table_file(r.recording_path, "imu");
  if (std::filesystem::is_regular_file(imu) && sha256_file(imu) != r.recording_sha256)
    throw InputError(file, 0, "recording.sha256",
                     imu.string() + " has changed since the fit (its SHA-256 differs): refit, or import on the machine "
                     "that holds the recording it was fitted on");
  return r;
}

// The output folder of a multi-unit `fit drive` (units.json, calbench-fit-units/1): every unit's result.
void import_units(const DbArgs& a) {
  namespace fs = std::filesystem;
  const fs::path dir(a.file), file = dir / "units.json";
  const json j = read_json_file(file);
  if (j.is_object() && j.value("format", "") == "calbench-drive-units/1")
    throw InputError(file.string(), 0, "format",
                     "a multi-unit drive, not fit results: fit it first (calbench fit drive " + dir.string() +
                         " --out OUT), then import OUT");
  if (!j.is_object() || j.value("format", "") != "calbench-fit-units/1" || !j.contains("units") || !j["units"].is_array())
    throw InputError(file.string(), 0, "format", "expected the units.json of a multi-unit `fit drive` (calbench-fit-units/1)");
  if (a.parent) throw InputError("--parent", 0, "", "one parent set cannot be every unit's: import a unit's RESULT.json alone");
  std::vector<std::pair<std::string, InMotionResult>> results;  // all checked before anything is stored
  std::vector<std::string> files;
  for (const auto& u : j["units"]) {
    if (!u.value("ok", false)) {
      std::cerr << "unit " << u.value("slot", "?") << ": not fitted (" << u.value("error", "") << "), skipped\n";
      continue;
    }
    const std::string f = (dir / u.value("result", "")).string();
    results.emplace_back(u.value("slot", ""), read_result(f));
    files.push_back(f);
  }
  if (results.empty()) throw InputError(file.string(), 0, "units", "no fitted unit to import");
  auto s = open_store(a);
  json out = json::array();
  for (std::size_t k = 0; k < results.size(); ++k) {
    const auto& [slot, r] = results[k];
    const ImportOutcome o = import_inmotion(*s, r, files[k], std::nullopt);
    out.push_back({{"slot", slot}, {"serial", r.device.serial}, {"set", o.set_id}, {"version", o.version},
                   {"source", to_string(o.source)}, {"parent", o.parent_id ? json(*o.parent_id) : json(nullptr)},
                   {"inmotion_run", o.run_id}, {"note", o.note}});
    if (!a.json)
      std::cout << "unit " << slot << ": stored in-motion run " << o.run_id << " and set " << o.set_id << " ("
                << r.device.serial << " v" << o.version << ", " << to_string(o.source)
                << (o.parent_id ? ", parent set " + std::to_string(*o.parent_id) : std::string()) << ", draft)\n";
  }
  if (a.json) print_json(json{{"units", out}}.dump(2));
}
}  // namespace

void cmd_import_inmotion(const DbArgs& a) {
  if (std::filesystem::is_directory(a.file) && std::filesystem::is_regular_file(std::filesystem::path(a.file) / "units.json"))
    return import_units(a);
  const InMotionResult r = read_result(a.file);  // before opening: nothing written on bad input
  auto s = open_store(a);
  const ImportOutcome o = import_inmotion(*s, r, a.file, a.parent ? std::optional<std::int64_t>(a.parent) : std::nullopt);
  if (a.json) {
    print_json(json{{"set", o.set_id}, {"version", o.version}, {"source", to_string(o.source)},
                    {"parent", o.parent_id ? json(*o.parent_id) : json(nullptr)}, {"inmotion_run", o.run_id},
                    {"qc_metrics", r.qc.size()}, {"note", o.note}}
                   .dump(2));
    return;
  }
  std::cout << "stored in-motion run " << o.run_id << " and set " << o.set_id << " (" << r.device.serial << " v"
            << o.version << ", " << to_string(o.source)
            << (o.parent_id ? ", parent set " + std::to_string(*o.parent_id) : std::string()) << ", draft), "
            << r.qc.size() << " QC metric(s)\n";
  if (!o.note.empty()) std::cout << "note: " << o.note << "\n";
}

namespace {
// --qc NAME=VALUE[:THRESHOLD[:UNIT[:SAMPLE]]]  (pass = |value| ≤ threshold when a threshold is given;
// SAMPLE in-sample, out-of-sample or "not applicable")
QcResult parse_qc_option(const std::string& s) {
  const auto eq = s.find('=');
  if (eq == std::string::npos || eq == 0)
    throw arg_error("--qc", "expected NAME=VALUE[:THRESHOLD[:UNIT[:SAMPLE]]], got '" + s + "'");
  QcResult q;
  q.metric = s.substr(0, eq);
  std::vector<std::string> parts;
  std::stringstream rest(s.substr(eq + 1));
  for (std::string p; std::getline(rest, p, ':');) parts.push_back(p);
  auto num = [&](const std::string& t) {
    std::size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(t, &used);
    } catch (...) {
    }
    if (used != t.size() || !std::isfinite(v)) throw arg_error("--qc " + q.metric, "'" + t + "' is not a finite number");
    return v;
  };
  if (parts.empty()) throw arg_error("--qc " + q.metric, "missing value");
  q.value = num(parts[0]);
  if (parts.size() > 1 && !parts[1].empty()) {
    q.threshold = num(parts[1]);
    q.pass = std::abs(q.value) <= *q.threshold;
    q.criterion = "|value| ≤ threshold";
  }
  if (parts.size() > 2) q.unit = parts[2];
  if (parts.size() > 3) {
    q.sample = parts[3];
    if (q.sample != kInSample && q.sample != kOutOfSample && q.sample != kSampleNotApplicable)
      throw arg_error("--qc " + q.metric, "sample '" + q.sample + "' is not in-sample, out-of-sample or \"not applicable\"");
  }
  if (parts.size() > 4) throw arg_error("--qc " + q.metric, "expected NAME=VALUE[:THRESHOLD[:UNIT[:SAMPLE]]]");
  return q;
}

}  // namespace

void cmd_store_bench(const DbArgs& a) {
  const CoefficientSet c = read_coefficients(a.coeffs);  // validates, names the file
  DeviceInfo d{c.device.model, c.device.serial, a.firmware};
  BenchRunInput run;
  run.station = a.station.empty() ? Actor::from_environment(a.op).station : a.station;
  run.plan = a.plan;
  if (!a.recording.empty()) {
    check_same_unit(c.device, a.coeffs, a.recording);  // another unit's recording is not this set's run
    describe_recording(run, a.recording);              // absolute URI and digest of its files
  }
  run.recording_sha256 = a.sha256;
  if (run.recording_sha256.empty() && !a.recording.empty()) {
    const std::filesystem::path imu = table_file(a.recording, "imu");  // imu.csv, or recording.h5
    if (!std::filesystem::exists(imu)) throw InputError(imu.string(), 0, "", "recording has no imu.csv (and no recording.h5)");
    run.recording_sha256 = sha256_file(imu);
  }
  // A set that names the IMU table it was fitted from (fit multipos: "source": {"imu_sha256"}) is
  // stored only with that recording.
  if (const auto src = c.extra.find("source"); src != c.extra.end() && src->is_object() && src->contains("imu_sha256") &&
                                               !run.recording_sha256.empty()) {
    const auto& h = (*src)["imu_sha256"];
    if (!h.is_string() || h.get<std::string>() != run.recording_sha256)
      throw InputError(a.coeffs, 0, "source.imu_sha256",
                       "the set was fitted from another recording (" + src->value("recording", std::string("?")) +
                           "): its IMU table's SHA-256 differs from the one given (" +
                           (a.recording.empty() ? std::string("--sha256") : a.recording) + ")");
  }
  run.started_at = a.started;
  run.ended_at = a.ended;
  // Both were checked by their options (number_options.hpp, iso8601_utc).
  if (const auto t0 = iso8601_utc_seconds(a.started), t1 = iso8601_utc_seconds(a.ended); t0 && t1 && *t1 < *t0)
    throw InputError("--ended", 0, "", a.ended + " is before --started " + a.started);

  run.outcome = a.outcome;
  for (const auto& q : a.qc) run.qc.push_back(parse_qc_option(q));
  if (is_postgres_uri(db_path(a))) {
    // A central store: the journal first (never waits for the network), then forwarded.
    check_target(db_path(a));
    OpenOptions o;
    o.create = true;
    Store j(journal_path(a.journal), o, Actor::from_environment(a.op));
    const StoredSet st = j.store_bench(d, run, coefficients_to_json(c).dump(2));
    const SyncOutcome so = sync_journal(j, db_path(a));
    if (a.json) {
      print_json(json{{"journal", j.connection().path()}, {"journal_bench_run", st.run_id}, {"journal_set", st.set_id},
                      {"central", redact_uri(db_path(a))}, {"reached", so.reached}, {"forwarded", so.forwarded + so.already},
                      {"pending", so.pending_after}, {"lines", so.lines}}.dump(2));
      return;
    }
    std::cout << "stored bench run " << st.run_id << " and set " << st.set_id << " in the journal " << j.connection().path()
              << "\n";
    for (const auto& l : so.lines) std::cout << "  forwarded: " << l << "\n";
    if (!so.reached)
      std::cout << "central store not reached (" << so.error << "): " << so.pending_after
                << " run(s) wait in the journal; `calbench db sync` forwards them\n";
    return;
  }
  auto s = open_store(a, true);
  const StoredSet st = s->store_bench(d, run, coefficients_to_json(c).dump(2));
  if (a.json) {
    print_json(json{{"device", st.device_id}, {"bench_run", st.run_id}, {"set", st.set_id}, {"version", st.version}}.dump(2));
    return;
  }
  std::cout << "stored bench run " << st.run_id << " and set " << st.set_id << " (" << d.serial << " v" << st.version
            << ", draft)\n";
}

// db sync: forward the journal's pending runs and sets to the central store (--db URI).
void cmd_sync(const DbArgs& a) {
  const std::string central = db_path(a);
  if (!is_postgres_uri(central))
    throw arg_error("--db", "db sync forwards a station's journal to a central PostgreSQL store: give --db postgresql://... "
                            "(or CALBENCH_DB)");
  check_target(central);
  const std::string jp = journal_path(a.journal);
  if (!std::filesystem::exists(jp))
    throw InputError(jp, 0, "", "no journal here (a station run or db store-bench with a PostgreSQL --db writes it): give "
                                "--journal FILE or CALBENCH_JOURNAL");
  OpenOptions o;  // the journal must exist (a typo would otherwise create an empty one and report nothing to do)
  Store j(jp, o, Actor::from_environment(a.op));
  if (a.status) {
    const auto items = pending(j);
    if (a.json) {
      json arr = json::array();
      for (const auto& i : items)
        arr.push_back({{"uid", i.uid}, {"serial", i.serial}, {"bench_run", i.local_run_id}, {"outcome", i.outcome},
                       {"set", i.has_set}, {"created_at", i.created_at}});
      print_json(json{{"journal", j.connection().path()}, {"central", redact_uri(central)}, {"pending", arr}}.dump(2));
      return;
    }
    std::cout << "journal " << j.connection().path() << ": " << items.size() << " run(s) not yet in " << redact_uri(central)
              << "\n";
    for (const auto& i : items)
      std::cout << "  " << i.created_at << "  " << i.serial << "  run " << i.local_run_id << " (" << i.outcome << ")"
                << (i.has_set ? " with its set" : "") << "\n";
    return;
  }
  const SyncOutcome so = sync_journal(j, central);
  if (a.json) {
    print_json(json{{"journal", j.connection().path()}, {"central", redact_uri(central)}, {"reached", so.reached},
                    {"forwarded", so.forwarded}, {"already", so.already}, {"pending", so.pending_after},
                    {"error", so.error}, {"lines", so.lines}}.dump(2));
  } else {
    for (const auto& l : so.lines) std::cout << "forwarded: " << l << "\n";
    std::cout << so.forwarded << " forwarded, " << so.already << " already there, " << so.pending_after << " pending\n";
  }
  if (!so.reached || so.pending_after > 0)
    throw DbError(1, "central store not reached: " + so.error + " (" + std::to_string(so.pending_after) +
                         " run(s) still in the journal " + j.connection().path() + ")");
}

}  // namespace calbench::cli::dbcmd
