// The logger's sample timing measured from the stamps (calibration/identification/sample_timing.hpp)
// and the GNSS velocity's latency measured from the fixes (gnss_velocity_latency.hpp), on streams
// made here with known timing (fixed seeds).
#include "calibration/identification/gnss_velocity_latency.hpp"
#include "calibration/identification/sample_timing.hpp"
#include "calibration/ins/nav_math.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace calbench::identification {
namespace {

Vec3 sample(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng));
}

TEST(SampleTiming, RegularStampsAreZero) {
  // A simulator's stamps (k / rate, printed and read back with rounding in the last digit).
  SampleTimingEstimator e;
  std::mt19937_64 rng(1);
  for (int k = 0; k < 20000; ++k) e.add(std::round(k / 200.0 * 1e9) / 1e9, sample(rng), sample(rng));
  const SampleTiming t = e.result();
  EXPECT_TRUE(t.regular);
  EXPECT_EQ(t.sigma_s, 0.0);
  EXPECT_EQ(t.repeated, 0u);
  EXPECT_NEAR(t.distinct_rate_hz, 200.0, 1e-6);
}

TEST(SampleTiming, ALoggerPollingFasterThanTheSensor) {
  // A sensor at 100.5 Hz on its own clock, read every 6.6 ms on average (6, 7, 8 or 9 ms) and
  // stamped at the read: a read sees the newest sample, a second read repeats it. The first read's
  // lateness is about uniform over a read interval: σ ≈ 6.6 ms / √12 = 1.9 ms.
  SampleTimingEstimator e;
  std::mt19937_64 rng(2);
  std::discrete_distribution<int> pick({60, 15, 20, 5});
  const double Ts = 1.0 / 100.5;
  double t = 0;
  long last = -1, distinct = 0, rows = 0;
  double late = 0;  // the first reads' lateness after their sample, summed
  Vec3 w = Vec3::Zero(), f = Vec3::Zero();
  while (t < 120) {
    const long k = static_cast<long>(std::floor(t / Ts));
    if (k != last) {
      w = sample(rng);
      f = sample(rng);
      last = k;
      ++distinct;
      late += t - k * Ts;
    }
    e.add(t, w, f);
    ++rows;
    t += 1e-3 * (6 + pick(rng));
  }
  const SampleTiming r = e.result();
  EXPECT_FALSE(r.regular);
  EXPECT_EQ(static_cast<long>(r.rows), rows);
  EXPECT_EQ(static_cast<long>(r.rows - r.repeated), distinct);
  EXPECT_NEAR(r.distinct_rate_hz, 100.5, 0.5);
  EXPECT_GT(r.sigma_s, 1.3e-3);
  EXPECT_LT(r.sigma_s, 2.6e-3);
  // The stamps' mean lateness above the earliest (about 3.4 ms: the mean residual life of the
  // 6–9 ms read intervals), against the lateness this stream really had; the second reads show a
  // polling logger.
  EXPECT_TRUE(r.polling());
  EXPECT_NEAR(r.lateness_s, late / static_cast<double>(distinct), 0.4e-3);
  EXPECT_GT(r.lateness_s, 2.5e-3);
}

TEST(SampleTiming, JitteredStampsWithoutRepeats) {
  // Stamps scattered uniformly ±1 ms about a 100-Hz clock: σ = 2 ms / √12 = 0.577 ms.
  SampleTimingEstimator e;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  for (int k = 0; k < 30000; ++k) e.add(k * 0.01 + u(rng), sample(rng), sample(rng));
  const SampleTiming r = e.result();
  EXPECT_EQ(r.repeated, 0u);
  EXPECT_NEAR(r.sigma_s, 0.577e-3, 0.1e-3);
  // Without second reads nothing says the scatter is a delay: not a polling logger (fit drive leaves
  // the stamps where they are), whatever the spread above the earliest.
  EXPECT_FALSE(r.polling());
  EXPECT_NEAR(r.lateness_s, 1e-3, 0.1e-3);
}

