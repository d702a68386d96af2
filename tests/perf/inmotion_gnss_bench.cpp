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
// INMOTION_GNSS_RATES=200,2460, INMOTION_GNSS_DURATION_S=3600, INMOTION_GNSS_SEED0=1 (first seed).
// Diagnostics (evaluation only): INMOTION_GNSS_DUMP=dir writes a CSV per run and configuration (heading
// error against the filter's heading σ, yaw rate, gyro z scale and total drift against the truth,
// position innovation, per fix); INMOTION_GNSS_ORACLE=1 adds the bound "oracle params" (data
// corrected by the true bias and M, true mounting, parameter priors ~0: navigation and in-run drift
// only); INMOTION_GNSS_NO_GYRO_DRIFT=1 drives a unit without gyro in-run drift (an experiment).
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

#include "bench/io/imu_class_toml.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/drive/route_toml.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"

using namespace calbench;
using units::kDeg;

namespace {

struct RunResult {
  long used = 0, rejected = 0, forced = 0, realigned = 0, widened = 0, skipped = 0;
  double heading_t = -1;
  double head_max_after = 0, head_end = 0;  // |heading error| after the first 300 s of motion, deg
  double head_max_t = -1;                   // when the maximum occurred, s
  double head_at[3] = {-1, -1, -1};         // |heading error| at 60, 120, 300 s of motion, deg
  double z2_sum = 0, z_max = 0;             // heading error / filter's heading σ after 300 s: Σz², max |z|
  long z_n = 0;
  int within = 0, params = 0, mount_within = 0;
  int bias_within = 0, bias_params = 0, m_within = 0, m_params = 0;
  std::vector<std::string> misses;  // parameters outside 3σ
};

// Configurations 4 and 5 only with INMOTION_GNSS_ORACLE=1: an evaluation bound, not a calibration. The
// data corrected by the simulator's true bias and M, the true mounting as nominal and every
// parameter prior ~0, so that the filter is left with navigation and in-run drift only (what a
// filter that knew the unit perfectly could do with the same fixes).
const char* kCfgName[6] = {"pos, raw priors", "pos,vel, raw priors", "pos, bench priors", "pos,vel, bench priors",
                           "pos, oracle params", "pos,vel, oracle params"};
int n_cfg() { return std::getenv("INMOTION_GNSS_ORACLE") ? 6 : 4; }

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
  // INMOTION_GNSS_NO_GYRO_DRIFT=1, an experiment (not the acceptance): the unit without the gyro
  // in-run drift, and the filters told so, to see how much of the heading error the drift makes.
  const bool no_drift = std::getenv("INMOTION_GNSS_NO_GYRO_DRIFT") != nullptr;
  if (no_drift) cfg.noise.gyro.drift_sigma = 0;
  const Mat3 C_nom = ins::dcm_from_rpy(rf.mounting_rpy_deg * kDeg);
  const Mat3 C_mb_true = ins::dcm_from_rpy(cfg.mounting_rpy);
  const TriadCorrector cg(bench.gyro), ca(bench.accel);

