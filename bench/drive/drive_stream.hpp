// Reads a drive recording in time order for the in-motion fit and the QC: IMU rows turned into
// increments (rates are integrated by the trapezoidal rule), optionally corrected with a
// coefficient set first, interleaved with the reference epochs (each delivered right after the
// IMU row that reaches its time). Catalogue terms of the set (docs/diagnosis.md) are compensated
// on the raw samples first (calibration/effects/effect_compensation.hpp): output terms removed,
// time stamps moved by the time offset; with a time offset the IMU interval that straddles a
// reference epoch is split there (increments in proportion), so that epochs still meet IMU stamps.
#pragma once
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench/io/recording.hpp"
#include "calibration/effects/effect_compensation.hpp"
#include "calibration/inmotion/observation.hpp"
#include "calibration/ins/strapdown.hpp"

namespace calbench {

inmotion::RefObs to_ref_obs(const DriveRefRow& r);
// A gnss.csv row as an observation (antenna = reference body origin; no attitude; velocity where
// the row has it with a usable σ).
inmotion::RefObs to_ref_obs(const GnssRow& r);

// Which file aids the filter: reference.csv (reference INS) or gnss.csv (GNSS fixes only).
enum class Aiding { reference, gnss };

// A drive's reference.csv parsed once, for several MEMS units recorded against it (a multi-unit
// drive, docs/recording-units.md): every unit's fit and QC take their epochs from here.
struct SharedReference {
  fs::path file;
  std::vector<DriveRefRow> rows;
  std::string sha256;
};
std::shared_ptr<const SharedReference> load_shared_reference(const fs::path& file);

// What fit drive corrects of the logger before the filter sees the rows (DriveStream::
// set_logger_correction; measured by identification::SampleTimingEstimator).
struct LoggerCorrection {
  bool drop_repeats = false;  // rows repeating the previous row's six rates are second reads
};

class DriveStream {
 public:
  // effects: catalogue terms to compensate (with the set they belong to: pre_correction, or zero).
  // shared: the reference epochs from memory instead of dir/reference.csv (reference aiding only).
  // digest: SHA-256 of the IMU and aiding files computed while they are read (imu_sha256(),
  // aiding_sha256() once the stream has reached their ends).
  DriveStream(const fs::path& dir, const std::optional<SensorErrors>& pre_correction, const EffectTerms* effects = nullptr,
              Aiding aiding = Aiding::reference, std::shared_ptr<const SharedReference> shared = nullptr, bool digest = false);
  const RecordingMeta& meta() const { return meta_; }
  Mat3 nominal_mounting() const;  // C_mb from meta.json
  Vec3 lever_arm() const;

  struct Event {
    bool is_ref = false;
    double t = 0, dt = 0;
    Vec3 dtheta = Vec3::Zero(), dv = Vec3::Zero();  // IMU increments
    double temp_c = std::numeric_limits<double>::quiet_NaN();  // device temperature, if recorded
    inmotion::RefObs ref;
  };
  // Next IMU interval or reference epoch; false at the end.
  bool next(Event& e);
  // IMU rows read so far that carried a temperature.
  long rows_with_temperature() const { return rows_temp_; }
  // The reference.csv row of the reference epoch last returned (nullptr: GNSS aiding, or none yet).
  const DriveRefRow* last_reference_row() const { return have_row_ && !gnss_ ? &row_out_ : nullptr; }
  // The gnss.csv row of the fix last returned (nullptr: reference aiding, or none yet).
  const GnssRow* last_gnss_row() const { return have_row_ && gnss_ ? &gnss_out_ : nullptr; }
  // The logger's correction (identification/sample_timing.hpp; issue 53): rows that repeat the
  // previous row's six rates are second reads of one sample and are dropped (their interval joins the
  // next distinct sample's, so the trapezoid runs between distinct samples). Call before the first
  // next(); rates recordings only (increments are summed as they come).
  void set_logger_correction(const LoggerCorrection& c) { drop_repeats_ = c.drop_repeats; }
  long dropped_repeats() const { return dropped_; }
  std::optional<std::string> imu_sha256() const { return imu_->sha256(); }
  std::optional<std::string> aiding_sha256() const;

 private:
  fs::path dir_;
  RecordingMeta meta_;
  std::unique_ptr<ImuReader> imu_;
  std::unique_ptr<DriveRefReader> ref_;
  std::unique_ptr<GnssReader> gnss_;
  std::shared_ptr<const SharedReference> shared_;
  std::size_t shared_next_ = 0;
  std::optional<TriadCorrector> cg_, ca_;
  std::optional<ImuEffectCompensator> comp_;
  Event rest_;  // remainder of an IMU interval split at a reference epoch (time offset only)
  bool have_rest_ = false;
  long rows_temp_ = 0;
  ins::RateIntegrator integ_;
  bool have_ref_ = false, imu_done_ = false;
  inmotion::RefObs pending_;  // the next epoch of the aiding file
  DriveRefRow pending_row_, row_out_;  // its reference.csv row; that of the epoch last returned
  GnssRow pending_gnss_, gnss_out_;    // the same of gnss.csv
  bool have_row_ = false;
  bool ref_done_ = false, gnss_done_ = false;  // the aiding file read to its end
  bool read_epoch();
  double last_imu_t_ = -1e300;
  bool drop_repeats_ = false, have_raw_ = false;
  double skipped_dt_ = 0;
  long dropped_ = 0;
  Vec3 raw_g_ = Vec3::Zero(), raw_a_ = Vec3::Zero();  // the last distinct row as read
};

}  // namespace calbench
