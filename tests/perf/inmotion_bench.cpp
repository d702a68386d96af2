// In-motion calibration: filter throughput at 2460 Hz and memory, and the acceptance measurement
// of the two-stage calibration (issues 5 and 16; 10 seeds on the default route, in memory, no CSV):
//   BM_InMotion_FitThroughput   IMU samples/s of the EKF pass (INS + covariance at 10 Hz + updates)
//   BM_InMotion_Acceptance      per seed: random unit and mounting; the factory stage simulated on
//                               bench/plans/factory.toml and fitted by least squares (the bench set,
//                               never the truth); the drive's unit is that unit after a turn-on bias
//                               shift; fit on all but the last 10 minutes with the bench set applied
//                               first and priors from it (set σ ⊕ stability allowance), the combined
//                               set = the fused estimate; then inertial-only ΔS over those 10 minutes
//                               (out of sample) for bench-only, bench + in-motion and the oracle (the
//                               unit's true constant errors and mounting: the floor no calibration
//                               beats). Primary figure: ΔS(bench + in-motion) / ΔS(oracle).
//   BM_InMotion_AcceptanceRaw   the same drives fitted on raw data (no --coeffs): data-sheet priors.
// Run: bench/drive/acceptance.sh (or calbench_perf --benchmark_filter=InMotion).
// It runs only with INMOTION_ACCEPTANCE=1 (minutes of CPU). INMOTION_SEEDS=N overrides the number of seeds of the acceptance run.
// INMOTION_DIAG=1 prints per seed and axis the combined set's bias error against its σ and the unit's true in-run
// drift at the end of the window (SimTruth, evaluation only).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "bench/io/imu_class_toml.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/drive/route_toml.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/qc/inertial_qc.hpp"
#include "common/units.hpp"

using namespace calbench;
using units::kDeg;

