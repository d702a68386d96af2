// Bench recordings on disk ↔ the bench fit: streams imu.csv and reference.csv together,
// interpolating the reference at each IMU sample, and aggregates blocks for the estimators.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>

#include "bench/io/coefficients_json.hpp"
#include "bench/io/recording.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"

namespace calbench {

struct BenchRecordingData {
  RecordingMeta meta;
  std::vector<BenchBlock> blocks;
  std::size_t imu_rows = 0, ref_rows = 0, used_rows = 0;
  ImuForm form = ImuForm::rates;
};

// One simulated bench sample as a row of imu.csv and of reference.csv.
void write_bench_sample(RecordingWriter& w, const BenchSample& s);

BenchRecordingData load_bench_blocks(const std::filesystem::path& dir, double block_s = 1.0);

// The bench's accuracy as recorded in meta.json ("bench": {"table": {...}}), else defaults.
TableSpec recording_table_spec(const RecordingMeta& meta);
nlohmann::json table_spec_json(const TableSpec& t);

// COEFFS.json content of a bench fit, with provenance and the not-determined coefficients.
CoefficientSet bench_result_to_coefficients(const BenchFitResult& r, const BenchFitOptions& opt,
                                            const RecordingMeta& meta, const std::string& recording_path);
// The --json report (coefficients, σ, unobservable, residual statistics per step).
nlohmann::json bench_result_json(const BenchFitResult& r, const CoefficientSet& c);
// Human-readable summary (°/h, ppm, mg).
std::string bench_result_text(const BenchFitResult& r);

}  // namespace calbench
