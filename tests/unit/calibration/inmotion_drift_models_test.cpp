// The in-motion EKF with identified drift models (issue 6): the exponential-cosine block (eqs
// 35–36) keeps its stationary covariance, and on a simulated drive whose real in-run drift
// differs from the data-sheet prior, the chain "fit with the default prior → identify the total
// drift series (eq 25) → refit with the identified models" makes the filter consistent: its
// innovations and its drift uncertainty match the errors it actually makes.
//
// The drift is added to the simulated MEMS output here (the sensor model is additive,
// y = (I+M)·true + b + d + noise), from calibration/identification/noise_processes.hpp, so the
// truth is known exactly; the simulator's own Gauss–Markov drift is switched off. The truth
// reaches only the error statistics, never the filter or the identification.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <random>

#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/identification/correlation_fit.hpp"
#include "calibration/identification/noise_processes.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/qc/inertial_qc.hpp"
#include "common/units.hpp"
#include "inmotion_test_drive.hpp"

using namespace calbench;
using namespace calbench::drivesim;
using namespace calbench::inmotion;
using namespace calbench::inmotion_test;
using units::kDeg;
using units::kDegPerHour;
using units::kMilliG;

namespace {

// The real drift of the simulated unit: the gyros differ from adis16488a_noise() (first order,
// 5.1 °/h, 300 s), the accelerometers follow it (0.1 mg, 300 s: far below what a drive resolves
// next to the horizontal bias/tilt ambiguity, so their series is not identified here).
// For the figures in docs/identification.md: INMOTION_DRIFT_LAPS=18 (≈ 35 min, the default route's
// length) and INMOTION_DRIFT_GM=1 (gyro first order, σ 20 °/h, T 60 s, instead of exp-cosine).
int env_int(const char* name, int dflt) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : dflt;
}
const bool kGm = env_int("INMOTION_DRIFT_GM", 0) != 0;
const double kGyroSigma = 20 * kDegPerHour, kGyroAlpha = kGm ? 1.0 / 60 : 1.0 / 40, kGyroBeta = kGm ? 0.0 : 0.05;
constexpr double kAccelSigma = 0.1 * kMilliG, kAccelT = 300;                              // first order

struct Drive {
  std::vector<SimImu> imu;                    // with the added drift
  std::vector<std::array<double, 6>> drift;   // truth, per IMU sample (gyro x,y,z, accel x,y,z)
  std::vector<SimRef> ref;
  SensorErrors unit;
  Mat3 C_nominal;
  Vec3 lever;
};

const Drive& drive() {
  static const Drive d = [] {
    Drive d;
    // Laps near Wuhan at 100 Hz, the unit and simulator of seed 21.
    const int laps = std::max(3, env_int("INMOTION_DRIFT_LAPS", 5));
    DriveSimConfig cfg = drive_config(lap_route(30.5, 114.3, 30, -40, laps), 21, 100, Vec3(0.3, -0.4, 0.6),
                                      Vec3(0.5, -0.3, 0.2));
    cfg.noise.gyro.drift_sigma = 0;  // the drift is added below, with its truth kept
    cfg.noise.accel.drift_sigma = 0;
    d.unit = cfg.mems;
    d.C_nominal = nominal_mounting();
    d.lever = cfg.lever_arm;
    DriveSinks s;
    s.imu = [&](const SimImu& m) { d.imu.push_back(m); };
    s.reference = [&](const SimRef& r) { d.ref.push_back(r); };
    simulate_drive(cfg, s);
    const std::size_t n = d.imu.size();
    const double dt = 1.0 / cfg.imu_rate_hz;
    std::mt19937_64 rng(2021);
    std::vector<double> p[6];
    for (int i = 0; i < 3; ++i) {
      p[i] = kGm ? identification::simulate_gauss_markov(n, dt, kGyroSigma, 1 / kGyroAlpha, rng)
                 : identification::simulate_exp_cosine(n, dt, kGyroSigma, kGyroAlpha, kGyroBeta, rng);
      p[3 + i] = identification::simulate_gauss_markov(n, dt, kAccelSigma, kAccelT, rng);
    }
    d.drift.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      for (int i = 0; i < 6; ++i) d.drift[k][static_cast<std::size_t>(i)] = p[i][k];
      d.imu[k].gyro += Vec3(p[0][k], p[1][k], p[2][k]);
      d.imu[k].accel += Vec3(p[3][k], p[4][k], p[5][k]);
    }
    return d;
  }();
  return d;
}

