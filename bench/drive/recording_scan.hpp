// What fit drive learns of the unit and its logger from the recording before the fit (issue 34's
// white noise, issue 53's timing): one pass over the IMU table gives the white noise on the
// standstills (identification/standstill_noise.hpp) and the stamps' scatter about the sensor's
// clock (identification/sample_timing.hpp); gnss.csv alone gives how long before its stamp a fix's
// velocity describes the motion (identification/gnss_velocity_latency.hpp). RESULT.json carries
// each with where it came from ("white_noise", "sample_timing", "gnss_velocity_latency").
#pragma once
#include <filesystem>

#include <nlohmann/json.hpp>

#include "bench/io/recording.hpp"
#include "calibration/identification/gnss_velocity_latency.hpp"
#include "bench/drive/drive_stream.hpp"
#include "calibration/identification/sample_timing.hpp"
#include "calibration/identification/standstill_noise.hpp"

namespace calbench {

struct RecordingScan {
  identification::NoiseMeasurement noise;
  identification::SampleTiming timing;
  // imu.csv holds rates (not increments): a row repeating the previous one can be a second read
  // only then (two equal increments at rest are two samples).
  bool rates = true;
  bool scanned = false;
};

// One pass over the recording's IMU table (imu.csv or recording.h5's imu dataset).
RecordingScan scan_recording(const fs::path& dir, const RecordingMeta& meta, const NoiseSpec& cls);

// The GNSS velocity's latency, from gnss.csv (one pass; the file is small).
identification::GnssVelocityLatency scan_gnss_velocity_latency(const fs::path& dir);

// RESULT.json "sample_timing" and "gnss_velocity_latency": the measurement, the rule, and what the
// filter takes. `option` is the --sample-time / --gnss-vel-latency value ("auto" or seconds).
// The correction a fit applied, read back from its RESULT.json `sample_timing` (for a QC that
// navigates the same rows from the fit's states: `calbench qc --outages`).
LoggerCorrection applied_logger_correction(const nlohmann::json& sample_timing);
nlohmann::json sample_timing_json(const identification::SampleTiming& t, bool scanned, double used_s, const std::string& option,
                                  const LoggerCorrection& applied);
nlohmann::json gnss_velocity_latency_json(const identification::GnssVelocityLatency& l, double used_s, const std::string& option);

}  // namespace calbench
