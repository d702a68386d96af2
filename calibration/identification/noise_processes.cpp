// Noise-process generators (see the header).
#include "calibration/identification/noise_processes.hpp"

#include <fftw3.h>

#include <cmath>
#include <complex>
#include <mutex>
#include <stdexcept>

#include "calibration/identification/correlation.hpp"

namespace calbench::identification {

std::vector<double> simulate_gauss_markov(std::size_t n, double dt, double sigma, double T,
                                          std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  const double phi = std::exp(-dt / T);
  const double q = sigma * std::sqrt(-std::expm1(-2.0 * dt / T));
  std::vector<double> x(n);
  double v = sigma * n01(rng);  // stationary start
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = v;
    v = phi * v + q * n01(rng);
  }
  return x;
}

std::vector<double> simulate_exp_cosine(std::size_t n, double dt, double sigma, double alpha,
                                        double beta, std::mt19937_64& rng) {
  // z' = (−α + iβ) z + complex white noise; E[z(t+τ) z*(t)] = s² e^{−ατ} e^{iβτ} with
  // s² = E|z|²; Re z then has correlation (s²/2) e^{−ατ} cos βτ. Take s² = 2σ².
  std::normal_distribution<double> n01(0.0, 1.0);
  const std::complex<double> phi = std::exp(std::complex<double>(-alpha * dt, beta * dt));
  // Each of Re/Im of the innovation: variance (s²/2)(1 − e^{−2α dt}) = σ²(1 − e^{−2α dt}).
  const double q = sigma * std::sqrt(-std::expm1(-2.0 * alpha * dt));
  std::complex<double> z(sigma * n01(rng), sigma * n01(rng));
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = z.real();
    z = phi * z + std::complex<double>(q * n01(rng), q * n01(rng));
  }
  return x;
}

std::vector<double> simulate_white(std::size_t n, double dt, double N, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  const double s = N / std::sqrt(dt);
  std::vector<double> x(n);
  for (auto& v : x) v = s * n01(rng);
  return x;
}

std::vector<double> simulate_random_walk(std::size_t n, double dt, double K, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  const double s = K * std::sqrt(dt);
  std::vector<double> x(n);
  double v = 0;
  for (auto& e : x) {
    e = v;
    v += s * n01(rng);
  }
  return x;
}

std::vector<double> simulate_flicker(std::size_t n, double dt, double B, std::mt19937_64& rng) {
  (void)dt;  // the discrete filter's PSD is B²/(2πf) at any rate (white input of variance B²)
  if (n == 0) return {};
  std::normal_distribution<double> n01(0.0, 1.0);
  const std::size_t m = fft_size(2 * n);
  std::vector<double> w(m, 0.0), h(m, 0.0);
  for (std::size_t i = 0; i < n; ++i) w[i] = B * n01(rng);
  h[0] = 1.0;
  for (std::size_t k = 1; k < n; ++k) h[k] = h[k - 1] * (static_cast<double>(k) - 0.5) / static_cast<double>(k);
  std::vector<std::complex<double>> W(m / 2 + 1), Hs(m / 2 + 1);
  fftw_plan pw, ph, pinv;
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    pw = fftw_plan_dft_r2c_1d(static_cast<int>(m), w.data(), reinterpret_cast<fftw_complex*>(W.data()), FFTW_ESTIMATE);
    ph = fftw_plan_dft_r2c_1d(static_cast<int>(m), h.data(), reinterpret_cast<fftw_complex*>(Hs.data()), FFTW_ESTIMATE);
    pinv = fftw_plan_dft_c2r_1d(static_cast<int>(m), reinterpret_cast<fftw_complex*>(W.data()), w.data(), FFTW_ESTIMATE);
  }
  fftw_execute(pw);
  fftw_execute(ph);
  for (std::size_t k = 0; k < W.size(); ++k) W[k] *= Hs[k] / static_cast<double>(m);
  fftw_execute(pinv);
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    fftw_destroy_plan(pw);
    fftw_destroy_plan(ph);
    fftw_destroy_plan(pinv);
  }
  w.resize(n);
  return w;
}

}  // namespace calbench::identification
