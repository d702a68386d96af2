// The in-motion filter's analytic Jacobians against finite differences of the nonlinear models
// (issue 34): F of every block (error_model.cpp, state_blocks.cpp) and H of every observation
// (obs_position/velocity/attitude/nhc/zupt.cpp), in the default 42-state layout and the 48-state
// exp-cosine layout, and the latter with the antenna blocks (lever arm, time offset; antenna_blocks.cpp).
//
// Method. A nominal state x̂ (navigation, sensor model, mounting, drift shaping states, all
// nonzero and away from any symmetry) and, for each error-state direction e_j, the two "true"
// states x± = feedback(x̂, ±ε_j·e_j) made by the blocks' own feedback code (nominal ← nominal − δx,
// so x± is the truth whose error is ±ε_j·e_j). Central differences cancel every even order in ε.
//   F: the same raw IMU data (constant rate and specific force) drive x̂ and x± over T = 0.1 s
//      (the filter's cov_dt) in 100 strapdown steps of 1 ms, each corrected by its own sensor model, the
//      drift states moved by their shaping filters at every step (propagate_drift, the filter's own). The error after
//      T, read back through the inverse of the feedback convention (checked below against the
//      feedback itself), gives the column of the transition Φ_num; the filter's Φ = I + F̄T +
//      ½(F̄T)² comes from the blocks' dynamics() over the same samples (FAccumulator, nav_block).
//   H: z(x) − z(x̂) for the observation functions at the same reference epoch, raw rate and mean gyro
//      rate, the body rate ω_eb^b recomputed from each state (set_body_rate): H·e_j ≈ (z(x−) − z(x+))/(2ε_j).
// Both are compared in units of the states' scales s (Ã = S⁻¹·A·S): F̃ = (Φ − I)/T per second.
//
// Tolerance. What the analytic F leaves out is of order v/R (curvature and transport-rate terms
// of the position rows, 12 m/s / 6.4e6 m ≈ 2e-6 /s), of the strapdown's discretisation beyond
// ½(FT)² (|F̃|³T²/6 ≲ 1e-5 with |F̃| ≲ 0.1 /s at these scales), and the accumulator's attitude at
// the start of each IMU interval where the strapdown rotates within it (|f^n| error ≈ ω·Δt·|f|/2,
// 0.35 rad/s · 1 ms · 9.9 m/s² / 2 = 1.7e-3 m/s², 1.7e-5 /s in the scaled velocity-attitude
// entries; at 10 ms it is 10× that and shows), so an entry agrees within 2e-5 /s + 1 % of itself; H is exact
// (the lever-arm rate ω_eb^b moves with the attitude, the mounting and the gyro's sensor model, as in
// the filter) up to the rounding of the central difference, so 1e-6 + 1e-4 relative. The
// entries that carry the physics are 1e-3 … 0.1 in these units: a flipped sign, a missing factor
// or a transposed block is off by the entry itself, 50× and more beyond the tolerance (checked by
// hand: flipping the sign of nav_block's f^n× or of obs_nhc.cpp's mounting term fails the test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "calibration/inmotion/gauge.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/inmotion/observation.hpp"
#include "calibration/inmotion/state_blocks.hpp"
#include "common/units.hpp"

using namespace calbench;
using namespace calbench::inmotion;
using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

