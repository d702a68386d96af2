#include "db/signed_approval.hpp"

#include <nlohmann/json.hpp>

#include "db/audit_chain.hpp"
#include "db/signer.hpp"

namespace calbench::db {

SignedApproval signed_approval(Store& store, const CoefficientSetRecord& set) {
  SignedApproval out;
  const auto audit = store.audit_of_device(set.device_id);
  for (const auto& a : audit)
    if (a.entity == "coefficient_set" && a.entity_id == set.id && a.action == "status" &&
        a.detail.rfind("draft -> approved", 0) == 0) {
      out.found = true;
      out.row = a;
    }
  if (!out.found) {
    out.why = "the audit log holds no signed approval of set " + std::to_string(set.id) +
              ": its status was changed outside calbench";
    return out;
  }
  if (const ChainCheck link = check_audit_row(store, out.row.id); !link.ok()) {
    out.why = "the approval row of set " + std::to_string(set.id) + " (audit row " + std::to_string(out.row.id) +
              ") fails the audit log's hash chain: " + link.breaks.front().why;
    return out;
  }
  // Four-eyes at the time: the signer is another person than the creator, unless it was off.
  const bool off = out.row.detail.find(", four-eyes off") != std::string::npos;
  const bool same = same_person(out.row.user, creator_name(set)) ||
                    (store.authenticated() && out.row.login == set.created_by_login);
  if (same && !off) {
    out.why = "set " + std::to_string(set.id) + " was approved by '" + out.row.user +
              "', who stored it, with four-eyes on: not a valid signature";
    return out;
  }
  out.ok = true;
  return out;
}

std::vector<std::string> provisioning_refusals(Store& store, const CoefficientSetRecord& set, const Thresholds& t) {
  std::vector<std::string> why;
  if (store.authenticated()) {
    // PostgreSQL: the server's own check (a provisioning login reads neither the audit log nor
    // the QC results: calbench_provisioning_refusals does, and calbench_record_provisioning again).
    auto st = store.connection().prepare("SELECT array_to_json(calbench_provisioning_refusals(?))::text");
    st.bind(1, set.id);
    st.step();
    for (const auto& x : nlohmann::json::parse(st.text(0))) why.push_back(x.get<std::string>());
    (void)t;
    return why;
  }
  if (set.status != SetStatus::approved && set.status != SetStatus::provisioned)
    why.push_back("set " + std::to_string(set.id) + " is " + to_string(set.status) + ": only approved sets are provisioned");
  if (const SignedApproval a = signed_approval(store, set); !a.ok) why.push_back(a.why);
  const ApprovalCheck v = check_standing(store, set, t);
  for (const auto& r : v.reasons) why.push_back("verdict now: " + r);
  return why;
}

}  // namespace calbench::db
