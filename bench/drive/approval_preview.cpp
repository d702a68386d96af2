#include "bench/drive/approval_preview.hpp"

#include <sstream>

#include "bench/approval_thresholds.hpp"
#include "common/input_error.hpp"
#include "db/approval.hpp"
#include "db/inmotion_import.hpp"

namespace calbench {

namespace {

// The group of a reason, by what it is about (the approval's messages name it first).
std::string group_of(const std::string& why) {
  auto starts = [&](const char* p) { return why.rfind(p, 0) == 0; };
  if (starts("gyro")) return "gyro";
  if (starts("accel")) return "accel";
  if (starts("in-motion NIS")) return "NIS";
  if (starts("QC ") || starts("no QC") || starts("required QC")) return "QC";
  if (starts("combined")) return "combined";
  return "other";
}

// Reasons grouped in a fixed order, and "N gyro, M accel, ..." for the summary line.
nlohmann::json grouped(const std::vector<std::string>& reasons, std::string& summary) {
  nlohmann::json groups = nlohmann::json::array();
  for (const char* g : {"gyro", "accel", "QC", "NIS", "combined", "other"}) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& why : reasons)
      if (group_of(why) == g) list.push_back(why);
    if (list.empty()) continue;
    summary += (summary.empty() ? "" : ", ") + std::to_string(list.size()) + " " + g;
    groups.push_back({{"group", g}, {"reasons", list}});
  }
  return groups;
}

}  // namespace

nlohmann::json approval_preview(const DriveResult& r, const std::optional<CoefficientSet>& input,
                                const std::string& thresholds_file) {
  const nlohmann::json not_checked = {
      "the signature (a named operator; four-eyes)",
      input ? "the parent set's status in the store (it must be approved first)" : "the store's other sets"};
  auto verdict = [&](const db::Thresholds& t, const std::vector<std::string>& reasons) {
    std::string counts;
    const nlohmann::json groups = grouped(reasons, counts);
    const bool ok = reasons.empty();
    return nlohmann::json{
        {"verdict", ok ? "approvable" : "refused"},
        {"summary", ok ? std::string("every check passes") : std::to_string(reasons.size()) + " reason(s): " + counts},
        {"reasons", reasons},
        {"groups", groups},
        {"thresholds", t.source},
        {"not_checked", not_checked}};
  };
  db::InMotionResult in;
  try {
    in = db::parse_inmotion_result(drive_result_to_json(r).dump(), "fit drive result");
  } catch (const InputError& e) {
    return verdict(approval_thresholds(thresholds_file),
                   {std::string("db import-inmotion would refuse the result: ") + e.what()});
  }
  // The thresholds db approve will use for this set: its device class's, or the file's.
  const db::Thresholds t = approval_thresholds(thresholds_file, in.device.model);
  db::CoefficientSetRecord set;
  set.serial = in.device.serial;
  set.model = in.device.model;
  set.source = input ? db::SetSource::combined : db::SetSource::in_motion;
  set.errors = in.coefficients.errors;
  set.payload_json = in.coefficients.canonical_json;
  db::FitEvidence ev;
  ev.nis = r.nis;
  if (r.adaptive_noise) ev.adaptive = r.adaptive_noise;
  if (input) {
    db::CoefficientSetRecord parent;  // id 0: the input set, not yet a stored one
    parent.serial = input->device.serial;
    parent.model = input->device.model;
    parent.errors = input->errors;
    ev.parent = parent;
  }
  return verdict(t, db::check_verdict(set, in.qc, ev, t).reasons);
}

std::string approval_preview_text(const nlohmann::json& p, const std::string& out) {
  std::ostringstream o;
  const bool ok = p.value("verdict", "") == "approvable";
  o << "  approval preview " << (ok ? "db approve would approve this result" : "db approve will REFUSE this result") << " ("
    << p.value("summary", "") << "; thresholds: " << p.value("thresholds", "") << ")\n";
  for (const auto& g : p["groups"]) {
    o << "    " << g["group"].get<std::string>() << " (" << g["reasons"].size() << "):\n";
    for (const auto& why : g["reasons"]) o << "      - " << why.get<std::string>() << "\n";
  }
  o << "    other thresholds: fit drive --thresholds FILE (the JSON file of db approve --thresholds, docs/database.md)\n";
  o << "    not checked here: ";
  std::string sep;
  for (const auto& n : p["not_checked"]) {
    o << sep << n.get<std::string>();
    sep = "; ";
  }
  o << "\n";
  if (!out.empty()) {
    o << "RESULT.json written to " << out << "\n";
    o << "next: calbench db import-inmotion " << out << " --db DB --operator NAME"
      << (ok ? ", then calbench db approve SET --db DB --operator OTHER_NAME" : " (stores it as a draft; db approve will refuse it as above)")
      << "\n";
  }
  return o.str();
}

}  // namespace calbench
