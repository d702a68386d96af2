// The declarations of the in-motion filter's built-in blocks (state_blocks.hpp): per block its
// names and units, and its own code — initial covariance, feedback, sensor-model role (compensate,
// accumulate), F and Q, series value.
// Adding a block is one declaration like these (and its Jacobian in error_model.cpp when it is
// more than a line), here or, for a block the filter does not ship, in InMotionConfig::extra_blocks.
#include "calibration/inmotion/state_blocks.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"

namespace calbench::inmotion {

namespace {
using namespace units;

// Series columns: totals (estimate, not error) in display units.
const char* const kPosCols[] = {"lat_deg", "lon_deg", "h_m"};  // MEMS IMU position
const char* const kVelCols[] = {"vel_n_m_s", "vel_e_m_s", "vel_d_m_s"};
const char* const kAttCols[] = {"roll_deg", "pitch_deg", "yaw_deg"};
const char* const kBgCols[] = {"gyro_bias_x_dph", "gyro_bias_y_dph", "gyro_bias_z_dph"};
const char* const kBaCols[] = {"accel_bias_x_mg", "accel_bias_y_mg", "accel_bias_z_mg"};
const char* const kMgCols[] = {"gyro_M_xx_ppm", "gyro_M_xy_ppm", "gyro_M_xz_ppm", "gyro_M_yx_ppm", "gyro_M_yy_ppm",
                               "gyro_M_yz_ppm", "gyro_M_zx_ppm", "gyro_M_zy_ppm", "gyro_M_zz_ppm"};
const char* const kMaCols[] = {"accel_M_xx_ppm", "accel_M_xy_ppm", "accel_M_xz_ppm", "accel_M_yx_ppm", "accel_M_yy_ppm",
                               "accel_M_yz_ppm", "accel_M_zx_ppm", "accel_M_zy_ppm", "accel_M_zz_ppm"};
const char* const kMountCols[] = {"mount_roll_deg", "mount_pitch_deg", "mount_yaw_deg"};
const char* const kDgCols[] = {"gyro_drift_x_dph", "gyro_drift_y_dph", "gyro_drift_z_dph"};
const char* const kDaCols[] = {"accel_drift_x_mg", "accel_drift_y_mg", "accel_drift_z_mg"};
const char* const kDgAuxCols[] = {"gyro_drift_aux_x_dph_s", "gyro_drift_aux_y_dph_s", "gyro_drift_aux_z_dph_s"};
const char* const kDaAuxCols[] = {"accel_drift_aux_x_mg_s", "accel_drift_aux_y_mg_s", "accel_drift_aux_z_mg_s"};
// Series factors of blocks whose columns differ: latitude/longitude in degrees, height in metres.
const double kPosFactors[] = {kDeg, kDeg, 1.0};

void diag(MatRef P, int off, int n, double sigma) {
  for (int i = 0; i < n; ++i) P(off + i, off + i) = sigma * sigma;
}
void put3(const Vec3& v, double* x) {
  for (int i = 0; i < 3; ++i) x[i] = v(i);
}

// ---- navigation: position (eq 11's δr), velocity (δv), attitude (φ). Their F rows are one
// equation family (error_model.cpp nav_block), written by the position block.
BlockSpec pos_block() {
  BlockSpec b{Block::pos, "position", 3, kPosCols, "m (NED)", "deg, deg, m", 1.0, false, false, true};
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) { diag(P, off, 3, std::hypot(in.sp, 0.05)); };
  b.feedback = [](Nominal& n, int off, const VecCRef& dx) {
    ins::geodetic_add_ned(n.nav->lat, n.nav->lon, n.nav->h, -dx.segment<3>(off));
  };
  b.dynamics = [](const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F, MatRef Q) {
    nav_block(d.nav, off, L.offset(static_cast<int>(Block::vel)), L.offset(static_cast<int>(Block::att)), F);
    const double qa = d.cfg.noise.accel.white_density;
    for (int i = 0; i < 3; ++i) Q(off + i, off + i) = qa * qa * d.T * d.T * d.T / 3.0 * d.q_nav;
  };
  b.total = [](const Nominal& n, int, double* x) {
    x[0] = n.nav->lat;
    x[1] = n.nav->lon;
    x[2] = n.nav->h;
  };
  b.total_per_display = kPosFactors;
  return b;
}

BlockSpec vel_block() {
  BlockSpec b{Block::vel, "velocity", 3, kVelCols, "m/s (NED)", "m/s", 1.0, false, false, true};
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    diag(P, off, 3, std::hypot(in.sv, in.cfg.sigma_vel0));
  };
  b.feedback = [](Nominal& n, int off, const VecCRef& dx) { n.nav->v -= dx.segment<3>(off); };
  b.dynamics = [](const BlockDynamics& d, const filter::BlockLayout&, int off, MatRef, MatRef Q) {
    const double qa = d.cfg.noise.accel.white_density;
    for (int i = 0; i < 3; ++i) Q(off + i, off + i) = qa * qa * d.T * d.q_nav;
    const double st = d.cfg.sample_time_sigma;  // sampling-time noise (identification/sample_timing.hpp)
    if (st > 0) Q.block<3, 3>(off, off) += st * st * d.q_nav * d.acc.jump_f;
  };
  b.total = [](const Nominal& n, int, double* x) { put3(n.nav->v, x); };
  return b;
}

