#include "bench/drive/recording_scan.hpp"

#include <cmath>

#include "common/units.hpp"

namespace calbench {

RecordingScan scan_recording(const fs::path& dir, const RecordingMeta& meta, const NoiseSpec& cls) {
  RecordingScan out;
  identification::StandstillDetector det(cls);
  identification::SampleTimingEstimator timing;
  ImuReader rd(dir / "imu.csv", meta.imu_rate_hz);  // imu.csv, or the imu dataset of recording.h5
  ImuRecord r;
  const bool inc = rd.form() == ImuForm::increments;
  while (rd.next(r)) {
    timing.add(r.t, r.gyro, r.accel);  // the values as read: a second read repeats all six
    if (inc && !(r.dt > 0)) continue;
    det.add(r.t, inc ? Vec3(r.gyro / r.dt) : r.gyro, inc ? Vec3(r.accel / r.dt) : r.accel);
  }
  det.finish();
  out.noise = identification::measure_white_noise(det.standstills(), cls);
  out.timing = timing.result();
  out.scanned = true;
  out.rates = !inc;
  return out;
}

identification::GnssVelocityLatency scan_gnss_velocity_latency(const fs::path& dir) {
  std::vector<identification::GnssFixSample> fixes;
  GnssReader rd(dir / "gnss.csv");
  GnssRow g;
  while (rd.next(g)) {
    identification::GnssFixSample s;
    s.t = g.t;
    s.lat = g.lat_deg * units::kDeg;
    s.lon = g.lon_deg * units::kDeg;
    s.h = g.h_m;
    s.has_vel = g.v_ned.has_value() && !(g.sigma_vel_m_s >= 1e3);
    if (s.has_vel) s.v_ned = *g.v_ned;
    s.sigma_h = std::isfinite(g.sigma_h_m) ? g.sigma_h_m : 0.0;
    fixes.push_back(s);
  }
  return identification::measure_gnss_velocity_latency(fixes);
}

LoggerCorrection applied_logger_correction(const nlohmann::json& st) {
  LoggerCorrection c;
  if (!st.is_object() || !st.contains("applied")) return c;
  const nlohmann::json& a = st["applied"];
  c.drop_repeats = a.value("dropped_repeated_rows", false);
  return c;
}

nlohmann::json sample_timing_json(const identification::SampleTiming& t, bool scanned, double used_s, const std::string& option,
                                  const LoggerCorrection& applied) {
  nlohmann::json j = {
      {"method", "rows repeating the previous row's six values are second reads; the distinct samples' stamps fitted by a line "
                 "over runs of 256 (the sensor's clock); sigma = median over the runs of the residuals' sigma (beyond 5 robust sigma left "
                 "out); below 10 us: regular (0). Filter: process noise sigma^2 |dm|^2 per step on velocity and attitude. "
                 "Lateness: the stamps' mean above their earliest (each run's 1st percentile of the residuals; median over the runs), "
                 "reported, not applied. Where the stamps are not regular (and not --sample-time off) the rows repeating the "
                 "previous row are dropped as second reads (identification/sample_timing.hpp)"},
      {"scanned", scanned},
      {"option", option},
      {"used_ms", used_s * 1e3}};
  if (scanned) {
    j["rows"] = t.rows;
    j["repeated_rows"] = t.repeated;
    j["read_rate_hz"] = t.read_rate_hz;
    j["distinct_rate_hz"] = t.distinct_rate_hz;
    j["sigma_ms"] = t.sigma_s * 1e3;
    j["lateness_ms"] = t.lateness_s * 1e3;
    j["polling"] = t.polling();
    j["runs"] = t.runs;
    j["regular"] = t.regular;
  }
  j["applied"] = {{"dropped_repeated_rows", applied.drop_repeats}};
  j["source"] = option != "auto" ? "--sample-time" : !scanned ? "none (--no-noise-scan)" : t.regular ? "measured: regular stamps (0)" : "measured";
  return j;
}

nlohmann::json gnss_velocity_latency_json(const identification::GnssVelocityLatency& l, double used_s, const std::string& option) {
  nlohmann::json j = {
      {"method", "fix velocity against the position differences of consecutive fixes interpolated at t - tau, tau in -0.5..0.5 s; "
                 "taken when the best RMS is at most 0.7x that at 0 and either the position differences' noise is below half of it "
                 "or the best RMS is below a quarter of that noise (velocities differenced from these positions) "
                 "(identification/gnss_velocity_latency.hpp)"},
      {"option", option},
      {"used_s", used_s},
      {"best_s", l.best_s},
      {"rms_at_zero_m_s", l.rms_at_zero},
      {"rms_at_best_m_s", l.rms_at_best},
      {"position_difference_noise_m_s", l.diff_noise},
      {"fixes_compared", l.pairs},
      {"established", l.established}};
  if (!l.established) j["reason"] = l.reason;
  j["source"] = option != "auto" ? "--gnss-vel-latency" : l.established ? "measured" : "none (not established)";
  return j;
}

}  // namespace calbench