namespace {

// A nominal state: the navigation state it points to lives beside it.
struct State {
  ins::NavState nav;
  Nominal n;
  State() { n.nav = &nav; }
  State(const State& o) : nav(o.nav), n(o.n) { n.nav = &nav; }
  State& operator=(const State& o) {
    nav = o.nav;
    n = o.n;
    n.nav = &nav;
    return *this;
  }
};

// The nominal values in layout L (each block's slice of Nominal::x; the aux and antenna blocks only
// where L has them, the antenna blocks' values nonzero).
State nominal_values(const StateLayout& L) {
  State s;
  s.n.x = Vec::Zero(L.size());
  auto set3 = [&](Block b, const Vec3& v) {
    if (L.offset(b) >= 0) s.n.x.segment<3>(L.offset(b)) = v;
  };
  auto set9 = [&](Block b, std::initializer_list<double> m) {  // row by row
    int i = 0;
    for (double v : m) s.n.x(L.offset(b) + i++) = v;
  };
  s.nav.lat = 0.84;
  s.nav.lon = 0.2;
  s.nav.h = 480;
  s.nav.v = Vec3(11.0, -6.0, 0.4);
  s.nav.q_nb = ins::Quat(ins::dcm_from_rpy(Vec3(0.06, -0.11, 2.2)));
  set3(Block::bg, Vec3(2e-4, -1e-4, 3e-4));
  set3(Block::ba, Vec3(0.02, -0.03, 0.01));
  set3(Block::dg, Vec3(-5e-5, 4e-5, 2e-5));
  set3(Block::da, Vec3(1e-3, -2e-3, 5e-4));
  set3(Block::dg_aux, Vec3(1e-6, -2e-6, 3e-6));
  set3(Block::da_aux, Vec3(-2e-5, 1e-5, 3e-5));
  set9(Block::Mg, {2e-3, 1e-3, -5e-4, -7e-4, -1e-3, 8e-4, 3e-4, -2e-4, 1.5e-3});
  set9(Block::Ma, {-1e-3, 6e-4, 2e-4, -3e-4, 2e-3, -8e-4, 5e-4, 1e-4, -1.2e-3});
  s.n.C_mb = ins::dcm_from_rpy(Vec3(0.03, -0.02, units::kPi / 2 + 0.04));
  set3(kLeverArmBlock, Vec3(0.2, -0.15, 0.25));
  if (const int o = L.offset(kTimeOffsetBlock); o >= 0) s.n.x(o) = 0.012;
  return s;
}

// The scales of the error states (one per block), in SI.
double block_scale(Block b) {
  switch (b) {
    case Block::pos: return 1.0;
    case Block::vel: return 0.1;
    case Block::att: return 1e-3;
    case Block::bg: return 1e-4;
    case Block::ba: return 1e-3;
    case Block::Mg: return 1e-3;
    case Block::Ma: return 1e-3;
    case Block::mount: return 1e-3;
    case Block::dg: return 1e-4;
    case Block::da: return 1e-3;
    case Block::dg_aux: return 1e-6;
    case Block::da_aux: return 1e-5;
    default: return b == kLeverArmBlock ? 0.1 : b == kTimeOffsetBlock ? 0.01 : 1.0;
  }
}

Vec scales(const StateLayout& L) {
  Vec s(L.size());
  for (const BlockSpec* b : L.specs)
    for (int i = 0; i < b->size; ++i) s(L.offset(b->id) + i) = block_scale(b->id);
  return s;
}

// x = feedback(x̂, δx): every block's own feedback code.
State with_error(const State& x, const StateLayout& L, const Vec& dx) {
  State t = x;
  for (const BlockSpec* b : L.specs)
    if (b->feedback) b->feedback(t.n, L.offset(b->id), dx);
  return t;
}

// δx = x̂ ⊖ x, the inverse of the feedback conventions (state_blocks.cpp): position
// geodetic_add_ned(x̂, −δr) = x, velocity x̂ − x, attitude and mounting C = exp(δ×)·Ĉ, the other
// blocks (values in Nominal::x) x̂ − x.
Vec error_of(const State& xh, const State& x, const StateLayout& L) {
  Vec d = Vec::Zero(L.size());
  auto put = [&](Block b, const Vec3& v) { d.segment<3>(L.offset(b)) = v; };
  for (const BlockSpec* b : L.specs) {
    const int o = L.offset(b->id);
    switch (b->id) {
      case Block::pos: put(b->id, ins::geodetic_diff_ned(xh.nav.lat, xh.nav.lon, xh.nav.h, x.nav.lat, x.nav.lon, x.nav.h)); break;
      case Block::vel: put(b->id, xh.nav.v - x.nav.v); break;
      case Block::att: put(b->id, ins::rotvec_from_dcm(x.nav.C_nb() * xh.nav.C_nb().transpose())); break;
      case Block::mount: put(b->id, ins::rotvec_from_dcm(x.n.C_mb * xh.n.C_mb.transpose())); break;
      default: d.segment(o, b->size) = xh.n.x.segment(o, b->size) - x.n.x.segment(o, b->size);
    }
  }
  return d;
}

// The raw data of the step (constant over it): what the sensor outputs, biased and scaled.
const Vec3 kRawRate(0.05, -0.08, 0.35);       // rad/s (turning and pitching)
const Vec3 kRawForce(1.2, -2.1, -9.6);        // m/s² (accelerating in a turn)
constexpr int kSteps = 100;  // a 1 kHz IMU (the ADIS16488A gives 2460 Hz)
constexpr double kDt = 0.001;

// The nonlinear model over kSteps: strapdown with the state's own corrected increments, drift
// shaping states by their filters; with acc, the filter's accumulator of the nominal's samples.
State propagate(const State& x, const StateLayout& L, const DriftModels& drift, FAccumulator* acc) {
  State y = x;
  ins::Strapdown sd(y.nav);
  for (int k = 0; k < kSteps; ++k) {
    // Corrected by the blocks' own compensation (BlockSpec::compensate) of the state's values.
    const SensorCorrection corr = sensor_correction(L, y.n);
    // The drift states move continuously (the filter's shaping filters, step by step).
    const Vec3 dth = corr.apply(kGyro, kRawRate * kDt, kDt), dv = corr.apply(kAccel, kRawForce * kDt, kDt);
    const Mat3 C0 = sd.state().C_nb();
    sd.update(dth, dv, kDt);
    if (acc) acc->add(L, C0, corr, dth / kDt, dv / kDt, kDt);
    propagate_drift(drift, L, y.n, kDt);
  }
  y.nav = sd.state();
  return y;
}

InMotionConfig config(bool augmented, bool antenna = false) {
  InMotionConfig cfg;
  cfg.estimate_lever_arm = cfg.estimate_time_offset = antenna;
  if (augmented) {
    // Exp-cosine models on two gyro axes and one accelerometer axis (the others first-order).
    std::array<DriftPrior, 3> g{DriftPrior{3e-5, 200, true, 0.02}, DriftPrior{2e-5, 300, false, 0}, DriftPrior{3e-5, 150, true, 0.05}};
    std::array<DriftPrior, 3> a{DriftPrior{1e-3, 300, false, 0}, DriftPrior{2e-3, 100, true, 0.03}, DriftPrior{1e-3, 300, false, 0}};
    cfg.gyro_drift = g;
    cfg.accel_drift = a;
  }
  return cfg;
}

std::string state_name(const StateLayout& L, int k) { return column_names(L)[static_cast<std::size_t>(k)]; }

// Compares two matrices in scaled units, entry by entry.
void expect_close(const Mat& num, const Mat& an, double abs_tol, double rel_tol, const StateLayout& L, const std::string& what,
                  const std::vector<std::string>* row_names = nullptr) {
  int bad = 0;
  double worst = 0;  // the largest difference as a fraction of its tolerance
  for (int i = 0; i < num.rows(); ++i)
    for (int j = 0; j < num.cols(); ++j) {
      const double e = std::abs(num(i, j) - an(i, j)), tol = abs_tol + rel_tol * std::abs(an(i, j));
      worst = std::max(worst, e / tol);
      if (e <= tol) continue;
      if (++bad <= 10)
        ADD_FAILURE() << what << ": d(" << (row_names ? (*row_names)[static_cast<std::size_t>(i)] : state_name(L, i)) << ")/d("
                      << state_name(L, j) << ") analytic " << an(i, j) << ", finite differences " << num(i, j);
    }
  std::printf("%s: largest difference %.3g of its tolerance\n", what.c_str(), worst);
  EXPECT_EQ(bad, 0) << what << ": " << bad << " entries beyond the tolerance";
}


std::string layout_name(bool augmented, bool antenna) {
  return std::string(augmented ? " (48 states" : " (42 states") + (antenna ? " + antenna 4)" : ")");
}

void check_F(bool augmented, bool antenna = false) {
  const InMotionConfig cfg = config(augmented, antenna);
  const StateLayout L = make_layout(cfg);
  const int N = L.size();
  ASSERT_EQ(N, (augmented ? 48 : 42) + (antenna ? 4 : 0));  // the paper's layouts (+ the antenna blocks)
  const DriftModels drift = drift_models(cfg);
  const State x0 = nominal_values(L);
  const Vec s = scales(L);

  // The feedback and its inverse agree to first order (the inverse reads the blocks' convention).
  for (int j = 0; j < N; ++j) {
    Vec dx = Vec::Zero(N);
    dx(j) = 1e-3 * s(j);
    const Vec back = error_of(x0, with_error(x0, L, dx), L);
    EXPECT_NEAR((back - dx).cwiseQuotient(s).cwiseAbs().maxCoeff(), 0.0, 1e-5) << "inverse feedback of " << state_name(L, j);
  }

  // The analytic transition over the step, as InMotionFilter::propagate() builds it.
  FAccumulator acc;
  acc.resize(N);
  const State xh = propagate(x0, L, drift, &acc);
  const double T = acc.T;
  NavBlockInputs in;
  in.lat = xh.nav.lat;
  in.h = xh.nav.h;
  in.v_ned = xh.nav.v;
  in.f_n = acc.f_n / T;
  in.earth = ins::local_earth(in.lat, in.h, in.v_ned);
  Mat F = Mat::Zero(N, N), Q = Mat::Zero(N, N);
  const BlockDynamics dyn{cfg, acc, in, T, drift};
  for (const BlockSpec* b : L.specs)
    if (b->dynamics) b->dynamics(dyn, L.L, L.offset(b->id), F, Q);
  const Mat FT = F * T;
  const Mat Phi = Mat::Identity(N, N) + FT + 0.5 * FT * FT;

  // The transition by central differences of the nonlinear model.
  Mat Phi_num(N, N);
  for (int j = 0; j < N; ++j) {
    Vec dx = Vec::Zero(N);
    const double eps = 0.1 * s(j);
    dx(j) = eps;
    const Vec ep = error_of(xh, propagate(with_error(x0, L, dx), L, drift, nullptr), L);
    const Vec em = error_of(xh, propagate(with_error(x0, L, -dx), L, drift, nullptr), L);
    Phi_num.col(j) = (ep - em) / (2 * eps);
  }
  const Mat S = s.asDiagonal(), Si = s.cwiseInverse().asDiagonal();
  const Mat I = Mat::Identity(N, N);
  const Mat Fa = Si * (Phi - I) * S / T, Fn = Si * (Phi_num - I) * S / T;
  // The test must see what it checks: the physics' entries are well above the tolerance.
  EXPECT_GT(Fa.cwiseAbs().maxCoeff(), 0.05);
  expect_close(Fn, Fa, 2e-5, 1e-2, L, "F" + layout_name(augmented, antenna));
}

TEST(InMotionJacobian, TransitionMatchesFiniteDifferencesDefaultLayout) { check_F(false); }
TEST(InMotionJacobian, TransitionMatchesFiniteDifferencesExpCosineLayout) { check_F(true); }
TEST(InMotionJacobian, TransitionMatchesFiniteDifferencesAntennaBlocks) { check_F(true, true); }

// Every observation's H: pos, vel, att (a reference epoch at the predicted values), NHC, ZUPT and
// zero rate.
void check_H(bool augmented, bool antenna = false) {
  const InMotionConfig cfg = config(augmented, antenna);
  const StateLayout L = make_layout(cfg);
  const int N = L.size();
  const State x0 = nominal_values(L);
  const Vec s = scales(L);
  const Vec3 lever(-0.9, 0.35, -0.6);
  // The raw MEMS rate, corrected by each state's own sensor model; ω_eb^b follows the state's
  // attitude, mounting and gyro model as in the filter (set_body_rate), so eq 14's and the NHC's
  // lever-arm rate terms are perturbed with them.
  auto context = [&](const State& x) {
    ObsContext c;
    c.mems = &x.nav;
    c.C_mb = x.n.C_mb;
    c.lever = lever;
    c.set_layout(L);
    const SensorCorrection corr = sensor_correction(L, x.n);
    set_body_rate(c, L, corr, corr.apply(kGyro, kRawRate, 1.0));
    c.a_ned = Vec3(1.5, -2.0, 0.3);
    return c;
  };
  // The reference epoch the nominal predicts (z(x̂) = 0; the differences do not depend on it).
  RefObs r;
  {
    const ObsContext c = context(x0);
    const Mat3 C_nb = predicted_body_attitude(c);
    r.lat = x0.nav.lat;
    r.lon = x0.nav.lon;
    r.h = x0.nav.h;
    const Vec3 lever_all = lever + (L.offset(kLeverArmBlock) >= 0 ? Vec3(x0.n.x.segment<3>(L.offset(kLeverArmBlock))) : Vec3::Zero());
    ins::geodetic_add_ned(r.lat, r.lon, r.h, -(C_nb * lever_all));
    r.v_ned = x0.nav.v - C_nb * c.w_eb_b.cross(lever_all);
    r.rpy = ins::rpy_from_dcm(C_nb);
    r.sigma_pos = r.sigma_vel = r.sigma_att = 1;
  }
  // A standstill's mean raw gyro rate: the Earth rate in MEMS axes through the sensor model.
  const Vec3 y_mean = (Mat3::Identity() + x0.n.mat3(L.offset(Block::Mg))) * (x0.nav.C_nb().transpose() * ins::earth_rate_ned_at(x0.nav.lat)) +
                       x0.n.vec3(L.offset(Block::bg)) + x0.n.vec3(L.offset(Block::dg));

  // Eqs 13–14 with the blocks' own observation parts (the antenna blocks), as the filter forms them.
  auto with_blocks = [&](const State& x, int type) {
    const ObsContext c = context(x);
    Observation o = type == 0 ? position_observation(c, r) : velocity_observation(c, r);
    Mat H = o.H;
    observe_blocks(L, BlockObsInput{c, r}, x.n, type, H, o.z);
    o.H = H;
    return o;
  };
  struct Obs {
    const char* name;
    std::function<Eigen::VectorXd(const State&)> z;
    std::function<Eigen::MatrixXd(const State&)> H;
  };
  const std::vector<Obs> all = {
      {"position (eq 13)", [&](const State& x) -> Vec { return with_blocks(x, 0).z; },
       [&](const State& x) -> Mat { return with_blocks(x, 0).H; }},
      {"velocity (eq 14)", [&](const State& x) -> Vec { return with_blocks(x, 1).z; },
       [&](const State& x) -> Mat { return with_blocks(x, 1).H; }},
      {"attitude (eq 15)", [&](const State& x) -> Vec { return attitude_observation(context(x), r).z; },
       [&](const State& x) -> Mat { return attitude_observation(context(x), r).H; }},
      {"nhc", [&](const State& x) -> Vec { return nhc_observation(context(x), 0.1).z; },
       [&](const State& x) -> Mat { return nhc_observation(context(x), 0.1).H; }},
      {"zupt", [&](const State& x) -> Vec { return zupt_observation(context(x), 0.01).z; },
       [&](const State& x) -> Mat { return zupt_observation(context(x), 0.01).H; }},
      {"zero rate", [&](const State& x) -> Vec { return zero_rate_observation(context(x), x.n, y_mean, 1e-4).z; },
       [&](const State& x) -> Mat { return zero_rate_observation(context(x), x.n, y_mean, 1e-4).H; }},
  };
  const Mat S = s.asDiagonal();
  // ω_eb^b's own Jacobian (set_body_rate), column by column: the attitude's part (ω_ie^n×φ, 7e-5 of φ)
  // is too small to show through the lever arm at these scales, so it is checked here directly.
  {
    const Mat J = context(x0).w_eb_jac;
    ASSERT_EQ(J.cols(), N);
    Mat Jn(3, N);
    for (int j = 0; j < N; ++j) {
      Vec dx = Vec::Zero(N);
      const double eps = 0.1 * s(j);
      dx(j) = eps;
      Jn.col(j) = (context(with_error(x0, L, -dx)).w_eb_b - context(with_error(x0, L, dx)).w_eb_b) / (2 * eps);
    }
    const double k = (J * S).cwiseAbs().maxCoeff();
    ASSERT_GT(k, 0);
    const double k_att = (J.middleCols(L.offset(Block::att), 3) * S.block(L.offset(Block::att), L.offset(Block::att), 3, 3)).cwiseAbs().maxCoeff();
    EXPECT_GT(k_att / k, 1e-5);  // the attitude's entries are well above the tolerance below
    const std::vector<std::string> rows = {"w_eb[0]", "w_eb[1]", "w_eb[2]"};
    expect_close(Jn * S / k, J * S / k, 1e-7, 1e-4, L, "d(w_eb)" + layout_name(augmented, antenna), &rows);
  }
  // The triads' common rotation (gauge.hpp) is invisible to every observation at its linearisation
  // point: H·N = 0 (the analytic H, checked against finite differences below), relative to what the
  // same H makes of the rotation's parts one at a time (Σ_j |H_j·N_j|, 1e-4…20 here). A wrong sign in
  // any of N's four parts leaves a residue of the size of that part.
  {
    const Mat Ng = unobservable_rotation(L, x0.n);
    ASSERT_EQ(Ng.rows(), N);
    ASSERT_EQ(Ng.cols(), 3);
    for (const Obs& o : all) {
      const Mat H = o.H(x0);
      Mat parts = Mat::Zero(H.rows(), 3);
      for (int j = 0; j < N; ++j) parts += (H.col(j) * Ng.row(j)).cwiseAbs();
      if (parts.maxCoeff() == 0) continue;  // zero velocity: no attitude, M or mounting column
      EXPECT_LT((H * Ng).cwiseAbs().maxCoeff(), 1e-9 * parts.maxCoeff()) << o.name << layout_name(augmented, antenna);
    }
  }
  for (const Obs& o : all) {
    const Mat H = o.H(x0);
    ASSERT_EQ(H.cols(), N) << o.name;
    Mat Hn(H.rows(), N);
    for (int j = 0; j < N; ++j) {
      Vec dx = Vec::Zero(N);
      const double eps = 0.1 * s(j);
      dx(j) = eps;
      // x+ is the truth with error +ε: z(x̂) − z(x+) = H·(+ε e_j); central: (z(x−) − z(x+))/2ε.
      Hn.col(j) = (o.z(with_error(x0, L, -dx)) - o.z(with_error(x0, L, dx))) / (2 * eps);
    }
    // Scaled by the states' scales and by the observation's own size (its largest entry).
    const double k = (H * S).cwiseAbs().maxCoeff();
    ASSERT_GT(k, 0) << o.name;
    std::vector<std::string> rows;
    for (int i = 0; i < H.rows(); ++i) rows.push_back(std::string(o.name) + "[" + std::to_string(i) + "]");
    expect_close(Hn * S / k, H * S / k, 1e-6, 1e-4, L, std::string("H ") + o.name + layout_name(augmented, antenna), &rows);
  }
}

TEST(InMotionJacobian, ObservationsMatchFiniteDifferencesDefaultLayout) { check_H(false); }
TEST(InMotionJacobian, ObservationsMatchFiniteDifferencesExpCosineLayout) { check_H(true); }
TEST(InMotionJacobian, ObservationsMatchFiniteDifferencesAntennaBlocks) { check_H(true, true); }

}  // namespace