BlockSpec att_block() {
  BlockSpec b{Block::att, "attitude", 3, kAttCols, "rad", "deg", kDeg, false, false, true};
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    if (in.first.has_att) {
      P.block<3, 3>(off, off) = Mat3::Identity() * (in.sa * in.sa);  // the mounting block adds its part
    } else {
      // A GNSS fix: no attitude. The MEMS is levelled from its own specific force (tilt error =
      // horizontal accelerometer bias / g, independent of the mounting); the heading is unknown
      // (a placeholder 1 rad σ, re-initialised by the course over ground).
      const double tilt = std::max(in.cfg.prior.accel_bias.maxCoeff(), 1e-3) / 9.8;
      P.block<3, 3>(off, off) = Vec3(tilt * tilt, tilt * tilt, 1.0).asDiagonal();
    }
  };
  b.feedback = [](Nominal& n, int off, const VecCRef& dx) {
    n.nav->q_nb = ins::quat_from_rotvec(dx.segment<3>(off)) * n.nav->q_nb;
    n.nav->q_nb.normalize();
  };
  b.dynamics = [](const BlockDynamics& d, const filter::BlockLayout&, int off, MatRef, MatRef Q) {
    const double qg = d.cfg.noise.gyro.white_density;
    for (int i = 0; i < 3; ++i) Q(off + i, off + i) = qg * qg * d.T * d.q_nav;
    const double st = d.cfg.sample_time_sigma;
    if (st > 0) Q.block<3, 3>(off, off) += st * st * d.q_nav * d.acc.jump_w;
  };
  b.total = [](const Nominal& n, int, double* x) { put3(ins::rpy_from_dcm(n.nav->C_nb()), x); };
  return b;
}

// ---- sensor model: constant parts of the drift/bias and M (identity transition, no noise).
// S: the sensor (kGyro, kAccel). The head of a per-sensor 3-state block in the sensor's units (gyro
// rad/s shown in °/h, accelerometer m/s² in mg).
template <int S>
BlockSpec sensor_triad(Block g, Block a, const char* gname, const char* aname, const char* const* gcols,
                       const char* const* acols) {
  return BlockSpec{S == 0 ? g : a, S == 0 ? gname : aname, 3, S == 0 ? gcols : acols, S == 0 ? "rad/s" : "m/s^2",
                   S == 0 ? "deg/h" : "mg", S == 0 ? kDegPerHour : kMilliG, true, false};
}

// The navigation rows a sensor's error feeds (error_model.hpp): gyro → attitude, accelerometer → velocity.
int sensor_rows(const filter::BlockLayout& L, int S) { return L.offset(static_cast<int>(S == kGyro ? Block::att : Block::vel)); }