struct Outcome {
  std::vector<double> t;
  std::vector<std::array<double, 6>> total, total_sigma, truth;  // SI
  double mean_nis[3] = {0, 0, 0};
  double coverage[2] = {0, 0};   // fraction of epochs after the burn-in with |error| ≤ 3σ (gyro, accel)
  double rms_err[2] = {0, 0};    // RMS error of the total drift (gyro rad/s, accel m/s²)
  double rms_sigma[2] = {0, 0};  // RMS of its 1σ
  double cpe_60s = 0;            // inertial-only ΔS 60 s after the window, with b̂ + d̂ at its end
};

constexpr double kBurnIn = 60;  // s: the constant parts converge from their wide priors first

template <class Filter>
Outcome run(const InMotionConfig& fc, double window_end) {
  const Drive& d = drive();
  Outcome o;
  FilterReplay<Filter> replay(fc, d.C_nominal, d.lever);
  std::size_t r = 0;
  const double t_truth0 = d.imu.front().t;
  const double dt_imu = d.imu[1].t - d.imu[0].t;
  long n[2] = {0, 0}, in3[2] = {0, 0};
  double se[2] = {0, 0}, ss[2] = {0, 0};
  std::size_t k = 0;
  for (; k < d.imu.size() && d.imu[k].t <= window_end + 1e-9; ++k) {
    const SimImu& m = d.imu[k];
    replay.imu(m, dt_imu);
    while (r < d.ref.size() && d.ref[r].t <= m.t + 1e-9) {
      const inmotion::RefObs ro = ref_obs(d.ref[r++]);
      if (!replay.reference(ro)) continue;  // the first epoch starts the filter
      typename Filter::Vec6 x, s;
      replay.filter().total_drift_si(x, s);
      std::array<double, 6> tot, sig, tru;
      const auto ki = static_cast<std::size_t>(std::lround((ro.t - t_truth0) / dt_imu));
      for (int i = 0; i < 6; ++i) {
        tot[i] = x(i);
        sig[i] = s(i);
        tru[i] = (i < 3 ? d.unit.gyro.bias(i) : d.unit.accel.bias(i - 3)) + d.drift[ki][static_cast<std::size_t>(i)];
        if (ro.t >= kBurnIn) {
          const int g = i < 3 ? 0 : 1;
          ++n[g];
          in3[g] += std::abs(tot[i] - tru[i]) <= 3 * sig[i];
          se[g] += (tot[i] - tru[i]) * (tot[i] - tru[i]);
          ss[g] += sig[i] * sig[i];
        }
      }
      o.t.push_back(ro.t);
      o.total.push_back(tot);
      o.total_sigma.push_back(sig);
      o.truth.push_back(tru);
    }
  }
  Filter& f = replay.filter();
  for (int i = 0; i < 3; ++i) o.mean_nis[i] = f.consistency(i).mean_nis();
  for (int g = 0; g < 2; ++g) {
    o.coverage[g] = static_cast<double>(in3[g]) / static_cast<double>(n[g]);
    o.rms_err[g] = std::sqrt(se[g] / static_cast<double>(n[g]));
    o.rms_sigma[g] = std::sqrt(ss[g] / static_cast<double>(n[g]));
  }
  // Out of sample: inertial-only navigation from the window end with the estimated set, its
  // biases being the total drift b̂ + d̂ at the end of the window.
  SensorErrors set = f.estimate();
  set.gyro.bias += f.gyro_drift();
  set.accel.bias += f.accel_drift();
  while (r < d.ref.size() && d.ref[r].t < d.imu[k - 1].t - 1e-9) ++r;
  if (r < d.ref.size()) {
    qc::InertialRun q(set, f.mounting(), d.lever, ref_obs(d.ref[r]));
    const double t_start = d.ref[r].t;
    for (std::size_t j = k; j < d.imu.size() && d.imu[j].t <= t_start + 60 + 1e-9; ++j) {
      const SimImu& m = d.imu[j];
      imu_increment(q, m, d.imu[j - 1], dt_imu);
      while (r < d.ref.size() && d.ref[r].t <= m.t + 1e-9) o.cpe_60s = q.cpe(ref_obs(d.ref[r++]));
    }
  }
  return o;
}

