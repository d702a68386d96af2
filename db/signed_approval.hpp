// Whether a set's approval is one calbench made (issue 54 item 4): the signed audit row of its
// draft -> approved change, intact and signed by another person than the creator (unless four-eyes
// was off then). The device report, provisioning and `db verify` ask the same question here.
#pragma once
#include <string>
#include <vector>

#include "db/approval.hpp"
#include "db/store.hpp"

namespace calbench::db {

struct SignedApproval {
  bool found = false;  // an audit row "status: draft -> approved…" of the set
  bool ok = false;     // found, intact (SQLite: its hash-chain link holds) and four-eyes held
  std::string why;     // why not ok
  AuditEntry row;
};
SignedApproval signed_approval(Store& store, const CoefficientSetRecord& set);

// Everything that must hold before `set` goes into a unit or a file: approved (or provisioned), its
// signed approval (signed_approval: intact in the hash chain, four-eyes held) and the verdict in
// force now (check_standing with `t`). Empty: it may be provisioned. (A row forged elsewhere in the
// device's log does not block a set approved properly since; the device report and db verify show it.)
std::vector<std::string> provisioning_refusals(Store& store, const CoefficientSetRecord& set, const Thresholds& t);

}  // namespace calbench::db