// An additive error of sensor S (bias, in-run drift): its transition columns are C·A, summed over the
// interval; its columns of F are their mean (signed by the sensor, sensor_jacobian).
template <int S>
void offset_accumulate(const ImuSample& s, SumRef sum) {
  sum += s.CA[S];
}
template <int S>
void offset_dynamics(const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F) {
  sensor_jacobian(d.acc, S, sensor_rows(L, S), off, 3, F);
}

template <int S>
BlockSpec bias_block() {
  BlockSpec b = sensor_triad<S>(Block::bg, Block::ba, "gyro_bias", "accel_bias", kBgCols, kBaCols);
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    const Vec3& p = S == 0 ? in.cfg.prior.gyro_bias : in.cfg.prior.accel_bias;
    for (int i = 0; i < 3; ++i) P(off + i, off + i) = p(i) * p(i);
  };
  b.feedback = additive_feedback<3>;
  b.compensate = [](const Nominal& n, int off, SensorCorrection& c) { c.offset[S] += n.vec3(off); };
  b.accumulate = offset_accumulate<S>;
  b.dynamics = [](const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F, MatRef) { offset_dynamics<S>(d, L, off, F); };
  b.total = slice_total<3>;
  return b;
}

template <int S>
BlockSpec m_block() {
  BlockSpec b{S == 0 ? Block::Mg : Block::Ma, S == 0 ? "gyro_M" : "accel_M", 9, S == 0 ? kMgCols : kMaCols, "1", "ppm", kPpm,
              true, false};
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    const Mat3& p = S == 0 ? in.cfg.prior.gyro_M : in.cfg.prior.accel_M;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) P(off + 3 * i + j, off + 3 * i + j) = p(i, j) * p(i, j);
  };
  b.feedback = additive_feedback<9>;  // M row by row
  b.compensate = [](const Nominal& n, int off, SensorCorrection& c) { c.A[S] = (Mat3::Identity() + n.mat3(off)).inverse(); };
  // (C A) W(x), W(x) = ∂(δM·x)/∂vec(δM): column block i is (C A)(:, i)·xᵀ.
  b.accumulate = [](const ImuSample& s, SumRef sum) {
    for (int i = 0; i < 3; ++i) sum.block<3, 3>(0, 3 * i) += s.CA[S].col(i) * s.x[S].transpose();
  };
  b.dynamics = [](const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F, MatRef) {
    sensor_jacobian(d.acc, S, sensor_rows(L, S), off, 9, F);
  };
  b.total = slice_total<9>;
  return b;
}

// ---- mounting misalignment δμ (reference body axes): Ĉ_mb = (I − δμ×)·C_mb. Its H columns are
// part of eqs 13–15 (obs_*.cpp).
BlockSpec mount_block() {
  BlockSpec b{Block::mount, "mounting", 3, kMountCols, "rad", "deg", kDeg, false, false};
  b.active = [](const InMotionConfig& cfg) { return cfg.mounting; };
  b.init = [](const BlockInit& in, const filter::BlockLayout& L, int off, MatRef P) {
    const ParameterPriors& pr = in.cfg.prior;
    const Mat3 Pm = pr.mount.cwiseProduct(pr.mount).asDiagonal();
    P.block<3, 3>(off, off) = Pm;
    if (!in.first.has_att) return;  // a GNSS start levels the MEMS itself: no correlation
    // The initial MEMS attitude error is the mounting error seen in NED plus the reference's own:
    // φ₀ = C_nb·δμ + ε_ref, so the two blocks start correlated.
    const int att = L.offset(static_cast<int>(Block::att));
    P.block<3, 3>(att, att) = in.C_nb * Pm * in.C_nb.transpose() + P.block<3, 3>(att, att);
    P.block<3, 3>(att, off) = in.C_nb * Pm;
    P.block<3, 3>(off, att) = (in.C_nb * Pm).transpose();
  };
  b.feedback = [](Nominal& n, int off, const VecCRef& dx) {
    n.C_mb = ins::quat_from_rotvec(dx.segment<3>(off)).toRotationMatrix() * n.C_mb;
  };
  b.total = [](const Nominal& n, int, double* x) { put3(ins::rpy_from_dcm(n.C_mb), x); };
  return b;
}

