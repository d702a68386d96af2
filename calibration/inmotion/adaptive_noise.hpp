// Adaptive process noise of the in-motion filter by covariance matching of the innovations
// (innovation-based adaptive estimation): Mehra, "Approaches to adaptive filtering", IEEE Trans.
// Automatic Control 17(5), 1972; Mohamed & Schwarz, "Adaptive Kalman filtering for INS/GPS",
// Journal of Geodesy 73, 1999; in the scale-factor form for GNSS/INS of Ding, Wang, Rizos &
// Kinlyside, "Improving adaptive Kalman estimation in GPS/INS integration", Journal of Navigation
// 60(3), 2007 (docs/in-motion.md, "Adaptive process noise and the robust gate").
//
// The filter predicts each innovation's covariance S = H·P⁻·Hᵀ + R. Over a block of epochs of one
// observation type (10 s; blocks do not overlap, so each innovation is tested once) the
// innovations' actual power Σ νᵀν is compared with the predicted Σ tr S; when the block's Σ NIS lies
// beyond the upper χ² quantile of its degrees of freedom (p = 1e-5; and at every epoch from the 10th
// on beyond the quantile at p = 1e-7, so that a block far off is decided at once; about 2e-5 per
// block of 100 epochs, a false alarm in about one of 70 one-hour drives with two observation types
// at 10 Hz: the filter is inconsistent, not unlucky), the part of S the process noise feeds,
// H·P⁻·Hᵀ, is scaled so that the predicted power matches the actual (covariance matching):
//     s = (Σ νᵀν − Σ tr R) / Σ tr(H·P⁻·Hᵀ),   q ← q·min(s, Σ NIS / dof)   (bounded, q ≥ 1):
// at most the block's NIS ratio per increase, since where R dominates S a modest excess (fixes
// whose σ is optimistic) would read as a large factor on the IMU's noise,
// where q multiplies the white-noise densities (squared) that drive the navigation states (ARW on
// the attitude, VRW on velocity and position, and the sampling-time noise, sample_timing.hpp).
// Each increase rests on a new block's evidence: an increase closes every type's open block, so
// that innovations predicted under the old q never raise it again (before, the position and the
// velocity blocks of the same seconds each multiplied q, and a block opened before an increase
// raised it once more: the real walk went ×10, ×38, ×36, ×3.8, ×6.8 in 5 s, to 3.8·10⁵, on blocks
// whose mean NIS per degree of freedom was 1.7–5.9).
// Healing: a block whose mean NIS is at or below its expectation lowers q by the same covariance
// matching, q ← q·max(s, 0.1) (at least ×0.8, at most ×0.1 per block; q ≥ 1), so q comes back
// down as soon as the innovations are consistent again instead of creeping back with a slow time
// constant. On innovations consistent with the model q stays 1 and the filter is the
// non-adaptive one, bit for bit.
//
// A scale far above 1 means the model lacks something; above kFailScale at the end of a fit the
// filter followed the fixes with the IMU scaled away: fit drive says so and the approval refuses
// the set (docs/in-motion.md, "Adaptive process noise and the robust gate").
//
// Gate-rejected innovations (outliers by the single-epoch gate) enter the block with their NIS
// and power capped at the gate: one outlier moves nothing, a run of rejections (a filter that
// is wrong, not a fix that is) raises q until the innovations pass the gate again. The filter's
// former last resort, the widening of the navigation covariance after a run of rejections,
// therefore stays a last resort (docs/in-motion.md).
#pragma once
#include <deque>
#include <vector>

namespace calbench::inmotion {

struct AdaptiveNoiseConfig {
  // Off unless asked: `fit drive --adaptive auto` turns it on with GNSS aiding; in-memory users of
  // the filter (tests, benchmarks, diagnose) get the non-adaptive filter.
  bool enabled = false;
  int min_epochs = 5;        // a block is tested when it holds this many innovations
  double window_s = 10;      // and spans this long (blocks do not overlap)
  double z_trigger = 4.264891;  // standard normal quantile of the χ² test at a block's end (p = 1e-5)
  double z_early = 5.199338;    // the same at every epoch within a block (p = 1e-7 per test)
  int min_epochs_early = 10;    // from this many innovations on (one outlier capped at the gate
                                // among them stays below that quantile)
  double max_step = 100;     // largest factor of one increase
  double max_scale = 1e6;    // largest q (variance scale; ×1000 on the noise densities)
  double min_step_down = 0.1;  // largest decrease of one consistent block (q ← q·max(s, this))
  double max_step_down = 0.8;  // smallest decrease of one consistent block
};

// One observation type's innovations, as the adaptation sees them.
struct AdaptiveSample {
  double t = 0;
  double nis = 0;   // νᵀS⁻¹ν (capped at the gate for a rejected epoch)
  int dof = 3;
  double nu2 = 0;   // νᵀν (scaled like the NIS when capped)
  double trR = 0;   // tr R
  double trHPH = 0; // tr(H·P⁻·Hᵀ)
  // The motion at the epoch, for reporting where the noise was raised (no part in the rule).
  double speed = 0, turn_rate = 0, accel = 0;  // m/s, rad/s (about the vertical), m/s² (horizontal)
};

// One change of q: when, on which observation type's block, from what to what, and that block's
// mean NIS per degree of freedom.
struct AdaptiveEvent {
  double t = 0;
  int type = 0;
  double q_from = 1, q_to = 1, nis_per_dof = 0;
  // The block's motion: mean speed (m/s), mean |turn rate| (rad/s), mean horizontal |acceleration|
  // (m/s²) over its epochs (issue 53, item 5: where the innovations grow).
  double speed = 0, turn_rate = 0, accel = 0;
};

class AdaptiveNoise {
 public:
  // A scale above this at the end of a fit: the IMU was scaled away (σ ×3.2 on every density).
  static constexpr double kFailScale = 10;
  explicit AdaptiveNoise(const AdaptiveNoiseConfig& cfg = {}) : cfg_(cfg) {}
  // One innovation of observation type `type` (0..kTypes−1). Returns true when q changed.
  bool add(int type, const AdaptiveSample& s);
  double scale() const { return q_; }
  double max_scale_reached() const { return q_max_; }
  long increases() const { return increases_; }
  long decreases() const { return decreases_; }
  // Every change of q, in time order (at most a few per minute: each needs a full block).
  const std::vector<AdaptiveEvent>& events() const { return events_; }
  // The start of the current stretch above kFailScale: the increase that crossed it (nullptr when
  // q is at or below it now).
  const AdaptiveEvent* above_fail_since() const;
  static constexpr int kTypes = 8;

 private:
  struct Window;
  bool raise(const Window& b, int type);
  bool lower(const Window& b, int type);
  static AdaptiveEvent event(const Window& b, int type, double from, double to);
  void close_all_blocks();
  struct Window {
    std::deque<AdaptiveSample> s;
    double nis = 0, nu2 = 0, trR = 0, trHPH = 0, speed = 0, turn = 0, accel = 0;
    int dof = 0;
    void push(const AdaptiveSample& x);
    void clear() { *this = Window{}; }
  };
  AdaptiveNoiseConfig cfg_;
  Window w_[kTypes];
  double q_ = 1, q_max_ = 1;
  long increases_ = 0, decreases_ = 0;
  std::vector<AdaptiveEvent> events_;
};

}  // namespace calbench::inmotion
