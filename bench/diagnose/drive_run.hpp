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

struct DriveDiagInput {
  RecordingMeta meta;
  DriveDiagData data;
  Vec3 mounting_rpy_deg = Vec3::Zero();  // used for the prediction
  std::string mounting_source;           // "meta.json (nominal)" or the coefficients file
  std::size_t imu_rows = 0, ref_rows = 0;
};

// One pass over imu.csv and reference.csv; mounting_rpy_deg overrides meta.json's rotation.
DriveDiagInput load_drive_diag_input(const std::filesystem::path& dir, const std::optional<Vec3>& mounting_rpy_deg);

// In memory (tests): the drive simulator on a route file, unit and true mounting drawn as
// `simulate drive --truth random --seed` does, with catalogue effects injected; the prediction
// uses the route's nominal mounting.
DriveDiagInput simulate_drive_diag_input(const std::string& route_file, std::uint64_t seed, const EffectTerms& effects,
                                         double until_s = 0);

struct DriveDiagRun {
  DriveDiagnoseResult result;
  CoefficientSet current;   // what was tested ("before")
  CoefficientSet improved;  // IMPROVED.json
  bool coeffs_given = false;
};

DriveDiagRun run_drive_diagnosis(const DriveDiagInput& in, const DriveCoeffs* coeffs);

nlohmann::json drive_diagnosis_json(const DriveDiagInput& in, const DriveDiagRun& run);
std::string drive_diagnosis_text(const DriveDiagInput& in, const DriveDiagRun& run);
// shown_sensor: sensor (0 gyro, 1 accel) of the axis the RMS figures are for (−1: the finding's).
std::string drive_finding_sentence(const DiagFinding& f, int shown_sensor = -1);
// HTML report: per finding, the residual of the axis where it shows against its revealing
// condition, before (red) and after (blue), gnuplot PNG embedded.
void write_drive_diagnosis_report(const std::filesystem::path& html, const DriveDiagInput& in, const DriveDiagRun& run,
                                  const std::string& title);

}  // namespace calbench