namespace {

long maxrss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

inmotion::RefObs ref_obs(const drivesim::SimRef& r) {
  return inmotion::RefObs{r.t, r.lat, r.lon, r.h, r.v_ned, r.rpy, r.sigma_pos, r.sigma_vel, r.sigma_att};
}

struct Recorded {
  std::vector<double> t;
  std::vector<Vec3> g, a;
  std::vector<inmotion::RefObs> ref;
  std::vector<std::size_t> ref_after;  // IMU index after which each reference epoch arrives
  Mat3 C_mb;
  Vec3 lever;
};

const Recorded& recorded_5min() {
  static const Recorded rec = [] {
    Recorded r;
    const RouteFile rf = load_route(std::string(CALBENCH_SOURCE_DIR) + "/bench/routes/default.toml");
    drivesim::DriveSimConfig cfg;
    cfg.route = rf.route;
    cfg.mems = draw_random_unit(5);
    cfg.imu_rate_hz = 2460;
    cfg.mounting_rpy = rf.mounting_rpy_deg * kDeg;
    cfg.lever_arm = rf.lever_arm_m;
    cfg.reference = rf.reference;
    cfg.gnss.rate_hz = 0;
    r.C_mb = ins::dcm_from_rpy(cfg.mounting_rpy);
    r.lever = cfg.lever_arm;
    drivesim::DriveSinks s;
    s.imu = [&](const drivesim::SimImu& m) {
      r.t.push_back(m.t);
      r.g.push_back(m.gyro);
      r.a.push_back(m.accel);
    };
    s.reference = [&](const drivesim::SimRef& x) {
      r.ref.push_back(ref_obs(x));
      r.ref_after.push_back(r.t.size() - 1);
    };
    drivesim::simulate_drive(cfg, s, 300.0);
    return r;
  }();
  return rec;
}

void BM_InMotion_FitThroughput(benchmark::State& state) {
  const Recorded& r = recorded_5min();
  const long rss0 = maxrss_kb();
  for (auto _ : state) {
    inmotion::InMotionConfig cfg;
    inmotion::InMotionFilter f(cfg, r.C_mb, r.lever, r.ref[0]);
    std::size_t ri = 1;
    Vec3 wp = r.g[0], ap = r.a[0];
    for (std::size_t k = 1; k < r.t.size(); ++k) {
      const double dt = r.t[k] - r.t[k - 1];
      f.imu(r.t[k], 0.5 * (r.g[k] + wp) * dt, 0.5 * (r.a[k] + ap) * dt, dt);
      wp = r.g[k];
      ap = r.a[k];
      while (ri < r.ref.size() && r.ref_after[ri] <= k) f.reference(r.ref[ri++]);
    }
    benchmark::DoNotOptimize(f.estimate());
  }
  const double n = static_cast<double>(r.t.size());
  state.SetItemsProcessed(static_cast<int64_t>(n) * state.iterations());
  state.counters["imu_rate_hz"] = 2460;
  state.counters["filter_state_bytes"] = sizeof(inmotion::InMotionFilter);
  state.counters["maxrss_delta_kb"] = static_cast<double>(maxrss_kb() - rss0);
}
BENCHMARK(BM_InMotion_FitThroughput)->Unit(benchmark::kSecond)->Iterations(1)->Repetitions(3);

// σ of the gyro states at a time of the fit (the observability story of --obs).
struct Checkpoint {
  double t = 0;
  Vec3 drift_total_sigma, drift_const_sigma;  // °/h
  double scale_sigma_ppm = 0, skew_sigma_ppm = 0;  // RMS over the three scales / six skews
  Vec3 mount_sigma_deg;
};

struct SeedResult {
  int within = 0, params = 0, mount_within = 0;
  int m_terms = 0, m_within_bound = 0;  // combined M error <= bench error + 3·allowance
  int biases = 0, bias_better = 0;      // combined bias error < bench bias error
  double max_m_err_over_bound = 0;
  double bias_err2_bench[2] = {0, 0}, bias_err2_comb[2] = {0, 0};  // Σ squared errors per triad (gyro, accel)
  std::vector<std::string> bias_misses;  // where the combined bias is not better, and why
  std::vector<Checkpoint> checkpoints;
  long rejected[3] = {0, 0, 0}, used[3] = {0, 0, 0}, forced[3] = {0, 0, 0};
  double mean_nis[3] = {0, 0, 0};
  double cpe_bench = 0, cpe_inmotion = 0, cpe_bench_nominal_mount = 0, cpe_oracle = 0;
  Vec3 gyro_sigma, gyro_err, gyro_total_sigma;
};

// How the drive's fit starts: from the factory stage's bench set (priors from it), or from raw data.
enum class Start { bench, raw };

// The unit at the drive: the factory unit after a turn-on bias shift (0.02 °/s gyro, 2 mg accel, 1σ
// per axis) since the factory calibration.
SensorErrors turned_on(const SensorErrors& factory_unit, std::uint64_t seed) {
  using namespace units;
  std::mt19937_64 rng(seed * 977 + 13);
  std::normal_distribution<double> n(0.0, 1.0);
  SensorErrors u = factory_unit;
  for (int i = 0; i < 3; ++i) {
    u.gyro.bias(i) += 0.02 * kDeg * n(rng);
    u.accel.bias(i) += 2.0 * kMilliG * n(rng);
  }
  return u;
}

SeedResult run_seed(const RouteFile& rf, std::uint64_t seed, bool att, double qc_horizon,
                    const std::vector<double>& checkpoint_times = {}, Start start = Start::bench) {
  drivesim::DriveSimConfig cfg;
  cfg.route = rf.route;
  // The factory stage: the unit on the factory plan, fitted as `calbench fit bench` does.
  const SensorErrors bench =
      start == Start::bench
          ? simulate_factory_coeffs(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml", seed, EffectTerms{},
                                    seed + 500000)
                .set.errors
          : SensorErrors{};
  cfg.mems = turned_on(draw_random_unit(seed), seed);
  cfg.imu_rate_hz = rf.imu_rate_hz;
  std::mt19937_64 rng(seed ^ 0x6d6f756e74ULL);
  std::normal_distribution<double> n(0.0, rf.misalignment_sigma_deg);
  Vec3 true_rpy_deg = rf.mounting_rpy_deg;
  for (int i = 0; i < 3; ++i) true_rpy_deg(i) += n(rng);
  cfg.mounting_rpy = true_rpy_deg * kDeg;
  cfg.lever_arm = rf.lever_arm_m;
  cfg.reference = rf.reference;
  cfg.gnss.rate_hz = 0;
  cfg.seed = seed;
  const drivesim::RouteProfile prof(rf.route);
  const double t_fit = prof.duration() - qc_horizon - 1.0;
  const TriadCorrector cg(bench.gyro), ca(bench.accel);
  const inmotion::StabilityAllowance allow = builtin_imu_class("ADIS16488A").allowance;
  const Mat3 C_nom = ins::dcm_from_rpy(rf.mounting_rpy_deg * kDeg);

  inmotion::InMotionConfig fc;
  fc.obs_att = att;
  // The data are bench-corrected: priors as `fit drive --coeffs` sets them (set σ unknown here).
  // Priors as `fit drive` sets them: from the bench set with --coeffs, the data-sheet class on raw data.
  if (start == Start::bench) fc.prior = inmotion::priors_from_set(bench, allow, Vec3::Constant(kUnknownSigma)).sigma;
  if (const char* e = std::getenv("INMOTION_PRIOR_GYRO_DPS")) fc.prior.gyro_bias.setConstant(std::atof(e) * kDeg);
  std::unique_ptr<inmotion::InMotionFilter> f;
  std::unique_ptr<qc::InertialRun> qb, qi, qbn, qo;
  SensorErrors total;
  Vec3 mr, ms;
  Vec3 wp, ap;
  double tp = -1;
  double t_qc0 = 0;
  SeedResult out;
  drivesim::DriveSinks s;
  // INMOTION_DIAG=1 (evaluation only): the unit's true in-run drift at the end of the fit window.
  const bool diag = std::getenv("INMOTION_DIAG") != nullptr;
  Vec3 true_dg = Vec3::Zero(), true_da = Vec3::Zero(), dg_hat = Vec3::Zero(), dg_fit = Vec3::Zero(), da_fit = Vec3::Zero();
  if (diag)
    s.truth = [&](const drivesim::SimTruth& x) {
      true_dg = x.gyro_drift;
      true_da = x.accel_drift;
    };
  s.imu = [&](const drivesim::SimImu& m) {
    if (tp >= 0) {
      const double dt = m.t - tp;
      const Vec3 dth = 0.5 * (m.gyro + wp) * dt, dv = 0.5 * (m.accel + ap) * dt;
      if (f && !qb) f->imu(m.t, cg.increment(dth, dt), ca.increment(dv, dt), dt);
      if (qb) {
        qb->imu(m.t, dth, dv, dt);
        qi->imu(m.t, dth, dv, dt);
        qbn->imu(m.t, dth, dv, dt);
        qo->imu(m.t, dth, dv, dt);
      }
    }
    wp = m.gyro;
    ap = m.accel;
    tp = m.t;
  };
  s.reference = [&](const drivesim::SimRef& x) {
    const inmotion::RefObs r = ref_obs(x);
    if (!f) {
      f = std::make_unique<inmotion::InMotionFilter>(fc, C_nom, cfg.lever_arm, r);
      return;
    }
    if (!qb) {
      f->reference(r);
      while (out.checkpoints.size() < checkpoint_times.size() && r.t >= checkpoint_times[out.checkpoints.size()]) {
        Checkpoint c;
        c.t = r.t;
        c.drift_total_sigma = f->gyro_total_drift_sigma() / units::kDegPerHour;
        const SensorErrors e = f->estimate();
        c.drift_const_sigma = e.gyro.sigma_bias / units::kDegPerHour;
        double sc = 0, sk = 0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) (i == j ? sc : sk) += e.gyro.sigma_M(i, j) * e.gyro.sigma_M(i, j);
        c.scale_sigma_ppm = std::sqrt(sc / 3) * 1e6;
        c.skew_sigma_ppm = std::sqrt(sk / 6) * 1e6;
        Vec3 rpy, sig;
        f->mounting_rpy(rpy, sig);
        c.mount_sigma_deg = sig / kDeg;
        out.checkpoints.push_back(c);
      }
      if (r.t >= t_fit) {
        total = start == Start::bench ? compose_fused(bench, f->estimate()) : f->estimate();
        f->mounting_rpy(mr, ms);
        dg_fit = true_dg;
        da_fit = true_da;
        dg_hat = f->gyro_drift();
        const Mat3 C_est = ins::dcm_from_rpy(mr);
        qb = std::make_unique<qc::InertialRun>(bench, C_est, cfg.lever_arm, r);
        qi = std::make_unique<qc::InertialRun>(total, C_est, cfg.lever_arm, r);
        qbn = std::make_unique<qc::InertialRun>(bench, C_nom, cfg.lever_arm, r);
        // The floor no calibration can beat: the unit's true constant errors and true mounting
        // (evaluation only; the estimator never sees them). What remains is the in-run drift.
        qo = std::make_unique<qc::InertialRun>(cfg.mems, ins::dcm_from_rpy(cfg.mounting_rpy), cfg.lever_arm, r);
        t_qc0 = r.t;
      }
      return;
    }
    if (r.t - t_qc0 <= qc_horizon + 1e-9) {
      out.cpe_bench = qb->cpe(r);
      out.cpe_inmotion = qi->cpe(r);
      out.cpe_bench_nominal_mount = qbn->cpe(r);
      out.cpe_oracle = qo->cpe(r);
    }
  };
  drivesim::simulate_drive(cfg, s);
  auto count = [&](const TriadErrors& t, const TriadErrors& e) {
    for (int i = 0; i < 3; ++i) {
      out.within += std::abs(e.bias(i) - t.bias(i)) <= 3 * e.sigma_bias(i);
      ++out.params;
      for (int j = 0; j < 3; ++j) {
        out.within += std::abs(e.M(i, j) - t.M(i, j)) <= 3 * e.sigma_M(i, j);
        ++out.params;
      }
    }
  };
  count(cfg.mems.gyro, total.gyro);
  count(cfg.mems.accel, total.accel);
  if (start == Start::bench) {
    // The composition criteria of issue 16: M no worse than the bench set's error plus 3× the
    // allowance; biases better than the bench set's (which carries the turn-on shift).
    for (int s = 0; s < 2; ++s) {
      const TriadErrors& t = s == 0 ? cfg.mems.gyro : cfg.mems.accel;
      const TriadErrors& c = s == 0 ? total.gyro : total.accel;
      const TriadErrors& b = s == 0 ? bench.gyro : bench.accel;
      for (int i = 0; i < 3; ++i) {
        ++out.biases;
        const double ec = std::abs(c.bias(i) - t.bias(i)), eb = std::abs(b.bias(i) - t.bias(i));
        out.bias_better += ec < eb;
        out.bias_err2_bench[s] += eb * eb;
        out.bias_err2_comb[s] += ec * ec;
        if (!(ec < eb)) {
          const double u = s == 0 ? units::kDegPerHour : units::kMilliG;
          char w[200];
          std::snprintf(w, sizeof w, "%s bias %c: bench error %.3g %s (the turn-on shift), combined error %.3g ± %.3g %s",
                        s == 0 ? "gyro" : "accel", "xyz"[i], eb / u, s == 0 ? "°/h" : "mg", ec / u, c.sigma_bias(i) / u,
                        s == 0 ? "°/h" : "mg");
          out.bias_misses.push_back(w);
        }
        for (int j = 0; j < 3; ++j) {
          const double a = i == j ? (s == 0 ? allow.gyro_scale : allow.accel_scale) : (s == 0 ? allow.gyro_skew : allow.accel_skew);
          const double bound = std::abs(b.M(i, j) - t.M(i, j)) + 3 * a, err = std::abs(c.M(i, j) - t.M(i, j));
          ++out.m_terms;
          out.m_within_bound += err <= bound;
          out.max_m_err_over_bound = std::max(out.max_m_err_over_bound, err / bound);
        }
      }
    }
  }
  for (int i = 0; i < 3; ++i)
    out.mount_within += std::abs(std::remainder(mr(i) - cfg.mounting_rpy(i), 2 * units::kPi)) <= 3 * ms(i);
  if (diag) {
    const double u = units::kDegPerHour, m = units::kMilliG;
    for (int i = 0; i < 3; ++i)
      std::printf("diag seed %llu gyro %c: b^-b %+.2f (sigma %.2f) d(t_fit) %+.2f d^ %+.2f d^+b^-b-d %+.2f deg/h;"
                  " accel: b^-b %+.3f (sigma %.3f) d(t_fit) %+.3f mg\n",
                  static_cast<unsigned long long>(seed), "xyz"[i], (total.gyro.bias(i) - cfg.mems.gyro.bias(i)) / u,
                  total.gyro.sigma_bias(i) / u, dg_fit(i) / u, dg_hat(i) / u,
                  (dg_hat(i) + total.gyro.bias(i) - cfg.mems.gyro.bias(i) - dg_fit(i)) / u,
                  (total.accel.bias(i) - cfg.mems.accel.bias(i)) / m, total.accel.sigma_bias(i) / m, da_fit(i) / m);
  }
  out.gyro_sigma = total.gyro.sigma_bias / units::kDegPerHour;
  out.gyro_err = (total.gyro.bias - cfg.mems.gyro.bias) / units::kDegPerHour;
  out.gyro_total_sigma = f->gyro_total_drift_sigma() / units::kDegPerHour;
  for (int k = 0; k < 3; ++k) {
    out.rejected[k] = f->consistency(k).rejected;
    out.forced[k] = f->consistency(k).forced;
    out.used[k] = f->consistency(k).used;
    out.mean_nis[k] = f->consistency(k).mean_nis();
  }
  return out;
}

