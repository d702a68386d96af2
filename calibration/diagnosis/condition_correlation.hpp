// Residuals against the conditions of a recording: which condition (rate, force, temperature,
// table angle; on drives speed, turn rate, …) a residual follows. The condition names and values
// are declared in diagnose.hpp (bench) and drive_diagnose.hpp (drive), which the reports use.
//
// Two Pearson correlations stand here: the bench's sums run over std::vector in index order, the
// drive's over Eigen arrays (vectorised); they are kept apart because the order of the sums is
// part of the compared outputs.
#pragma once
#include <vector>

#include <Eigen/Dense>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/diagnosis/drive_diagnose.hpp"

namespace calbench::diag {

// Bench: mean of a sub-block residual series over each parent block (sample-count weighted).
std::vector<double> parent_block_means(const DiagData& d, const Eigen::VectorXd& r);

double pearson(const std::vector<double>& x, const std::vector<double>& y);  // bench
double pearson(const Eigen::VectorXd& x, const Eigen::VectorXd& y);          // drive

// Correlation of a residual with every condition, strongest first. Bench: r per sub-block,
// parent level for the slow conditions, within-parent deviations against the table angle.
// Drive: r per parent block.
std::vector<ConditionCorrelation> correlations(const DiagData& d, const Eigen::VectorXd& r);
std::vector<ConditionCorrelation> correlations(const DriveDiagData& d, const Eigen::VectorXd& r);

// Bench: amplitude of harmonics 1..4 of the table angle in the within-parent residual (rotating
// sub-blocks); the strongest harmonic and its amplitude.
void angle_spectrum(const DiagData& d, const Eigen::VectorXd& r, int& best_k, double& best_amp);
// The strongest sinusoid in time in a sub-block residual (deviations from the parent means),
// 0.02–5 Hz: its frequency and amplitude (0 when the record is too short).
void time_spectrum(const DiagData& d, const Eigen::VectorXd& r, double& best_hz, double& best_amp);

}  // namespace calbench::diag
