#include "calibration/identification/gnss_velocity_latency.hpp"

#include <algorithm>
#include <cmath>

#include "calibration/ins/nav_math.hpp"

namespace calbench::identification {

namespace {
struct Mid {
  double t;
  double vn, ve;
};

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

// The position-difference velocities at the midpoints of consecutive fixes (north, east).
std::vector<Mid> midpoint_velocities(const std::vector<GnssFixSample>& f, double dt_med) {
  std::vector<Mid> m;
  for (std::size_t k = 1; k < f.size(); ++k) {
    const double dt = f[k].t - f[k - 1].t;
    if (!(dt > 0) || dt > 1.5 * dt_med) continue;
    const double lat = 0.5 * (f[k].lat + f[k - 1].lat);
    const ins::Radii r = ins::wgs84_radii(lat);
    const double h = 0.5 * (f[k].h + f[k - 1].h);
    m.push_back(Mid{0.5 * (f[k].t + f[k - 1].t), (f[k].lat - f[k - 1].lat) * (r.RM + h) / dt,
                    (f[k].lon - f[k - 1].lon) * (r.RN + h) * std::cos(lat) / dt});
  }
  return m;
}

// Horizontal RMS of v(t_k) − pd(t_k − τ) over the fixes with a velocity and midpoints on both sides
// within 1.5 intervals.
double rms_at(const std::vector<GnssFixSample>& f, const std::vector<Mid>& m, double tau, double dt_med, std::size_t& n) {
  double s = 0;
  n = 0;
  // At most about 4000 fixes per candidate (an hour at 10 Hz is 36 000): the RMS of a few thousand
  // differences decides a shift of 5 ms as well, at a tenth of the work.
  const std::size_t stride = std::max<std::size_t>(1, f.size() / 4000);
  for (std::size_t i = 0; i < f.size(); i += stride) {
    const GnssFixSample& x = f[i];
    if (!x.has_vel) continue;
    const double t = x.t - tau;
    const auto it = std::lower_bound(m.begin(), m.end(), t, [](const Mid& a, double v) { return a.t < v; });
    if (it == m.begin() || it == m.end()) continue;
    const Mid& b = *it;
    const Mid& a = *(it - 1);
    if (b.t - a.t > 1.5 * dt_med) continue;
    const double u = (t - a.t) / (b.t - a.t);
    const double dn = x.v_ned(0) - (a.vn + u * (b.vn - a.vn)), de = x.v_ned(1) - (a.ve + u * (b.ve - a.ve));
    s += dn * dn + de * de;
    ++n;
  }
  return n ? std::sqrt(s / static_cast<double>(n)) : 0.0;
}
}  // namespace

GnssVelocityLatency measure_gnss_velocity_latency(const std::vector<GnssFixSample>& fixes) {
  GnssVelocityLatency out;
  std::vector<double> dts, sig;
  for (std::size_t k = 1; k < fixes.size(); ++k) dts.push_back(fixes[k].t - fixes[k - 1].t);
  for (const GnssFixSample& x : fixes)
    if (x.sigma_h > 0) sig.push_back(x.sigma_h);
  const double dt_med = median_of(dts);
  if (!(dt_med > 0)) {
    out.reason = "fewer than two fixes";
    return out;
  }
  const std::vector<Mid> mid = midpoint_velocities(fixes, dt_med);
  std::size_t n0 = 0;
  out.rms_at_zero = rms_at(fixes, mid, 0.0, dt_med, n0);
  out.rms_at_best = out.rms_at_zero;
  out.pairs = n0;
  for (int i = -100; i <= 100; ++i) {
    const double tau = 0.005 * i;
    std::size_t n = 0;
    const double r = rms_at(fixes, mid, tau, dt_med, n);
    if (n >= n0 / 2 && n > 0 && r < out.rms_at_best) {
      out.rms_at_best = r;
      out.best_s = tau;
      out.pairs = n;
    }
  }
  const double sigma_h = sig.empty() ? 0.0 : median_of(sig);
  out.diff_noise = sigma_h > 0 ? std::sqrt(2.0) * sigma_h / dt_med : 0.0;
  if (n0 < 50) {
    out.reason = "fewer than 50 fixes with a velocity and neighbours to compare";
  } else if (out.rms_at_best <= 0.7 * out.rms_at_zero && sigma_h > 0 && out.rms_at_best < 0.25 * out.diff_noise) {
    // The velocities match the position differences far better than those differences' own noise:
    // they are made from these very positions, and the lag is certain however coarse the fixes.
    out.established = true;
    out.latency_s = out.best_s;
  } else if (!(sigma_h > 0) || out.diff_noise > 0.5 * out.rms_at_zero) {
    out.reason = "the fixes' positions are too coarse to tell (their differences' noise " + std::to_string(out.diff_noise) +
                 " m/s against " + std::to_string(out.rms_at_zero) + " m/s)";
  } else if (out.rms_at_best > 0.7 * out.rms_at_zero) {
    out.reason = "no latency explains most of the difference";
  } else {
    out.established = true;
    out.latency_s = out.best_s;
  }
  return out;
}

}  // namespace calbench::identification
