#include "bench/drive/drive_units.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "bench/io/json_util.hpp"
#include "bench/io/slot_name.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"

namespace calbench {
namespace fs = std::filesystem;

namespace {

// The unit's copy of a shared file is that file: the same file (a hard link), or equal bytes.
bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::equivalent(a, b, ec)) return true;
  if (fs::file_size(a, ec) != fs::file_size(b, ec) || ec) return false;
  return sha256_file(a) == sha256_file(b);
}

}  // namespace

bool is_multi_unit_drive(const fs::path& dir) { return fs::is_regular_file(dir / "units.json"); }

DriveUnits load_drive_units(const fs::path& dir) {
  const fs::path file = dir / "units.json";
  const std::string f = file.string();
  const nlohmann::json j = read_json_file(file);
  if (!j.is_object()) throw InputError(f, 0, "", "not a JSON object");
  if (!j.contains("format") || j["format"] != "calbench-drive-units/1")
    throw InputError(f, 0, "format", "expected \"calbench-drive-units/1\"");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "format" && it.key() != "reference" && it.key() != "gnss" && it.key() != "units" && it.key() != "notes")
      throw InputError(f, 0, it.key(), "unknown key (format, reference, gnss, units, notes)");
  DriveUnits d;
  d.dir = dir;
  auto shared = [&](const char* key, bool required) -> fs::path {
    if (!j.contains(key)) {
      if (required) throw InputError(f, 0, key, "missing (the drive's reference file, e.g. \"reference.csv\")");
      return {};
    }
    if (!j[key].is_string() || j[key].get<std::string>().empty()) throw InputError(f, 0, key, "expected a file name");
    const fs::path p = dir / j[key].get<std::string>();
    if (!fs::is_regular_file(p)) throw InputError(f, 0, key, "no such file: " + p.string());
    return p;
  };
  d.reference = shared("reference", true);
  d.gnss = shared("gnss", false);
  if (!j.contains("units") || !j["units"].is_array() || j["units"].empty())
    throw InputError(f, 0, "units", "expected a non-empty array of {\"slot\", \"dir\"}");
  if (j["units"].size() > 16) throw InputError(f, 0, "units", "at most 16 units");
  std::set<std::string> slots, dirs;
  for (std::size_t i = 0; i < j["units"].size(); ++i) {
    const auto& u = j["units"][i];
    const std::string key = "units[" + std::to_string(i) + "]";
    if (!u.is_object() || !u.contains("slot") || !u["slot"].is_string() || !u.contains("dir") || !u["dir"].is_string())
      throw InputError(f, 0, key, "expected {\"slot\": NAME, \"dir\": FOLDER}");
    DriveUnit du;
    du.slot = u["slot"].get<std::string>();
    if (!valid_slot_name(du.slot)) throw InputError(f, 0, key + ".slot", "'" + du.slot + "': " + kSlotNameRule);
    if (!slots.insert(du.slot).second) throw InputError(f, 0, key + ".slot", "duplicate slot '" + du.slot + "'");
    const std::string rel = u["dir"].get<std::string>();
    if (rel.empty() || fs::path(rel).is_absolute() || rel.find("..") != std::string::npos)
      throw InputError(f, 0, key + ".dir", "'" + rel + "': a folder inside the drive's folder");
    if (!dirs.insert(fs::path(rel).lexically_normal().string()).second)
      throw InputError(f, 0, key + ".dir", "'" + rel + "' is another unit's folder too");
    du.dir = dir / rel;
    if (!fs::is_regular_file(du.dir / "meta.json"))
      throw InputError(f, 0, key + ".dir", "no recording in " + du.dir.string() + " (no meta.json)");
    if (read_meta(du.dir).kind != RecordingKind::drive)
      throw InputError((du.dir / "meta.json").string(), 0, "kind", "expected a drive recording (kind \"drive\")");
    // Each unit folder is a whole recording: its reference.csv is the drive's (a hard link or a copy).
    if (!fs::exists(du.dir / "reference.csv") || !same_file(d.reference, du.dir / "reference.csv"))
      throw InputError((du.dir / "reference.csv").string(), 0, "",
                       "missing or not the drive's " + d.reference.filename().string() +
                           " (units.json: one reference for every unit)");
    d.units.push_back(du);
  }
  return d;
}

