// What `db approve` will say about a `fit drive` result (issue 35 item 6), with the default
// thresholds: the result read as `db import-inmotion` reads it (db/inmotion_import.hpp: its QC
// metrics), judged by the approval's own verdict (db::check_verdict: thresholds, QC, NIS, and a
// combined set against the input set it refines). RESULT.json "approval_preview"; the console
// summary ends with it.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>

#include "common/coefficients_codec.hpp"
#include "common/drive_result.hpp"

namespace calbench {

// {"verdict": "approvable" | "refused", "reasons": [...], "thresholds": "...", "not_checked": [...]}
// `input`: the set the fit started from (--coeffs), the parent of the combined set it becomes.
nlohmann::json approval_preview(const DriveResult& r, const std::optional<CoefficientSet>& input);

// The console lines of a preview (the end of the fit's summary).
std::string approval_preview_text(const nlohmann::json& preview);

}  // namespace calbench