// ---- in-run drifts (eq 22 shaping filters; exp-cosine second states, eqs 35–36).
template <int S>
BlockSpec drift_block() {
  BlockSpec b = sensor_triad<S>(Block::dg, Block::da, "gyro_drift", "accel_drift", kDgCols, kDaCols);
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    const Vec3& sig = S == 0 ? in.drift.sig_g : in.drift.sig_a;
    for (int i = 0; i < 3; ++i) P(off + i, off + i) = sig(i) * sig(i);
  };
  b.feedback = additive_feedback<3>;
  // The drift enters the sensor model as the bias does.
  b.compensate = [](const Nominal& n, int off, SensorCorrection& c) { c.offset[S] += n.vec3(off); };
  b.accumulate = offset_accumulate<S>;
  b.dynamics = [](const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F, MatRef Q) {
    offset_dynamics<S>(d, L, off, F);
    const Vec3& alpha = S == 0 ? d.drift.alpha_g : d.drift.alpha_a;
    const Vec3& sig = S == 0 ? d.drift.sig_g : d.drift.sig_a;
    drift_jacobian(alpha, off, F);
    for (int i = 0; i < 3; ++i) Q(off + i, off + i) = sig(i) * sig(i) * (1.0 - std::exp(-2.0 * alpha(i) * d.T));
  };
  // A first-order axis decays, d̂ ← e^{−αT}·d̂; an exp-cosine axis moves with its first state (the aux block).
  b.predict = [](const DriftModels& drift, const filter::BlockLayout&, int off, Nominal& n, double T) {
    const Vec3& alpha = S == 0 ? drift.alpha_g : drift.alpha_a;
    for (int i = 0; i < 3; ++i)
      if (!drift.expcos[3 * S + i]) n.x(off + i) *= std::exp(-alpha(i) * T);
  };
  b.total = slice_total<3>;
  return b;
}

// Exp-cosine first states Δμ (eqs 35–36) of the axes that carry that model; the 2×2 of (aux,
// drift) replaces the first-order entries of the drift block (set before it in layout order).
template <int S>
void aux_init(const BlockInit& in, const filter::BlockLayout& L, int off, MatRef P) {
  const int drift = L.offset(static_cast<int>(S == 0 ? Block::dg : Block::da));
  for (int i = 0; i < 3; ++i) {
    const int k = 3 * S + i;
    if (!in.drift.expcos[k]) continue;
    const int idx[2] = {off + i, drift + i};  // stationary covariance P∞ of (x[0], x[1])
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) P(idx[r], idx[c]) = in.drift.sf[k].P_inf(r, c);
  }
}
template <int S>
void aux_dynamics(const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F, MatRef Q) {
  const int drift = L.offset(static_cast<int>(S == 0 ? Block::dg : Block::da));
  for (int i = 0; i < 3; ++i) {
    const int k = 3 * S + i;
    if (!d.drift.expcos[k]) continue;
    expcos_drift_block(d.drift.sf[k], off + i, drift + i, F);
    expcos_drift_noise(d.drift.discrete(k, d.T), off + i, drift + i, Q);
  }
}

// (x[0], x[1]) ← Φ·(x[0], x[1]) of the exp-cosine axes: this block's first states and the drift's.
template <int S>
void aux_predict(const DriftModels& drift, const filter::BlockLayout& L, int off, Nominal& n, double T) {
  const int d = L.offset(static_cast<int>(S == 0 ? Block::dg : Block::da));
  for (int i = 0; i < 3; ++i) {
    const int k = 3 * S + i;
    if (!drift.expcos[k]) continue;
    const Eigen::Vector2d x = drift.discrete(k, T).Phi * Eigen::Vector2d(n.x(off + i), n.x(d + i));
    n.x(off + i) = x(0);
    n.x(d + i) = x(1);
  }
}

