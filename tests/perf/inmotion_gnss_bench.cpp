// GNSS-only in-motion calibration (issue 16, item 6), in memory: the acceptance measurement of
// docs/in-motion.md, "GNSS-only drives".
//   BM_InMotion_GnssAcceptance  per seed and IMU rate, one simulated 1 h drive of
//                               bench/routes/gnss_1h.toml (60 s opening standstill) by a unit that
//                               went through the factory (bench set fitted on the simulated factory
//                               plan, simulate_factory_coeffs) and whose turn-on bias moved since by
//                               N(0, 0.02 °/s) gyro and N(0, 2 mg) accel per axis. Four filters see
//                               the same drive: GNSS fixes at 1 Hz with --obs pos and pos,vel, on the
//                               raw data with the data-sheet priors and on the data corrected by the
//                               bench set with priors_from_set(set, allowance, mounting unknown).
// Evaluation only (the filters never see it): the simulator's truth — heading of the reference
// body at every fix, the unit's errors and mounting at the end.
// Runs only with INMOTION_GNSS_ACCEPTANCE=1 (minutes of CPU). INMOTION_GNSS_SEEDS=N (5),
// INMOTION_GNSS_RATES=200,2460, INMOTION_GNSS_DURATION_S=3600.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "bench/diagnose/drive_run.hpp"
#include "bench/drive/route_toml.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/units.hpp"

using namespace calbench;
using units::kDeg;

namespace {

struct RunResult {
  long used = 0, rejected = 0, forced = 0, realigned = 0, widened = 0, skipped = 0;
  double heading_t = -1;
  double head_max_after = 0, head_end = 0;  // |heading error| after the first 300 s of motion, deg
  double head_max_t = -1;                   // when the maximum occurred, s
  double head_at[3] = {-1, -1, -1};         // |heading error| at 60, 120, 300 s of motion, deg
  int within = 0, params = 0, mount_within = 0;
  int bias_within = 0, bias_params = 0, m_within = 0, m_params = 0;
  std::vector<std::string> misses;  // parameters outside 3σ
};

const char* kCfgName[4] = {"pos, raw priors", "pos,vel, raw priors", "pos, bench priors", "pos,vel, bench priors"};

std::vector<double> env_list(const char* name, std::vector<double> deflt) {
  const char* e = std::getenv(name);
  if (!e) return deflt;
  std::vector<double> v;
  std::stringstream ss(e);
  std::string tok;
  while (std::getline(ss, tok, ',')) v.push_back(std::atof(tok.c_str()));
  return v;
}

// One drive (seed, IMU rate) and the four filters on it.
std::vector<RunResult> run_drive(const RouteFile& rf, std::uint64_t seed, double rate_hz, double duration_s) {
  using namespace units;
  // The factory: the unit on the simulated factory plan, fitted (never the truth).
  static const std::string plan = std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml";
  const SensorErrors bench = simulate_factory_coeffs(plan, seed, EffectTerms{}, seed + 500000).set.errors;
  // The drive's unit: the factory unit after a turn-on bias shift.
  SensorErrors unit = draw_random_unit(seed);
  std::mt19937_64 rng(seed * 7919 + 3);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    unit.gyro.bias(i) += 0.02 * kDeg * n01(rng);
    unit.accel.bias(i) += 2.0 * kMilliG * n01(rng);
  }
  drivesim::DriveSimConfig cfg;
  cfg.route = rf.route;
  cfg.mems = unit;
  cfg.imu_rate_hz = rate_hz;
  cfg.mounting_rpy = draw_true_mounting_rpy_deg(rf, seed) * kDeg;  // as simulate drive --truth random
  cfg.lever_arm = rf.lever_arm_m;
  cfg.reference.rate_hz = 0;  // GNSS only
  cfg.gnss = rf.gnss;
  cfg.seed = seed;
  const Mat3 C_nom = ins::dcm_from_rpy(rf.mounting_rpy_deg * kDeg);
  const Mat3 C_mb_true = ins::dcm_from_rpy(cfg.mounting_rpy);
  const TriadCorrector cg(bench.gyro), ca(bench.accel);

