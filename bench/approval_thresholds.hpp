// The approval thresholds as every command uses them (db approve, report, the preview of fit drive):
// the thresholds file (or the built-in defaults, db/approval.hpp) with the device classes' stability
// allowances (bench/imu_classes/*.toml) that a combined set is compared with its parent by.
#pragma once
#include <string>

#include "db/approval.hpp"

namespace calbench {

// `file` empty: the built-in defaults, for the device class `model` names (meta.json / the set's
// device.model, matched as bench/imu_classes/*.toml match it): the coefficient limits are those of
// db::default_thresholds() scaled to the class's [spread] (bias and scale 5x the spread, skew 10x:
// for ADIS16488A exactly the built-in figures); σ limits and the rest as built in. A model of no
// built-in class (or none): the built-in ADIS16488A defaults. InputError naming the file and key
// on a bad file.
db::Thresholds approval_thresholds(const std::string& file, const std::string& model = "");

}  // namespace calbench
