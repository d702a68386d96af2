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
  Vec3 dw_ib_b;   // angular acceleration, IMU axes (rad/s²): d/dt of w_ib_b
};

// From the two axes' states (angle, rate) and the cube mount.
BenchKinematics bench_kinematics(const SiteEarth& earth, const AxisState& outer, const AxisState& inner, int mount);

// A unit on a multi-unit fixture: its axes relative to the fixture's (C_f_s: slot axes → fixture
// axes, the fixture taking the place of the cube in the plan's mounts) and its origin's offset from
// the centre of rotation, r_f (fixture axes, m).
struct SlotPose {
  Mat3 C_f_s = Mat3::Identity();
  Vec3 r_f = Vec3::Zero();
};

// What that unit experiences, from the kinematics at the centre: the same rotation in its own axes,
// and the specific force at its origin, f + ω̇×r + ω×(ω×r).
BenchKinematics slot_kinematics(const BenchKinematics& centre, const SlotPose& slot);

}  // namespace calbench