TEST(SampleTiming, ConstantDelayIsNotLateness) {
  // Every stamp 5 ms after the sensor's instant plus a ±0.2 ms scatter: a transport delay moves no
  // stamp against another, so the lateness seen is the scatter's alone (0.4 ms above the earliest).
  SampleTimingEstimator e;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.2e-3, 0.2e-3);
  for (int k = 0; k < 30000; ++k) e.add(k * 0.01 + 5e-3 + u(rng), sample(rng), sample(rng));
  const SampleTiming r = e.result();
  EXPECT_LT(r.lateness_s, 0.25e-3);
}

// A walk round a circle of 3 m at 1.3 m/s with a ±0.4 m/s surge at 0.7 Hz, fixes at 4 Hz: the
// velocity changes by 0.6–1.8 m/s², 0.1–0.2 m/s over a 0.125-s lag.
std::vector<GnssFixSample> fixes(double latency, double sigma_h, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const double R = 3, lat0 = 0.7, Re = 6.37e6, fs = 0.7, A = 0.4;
  auto s_of = [&](double t) { return 1.3 * t + A / (2 * M_PI * fs) * std::sin(2 * M_PI * fs * t); };
  auto v_of = [&](double t) { return 1.3 + A * std::cos(2 * M_PI * fs * t); };
  std::vector<GnssFixSample> out;
  for (int k = 0; k < 600; ++k) {
    const double t = 0.25 * k;
    const double a = s_of(t) / R;
    GnssFixSample g;
    g.t = t;
    g.lat = lat0 + (R * std::sin(a) + sigma_h * n(rng)) / Re;
    g.lon = (R * (1 - std::cos(a)) + sigma_h * n(rng)) / (Re * std::cos(lat0));
    const double tv = t - latency, av = s_of(tv) / R, sp = v_of(tv);
    g.v_ned = Vec3(sp * std::cos(av), sp * std::sin(av), 0) + 0.01 * Vec3(n(rng), n(rng), 0);
    g.has_vel = true;
    g.sigma_h = std::max(sigma_h, 0.01);
    out.push_back(g);
  }
  return out;
}

TEST(GnssVelocityLatency, ALaggingVelocityIsMeasured) {
  const GnssVelocityLatency l = measure_gnss_velocity_latency(fixes(0.125, 0.005, 4));
  EXPECT_TRUE(l.established) << l.reason;
  EXPECT_NEAR(l.latency_s, 0.125, 0.015);
  EXPECT_LT(l.rms_at_best, 0.7 * l.rms_at_zero);
}

TEST(GnssVelocityLatency, AVelocityAtItsStampIsLeftAlone) {
  const GnssVelocityLatency l = measure_gnss_velocity_latency(fixes(0.0, 0.005, 5));
  EXPECT_FALSE(l.established);
  EXPECT_EQ(l.latency_s, 0.0);
}

TEST(GnssVelocityLatency, CoarseFixesDoNotTellIt) {
  // Metre-level fixes: their differences' noise (√2·2 m / 0.25 s) hides the lag's 0.1–0.2 m/s.
  const GnssVelocityLatency l = measure_gnss_velocity_latency(fixes(0.125, 2.0, 6));
  EXPECT_FALSE(l.established);
  EXPECT_NE(l.reason.find("too coarse"), std::string::npos) << l.reason;
}

TEST(GnssVelocityLatency, AReceiverDifferencingItsOwnFixes) {
  // Coarse fixes (2 m) whose velocity is the difference of the last two: it matches the position
  // differences at t − Δt/2 to rounding, far below their own noise, so the lag is certain.
  std::vector<GnssFixSample> f = fixes(0.0, 2.0, 7);
  for (std::size_t k = 1; k < f.size(); ++k) {
    const double dt = f[k].t - f[k - 1].t, lat = 0.5 * (f[k].lat + f[k - 1].lat);
    const ins::Radii r = ins::wgs84_radii(lat);
    f[k].v_ned = Vec3((f[k].lat - f[k - 1].lat) * (r.RM + f[k].h) / dt, (f[k].lon - f[k - 1].lon) * (r.RN + f[k].h) * std::cos(lat) / dt, 0);
  }
  f.erase(f.begin());
  const GnssVelocityLatency l = measure_gnss_velocity_latency(f);
  EXPECT_TRUE(l.established) << l.reason;
  EXPECT_NEAR(l.latency_s, 0.125, 0.006);
}

}  // namespace
}  // namespace calbench::identification
