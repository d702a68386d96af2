// Generators of the stochastic processes the identification is tested on (and the simulators may
// use): exact discrete samples of a first-order Gauss–Markov process, of an exponential-cosine
// correlated process (independently of the shaping filter: the real part of a complex
// Ornstein–Uhlenbeck process), white noise of a given density, rate random walk, and flicker
// (1/f) noise by Kasdin's fractional-difference filter. All take a std::mt19937_64 by reference.
#pragma once
#include <cstddef>
#include <random>
#include <vector>

namespace calbench::identification {

// Stationary first-order Gauss–Markov: K(τ) = σ² e^{−|τ|/T}.
std::vector<double> simulate_gauss_markov(std::size_t n, double dt, double sigma, double T,
                                          std::mt19937_64& rng);
// Stationary exponential-cosine process: K(τ) = σ² e^{−α|τ|} cos βτ.
std::vector<double> simulate_exp_cosine(std::size_t n, double dt, double sigma, double alpha,
                                        double beta, std::mt19937_64& rng);
// White rate noise of angle/velocity random walk N (units/√s, = two-sided PSD^½): samples of
// variance N²/dt, so that their τ-average has variance N²/τ and AVAR = N²/τ.
std::vector<double> simulate_white(std::size_t n, double dt, double N, std::mt19937_64& rng);
// Rate random walk K (units/s/√s): Wiener process with diffusion K², AVAR = K²τ/3. Starts at 0.
std::vector<double> simulate_random_walk(std::size_t n, double dt, double K, std::mt19937_64& rng);
// Flicker (1/f) noise with two-sided PSD S(f) = B²/(2π f) for f ≪ 1/dt, hence Allan plateau
// σ = B √(2 ln 2/π) ≈ 0.664 B (IEEE Std 952 bias instability B). Kasdin–Walter filter
// h_0 = 1, h_k = h_{k−1}(k − ½)/k applied by FFT convolution to white noise of variance B².
std::vector<double> simulate_flicker(std::size_t n, double dt, double B, std::mt19937_64& rng);

}  // namespace calbench::identification