  const int nc = n_cfg();
  const TriadCorrector og(unit.gyro), oa(unit.accel);
  std::unique_ptr<inmotion::InMotionFilter> f[6];
  inmotion::InMotionConfig fc[6];
  for (int k = 0; k < nc; ++k) {
    fc[k].obs_pos = true;
    fc[k].obs_vel = k % 2 == 1;
    fc[k].obs_att = false;
    fc[k].ref_sigma_pos = 2.0;  // as fit drive --aiding gnss (the simulator's fixes carry their σ)
    fc[k].ref_sigma_vel = 0.1;
    if (k >= 2)
      fc[k].prior =
          inmotion::priors_from_set(bench, builtin_imu_class("ADIS16488A").allowance, Vec3::Constant(kUnknownSigma)).sigma;
    if (no_drift) {
      fc[k].gyro_drift = std::array<inmotion::DriftPrior, 3>{};
      for (auto& d : *fc[k].gyro_drift) d = inmotion::DriftPrior{1e-3 * units::kDegPerHour, 300};
    }
    if (k >= 4) {
      inmotion::ParameterPriors& p = fc[k].prior;
      p.gyro_bias.setConstant(1e-4 * units::kDegPerHour);
      p.accel_bias.setConstant(1e-4 * kMilliG);
      p.gyro_M.setConstant(1e-3 * kPpm);
      p.accel_M.setConstant(1e-3 * kPpm);
      p.mount.setConstant(1e-5 * kDeg);
    }
  }
  std::vector<RunResult> out(static_cast<std::size_t>(nc));
  Vec3 wp, ap;
  double tp = -1, t_motion = -1;
  Mat3 C_true = Mat3::Identity();
  Vec3 w_true = Vec3::Zero(), v_true = Vec3::Zero();
  Vec3 drift_sum = Vec3::Zero(), drift_true = Vec3::Zero();  // the simulator's drift + noise, mean since the last fix
  long drift_n = 0;
  // Evaluation dump (INMOTION_GNSS_DUMP=dir): per fix and configuration, the heading error against
  // the filter's own heading σ, the yaw rate, the gyro z scale/bias against the truth, the last
  // position innovation. Evaluation only.
  std::FILE* dump[6] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  if (const char* d = std::getenv("INMOTION_GNSS_DUMP"))
    for (int k = 0; k < nc; ++k) {
      const std::string fn = std::string(d) + "/r" + std::to_string(static_cast<int>(rate_hz)) + "_s" + std::to_string(seed) + "_c" +
                             std::to_string(k) + ".csv";
      dump[k] = std::fopen(fn.c_str(), "w");
      if (dump[k])
        std::fprintf(dump[k], "t,tm,herr_deg,sig_psi_deg,yawrate_dps,speed,mgzz_err_ppm,mgzz_sig_ppm,bgz_err_dph,bgz_sig_dph,"
                              "nu_n,nu_e,nis_pos,tilt_err_x_deg,tilt_err_y_deg,mount_z_err_deg,mount_z_sig_deg,herr_prior_deg,"
                              "drift_true_z_dph,bgz_tot_err_dph,bgz_tot_sig_dph\n");
    }
  drivesim::DriveSinks s;
  s.imu = [&](const drivesim::SimImu& m) {
    if (tp >= 0) {
      const double dt = m.t - tp;
      const Vec3 dth = 0.5 * (m.gyro + wp) * dt, dv = 0.5 * (m.accel + ap) * dt;
      const Vec3 dthc = cg.increment(dth, dt), dvc = ca.increment(dv, dt);
      Vec3 dtho = dth, dvo = dv;
      if (nc > 4) dtho = og.increment(dth, dt), dvo = oa.increment(dv, dt);
      for (int k = 0; k < nc; ++k)
        if (f[k]) f[k]->imu(m.t, k < 2 ? dth : k < 4 ? dthc : dtho, k < 2 ? dv : k < 4 ? dvc : dvo, dt);
    }
    wp = m.gyro;
    ap = m.accel;
    tp = m.t;
  };
  s.truth = [&](const drivesim::SimTruth& x) {
    C_true = x.C_nb;
    w_true = x.w_ib_b;
    v_true = x.v_ned;
    if (dump[0]) {
      drift_sum += wp - (Mat3::Identity() + unit.gyro.M) * (C_mb_true.transpose() * x.w_ib_b) - unit.gyro.bias;
      ++drift_n;
    }
    if (t_motion < 0 && x.v_ned.norm() > 0.5) t_motion = x.t;
  };
  s.gnss = [&](const drivesim::SimGnss& g) {
    const inmotion::RefObs o = inmotion::gnss_fix_obs(g.t, g.lat, g.lon, g.h, &g.v_ned, g.sigma_h, g.sigma_v, g.sigma_vel);
    if (drift_n > 0) drift_true = drift_sum / static_cast<double>(drift_n);
    drift_sum.setZero();
    drift_n = 0;
    for (int k = 0; k < nc; ++k) {
      if (!f[k]) {
        f[k] = std::make_unique<inmotion::InMotionFilter>(fc[k], k < 4 ? C_nom : C_mb_true, cfg.lever_arm, o);
        continue;
      }
      const double e_prior = f[k]->heading_known()
                                 ? ins::rotvec_from_dcm(f[k]->nav().C_nb() * (C_true * C_mb_true).transpose())(2) / kDeg
                                 : 0.0;
      f[k]->reference(o);
      if (!f[k]->heading_known() || t_motion < 0) continue;
      // Heading error of the navigation solution (the MEMS frame): the down component of the
      // attitude error rotation, Ĉ_nm·C_nmᵀ = exp(−φ×).
      const Vec3 rv = ins::rotvec_from_dcm(f[k]->nav().C_nb() * (C_true * C_mb_true).transpose());
      const double e = std::abs(rv(2)) / kDeg;
      const double tm = g.t - t_motion;
      if (dump[k]) {
        const SensorErrors est = k >= 4 ? compose_fused(unit, f[k]->estimate()) : k >= 2 ? compose_fused(bench, f[k]->estimate()) : f[k]->estimate();
        const auto& P = f[k]->P();
        const auto& in = f[k]->last_innovation(0);
        const Vec3 mrv = ins::rotvec_from_dcm(f[k]->mounting() * C_mb_true.transpose());
        std::fprintf(dump[k], "%.3f,%.3f,%.5f,%.5f,%.3f,%.3f,%.1f,%.1f,%.2f,%.2f,%.3f,%.3f,%.2f,%.5f,%.5f,%.5f,%.5f,%.5f,%.2f,%.2f,%.2f\n", g.t, tm,
                     rv(2) / kDeg, std::sqrt(P(f[k]->offset(inmotion::Block::att) + 2, f[k]->offset(inmotion::Block::att) + 2)) / kDeg, (C_true * w_true)(2) / kDeg,
                     v_true.head<2>().norm(), (est.gyro.M(2, 2) - unit.gyro.M(2, 2)) / units::kPpm,
                     std::sqrt(P(f[k]->offset(inmotion::Block::Mg) + 8, f[k]->offset(inmotion::Block::Mg) + 8)) / units::kPpm,
                     (est.gyro.bias(2) + f[k]->gyro_drift()(2) - unit.gyro.bias(2)) / units::kDegPerHour,
                     std::sqrt(P(f[k]->offset(inmotion::Block::bg) + 2, f[k]->offset(inmotion::Block::bg) + 2)) / units::kDegPerHour, in.nu(0), in.nu(1), in.nis,
                     rv(0) / kDeg, rv(1) / kDeg, mrv(2) / kDeg, std::sqrt(P(f[k]->offset(inmotion::Block::mount) + 2, f[k]->offset(inmotion::Block::mount) + 2)) / kDeg, e_prior,
                     drift_true(2) / units::kDegPerHour,
                     (est.gyro.bias(2) + f[k]->gyro_drift()(2) - unit.gyro.bias(2) - drift_true(2)) / units::kDegPerHour,
                     f[k]->gyro_total_drift_sigma()(2) / units::kDegPerHour);
      }
      for (int c = 0; c < 3; ++c)
        if (out[k].head_at[c] < 0 && tm >= (c == 0 ? 60 : c == 1 ? 120 : 300)) out[k].head_at[c] = e;
      if (tm >= 300) {
        const double z = rv(2) / std::sqrt(f[k]->P()(f[k]->offset(inmotion::Block::att) + 2, f[k]->offset(inmotion::Block::att) + 2));
        out[k].z2_sum += z * z;
        out[k].z_max = std::max(out[k].z_max, std::abs(z));
        ++out[k].z_n;
        if (e > out[k].head_max_after) out[k].head_max_t = g.t;
        out[k].head_max_after = std::max(out[k].head_max_after, e);
        out[k].head_end = e;
      }
    }
  };
  drivesim::simulate_drive(cfg, s, duration_s);
  for (std::FILE* d : dump)
    if (d) std::fclose(d);