void run_acceptance(benchmark::State& state, Start start) {
  const RouteFile rf = load_route(std::string(CALBENCH_SOURCE_DIR) + "/bench/routes/default.toml");
  // Minutes of CPU: only when asked for (bench/drive/acceptance.sh sets INMOTION_ACCEPTANCE=1).
  if (!std::getenv("INMOTION_ACCEPTANCE")) {
    state.SkipWithError("set INMOTION_ACCEPTANCE=1 (bench/drive/acceptance.sh) to run the 10-seed acceptance");
    for (auto _ : state) {
    }
    return;
  }
  int seeds = 10;
  if (const char* e = std::getenv("INMOTION_SEEDS")) seeds = std::max(1, std::atoi(e));
  const char* before = start == Start::bench ? "bench-only" : "uncalibrated";
  for (auto _ : state) {
    int within = 0, params = 0, mount_within = 0, m_terms = 0, m_ok = 0, biases = 0, bias_better = 0, worse = 0;
    double e2b[2] = {0, 0}, e2c[2] = {0, 0};
    std::vector<double> ratios, ratios_nominal, over_floor;
    for (int s = 1; s <= seeds; ++s) {
      const SeedResult r = run_seed(rf, static_cast<std::uint64_t>(s), true, 600.0, {}, start);
      within += r.within;
      params += r.params;
      mount_within += r.mount_within;
      m_terms += r.m_terms;
      m_ok += r.m_within_bound;
      biases += r.biases;
      bias_better += r.bias_better;
      for (int k = 0; k < 2; ++k) {
        e2b[k] += r.bias_err2_bench[k];
        e2c[k] += r.bias_err2_comb[k];
      }
      worse += r.cpe_inmotion > r.cpe_bench;
      ratios.push_back(r.cpe_bench / r.cpe_inmotion);
      ratios_nominal.push_back(r.cpe_bench_nominal_mount / r.cpe_inmotion);
      over_floor.push_back(r.cpe_inmotion / r.cpe_oracle);
      std::printf("seed %2d: %2d/%2d params within 3σ, mounting %d/3", s, r.within, r.params, r.mount_within);
      if (start == Start::bench)
        std::printf(", M within bench error + 3·allowance %d/%d (worst %.2f of the bound), biases better than bench %d/%d",
                    r.m_within_bound, r.m_terms, r.max_m_err_over_bound, r.bias_better, r.biases);
      std::printf("; ΔS(600 s) %s %.1f m (nominal mounting %.1f m), %s + in-motion %.1f m, oracle %.1f m:"
                  " in-motion/oracle %.2f, %s/in-motion %.1f\n",
                  before, r.cpe_bench, r.cpe_bench_nominal_mount, start == Start::bench ? "bench" : "raw", r.cpe_inmotion,
                  r.cpe_oracle, r.cpe_inmotion / r.cpe_oracle, before, r.cpe_bench / r.cpe_inmotion);
      for (const auto& m : r.bias_misses) std::printf("         not better: %s\n", m.c_str());
      std::fflush(stdout);
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      const std::size_t n = v.size();
      return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    };
    state.counters["params_within_3sigma_pct"] = 100.0 * within / params;
    state.counters["mounting_within_3sigma_pct"] = 100.0 * mount_within / (3.0 * seeds);
    state.counters["inmotion_over_oracle_median"] = median(over_floor);
    state.counters["inmotion_over_oracle_max"] = *std::max_element(over_floor.begin(), over_floor.end());
    state.counters["before_over_inmotion_median"] = median(ratios);
    state.counters["before_over_inmotion_min"] = *std::min_element(ratios.begin(), ratios.end());
    state.counters["before_nominal_mount_over_inmotion_median"] = median(ratios_nominal);
    state.counters["seeds_inmotion_worse_than_before"] = worse;
    if (start == Start::bench) {
      state.counters["M_within_bench_err_plus_3_allowance_pct"] = 100.0 * m_ok / m_terms;
      state.counters["bias_better_than_bench_pct"] = 100.0 * bias_better / biases;
      const double n = 3.0 * seeds;
      state.counters["gyro_bias_rms_bench_dph"] = std::sqrt(e2b[0] / n) / units::kDegPerHour;
      state.counters["gyro_bias_rms_combined_dph"] = std::sqrt(e2c[0] / n) / units::kDegPerHour;
      state.counters["accel_bias_rms_bench_mg"] = std::sqrt(e2b[1] / n) / units::kMilliG;
      state.counters["accel_bias_rms_combined_mg"] = std::sqrt(e2c[1] / n) / units::kMilliG;
    }
  }
}

