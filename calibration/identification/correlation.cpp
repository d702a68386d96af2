// Statistical correlation function by FFT, paper eq 25 (see the header).
#include "calibration/identification/correlation.hpp"

#include <fftw3.h>

#include <algorithm>
#include <complex>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>

namespace calbench::identification {

std::mutex& fftw_planner_mutex() {  // FFTW's planner is not thread-safe; execution is.
  static std::mutex m;
  return m;
}

namespace {
struct FftwFree {
  void operator()(void* p) const { fftw_free(p); }
};
}  // namespace

std::size_t fft_size(std::size_t n) {
  if (n <= 1) return 1;
  // m = 2^a · 3^b · 5^c with the odd part r = 3^b 5^c ≤ 1125 and 2^a ≥ r (for small n any smooth
  // r): a large power of two keeps FFTW fast with FFTW_ESTIMATE plans, while the odd factors keep
  // the padding below ~10 % instead of up to 100 %.
  std::size_t best = 0;
  for (std::size_t r3 = 1; r3 <= 1125; r3 *= 3)
    for (std::size_t r = r3; r <= 1125; r *= 5) {
      std::size_t m = r;
      while (m < n) m *= 2;
      if (m / r < r && m > 4096) continue;  // power of two must dominate for large sizes
      if (best == 0 || m < best) best = m;
    }
  return best;
}

std::vector<double> lagged_sums(std::span<const double> x, std::size_t max_lag) {
  const std::size_t n = x.size();
  if (n == 0) return {};
  max_lag = std::min(max_lag, n - 1);
  // Linear (not circular) correlation needs M ≥ N + max_lag.
  const std::size_t m = fft_size(n + max_lag + 1);
  std::unique_ptr<double, FftwFree> buf(static_cast<double*>(fftw_malloc(sizeof(double) * m)));
  std::unique_ptr<fftw_complex, FftwFree> spec(
      static_cast<fftw_complex*>(fftw_malloc(sizeof(fftw_complex) * (m / 2 + 1))));
  if (!buf || !spec) throw std::bad_alloc();
  fftw_plan fwd, inv;
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    fwd = fftw_plan_dft_r2c_1d(static_cast<int>(m), buf.get(), spec.get(), FFTW_ESTIMATE);
    inv = fftw_plan_dft_c2r_1d(static_cast<int>(m), spec.get(), buf.get(), FFTW_ESTIMATE);
  }
  std::copy(x.begin(), x.end(), buf.get());
  std::fill(buf.get() + n, buf.get() + m, 0.0);
  fftw_execute(fwd);
  for (std::size_t k = 0; k < m / 2 + 1; ++k) {
    const double re = spec.get()[k][0], im = spec.get()[k][1];
    spec.get()[k][0] = re * re + im * im;
    spec.get()[k][1] = 0.0;
  }
  fftw_execute(inv);
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    fftw_destroy_plan(fwd);
    fftw_destroy_plan(inv);
  }
  std::vector<double> s(max_lag + 1);
  const double scale = 1.0 / static_cast<double>(m);  // FFTW transforms are unnormalised
  for (std::size_t k = 0; k <= max_lag; ++k) s[k] = buf.get()[k] * scale;
  return s;
}

namespace {
std::vector<double> centred(std::span<const double> x) {
  if (x.size() < 2) throw std::invalid_argument("autocovariance: need at least 2 samples");
  // Two-pass mean (accurate for series with a large offset).
  long double sum = 0;
  for (double v : x) sum += v;
  const double mean = static_cast<double>(sum / static_cast<long double>(x.size()));
  std::vector<double> c(x.size());
  std::transform(x.begin(), x.end(), c.begin(), [mean](double v) { return v - mean; });
  return c;
}
}  // namespace

std::vector<double> autocovariance(std::span<const double> x, std::size_t max_lag) {
  const std::vector<double> c = centred(x);
  std::vector<double> k = lagged_sums(c, max_lag);
  const double inv_n = 1.0 / static_cast<double>(x.size());
  for (double& v : k) v *= inv_n;
  return k;
}

std::vector<double> autocovariance_direct(std::span<const double> x, std::size_t max_lag) {
  const std::vector<double> c = centred(x);
  const std::size_t n = c.size();
  max_lag = std::min(max_lag, n - 1);
  std::vector<double> k(max_lag + 1);
  for (std::size_t lag = 0; lag <= max_lag; ++lag) {
    long double s = 0;
    for (std::size_t i = 0; i + lag < n; ++i) s += c[i] * c[i + lag];
    k[lag] = static_cast<double>(s / static_cast<long double>(n));
  }
  return k;
}

}  // namespace calbench::identification
