// Recording-level driver of `calbench diagnose` on a drive recording (docs/diagnosis.md, "Drives"):
// reads imu.csv and reference.csv (or simulates a drive in memory), predicts the MEMS output from
// the reference trajectory, runs the drive diagnosis and turns the result into JSON (the bench
// side's schema), text, IMPROVED.json and an HTML report.
#pragma once
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "bench/io/coefficients_json.hpp"
#include "bench/io/recording.hpp"
#include "calibration/diagnosis/drive_diagnose.hpp"
#include "calibration/diagnosis/drive_innovations.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"

namespace calbench {

// --coeffs for a drive: a coefficients.json (catalogue keys it carries are applied), an in-motion
// RESULT.json ("coefficients" and the estimated mounting), or a truth.json with "mounting".
struct DriveCoeffs {
  CoefficientSet set;
  EffectTerms carried;
  std::optional<Vec3> mounting_rpy_deg;
  std::string file;
};
DriveCoeffs read_drive_coeffs(const std::string& file);

// One innovation of the in-motion filter (its on_innovation record) as the diagnosis's sample.
InnovationSample innovation_sample(const inmotion::InnovationRecord& r);

struct DriveDiagInput {
  std::filesystem::path dir;  // the recording (empty: simulated in memory)
  RecordingMeta meta;
  DriveDiagData data;
  Vec3 mounting_rpy_deg = Vec3::Zero();  // used for the prediction
  std::string mounting_source;           // "meta.json (nominal)" or the coefficients file
  std::size_t imu_rows = 0, ref_rows = 0;
  // The device class of the in-motion filter runs (fit drive --device-class); "" = meta.json's model.
  std::string device_class;
};

// One pass over imu.csv and reference.csv; mounting_rpy_deg overrides meta.json's rotation.
DriveDiagInput load_drive_diag_input(const std::filesystem::path& dir, const std::optional<Vec3>& mounting_rpy_deg);

// In memory (tests): the drive simulator on a route file, unit and true mounting drawn as
// `simulate drive --truth random --seed` does, with catalogue effects injected; the prediction
// uses the route's nominal mounting.
DriveDiagInput simulate_drive_diag_input(const std::string& route_file, std::uint64_t seed, const EffectTerms& effects,
                                         double until_s = 0);
// In memory (tests): the factory coefficients of that drive's unit — the unit of seed simulated on
// a bench plan (e.g. bench/plans/factory.toml) with the sensor-side catalogue effects of `effects`
// present (not the drive's time offset or lever arm, nor a scale_factor: a shift since the
// calibration), noise seed `bench_seed`, fitted by least
// squares without catalogue terms, as `calbench fit bench` does.
DriveCoeffs simulate_factory_coeffs(const std::string& plan_file, std::uint64_t seed, const EffectTerms& effects,
                                    std::uint64_t bench_seed);

// The in-motion filter (as `fit drive --coeffs` runs it, default observations pos,vel,att) over the
// drive, once with the improved b and M and only the catalogue terms that were tested (those the
// given coefficients carried: "before"), once with IMPROVED.json (the new terms too: "after"), and
// its innovation statistics per observation type (calibration/diagnosis/drive_innovations.hpp).
// Without new terms the second run is the first.
struct DriveInnovations {
  InnovationStats before[3], after[3];  // position, velocity, attitude
  bool compared = false;                // a second run with the new terms was made
  std::vector<std::string> applied_before, applied_after;  // catalogue keys the filter applied
  double cpu_s = 0;                     // both runs
};

struct DriveDiagRun {
  DriveDiagnoseResult result;
  // The device class whose noise (the drift prior) the drive is judged by, and how it was chosen.
  std::string noise_class;
  CoefficientSet current;   // what was tested ("before")
  CoefficientSet improved;  // IMPROVED.json
  bool coeffs_given = false;
  std::optional<DriveInnovations> innovations;  // with a recording on disk, unless skipped
  std::string innovations_skipped;              // why not (empty: ran, or simulated in memory)
};

// innovations: run the in-motion filter for the innovation statistics (needs in.dir).
DriveDiagRun run_drive_diagnosis(const DriveDiagInput& in, const DriveCoeffs* coeffs, bool innovations = true);
// The innovation part alone (run_drive_diagnosis calls it).
DriveInnovations drive_innovations(const DriveDiagInput& in, const DriveDiagRun& run);

nlohmann::json drive_diagnosis_json(const DriveDiagInput& in, const DriveDiagRun& run);
// The "innovations" object of the JSON and its text lines (empty when simulated in memory).
nlohmann::json drive_innovations_json(const DriveDiagRun& run);
std::string drive_innovations_text(const DriveDiagRun& run);
std::string drive_diagnosis_text(const DriveDiagInput& in, const DriveDiagRun& run);
// shown_sensor: sensor (0 gyro, 1 accel) of the axis the RMS figures are for (−1: the finding's).
std::string drive_finding_sentence(const DiagFinding& f, int shown_sensor = -1);
// HTML report: per finding, the residual of the axis where it shows against its revealing
// condition, before (red) and after (blue), gnuplot PNG embedded.
void write_drive_diagnosis_report(const std::filesystem::path& html, const DriveDiagInput& in, const DriveDiagRun& run,
                                  const std::string& title);

}  // namespace calbench
