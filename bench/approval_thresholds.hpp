// The approval thresholds as every command uses them (db approve, report, the preview of fit drive):
// the thresholds file (or the built-in defaults, db/approval.hpp) with the device classes' stability
// allowances (bench/imu_classes/*.toml) that a combined set is compared with its parent by.
#pragma once
#include <string>

#include "db/approval.hpp"

namespace calbench {

// `file` empty: the built-in defaults. InputError naming the file and key on a bad file.
db::Thresholds approval_thresholds(const std::string& file);

}  // namespace calbench
