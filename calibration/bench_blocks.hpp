// Block aggregation of bench data. Within a plan step the model is linear in the reference,
//   measured − reference = b + M·reference + drift + bench error + noise,
// so block means carry all of the information about b and M while cutting 2460 samples/s down
// to one observation per block; the scatter inside the blocks measures the white noise.
#pragma once
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench {

struct BenchBlock {
  int step = -1;
  double t_mid = 0;      // s
  double duration = 0;   // s
  int n = 0;             // samples
  Vec3 gyro = Vec3::Zero(), accel = Vec3::Zero();  // mean measured rate (rad/s), specific force (m/s²)
  Vec3 w = Vec3::Zero(), f = Vec3::Zero();          // mean reference
  double temp_c = std::numeric_limits<double>::quiet_NaN();  // mean temperature (NaN if absent)
  Vec3 gyro_ss = Vec3::Zero(), accel_ss = Vec3::Zero();  // Σ (resid − mean resid)² inside the block
  bool saturated = false;
};

class BenchBlockBuilder {
 public:
  explicit BenchBlockBuilder(double block_s = 1.0) : block_s_(block_s) {}
  // One sample: measured rate and specific force (already rates, not increments), reference
  // at the same instant, plan step (−1 = not part of any step: skipped).
  void add(double t, double dt, const Vec3& gyro, const Vec3& accel, const Vec3& w_ref, const Vec3& f_ref, int step,
           double temp_c = std::numeric_limits<double>::quiet_NaN(), bool saturated = false);
  std::vector<BenchBlock> finish();
  std::size_t samples() const { return samples_; }

 private:
  void close();
  double block_s_;
  std::vector<BenchBlock> blocks_;
  // Open block accumulators (Welford on the residual measured − reference).
  bool open_ = false;
  BenchBlock cur_;
  double t0_ = 0, t_last_ = 0, dt_last_ = 0;
  Vec3 rg_mean_, ra_mean_;
  double temp_sum_ = 0;
  int temp_n_ = 0;
  std::size_t samples_ = 0;
};

}  // namespace calbench