void BM_InMotion_Acceptance(benchmark::State& state) {
  run_acceptance(state, Start::bench);
  if (!std::getenv("INMOTION_ACCEPTANCE")) return;
  // The paper's point: gyro drift with and without the attitude observation (seed 1).
  const RouteFile rf = load_route(std::string(CALBENCH_SOURCE_DIR) + "/bench/routes/default.toml");
  const SeedResult a = run_seed(rf, 1, true, 600.0), b = run_seed(rf, 1, false, 600.0);
  for (int i = 0; i < 3; ++i)
    std::printf("obs comparison, gyro %c: pos,vel,att: error %.2f σ %.2f (total drift σ %.2f) °/h;"
                " pos,vel: error %.2f σ %.2f (total drift σ %.2f) °/h\n",
                "xyz"[i], a.gyro_err(i), a.gyro_sigma(i), a.gyro_total_sigma(i), b.gyro_err(i), b.gyro_sigma(i),
                b.gyro_total_sigma(i));
  state.counters["gyro_total_sigma_z_att_dph"] = a.gyro_total_sigma(2);
  state.counters["gyro_total_sigma_z_noatt_dph"] = b.gyro_total_sigma(2);
}
BENCHMARK(BM_InMotion_Acceptance)->Unit(benchmark::kSecond)->Iterations(1);

