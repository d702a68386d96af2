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
// The strongest sinusoid of x(t) (irregular times allowed; a least-squares sinusoid per trial
// frequency, fmin…fmax on a 0.5 % grid): its frequency and amplitude, or 0 and 0 when the peak is
// not significant — its power against the median power near it (within a factor 1.5 of its
// frequency, outside its main lobe: a robust local noise level; for noise alone power/mean is
// Exp(1)) below ln(M/10⁻³), M the independent frequencies in the band ((fmax − fmin)·record
// length), i.e. a false-alarm probability above 10⁻³ — or x is too short.
// With `group` (a group index per sample, 0…G−1, and weights w), x holds deviations from its
// groups' weighted means, and the sinusoid is taken the same way, so its amplitude stays unbiased.
void strongest_sinusoid(const std::vector<double>& t, const std::vector<double>& x, double fmin, double fmax,
                        double& best_hz, double& best_amp, const std::vector<int>* group = nullptr,
                        const std::vector<double>* w = nullptr);
// Bench: the strongest sinusoid in time in a sub-block residual (deviations from the parent means),
// 0.02–5 Hz (strongest_sinusoid).
void time_spectrum(const DiagData& d, const Eigen::VectorXd& r, double& best_hz, double& best_amp);
// Drive: the same in a parent-block residual r (drift removed), 0.01 Hz up to 0.45 of the blocks'
// rate; the amplitude corrected for the block averaging (÷ sinc(f·block length)).
void time_spectrum(const DriveDiagData& d, const Eigen::VectorXd& r, double& best_hz, double& best_amp);

}  // namespace calbench::diag