// Identification (eq 25 and the fits) of one total-drift column of a run's series.
identification::Identification identify_column(const Outcome& o, int col) {
  std::vector<double> x;
  for (std::size_t k = 0; k < o.t.size(); ++k)
    if (o.t[k] >= kBurnIn) x.push_back(o.total[k][static_cast<std::size_t>(col)]);
  return identification::identify(x, o.t[1] - o.t[0]);
}

double nis_badness(double nis) { return std::abs(std::log(nis / 3.0)); }

}  // namespace

TEST(InmotionDriftModels, ExpCosineBlockKeepsItsStationaryCovariance) {
  // Without observations the (x0, x1) block evolves on its own, P ← ΦPΦᵀ + Qd from P∞: it must
  // stay at P∞ (eqs 35–36 discretised; a wrong sign or a transposed A would not).
  InMotionConfig fc;
  std::array<DriftPrior, 3> g;
  for (auto& p : g) p = DriftPrior{kGyroSigma, 40, true, 0.05};
  fc.gyro_drift = g;
  ASSERT_TRUE(needs_augmented_layout(fc));
  InMotionConfig plain;
  EXPECT_FALSE(needs_augmented_layout(plain));
  RefObs r0{0, 0.5, 2.0, 30, Vec3(5, 0, 0), Vec3(0, 0, 0.3), 0.02, 0.005, 1e-4};
  InMotionFilterAug f(fc, Mat3::Identity(), Vec3::Zero(), r0);
  const identification::ShapingFilter sf =
      identification::shaping_filter({identification::DriftModelKind::exp_cosine, kGyroSigma, 1.0 / 40, 0.05});
  const double dt = 0.01;
  for (int k = 1; k <= 20000; ++k) f.imu(k * dt, Vec3::Zero(), Vec3(0, 0, -9.8 * dt), dt);
  for (int i = 0; i < 3; ++i) {
    const int a = f.offset(Block::dg_aux) + i, d = f.offset(Block::dg) + i;
    EXPECT_NEAR(f.P()(d, d), sf.P_inf(1, 1), 1e-3 * sf.P_inf(1, 1)) << i;
    EXPECT_NEAR(f.P()(a, a), sf.P_inf(0, 0), 1e-3 * sf.P_inf(0, 0)) << i;
    EXPECT_NEAR(f.P()(a, d), sf.P_inf(0, 1), 1e-3 * std::sqrt(sf.P_inf(0, 0) * sf.P_inf(1, 1))) << i;
  }
  // The configuration chooses the layout (issue 19: blocks by configuration, not by a template
  // parameter): an exp-cosine model brings its aux states, the default configuration does not.
  EXPECT_EQ(InMotionFilter(fc, Mat3::Identity(), Vec3::Zero(), r0).layout().size(), 48);  // the paper's augmented layout
  EXPECT_EQ(InMotionFilter(plain, Mat3::Identity(), Vec3::Zero(), r0).layout().size(), 42);
}

