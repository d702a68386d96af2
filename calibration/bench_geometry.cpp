#include <cmath>

#include "calibration/bench_plan.hpp"
#include "common/table_motion.hpp"

namespace calbench {
namespace {
Mat3 rx(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
Mat3 ry(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }
Mat3 rz(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }
}  // namespace

const char* mount_name(int mount) {
  static const char* const names[kMountCount] = {"x", "y", "z", "xy", "yz", "zx"};
  return mount >= 0 && mount < kMountCount ? names[mount] : "?";
}

int mount_from_name(const std::string& name) {
  const std::string n = !name.empty() && name[0] == '+' ? name.substr(1) : name;
  for (int m = 0; m < kMountCount; ++m)
    if (n == mount_name(m)) return m;
  return -1;
}

Mat3 mount_rotation(int mount) {
  constexpr double kHalfPi = 1.5707963267948966;
  switch (mount) {
    case 0: return ry(-kHalfPi);  // IMU x → platform z
    case 1: return rx(kHalfPi);   // IMU y → platform z
    case 3:
    case 4:
    case 5: {  // wedge: (e_i + e_j)/√2 → platform z, the third axis e_k → platform x
      const int i = mount - 3, j = (i + 1) % 3, k = (i + 2) % 3;
      const Vec3 z = (Vec3::Unit(i) + Vec3::Unit(j)) / std::sqrt(2.0), x = Vec3::Unit(k);
      Mat3 C;  // rows: the platform's axes in IMU axes
      C.row(0) = x.transpose();
      C.row(1) = z.cross(x).transpose();
      C.row(2) = z.transpose();
      return C;
    }
    default: return Mat3::Identity();
  }
}

Vec3 mount_direction(int mount) { return mount_rotation(mount).row(2).transpose(); }

Mat3 imu_attitude(double outer, double inner, int mount) {
  return rx(outer) * rz(inner) * mount_rotation(mount);
}

bool solve_table_angles(const Mat3& C_b_l, int mount, double& outer, double& inner, double tol) {
  const Mat3 R = C_b_l * mount_rotation(mount).transpose();  // = Rx(θo)·Rz(θi)
  if (std::abs(R(0, 2)) > tol) return false;
  outer = std::atan2(-R(1, 2), R(2, 2));
  const Mat3 Z = rx(outer).transpose() * R;
  inner = std::atan2(Z(1, 0), Z(0, 0));
  return (imu_attitude(outer, inner, mount) - C_b_l).cwiseAbs().maxCoeff() < 1e-6;
}

double plan_duration_s(const BenchPlan& plan) {
  double t = 0, outer = 0, inner = 0, rate = 0;
  int mount = plan.steps.empty() ? 2 : plan.steps.front().mount;
  for (const auto& s : plan.steps) {
    if (s.mount != mount) {
      t += move_duration(rate, 0.0, plan.table.max_accel) + plan.table.remount_s;
      rate = 0;
      mount = s.mount;
    }
    const double tr = move_duration(rate, 0.0, plan.table.max_accel);  // stop spinning
    const double to = slew_duration(std::remainder(s.outer - outer, 2 * M_PI), plan.table.slew_rate, plan.table.max_accel);
    const double ti = slew_duration(std::remainder(s.inner - inner, 2 * M_PI), plan.table.slew_rate, plan.table.max_accel);
    t += tr + std::max(to, ti);
    if (s.kind == StepKind::rate) {
      t += move_duration(0.0, s.rate, plan.table.max_accel);
      rate = s.rate;
    } else {
      rate = 0;
    }
    t += plan.table.settle_s + s.dwell_s;
    outer = s.outer;
    inner = s.inner;
  }
  return t + move_duration(rate, 0.0, plan.table.max_accel);
}

}  // namespace calbench

#include "calibration/bench_kinematics.hpp"

namespace calbench {

BenchKinematics bench_kinematics(const SiteEarth& earth, const AxisState& outer, const AxisState& inner, int mount) {
  BenchKinematics k;
  const Mat3 Co = Eigen::AngleAxisd(outer.angle, Vec3::UnitX()).toRotationMatrix();
  const Mat3 Ci = Eigen::AngleAxisd(inner.angle, Vec3::UnitZ()).toRotationMatrix();
  k.C_b_l = Co * Ci * mount_rotation(mount);
  // Rate of the platform w.r.t. local level, in L: outer about x_L, inner about the outer gimbal's z.
  const Vec3 w_lb_l = outer.rate * Vec3::UnitX() + Co * (inner.rate * Vec3::UnitZ());
  k.w_ib_b = k.C_b_l.transpose() * (w_lb_l + earth.w_ie_ned);
  k.f_b = k.C_b_l.transpose() * (-earth.g_ned);
  // d/dt (C_b_lᵀ·w_ib_l) = C_b_lᵀ·ẇ_lb_l − w_lb_b × w_ib_b, with ẇ_lb_l from both axes' accelerations and
  // the outer gimbal carrying the inner axis round (the local-level frame itself is taken as fixed).
  const Vec3 dw_lb_l = outer.accel * Vec3::UnitX() + Co * (inner.accel * Vec3::UnitZ()) +
                       (outer.rate * Vec3::UnitX()).cross(Co * (inner.rate * Vec3::UnitZ()));
  k.dw_ib_b = k.C_b_l.transpose() * dw_lb_l - (k.C_b_l.transpose() * w_lb_l).cross(k.w_ib_b);
  return k;
}

BenchKinematics slot_kinematics(const BenchKinematics& c, const SlotPose& slot) {
  BenchKinematics k;
  const Vec3& r = slot.r_f;
  k.C_b_l = c.C_b_l * slot.C_f_s;
  k.w_ib_b = slot.C_f_s.transpose() * c.w_ib_b;
  k.dw_ib_b = slot.C_f_s.transpose() * c.dw_ib_b;
  k.f_b = slot.C_f_s.transpose() * (c.f_b + c.dw_ib_b.cross(r) + c.w_ib_b.cross(c.w_ib_b.cross(r)));
  return k;
}

}  // namespace calbench
