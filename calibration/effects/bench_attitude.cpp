#include "calibration/effects/bench_attitude.hpp"

#include <cmath>

#include "calibration/bench_plan.hpp"

namespace calbench {

bool static_attitude(const Vec3& w, const Vec3& f, Mat3& C) {
  if (w.norm() > 1e-3 || f.norm() < 1.0) return false;  // rotating, or no gravity reference
  const Vec3 d = -f.normalized();                        // down, IMU axes
  Vec3 n = w - w.dot(d) * d;                             // Earth rate: its horizontal part points north
  if (n.norm() < 1e-6) return false;
  n.normalize();
  const Vec3 e = d.cross(n);
  // C_b_l: rows are the level axes (N, E, D) in IMU coordinates.
  C.row(0) = n.transpose();
  C.row(1) = e.transpose();
  C.row(2) = d.transpose();
  return true;
}

bool bench_attitude(const Vec3& w, const Vec3& f, Mat3& C) {
  if (w.norm() <= 1e-3) return static_attitude(w, f, C);
  if (f.norm() < 1.0) return false;
  // The spin axis: the fixture direction (an IMU axis or a face diagonal) nearest the rate.
  Vec3 k = Vec3::UnitZ();
  double best = -1;
  for (int m = 0; m < kMountCount; ++m) {
    const Vec3 km = mount_direction(m);
    if (std::abs(km.dot(w)) > best) {
      best = std::abs(km.dot(w));
      k = km;
    }
  }
  const Vec3 w_perp = w - w.dot(k) * k;          // Earth rate only when the table spins about k
  if (w_perp.norm() > 1e-3) return false;
  const Vec3 d = -f.normalized();
  const Vec3 c = k.cross(d);
  Vec3 n;
  if (c.norm() > 1e-3) {
    n = c.normalized();                          // north ⟂ k and ⟂ down
    if (w.dot(n) < 0) n = -n;                    // the horizontal Earth rate points north
  } else {
    if (w_perp.norm() < 1e-7) return false;      // at a pole, or no Earth rate in the reference
    n = (w_perp - w_perp.dot(d) * d).normalized();
  }
  const Vec3 e = d.cross(n);
  C.row(0) = n.transpose();
  C.row(1) = e.transpose();
  C.row(2) = d.transpose();
  return true;
}

}  // namespace calbench
