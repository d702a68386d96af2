#include "bench/drive/approval_preview.hpp"

#include <sstream>

#include "bench/approval_thresholds.hpp"
#include "common/input_error.hpp"
#include "db/approval.hpp"
#include "db/inmotion_import.hpp"

namespace calbench {

nlohmann::json approval_preview(const DriveResult& r, const std::optional<CoefficientSet>& input) {
  const db::Thresholds t = approval_thresholds("");
  const nlohmann::json not_checked = {
      "the signature (a named operator; four-eyes)",
      input ? "the parent set's status in the store (it must be approved first)" : "the store's other sets"};
  db::InMotionResult in;
  try {
    in = db::parse_inmotion_result(drive_result_to_json(r).dump(), "fit drive result");
  } catch (const InputError& e) {
    return {{"verdict", "refused"},
            {"reasons", {std::string("db import-inmotion would refuse the result: ") + e.what()}},
            {"thresholds", t.source},
            {"not_checked", not_checked}};
  }
  db::CoefficientSetRecord set;
  set.serial = in.device.serial;
  set.model = in.device.model;
  set.source = input ? db::SetSource::combined : db::SetSource::in_motion;
  set.errors = in.coefficients.errors;
  set.payload_json = in.coefficients.canonical_json;
  db::FitEvidence ev;
  ev.nis = r.nis;
  if (input) {
    db::CoefficientSetRecord parent;  // id 0: the input set, not yet a stored one
    parent.serial = input->device.serial;
    parent.model = input->device.model;
    parent.errors = input->errors;
    ev.parent = parent;
  }
  const db::ApprovalCheck c = db::check_verdict(set, in.qc, ev, t);
  return {{"verdict", c.ok ? "approvable" : "refused"},
          {"reasons", c.reasons},
          {"thresholds", t.source},
          {"not_checked", not_checked}};
}

std::string approval_preview_text(const nlohmann::json& p) {
  std::ostringstream o;
  const bool ok = p.value("verdict", "") == "approvable";
  o << "  approval preview " << (ok ? "db approve would approve this result" : "db approve will REFUSE this result") << " ("
    << p.value("thresholds", "") << ")" << (ok ? "" : ":") << "\n";
  for (const auto& why : p["reasons"]) o << "    - " << why.get<std::string>() << "\n";
  o << "    not checked here:";
  for (const auto& n : p["not_checked"]) o << " " << n.get<std::string>() << ";";
  o << "\n";
  return o.str();
}

}  // namespace calbench