  std::unique_ptr<inmotion::InMotionFilter> f[4];
  inmotion::InMotionConfig fc[4];
  for (int k = 0; k < 4; ++k) {
    fc[k].obs_pos = true;
    fc[k].obs_vel = k % 2 == 1;
    fc[k].obs_att = false;
    fc[k].ref_sigma_pos = 2.0;  // as fit drive --aiding gnss (the simulator's fixes carry their σ)
    fc[k].ref_sigma_vel = 0.1;
    if (k >= 2)
      fc[k].prior =
          inmotion::priors_from_set(bench, inmotion::stability_allowance_table().front(), Vec3::Constant(kUnknownSigma)).sigma;
  }
  std::vector<RunResult> out(4);
  Vec3 wp, ap;
  double tp = -1, t_motion = -1;
  Mat3 C_true = Mat3::Identity();
  drivesim::DriveSinks s;
  s.imu = [&](const drivesim::SimImu& m) {
    if (tp >= 0) {
      const double dt = m.t - tp;
      const Vec3 dth = 0.5 * (m.gyro + wp) * dt, dv = 0.5 * (m.accel + ap) * dt;
      const Vec3 dthc = cg.increment(dth, dt), dvc = ca.increment(dv, dt);
      for (int k = 0; k < 4; ++k)
        if (f[k]) f[k]->imu(m.t, k < 2 ? dth : dthc, k < 2 ? dv : dvc, dt);
    }
    wp = m.gyro;
    ap = m.accel;
    tp = m.t;
  };
  s.truth = [&](const drivesim::SimTruth& x) {
    C_true = x.C_nb;
    if (t_motion < 0 && x.v_ned.norm() > 0.5) t_motion = x.t;
  };
  s.gnss = [&](const drivesim::SimGnss& g) {
    const inmotion::RefObs o = inmotion::gnss_fix_obs(g.t, g.lat, g.lon, g.h, &g.v_ned, g.sigma_h, g.sigma_v, g.sigma_vel);
    for (int k = 0; k < 4; ++k) {
      if (!f[k]) {
        f[k] = std::make_unique<inmotion::InMotionFilter>(fc[k], C_nom, cfg.lever_arm, o);
        continue;
      }
      f[k]->reference(o);
      if (!f[k]->heading_known() || t_motion < 0) continue;
      // Heading error of the navigation solution (the MEMS frame): the down component of the
      // attitude error rotation, Ĉ_nm·C_nmᵀ = exp(−φ×).
      const double e = std::abs(ins::rotvec_from_dcm(f[k]->nav().C_nb() * (C_true * C_mb_true).transpose())(2)) / kDeg;
      const double tm = g.t - t_motion;
      for (int c = 0; c < 3; ++c)
        if (out[k].head_at[c] < 0 && tm >= (c == 0 ? 60 : c == 1 ? 120 : 300)) out[k].head_at[c] = e;
      if (tm >= 300) {
        if (e > out[k].head_max_after) out[k].head_max_t = g.t;
        out[k].head_max_after = std::max(out[k].head_max_after, e);
        out[k].head_end = e;
      }
    }
  };
  drivesim::simulate_drive(cfg, s, duration_s);

  for (int k = 0; k < 4; ++k) {
    RunResult& r = out[k];
    const inmotion::InMotionFilter& F = *f[k];
    r.used = F.consistency(0).used;
    r.rejected = F.consistency(0).rejected + F.consistency(1).rejected;
    r.forced = F.consistency(0).forced + F.consistency(1).forced;
    for (const auto& rc : F.recoveries()) (rc.action.rfind("heading", 0) == 0 ? r.realigned : r.widened) += 1;
    r.skipped = F.alignment().skipped_unaligned;
    r.heading_t = F.alignment().heading_t;
    const SensorErrors corr = F.estimate();
    const SensorErrors total = k >= 2 ? compose_fused(bench, corr) : corr;
    const char* tri[2] = {"gyro", "accel"};
    for (int t = 0; t < 2; ++t) {
      const TriadErrors& tr = t == 0 ? unit.gyro : unit.accel;
      const TriadErrors& es = t == 0 ? total.gyro : total.accel;
      for (int i = 0; i < 3; ++i) {
        const bool ok = std::abs(es.bias(i) - tr.bias(i)) <= 3 * es.sigma_bias(i);
        r.bias_within += ok;
        ++r.bias_params;
        if (!ok) r.misses.push_back(std::string(tri[t]) + ".bias." + "xyz"[i]);
        for (int j = 0; j < 3; ++j) {
          const bool okm = std::abs(es.M(i, j) - tr.M(i, j)) <= 3 * es.sigma_M(i, j);
          r.m_within += okm;
          ++r.m_params;
          if (!okm) r.misses.push_back(std::string(tri[t]) + ".M." + "xyz"[i] + "xyz"[j]);
        }
      }
    }
    r.within = r.bias_within + r.m_within;
    r.params = r.bias_params + r.m_params;
    Vec3 mr, ms;
    F.mounting_rpy(mr, ms);
    for (int i = 0; i < 3; ++i) r.mount_within += std::abs(std::remainder(mr(i) - cfg.mounting_rpy(i), 2 * units::kPi)) <= 3 * ms(i);
  }
  return out;
}