BlockSpec aux_block(Block id) {
  const bool g = id == Block::dg_aux;
  BlockSpec b{id, g ? "gyro_drift_aux" : "accel_drift_aux", 3, g ? kDgAuxCols : kDaAuxCols, g ? "rad/s^2" : "m/s^3",
              g ? "deg/h/s" : "mg/s", g ? kDegPerHour : kMilliG, true, true};
  b.active = [](const InMotionConfig& cfg) { return needs_augmented_layout(cfg); };
  b.init = g ? aux_init<0> : aux_init<1>;
  b.dynamics = g ? aux_dynamics<0> : aux_dynamics<1>;
  b.predict = g ? aux_predict<0> : aux_predict<1>;
  b.feedback = additive_feedback<3>;
  b.total = slice_total<3>;
  return b;
}

}  // namespace

const std::array<BlockSpec, static_cast<std::size_t>(Block::count)>& block_specs() {
  static const std::array<BlockSpec, static_cast<std::size_t>(Block::count)> specs = {{
      pos_block(),
      vel_block(),
      att_block(),
      bias_block<0>(),
      bias_block<1>(),
      m_block<0>(),
      m_block<1>(),
      mount_block(),
      drift_block<0>(),
      drift_block<1>(),
      aux_block(Block::dg_aux),
      aux_block(Block::da_aux),
  }};
  return specs;
}

StateLayout make_layout(const InMotionConfig& cfg) {
  StateLayout s;
  for (const BlockSpec& b : block_specs())
    if (!b.active || b.active(cfg)) {
      s.L.add(static_cast<int>(b.id), b.size);
      s.specs.push_back(&b);
    }
  for (const BlockSpec& b : antenna_blocks())
    if (b.active(cfg)) {
      s.L.add(static_cast<int>(b.id), b.size);
      s.specs.push_back(&b);
    }
  for (const BlockSpec& b : cfg.extra_blocks) {
    if (static_cast<int>(b.id) < static_cast<int>(Block::count) + static_cast<int>(antenna_blocks().size()))
      throw std::invalid_argument(std::string("in-motion filter: the extra block '") + b.name + "' has a built-in id");
    if (!b.active || b.active(cfg)) {
      s.L.add(static_cast<int>(b.id), b.size);
      s.specs.push_back(&b);
    }
  }
  return s;
}

SensorCorrection sensor_correction(const StateLayout& s, const Nominal& n) {
  SensorCorrection c;
  for (const BlockSpec* b : s.specs)
    if (b->compensate) b->compensate(n, s.L.offset(static_cast<int>(b->id)), c);
  return c;
}

void observe_blocks(const StateLayout& s, const BlockObsInput& o, const Nominal& n, int type, MatRef H, Eigen::Vector3d& z) {
  for (const BlockSpec* b : s.specs)
    if (b->observe) b->observe(o, n, type, s.L.offset(static_cast<int>(b->id)), H, z);
}

void series_display(const StateLayout& s, Eigen::VectorXd& x, Eigen::VectorXd& sigma) {
  for (const BlockSpec* b : s.specs) {
    const int o = s.L.offset(static_cast<int>(b->id));
    for (int i = 0; i < b->size; ++i) {
      x(o + i) /= b->total_per_display ? b->total_per_display[i] : b->si_per_display;
      sigma(o + i) /= b->si_per_display;
    }
  }
}

void series_total_drift(const StateLayout& s, const Eigen::VectorXd& x_series, const Eigen::Matrix<double, 6, 1>& sigma_si,
                        Eigen::Matrix<double, 6, 1>& x, Eigen::Matrix<double, 6, 1>& sigma) {
  const int bg = s.offset(Block::bg), ba = s.offset(Block::ba), dg = s.offset(Block::dg), da = s.offset(Block::da);
  for (int k = 0; k < 6; ++k) {
    x(k) = k < 3 ? x_series(bg + k) + x_series(dg + k) : x_series(ba + k - 3) + x_series(da + k - 3);
    sigma(k) = sigma_si(k) / (k < 3 ? kDegPerHour : kMilliG);
  }
}

std::vector<std::string> column_names(const StateLayout& s) {
  std::vector<std::string> n;
  for (const BlockSpec* b : s.specs)
    for (int i = 0; i < b->size; ++i) n.push_back(b->columns[i]);
  return n;
}

}  // namespace calbench::inmotion
