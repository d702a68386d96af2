// Data of a bench recording as `diagnose` needs it: short sub-blocks (default 0.05 s) that keep
// what happens within a revolution of the table (angle, rate and specific-force derivatives), and
// the ~1 s parent blocks they belong to (the level at which slow effects and drift are judged).
// Only samples inside plan steps (step ≥ 0) are kept; the rows between steps (step −1) serve only
// to find the direction of the table axis whose angle the recording gives (inner_axis below).
#pragma once
#include <limits>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench {

struct DiagSample {
  double t = 0, dt = 0;
  Vec3 gyro = Vec3::Zero(), accel = Vec3::Zero();  // measured rates (rad/s, m/s²)
  Vec3 w = Vec3::Zero(), f = Vec3::Zero();          // reference
  int step = -1;
  double temp_c = std::numeric_limits<double>::quiet_NaN();
  double angle_deg = std::numeric_limits<double>::quiet_NaN();  // inner-axis angle, if recorded
};

struct SubBlock {
  int step = -1, parent = -1;
  double t_mid = 0, duration = 0;
  int n = 0;
  Vec3 gyro = Vec3::Zero(), accel = Vec3::Zero(), w = Vec3::Zero(), f = Vec3::Zero();  // means
  Vec3 dw = Vec3::Zero(), df = Vec3::Zero();  // reference derivatives over the sub-block (1/s)
  double temp_c = std::numeric_limits<double>::quiet_NaN();
  double dtemp = 0;  // dT/dt (K/s): that of the parent block (smoothed, see ParentBlock)
  double angle = std::numeric_limits<double>::quiet_NaN();  // rad, middle of the sub-block
  double angle_rate = 0;                                      // rad/s from the angle column
  Vec3 gyro_ss = Vec3::Zero(), accel_ss = Vec3::Zero();       // Σ (resid − mean)² inside
  // Unit vector, in IMU axes, of the table axis whose angle is in the angle column, signed so that
  // an increasing angle is a positive rotation about it; zero when the recording does not tell.
  // Derived per gap-free stretch of the recording (a remount interrupts it) from the rows, steps
  // and transitions alike, where only that axis turns: there the reference rate is ω = θ̇·u (plus
  // the Earth rate), so u ∝ Σ ω·Δθ; the stretch's rows must agree (else zero). Known in static
  // steps too (from the slews and rate steps of the same mounting), where the table angle error
  // of table_wobble turns gravity and the Earth rate about it.
  Vec3 inner_axis = Vec3::Zero();
  bool rotating() const { return w.norm() > 0.0174533; }      // |ω| > 1 °/s
};

struct ParentBlock {
  int step = -1;
  int first = 0, count = 0;  // sub-blocks [first, first + count)
  double t_mid = 0, duration = 0;
  int n = 0;
  double temp_c = std::numeric_limits<double>::quiet_NaN();
  double dtemp = 0;          // dT/dt (K/s), from neighbouring blocks
  Vec3 w = Vec3::Zero(), f = Vec3::Zero();
};

struct DiagData {
  std::vector<SubBlock> subs;
  std::vector<ParentBlock> parents;
  double sample_rate_hz = 0;
  bool has_temperature = false, has_angle = false;
  // Per gap-free stretch (see SubBlock::inner_axis): the derived axis (zero if not known).
  std::vector<Vec3> stretch_axes;
};

class DiagDataBuilder {
 public:
  // max_parents > 0: longer parents when the data would give more than that many (long thermal
  // runs; the diagnosis keeps a dense parent covariance per axis).
  explicit DiagDataBuilder(double sub_s = 0.05, double parent_s = 1.0, int max_parents = 0)
      : sub_s_(sub_s), parent_s_(parent_s), max_parents_(max_parents) {}
  void add(const DiagSample& s);
  DiagData finish();

 private:
  void close_sub();
  void track_axis(const DiagSample& s, bool gap);
  double sub_s_, parent_s_;
  int max_parents_ = 0;
  DiagData d_;
  bool open_ = false;
  SubBlock cur_;
  double t0_ = 0, t_last_ = 0, dt_last_ = 0, a0_ = 0, a_first_ = 0, a_last_ = 0, t_first_ = 0;
  Vec3 w_first_, f_first_, w_last_, f_last_, rg_, ra_;
  double temp_sum_ = 0, ang_sum_ = 0, rate_sum_ = 0;
  int temp_n_ = 0, ang_n_ = 0;
  std::size_t samples_ = 0;
  // Axis of the angle column per gap-free stretch. Rows are summed into chunks of ≥ 0.05 s (an
  // encoder's quantisation averages out); a chunk where only that axis turns (|ω| = |θ̇| within
  // 0.2 %, |θ̇| > 5 °/s) adds Σ ω·Δθ, Σ |ω|·|Δθ|, Σ |Δθ| to its stretch.
  struct Stretch {
    Vec3 w_dth = Vec3::Zero();
    double w_abs_dth = 0, turn = 0;
  };
  std::vector<Stretch> stretches_;
  std::vector<int> sub_stretch_;
  bool have_prev_ = false;
  double prev_t_ = 0, prev_angle_ = std::numeric_limits<double>::quiet_NaN();
  Vec3 prev_w_ = Vec3::Zero();
  Vec3 ch_wh_ = Vec3::Zero();
  double ch_dth_ = 0, ch_h_ = 0;
};

}  // namespace calbench