void BM_InMotion_GnssAcceptance(benchmark::State& state) {
  if (!std::getenv("INMOTION_GNSS_ACCEPTANCE")) {
    state.SkipWithError("set INMOTION_GNSS_ACCEPTANCE=1 to run the GNSS-only acceptance (minutes of CPU)");
    for (auto _ : state) {
    }
    return;
  }
  const RouteFile rf = load_route(std::string(CALBENCH_SOURCE_DIR) + "/bench/routes/gnss_1h.toml");
  const int seeds = std::getenv("INMOTION_GNSS_SEEDS") ? std::max(1, std::atoi(std::getenv("INMOTION_GNSS_SEEDS"))) : 5;
  const std::vector<double> rates = env_list("INMOTION_GNSS_RATES", {200, 2460});
  const double duration = std::getenv("INMOTION_GNSS_DURATION_S") ? std::atof(std::getenv("INMOTION_GNSS_DURATION_S")) : 3600;
  for (auto _ : state) {
    for (double rate : rates) {
      // Per configuration over the seeds: counts summed, heading errors the worst.
      struct Agg : RunResult {
        int runs = 0, heading_ok = 0, lockouts = 0;
        void add(const RunResult& r) {
          for (auto [sum, x] : {std::pair{&used, r.used}, {&rejected, r.rejected}, {&forced, r.forced},
                                {&realigned, r.realigned}, {&widened, r.widened}})
            *sum += x;
          for (auto [sum, x] : {std::pair{&within, r.within}, {&params, r.params}, {&bias_within, r.bias_within},
                                {&bias_params, r.bias_params}, {&m_within, r.m_within}, {&m_params, r.m_params},
                                {&mount_within, r.mount_within}})
            *sum += x;
          head_max_after = std::max(head_max_after, r.head_max_after);
          head_end = std::max(head_end, r.head_end);
          heading_ok += r.head_max_after < 0.5;
          lockouts += r.forced > 0;
          ++runs;
        }
      } agg[4];
      for (int sd = 1; sd <= seeds; ++sd) {
        const std::vector<RunResult> rr = run_drive(rf, static_cast<std::uint64_t>(sd), rate, duration);
        for (int k = 0; k < 4; ++k) {
          const RunResult& r = rr[k];
          agg[k].add(r);
          std::string miss;
          for (const auto& m : r.misses) miss += " " + m;
          std::printf("%4.0f Hz seed %d %-22s: fixes used %ld, rejected %ld, forced %ld, re-alignments %ld (first heading at "
                      "%.0f s, %ld skipped), heading error at 60/120/300 s of motion %.2f/%.2f/%.2f°, after 300 s max %.3f° "
                      "(t %.0f s) end %.3f°; within 3σ %d/%d (bias %d/%d, M %d/%d), mounting %d/3;%s%s\n",
                      rate, sd, kCfgName[k], r.used, r.rejected, r.forced, r.realigned, r.heading_t, r.skipped, r.head_at[0],
                      r.head_at[1], r.head_at[2], r.head_max_after, r.head_max_t, r.head_end, r.within, r.params,
                      r.bias_within, r.bias_params, r.m_within, r.m_params, r.mount_within, miss.empty() ? "" : " outside:",
                      miss.c_str());
          std::fflush(stdout);
        }
      }
      std::printf("\n| IMU rate | configuration | runs | lock-outs (runs with forced epochs) | rejected / forced epochs | "
                  "heading re-alignments | heading error after 300 s of motion: max / max at end | runs < 0.5° | bias, M within 3σ | "
                  "bias | M | mounting within 3σ |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
      for (int k = 0; k < 4; ++k) {
        const Agg& a = agg[k];
        std::printf("| %.0f Hz | %s | %d | %d | %ld / %ld | %ld | %.2f° / %.2f° | %d/%d | %.1f %% (%d/%d) | %d/%d | %d/%d | %d/%d |\n", rate,
                    kCfgName[k], a.runs, a.lockouts, a.rejected, a.forced, a.realigned, a.head_max_after, a.head_end, a.heading_ok,
                    a.runs, 100.0 * a.within / a.params, a.within, a.params, a.bias_within, a.bias_params, a.m_within, a.m_params,
                    a.mount_within, 3 * a.runs);
        const std::string p = std::to_string(static_cast<int>(rate)) + "hz_" + std::to_string(k) + "_";
        state.counters[p + "within3s_pct"] = 100.0 * a.within / a.params;
        state.counters[p + "head_max_deg"] = a.head_max_after;
        state.counters[p + "lockouts"] = a.lockouts;
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
}
BENCHMARK(BM_InMotion_GnssAcceptance)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
