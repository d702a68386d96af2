// Blocks of the in-motion error state, each declared once (state_blocks.cpp), as open_vins' ov_core
// Type blocks: name, size, SI and display units, series column names, whether the smoother
// corrects it, and its own code — initial covariance, feedback into its nominal value (its slice of
// Nominal::x, or for the navigation and mounting blocks the INS state and C_mb), the motion of that
// value between updates, its role in the sensor model (compensation of the raw increments, its part
// of the transition accumulated over the IMU samples), transition (F) and process noise (Q), extra
// observation columns. The filter
// builds its layout from the blocks the configuration activates (the exp-cosine aux blocks only for
// an exp-cosine drift model, the mounting block unless switched off, blocks declared outside the
// filter's files from InMotionConfig::extra_blocks) and computes the offsets; sizes and offsets
// exist only there (StateLayout), and the filter's sensor correction and transition iterate the
// blocks without naming one.
//
// Order of the built-in blocks = the paper's state order (section IV, eq 11); the exp-cosine aux
// blocks (eqs 35–36) come after the default layout so that the default layout is a prefix of the
// augmented one.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "calibration/filter/block_layout.hpp"

namespace calbench::inmotion {

enum class Block { pos, vel, att, bg, ba, Mg, Ma, mount, dg, da, dg_aux, da_aux, count };

struct InMotionConfig;
struct BlockInit;       // what a block's initial covariance depends on (inmotion_filter.hpp)
struct Nominal;         // the filter's nominal state (inmotion_filter.hpp)
struct BlockDynamics;   // what a block's F and Q depend on over one propagation step
struct BlockObsInput;   // what a block's extra observation columns depend on
struct SensorCorrection;  // the correction of the raw IMU increments (error_model.hpp)
struct ImuSample;         // one IMU interval as the transition sees it (error_model.hpp)
struct DriftModels;       // the in-run drift shaping filters (inmotion_filter.hpp)
using MatRef = Eigen::Ref<Eigen::MatrixXd>;
using VecCRef = Eigen::Ref<const Eigen::VectorXd>;
using Mat3Ref = Eigen::Ref<const Eigen::Matrix3d>;
using Vec3Ref = Eigen::Ref<const Eigen::Vector3d>;
using SumRef = Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>>;

struct BlockSpec {
  Block id;              // built-in: its Block; a block declared elsewhere: any value ≥ Block::count
  const char* name;
  int size;
  const char* const* columns;  // `size` series column names, in state order within the block
  const char* si_unit;         // unit of the estimated error state
  const char* display_unit;    // unit of the series/RESULT columns
  // SI per display unit of the σ columns (e.g. rad/s per °/h): σ shown = σ_SI / si_per_display.
  double si_per_display;
  bool sensor;  // a sensor-error block: the smoother corrects its series value (nav blocks it leaves)
  bool aux;     // only in the augmented (exp-cosine) layout
  // A navigation block (position, velocity, attitude: NED errors): turned with the heading at a
  // re-alignment, widened when the filter has lost track.
  bool navigation = false;
  // Is the block in the layout for this configuration? nullptr: always.
  bool (*active)(const InMotionConfig& cfg) = nullptr;
  // Initial covariance: its rows/columns of P (P zero before; blocks are set in layout order).
  void (*init)(const BlockInit& in, const filter::BlockLayout& L, int off, MatRef P) = nullptr;
  // Feedback of the estimated error dx (the whole state; the block reads its segment at off):
  // nominal ← nominal − dx.
  void (*feedback)(Nominal& n, int off, const VecCRef& dx) = nullptr;
  // The motion of its nominal value between updates over T seconds (x̂ ← Φ·x̂ of its shaping
  // filter: the in-run drifts and the exp-cosine first states), or nullptr (held).
  void (*predict)(const DriftModels& drift, const filter::BlockLayout& L, int off, Nominal& n, double T) = nullptr;
  // Its role in the sensor model, y = (I + M)·true + b + d (error_model.hpp): its part of the
  // correction of the raw increments from its nominal value (an additive offset b̂ or d̂, or the
  // A = (I + M̂)⁻¹ of a sensor), or nullptr.
  void (*compensate)(const Nominal& n, int off, SensorCorrection& c) = nullptr;
  // Its part of the transition over one IMU interval: adds to its own columns of the accumulator
  // (3 rows: the navigation rows its error feeds, `size` columns) what dynamics reads back as the
  // interval's mean, or nullptr. Contract: a sensor S's block writes −C·∂x̂_S/∂δx·dt from s.CA[S]
  // and s.x[S] only (x̂_S the corrected output), nothing from the other sensor's fields; set_body_rate
  // (observation.hpp) reads the gyro blocks' columns of one sample with the accelerometer's zero.
  void (*accumulate)(const ImuSample& s, SumRef sum) = nullptr;
  // Its entries of F (continuous time) and Q (discrete, over the step) for one propagation step.
  void (*dynamics)(const BlockDynamics& d, const filter::BlockLayout& L, int off, MatRef F, MatRef Q) = nullptr;
  // Its part of an observation (type 0 position, 1 velocity, 2 attitude; eqs 13–15 in the obs_*.cpp
  // files write the navigation and mounting parts): its columns of H, and what its nominal value
  // adds to the predicted reference (z = predicted − reference), or nullptr.
  void (*observe)(const BlockObsInput& o, const Nominal& n, int type, int off, MatRef H, Eigen::Vector3d& z) = nullptr;
  // The series value of the block's states in SI (`size` values), and their display factor for
  // the series (value shown = SI / factor per column; nullptr: si_per_display for every column).
  void (*total)(const Nominal& n, int off, double* x) = nullptr;
  const double* total_per_display = nullptr;
  // When the filter sets the MEMS position from a reference epoch (start from a reference INS,
  // heading re-alignment): the block's part of the MEMS position, MEMS = fix + C_nb·lever + A·x̂
  // (A: 3 × size, NED, at attitude C_nb and velocity v), so that the position error starts as
  // A·δx (correlated with the block), or nullptr.
  void (*position_offset)(const Nominal& n, const Mat3Ref& C_nb, const Vec3Ref& v, int off, Eigen::MatrixXd& A) = nullptr;
};

// The built-in declarations (state_blocks.cpp); index = static_cast<int>(Block).
const std::array<BlockSpec, static_cast<std::size_t>(Block::count)>& block_specs();

// The optional antenna blocks (antenna_blocks.cpp, issue 34 item 4): the GNSS antenna's lever-arm
// correction ℓ (3 states, m) and the IMU–GNSS time offset δt (1 state, s), active by
// InMotionConfig::estimate_lever_arm / estimate_time_offset, after the built-in blocks and before
// the extra ones. Their ids follow the built-in ones.
inline constexpr Block kLeverArmBlock = static_cast<Block>(static_cast<int>(Block::count));
inline constexpr Block kTimeOffsetBlock = static_cast<Block>(static_cast<int>(Block::count) + 1);
const std::array<BlockSpec, 2>& antenna_blocks();

// The layout of a configuration: the active built-in blocks in declaration order, then the extra
// ones; `specs` in layout order.
struct StateLayout {
  filter::BlockLayout L;
  std::vector<const BlockSpec*> specs;
  int offset(Block b) const { return L.offset(static_cast<int>(b)); }
  int size() const { return L.size(); }
};
StateLayout make_layout(const InMotionConfig& cfg);
// The correction of the raw increments by the layout's blocks (BlockSpec::compensate, in layout
// order) at the nominal state n.
SensorCorrection sensor_correction(const StateLayout& s, const Nominal& n);
// Every active block's observation part (BlockSpec::observe) of one observation type, in layout order.
void observe_blocks(const StateLayout& s, const BlockObsInput& o, const Nominal& n, int type, MatRef H, Eigen::Vector3d& z);
// Series column names of a layout's states, in state order (the blocks' declarations).
std::vector<std::string> column_names(const StateLayout& s);
// The one place where SI becomes series units (°/h, mg, ppm, deg; latitude and longitude in
// degrees): every state's value and σ (InMotionFilter::state_si), in place, by the declarations.
void series_display(const StateLayout& s, Eigen::VectorXd& x, Eigen::VectorXd& sigma);
// Total drift b + d per axis in series units (gyro °/h, accel mg): the sum of the two series
// columns x_series (already displayed) and the SI σ (InMotionFilter::total_drift_si) converted.
void series_total_drift(const StateLayout& s, const Eigen::VectorXd& x_series, const Eigen::Matrix<double, 6, 1>& sigma_si,
                        Eigen::Matrix<double, 6, 1>& x, Eigen::Matrix<double, 6, 1>& sigma);

}  // namespace calbench::inmotion
