// Statistical correlation function of a uniformly sampled series, paper eq 25:
//   K̂(k) = (1/N) Σ_{i=1}^{N−k} x̃_i x̃_{i+k},  x̃_i = x_i − m_x,  m_x = (1/N) Σ x_i,  k = 0 … max_lag.
// (The paper writes the sum as i = k+1 … N+k; only the N − k products of existing samples exist,
// and the divisor is N, the "biased" estimator, which keeps K̂ positive semi-definite.)
// Computed by FFT (FFTW), zero-padded to at least N + max_lag points so there is no circular
// wrap-around: O(N log N).
#pragma once
#include <cstddef>
#include <mutex>
#include <span>
#include <vector>

namespace calbench::identification {

// Eq 25 with the mean removed, lags 0 … max_lag (max_lag is clamped to N − 1). Needs N ≥ 2.
std::vector<double> autocovariance(std::span<const double> x, std::size_t max_lag);
// The same by the O(N·max_lag) direct sum (reference for tests).
std::vector<double> autocovariance_direct(std::span<const double> x, std::size_t max_lag);
// Raw lagged sums S(k) = Σ_{i} x_i x_{i+k}, k = 0 … max_lag, no mean removal, no divisor (FFT).
std::vector<double> lagged_sums(std::span<const double> x, std::size_t max_lag);
// A fast FFT size n' ≥ n: 2^a·3^b·5^c with a dominant power of two (within ~10 % of n).
std::size_t fft_size(std::size_t n);
// FFTW's planner is not thread-safe: hold this while creating or destroying plans.
std::mutex& fftw_planner_mutex();

}  // namespace calbench::identification