std::vector<UnitFit> fit_drive_units(const FitDriveArgs& a, unsigned threads, nlohmann::json* summary) {
  const DriveUnits du = load_drive_units(a.dir);
  const fs::path out(a.out);
  if (fs::exists(out) && !fs::is_directory(out))
    throw InputError(a.out, 0, "", "several units: --out names a folder (OUT/SLOT/RESULT.json), not a file");
  if (!a.coeffs.empty() && !fs::is_directory(a.coeffs))
    throw InputError(a.coeffs, 0, "",
                     "several units: --coeffs names a folder with SLOT/COEFFS.json (or SLOT/RESULT.json) per unit, as "
                     "`station run --fixture` writes");
  check_output_folder(out);
  // Per unit: its input set (if any) and its output, checked before any fit runs.
  std::vector<FitDriveArgs> args;
  for (const DriveUnit& u : du.units) {
    FitDriveArgs x = a;
    x.dir = u.dir.string();
    x.out = (out / u.slot / "RESULT.json").string();
    if (!a.series.empty()) x.series = (out / u.slot / fs::path(a.series).filename()).string();
    if (!a.coeffs.empty()) {
      const fs::path c = fs::path(a.coeffs) / u.slot;
      if (fs::is_regular_file(c / "COEFFS.json")) x.coeffs = (c / "COEFFS.json").string();
      else if (fs::is_regular_file(c / "RESULT.json")) x.coeffs = (c / "RESULT.json").string();
      else throw InputError(a.coeffs, 0, u.slot, "no " + u.slot + "/COEFFS.json or " + u.slot + "/RESULT.json for slot '" + u.slot + "'");
    }
    args.push_back(std::move(x));
  }
  // The reference, once for every unit (GNSS aiding reads each unit's gnss.csv: small).
  std::shared_ptr<const SharedReference> ref;
  if (a.aiding != "gnss") ref = load_shared_reference(du.reference);
  for (auto& x : args) x.shared_reference = ref;
  // What this run makes is removed again where it holds no result: a unit's folder when the unit
  // failed, and --out with units.json when every unit failed (a failed run leaves nothing behind).
  const bool out_existed = fs::exists(out);
  std::vector<bool> slot_existed;
  for (const DriveUnit& u : du.units) {
    slot_existed.push_back(fs::exists(out / u.slot));
    fs::create_directories(out / u.slot);
  }
  // A unit that fails leaves no result in its slot, nor one from an earlier run into the same OUT
  // (units.json says it failed): this run's outputs there go, and the slot folder when this run
  // made it or nothing else is left in it.
  const auto remove_made = [&](std::size_t k) {
    std::error_code ec;
    const fs::path slot = out / du.units[k].slot;
    if (!slot_existed[k]) {
      fs::remove_all(slot, ec);
      return;
    }
    fs::remove(args[k].out, ec);
    if (!args[k].series.empty()) fs::remove(args[k].series, ec);
    if (fs::is_empty(slot, ec) && !ec) fs::remove(slot, ec);
  };

  std::vector<UnitFit> fits(du.units.size());
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t k; (k = next++) < args.size();) {
      UnitFit& r = fits[k];
      r.slot = du.units[k].slot;
      r.out = args[k].out;
      try {
        r.result = fit_drive(args[k]);
      } catch (const InputError& e) {
        r.error = e.what();
        r.bad_input = true;
      } catch (const std::exception& e) {
        r.error = e.what();
      }
    }
  };
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  threads = std::min<unsigned>(threads, static_cast<unsigned>(args.size()));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();

  bool any_fitted = false;
  for (std::size_t k = 0; k < fits.size(); ++k) {
    if (fits[k].error.empty()) any_fitted = true;
    else remove_made(k);
  }
  nlohmann::json units = nlohmann::json::array();
  for (const UnitFit& r : fits) {
    nlohmann::json u = {{"slot", r.slot}, {"ok", r.error.empty()}};
    if (r.error.empty()) {
      u["result"] = fs::path(r.out).lexically_relative(out).string();
      u["serial"] = r.result.device.serial;
    } else {
      u["error"] = r.error;
    }
    units.push_back(u);
  }
  nlohmann::json s = {{"format", "calbench-fit-units/1"},
                      {"drive", du.dir.string()},
                      {"reference", {{"file", du.reference.string()},
                                     {"rows", ref ? nlohmann::json(ref->rows.size()) : nlohmann::json(nullptr)},
                                     {"sha256", ref ? nlohmann::json(ref->sha256) : nlohmann::json(nullptr)},
                                     {"parsed", ref ? "once, for every unit" : "not used (GNSS aiding)"}}},
                      {"threads", threads},
                      {"units", units}};
  if (any_fitted) write_text_atomic(out / "units.json", s.dump(2) + "\n");
  else {  // every unit failed: nothing made stays, and no units.json of an earlier run names results gone
    std::error_code ec;
    if (!out_existed) fs::remove_all(out, ec);
    else fs::remove(out / "units.json", ec);
  }
  if (summary) *summary = s;
  return fits;
}

}  // namespace calbench