TEST(InmotionDriftModels, IdentifiedModelsMakeTheFilterConsistent) {
  const double window = drive().imu.back().t - 70;  // the last 70 s are for the inertial-only QC
  const InMotionConfig base;
  const Outcome def = run<InMotionFilter>(base, window);

  // Identify the gyro models from the default fit's total drift series (no truth involved); the
  // accelerometers keep the data-sheet default. Then once more from the refit's series: the
  // default filter, too confident in its drift prior, lags the real drift, and its series
  // understates σ; the refit follows the drift and its series is closer to the process.
  auto identified = [&](const Outcome& o, const char* pass) {
    InMotionConfig c;
    std::array<DriftPrior, 3> g;
    for (int i = 0; i < 3; ++i) {
      const auto id = identify_column(o, i);
      const auto& b = id.best();
      EXPECT_TRUE(b.usable) << pass << ' ' << i;
      const bool ec = id.chosen == identification::DriftModelKind::exp_cosine;
      g[static_cast<std::size_t>(i)] = DriftPrior{b.sigma, 1.0 / b.alpha, ec, ec ? b.beta : 0.0};
      std::printf("%s: gyro %c %s sigma %.3g deg/h (truth %.3g, prior 5.1) T %.3g s (truth %.3g, prior 300) beta %.3g (truth %.3g)\n",
                  pass, "xyz"[i], identification::drift_model_name(id.chosen), b.sigma / kDegPerHour,
                  kGyroSigma / kDegPerHour, 1 / b.alpha, 1 / kGyroAlpha, ec ? b.beta : 0.0, kGyroBeta);
      // The identified σ is nearer the truth than the data-sheet prior (log ratio).
      EXPECT_LT(std::abs(std::log(b.sigma / kGyroSigma)), std::abs(std::log(5.1 * kDegPerHour / kGyroSigma))) << i;
    }
    c.gyro_drift = g;
    return c;
  };
  auto fit = [&](const InMotionConfig& c) {
    return needs_augmented_layout(c) ? run<InMotionFilterAug>(c, window) : run<InMotionFilter>(c, window);
  };
  const InMotionConfig withm = identified(def, "pass 1");
  const Outcome mod1 = fit(withm);
  const Outcome mod = fit(identified(mod1, "pass 2"));
  std::printf("pass 1: NIS %.3f %.3f %.3f, gyro coverage %.3f, RMS error %.3g deg/h, sigma %.3g\n", mod1.mean_nis[0],
              mod1.mean_nis[1], mod1.mean_nis[2], mod1.coverage[0], mod1.rms_err[0] / kDegPerHour,
              mod1.rms_sigma[0] / kDegPerHour);

  const char* nm[3] = {"position", "velocity", "attitude"};
  for (int i = 0; i < 3; ++i)
    std::printf("mean NIS %-8s default %.3f  with models %.3f (expected 3)\n", nm[i], def.mean_nis[i], mod.mean_nis[i]);
  for (int s = 0; s < 2; ++s) {
    const double u = s == 0 ? kDegPerHour : kMilliG;
    std::printf("%s total drift: RMS error %.3g vs %.3g %s, RMS sigma %.3g vs %.3g, 3-sigma coverage %.3f vs %.3f\n",
                s == 0 ? "gyro " : "accel", def.rms_err[s] / u, mod.rms_err[s] / u, s == 0 ? "deg/h" : "mg",
                def.rms_sigma[s] / u, mod.rms_sigma[s] / u, def.coverage[s], mod.coverage[s]);
  }
  std::printf("inertial-only dS 60 s after the window: default %.2f m, with models %.2f m\n", def.cpe_60s, mod.cpe_60s);

  // The attitude innovations carry the gyro drift: with the real drift model they are consistent
  // (closer to the expected χ²₃ mean), and so are the others.
  EXPECT_LT(nis_badness(mod1.mean_nis[2]), nis_badness(def.mean_nis[2]));
  EXPECT_LT(nis_badness(mod.mean_nis[2]), nis_badness(def.mean_nis[2]));
  // The stated uncertainty of the total gyro drift covers its real error (3σ) with the
  // identified models; with the data-sheet prior the filter is overconfident.
  EXPECT_GT(mod1.coverage[0], def.coverage[0]);
  EXPECT_GT(mod.coverage[0], def.coverage[0]);
  EXPECT_GT(mod.coverage[0], 0.95);
  EXPECT_LT(mod.rms_err[0], def.rms_err[0]);
}