  for (int k = 0; k < nc; ++k) {
    RunResult& r = out[static_cast<std::size_t>(k)];
    const inmotion::InMotionFilter& F = *f[k];
    r.used = F.consistency(0).used;
    r.rejected = F.consistency(0).rejected + F.consistency(1).rejected;
    r.forced = F.consistency(0).forced + F.consistency(1).forced;
    for (const auto& rc : F.recoveries()) (rc.action.rfind("heading", 0) == 0 ? r.realigned : r.widened) += 1;
    r.skipped = F.alignment().skipped_unaligned;
    r.heading_t = F.alignment().heading_t;
    const SensorErrors corr = F.estimate();
    const SensorErrors total = k >= 4 ? compose_fused(unit, corr) : k >= 2 ? compose_fused(bench, corr) : corr;
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
  const int seed0 = std::getenv("INMOTION_GNSS_SEED0") ? std::max(1, std::atoi(std::getenv("INMOTION_GNSS_SEED0"))) : 1;
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
          z2_sum += r.z2_sum;
          z_n += r.z_n;
          z_max = std::max(z_max, r.z_max);
          head_max_after = std::max(head_max_after, r.head_max_after);
          head_end = std::max(head_end, r.head_end);
          heading_ok += r.head_max_after < 0.5;
          lockouts += r.forced > 0;
          ++runs;
        }
      } agg[6];
      const int nc = n_cfg();
      for (int sd = seed0; sd < seed0 + seeds; ++sd) {
        const std::vector<RunResult> rr = run_drive(rf, static_cast<std::uint64_t>(sd), rate, duration);
        for (int k = 0; k < nc; ++k) {
          const RunResult& r = rr[static_cast<std::size_t>(k)];
          agg[k].add(r);
          std::string miss;
          for (const auto& m : r.misses) miss += " " + m;
          std::printf("%4.0f Hz seed %d %-22s: fixes used %ld, rejected %ld, forced %ld, re-alignments %ld (first heading at "
                      "%.0f s, %ld skipped), heading error at 60/120/300 s of motion %.2f/%.2f/%.2f°, after 300 s max %.3f° "
                      "(t %.0f s) end %.3f°, error/σ RMS %.2f max %.1f; within 3σ %d/%d (bias %d/%d, M %d/%d), mounting %d/3;%s%s\n",
                      rate, sd, kCfgName[k], r.used, r.rejected, r.forced, r.realigned, r.heading_t, r.skipped, r.head_at[0],
                      r.head_at[1], r.head_at[2], r.head_max_after, r.head_max_t, r.head_end,
                      r.z_n ? std::sqrt(r.z2_sum / r.z_n) : 0.0, r.z_max, r.within, r.params,
                      r.bias_within, r.bias_params, r.m_within, r.m_params, r.mount_within, miss.empty() ? "" : " outside:",
                      miss.c_str());
          std::fflush(stdout);
        }
      }
      std::printf("\n| IMU rate | configuration | runs | lock-outs (runs with forced epochs) | rejected / forced epochs | "
                  "heading re-alignments | heading error after 300 s of motion: max / max at end | runs < 0.5° | heading error / own σ: "
                  "RMS, max | bias, M within 3σ | bias | M | mounting within 3σ |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
      for (int k = 0; k < nc; ++k) {
        const Agg& a = agg[k];
        if (k == 4)  // the bound: its parameter and mounting columns say nothing (priors ~0, truth given)
          std::printf("\nThe bound, same drives and fixes:\n\n| IMU rate | bound | runs | lock-outs (runs with forced epochs) | "
                      "rejected / forced epochs | heading error after 300 s of motion: max / max at end | runs < 0.5° | "
                      "heading error / own σ: RMS, max |\n|---|---|---|---|---|---|---|---|\n");
        if (k >= 4) {
          std::printf("| %.0f Hz | %s | %d | %d | %ld / %ld | %.2f° / %.2f° | %d/%d | %.2f, %.1f |\n", rate, kCfgName[k], a.runs,
                      a.lockouts, a.rejected, a.forced, a.head_max_after, a.head_end, a.heading_ok, a.runs,
                      a.z_n ? std::sqrt(a.z2_sum / a.z_n) : 0.0, a.z_max);
        } else {
          std::printf("| %.0f Hz | %s | %d | %d | %ld / %ld | %ld | %.2f° / %.2f° | %d/%d | %.2f, %.1f | %.1f %% (%d/%d) | %d/%d | %d/%d | %d/%d |\n",
                      rate, kCfgName[k], a.runs, a.lockouts, a.rejected, a.forced, a.realigned, a.head_max_after, a.head_end,
                      a.heading_ok, a.runs, a.z_n ? std::sqrt(a.z2_sum / a.z_n) : 0.0, a.z_max, 100.0 * a.within / a.params, a.within, a.params, a.bias_within, a.bias_params, a.m_within, a.m_params,
                      a.mount_within, 3 * a.runs);
        }
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
