// What an IMU on the two-axis table experiences (nominal bench model: IMU at the centre of
// rotation, table axes exact). Shared by the bench simulator, the IMU emulator and the estimators.
#pragma once
#include "calibration/bench_plan.hpp"
#include "calibration/earth.hpp"
#include "common/table_motion.hpp"

namespace calbench {

struct BenchKinematics {
  Mat3 C_b_l;     // IMU axes -> local level (NED)
  Vec3 w_ib_b;    // angular rate of the IMU w.r.t. inertial space, IMU axes (rad/s)
  Vec3 f_b;       // specific force, IMU axes (m/s²)
};

// From the two axes' states (angle, rate) and the cube mount.
BenchKinematics bench_kinematics(const SiteEarth& earth, const AxisState& outer, const AxisState& inner, int mount);

}  // namespace calbench
