// Recording-level driver of `calbench diagnose`: reads a bench recording (or simulates one in
// memory), gets the current coefficients (given, or by the bench fit), runs the diagnosis and
// turns the result into JSON, text, IMPROVED.json and an HTML report with gnuplot plots.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "bench/io/coefficients_json.hpp"
#include "bench/io/recording.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"
#include "calibration/diagnosis/diagnose.hpp"

namespace calbench {

struct DiagInput {
  std::filesystem::path dir;  // the recording ("" in memory)
  RecordingMeta meta;
  DiagData data;
  std::vector<BenchBlock> blocks;  // 1 s blocks for the bench fit
  std::size_t imu_rows = 0;
  std::size_t ref_rows = 0, used_rows = 0;  // reference.csv rows; IMU rows inside plan steps
};

// One pass over imu.csv and reference.csv.
// parent_s: length of the parent blocks (the bench fit's blocks), sub-blocks min(0.05 s, parent_s).
DiagInput load_diag_input(const std::filesystem::path& dir, double parent_s = 1.0);
// In memory: the bench simulator with injected effects.
DiagInput simulate_diag_input(const BenchPlan& plan, const SensorErrors& truth, const BenchSimOptions& opt);

struct DiagRun {
  std::string noise_class;  // the device class whose drift prior judged the residual, and why
  DiagnoseResult result;
  CoefficientSet current;   // what was tested ("before")
  CoefficientSet improved;  // IMPROVED.json
  bool fitted_first = false;
};

// The drift prior a recording is judged by: the device class's, chosen as the in-motion filter runs
// choose it (`device_class`: --device-class, else meta.json device.model); the ADIS16488A's when
// the model is no known class and none is given. Returns the class's name and why, for the output.
// (Judged by the ADIS16488A's drift, clean ICM-42688-P drives on the short route were given an
// established correlated_drift in 22 of 33.) A --device-class that names no class is bad input.
std::string diagnosis_noise_class(const std::string& device_class, const std::string& model,
                                  const std::filesystem::path& meta_file, NoiseSpec& noise);

// coeffs == nullptr: fit first with the bench fit (lsq, full model). device_class: as
// diagnosis_noise_class's ("" = meta.json's model).
DiagRun run_diagnosis(const DiagInput& in, const CoefficientSet* coeffs, const TableSpec& table,
                      const std::string& device_class = "");

// --json document: {"findings": [...], "unexplained": [...], "axes": {...}, ...}
nlohmann::json diagnosis_json(const DiagRun& run);
// Plain-language sentences, one per finding, and the per-axis table.
std::string diagnosis_text(const DiagRun& run);
std::string finding_sentence(const DiagFinding& f);
// HTML report with before/after plots (gnuplot); plots are embedded as inline SVG.
void write_diagnosis_report(const std::filesystem::path& html, const DiagInput& in, const DiagRun& run,
                            const std::string& title);

}  // namespace calbench
