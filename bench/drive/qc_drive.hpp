// `calbench qc`: inertial-only navigation on a drive recording with several coefficient sets and
// the circular position error ΔS(t) (eq 39) of each against the reference.
#pragma once
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bench/drive/drive_stream.hpp"
#include "calibration/effects/effect_terms.hpp"
#include "calibration/qc/inertial_qc.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

struct QcSet {
  std::string name;
  SensorErrors errors;                 // zero for "none"
  std::optional<Vec3> mounting_rpy_deg;  // from an in-motion RESULT.json; else the nominal one
  std::optional<std::pair<double, double>> fit_window_s;  // the data the set was fitted on, if known
  EffectTerms effects;                 // catalogue keys of the set (compensated on the IMU samples)
  std::optional<DeviceId> device;      // the unit the set is of (none for "none")
};
// A coefficients.json, an in-motion RESULT.json (its "coefficients" and "mounting_rpy_deg"), or "none".
// Catalogue keys (docs/diagnosis.md) of the set are read into `effects`.
QcSet load_qc_set(const std::string& arg);

// The sets in groups of equal time offset (a catalogue term moves the time stamps: one pass over
// the data per group), in order of appearance.
std::vector<std::vector<std::size_t>> time_offset_groups(const std::vector<QcSet>& sets);
// Sensor-side catalogue terms of the sets idx (none: nullopt), and one IMU interval into a QC run
// with them removed first.
std::vector<std::optional<ImuEffectCompensator>> qc_compensators(const std::vector<QcSet>& sets, const std::vector<std::size_t>& idx);
void qc_imu(qc::InertialRun& run, std::optional<ImuEffectCompensator>& comp, const DriveStream::Event& e);

struct QcCurve {
  std::string name;
  std::vector<double> t, cpe;  // time since T0 (s), ΔS (m)
};
struct QcOutcome {
  double from_s = 0, horizon_s = 0;
  bool has_temperature = false;  // the IMU rows read carried a temperature
  std::vector<QcCurve> curves;
};
// Sets with catalogue terms: the output terms are removed from the raw samples before the set's
// correction and the time stamps moved by the time offset (one pass over the data per distinct
// time offset); bench-only terms are ignored.
// shared: the drive's reference already in memory (a multi-unit drive), else dir/reference.csv.
QcOutcome run_qc(const std::filesystem::path& dir, const std::vector<QcSet>& sets, std::optional<double> from_s,
                 double horizon_s, std::shared_ptr<const SharedReference> shared = nullptr);
// The JSON: {"from_s", "horizon_s", "sets": [{"name", "final_cpe_m", "max_cpe_m", "cpe_m_at": {...},
// "cpe_series": {"t_s": [...], "cpe_m": [...]}}]}; cpe_series is ΔS(t) over the whole horizon at 1 s
// spacing (wider beyond a 1 h horizon: at most 3600 points plus the last epoch).
nlohmann::json qc_json(const QcOutcome& q);
// "12.34 m", or "no data" for a figure qc_json left null (nothing navigated): the one way printers
// show a ΔS, so that no data never reads as 0 m.
std::string metres_or_no_data(const nlohmann::json& v);
// gnuplot PNG with one curve per set.
void qc_plot(const QcOutcome& q, const std::filesystem::path& png, const std::string& title);

}  // namespace calbench
