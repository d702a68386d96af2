// Reads a drive recording in time order for the in-motion fit and the QC: IMU rows turned into
// increments (rates are integrated by the trapezoidal rule), optionally corrected with a
// coefficient set first, interleaved with the reference epochs (each delivered right after the
// IMU row that reaches its time).
#pragma once
#include <filesystem>
#include <optional>

#include "bench/io/recording.hpp"
#include "calibration/inmotion/observation.hpp"
#include "calibration/ins/strapdown.hpp"

namespace calbench {

inmotion::RefObs to_ref_obs(const DriveRefRow& r);

class DriveStream {
 public:
  DriveStream(const fs::path& dir, const std::optional<SensorErrors>& pre_correction);
  const RecordingMeta& meta() const { return meta_; }
  Mat3 nominal_mounting() const;  // C_mb from meta.json
  Vec3 lever_arm() const;

  struct Event {
    bool is_ref = false;
    double t = 0, dt = 0;
    Vec3 dtheta = Vec3::Zero(), dv = Vec3::Zero();  // IMU increments
    inmotion::RefObs ref;
  };
  // Next IMU interval or reference epoch; false at the end.
  bool next(Event& e);

 private:
  fs::path dir_;
  RecordingMeta meta_;
  std::unique_ptr<ImuReader> imu_;
  std::unique_ptr<DriveRefReader> ref_;
  std::optional<TriadCorrector> cg_, ca_;
  ins::RateIntegrator integ_;
  bool have_ref_ = false, imu_done_ = false;
  DriveRefRow ref_row_;
  double last_imu_t_ = -1e300;
};

}  // namespace calbench
