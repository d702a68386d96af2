// Filter consistency from normalised innovations (NIS = νᵀS⁻¹ν): the time-average test of
// Bar-Shalom, Li & Kirubarajan, "Estimation with Applications to Tracking and Navigation" (2001),
// section 5.4. For a consistent filter with independent innovations of `dof` components, N·mean(NIS)
// is χ²-distributed with N·dof degrees of freedom; the mean is tested against the two-sided
// region [χ²_{α/2}(N·dof), χ²_{1−α/2}(N·dof)] / N. The fraction of epochs with NIS under the
// single-epoch 95 % bound is tested against 0.95 with the binomial (normal-approximation) region.
// Innovations of a filter fed by a reference with time-correlated errors are correlated, which
// makes the true region wider than this one: outside the region is then weaker evidence.
#pragma once

namespace calbench::qc {

// Quantile of χ²(ν) at the standard normal quantile z (p = Φ(z)), Wilson–Hilferty approximation:
// in the central 95 % within 1e-3 (relative) from ν = 30 and 1e-4 from ν = 100; poor in the lower
// tail of small ν (16 % low at ν = 3, p = 0.025). The NIS test uses ν = 3·epochs.
double chi2_quantile(double nu, double z);

// Standard normal quantile: Φ(z) = p, 0 < p < 1 (bisection on erfc, |error| < 1e-12).
double normal_quantile(double p);

// Standard normal quantile of the upper α/2 point: 1.959964 for level 0.95, 2.575829 for 0.99.
double two_sided_z(double level);

enum class NisVerdict { no_data, consistent, too_large, too_small };

struct NisTest {
  double level = 0.95;               // two-sided confidence level of the regions
  double mean_lo = 0, mean_hi = 0;   // region of the mean NIS
  double frac_lo = 0, frac_hi = 1;   // region of the fraction within the single-epoch 95 % bound
  NisVerdict mean = NisVerdict::no_data;
  NisVerdict fraction = NisVerdict::no_data;  // too_large: fewer inside than expected (NIS too big)
};

// epochs: innovations in the mean; dof: components per innovation (3 for eqs 13–15).
NisTest nis_test(long epochs, int dof, double mean_nis, double fraction_within_95, double level = 0.95);

}  // namespace calbench::qc
