// What `db approve` will say about a `fit drive` result (issue 35 item 6), with the thresholds it
// will use: the built-in defaults of the recording's device class (meta.json device.model, as db
// approve takes the set's model) or a thresholds file (fit drive --thresholds, as db approve
// --thresholds). The result is read as `db import-inmotion` reads it (db/inmotion_import.hpp: its
// QC metrics) and judged by the approval's own verdict (db::check_verdict: thresholds, QC, NIS,
// and a combined set against the input set it refines). RESULT.json "approval_preview"; the
// console summary ends with it.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "common/coefficients_codec.hpp"
#include "common/drive_result.hpp"

namespace calbench {

// {"verdict": "approvable" | "refused", "summary": "...", "reasons": [...],
//  "groups": [{"group": "gyro" | "accel" | "QC" | "NIS" | "combined" | "other", "reasons": [...]}],
//  "thresholds": "...", "not_checked": [...]}
// `input`: the set the fit started from (--coeffs), the parent of the combined set it becomes.
// `thresholds_file`: "" = the built-in defaults of the device class.
nlohmann::json approval_preview(const DriveResult& r, const std::optional<CoefficientSet>& input,
                                const std::string& thresholds_file = "");

// The console lines of a preview (the end of the fit's summary): the verdict with a one-line
// summary, the reasons by group, how to judge with another thresholds file, what is not checked,
// where RESULT.json is (`out`) and the next command.
std::string approval_preview_text(const nlohmann::json& preview, const std::string& out);

}  // namespace calbench