void BM_InMotion_AcceptanceRaw(benchmark::State& state) { run_acceptance(state, Start::raw); }
BENCHMARK(BM_InMotion_AcceptanceRaw)->Unit(benchmark::kSecond)->Iterations(1);

// The paper's motivation for the attitude observation (eq 15), over several seeds: the σ of the
// gyro states as the drive goes on, and the errors at the end, with --obs pos,vel,att and pos,vel.
void BM_InMotion_ObsComparison(benchmark::State& state) {
  const RouteFile rf = load_route(std::string(CALBENCH_SOURCE_DIR) + "/bench/routes/default.toml");
  if (!std::getenv("INMOTION_ACCEPTANCE")) {
    state.SkipWithError("set INMOTION_ACCEPTANCE=1 (bench/drive/acceptance.sh) to run the obs comparison");
    for (auto _ : state) {
    }
    return;
  }
  int seeds = 4;
  if (const char* e = std::getenv("INMOTION_OBS_SEEDS")) seeds = std::max(1, std::atoi(e));
  const std::vector<double> cps = {30, 60, 120, 300, 600, 1500};
  for (auto _ : state) {
    for (int att = 1; att >= 0; --att) {
      std::vector<Checkpoint> mean(cps.size());
      double err2 = 0, nerr2 = 0, worst_n = 0;
      int n = 0;
      for (int s = 1; s <= seeds; ++s) {
        const SeedResult r = run_seed(rf, static_cast<std::uint64_t>(s), att == 1, 600.0, cps);
        for (std::size_t k = 0; k < r.checkpoints.size(); ++k) {
          const Checkpoint& c = r.checkpoints[k];
          mean[k].t += c.t / seeds;
          mean[k].drift_total_sigma += c.drift_total_sigma / seeds;
          mean[k].drift_const_sigma += c.drift_const_sigma / seeds;
          mean[k].scale_sigma_ppm += c.scale_sigma_ppm / seeds;
          mean[k].skew_sigma_ppm += c.skew_sigma_ppm / seeds;
          mean[k].mount_sigma_deg += c.mount_sigma_deg / seeds;
        }
        std::printf("  seed %d: gyro drift error %.2f %.2f %.2f °/h, σ %.2f %.2f %.2f; obs used/rejected/forced/mean NIS"
                    " pos %ld/%ld/%ld/%.2f vel %ld/%ld/%ld/%.2f att %ld/%ld/%ld/%.2f\n",
                    s, r.gyro_err(0), r.gyro_err(1), r.gyro_err(2), r.gyro_sigma(0), r.gyro_sigma(1), r.gyro_sigma(2),
                    r.used[0], r.rejected[0], r.forced[0], r.mean_nis[0], r.used[1], r.rejected[1], r.forced[1],
                    r.mean_nis[1], r.used[2], r.rejected[2], r.forced[2], r.mean_nis[2]);
        for (int i = 0; i < 3; ++i) {
          err2 += r.gyro_err(i) * r.gyro_err(i);
          const double z = r.gyro_err(i) / r.gyro_sigma(i);
          nerr2 += z * z;
          worst_n = std::max(worst_n, std::abs(z));
          ++n;
        }
      }
      const char* name = att ? "pos,vel,att" : "pos,vel";
      std::printf("--obs %s (%d seeds, mean σ):\n", name, seeds);
      std::printf("  %7s %28s %28s %9s %9s %22s\n", "t [s]", "total drift σ x/y/z [°/h]", "constant drift σ x/y/z [°/h]",
                  "scale σ", "skew σ", "mounting σ r/p/y [°]");
      for (const Checkpoint& c : mean)
        std::printf("  %7.0f %8.2f %8.2f %8.2f   %8.2f %8.2f %8.2f   %6.0f ppm %6.0f ppm %6.3f %6.3f %6.3f\n", c.t,
                    c.drift_total_sigma(0), c.drift_total_sigma(1), c.drift_total_sigma(2), c.drift_const_sigma(0),
                    c.drift_const_sigma(1), c.drift_const_sigma(2), c.scale_sigma_ppm, c.skew_sigma_ppm,
                    c.mount_sigma_deg(0), c.mount_sigma_deg(1), c.mount_sigma_deg(2));
      std::printf("  end of fit: constant gyro drift error RMS %.2f °/h, RMS error/σ %.2f, worst |error|/σ %.2f\n",
                  std::sqrt(err2 / n), std::sqrt(nerr2 / n), worst_n);
      std::fflush(stdout);
      const std::string p = att ? "att_" : "noatt_";
      state.counters[p + "drift_err_rms_dph"] = std::sqrt(err2 / n);
      state.counters[p + "drift_err_over_sigma_rms"] = std::sqrt(nerr2 / n);
      state.counters[p + "total_sigma_z_60s_dph"] = mean[1].drift_total_sigma(2);
      state.counters[p + "total_sigma_z_end_dph"] = mean.back().drift_total_sigma(2);
    }
  }
}
BENCHMARK(BM_InMotion_ObsComparison)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
