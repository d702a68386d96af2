#include "calibration/inmotion/standstill.hpp"

#include <algorithm>

namespace calbench::inmotion {

void StandstillDetector::add(double t, const Vec3& w, const Vec3& f, double dt) {
  s_.push_back({t, dt, w, f});
  while (!s_.empty() && s_.front().t - s_.front().dt < t - window_s_ - 1e-9) s_.pop_front();
}

bool StandstillDetector::quiet(const NoiseSpec& n, double factor, double* gyro_ratio, double* accel_ratio) const {
  if (gyro_ratio) *gyro_ratio = -1;
  if (accel_ratio) *accel_ratio = -1;
  if (s_.size() < 10) return false;
  const double span = s_.back().t - (s_.front().t - s_.front().dt);
  if (span < 0.9 * window_s_) return false;
  const double N = static_cast<double>(s_.size());
  const double dt = span / N;
  Vec3 mw = Vec3::Zero(), mf = Vec3::Zero();
  for (const Sample& s : s_) {
    mw += s.w;
    mf += s.f;
  }
  mw /= N;
  mf /= N;
  Vec3 vw = Vec3::Zero(), vf = Vec3::Zero();
  for (const Sample& s : s_) {
    vw += (s.w - mw).cwiseAbs2();
    vf += (s.f - mf).cwiseAbs2();
  }
  vw /= N - 1;
  vf /= N - 1;
  const auto white = [dt](const TriadNoise& q) { return q.white_density * q.white_density / dt + q.lsb * q.lsb / 12.0; };
  const double rg = vw.maxCoeff() / white(n.gyro), ra = vf.maxCoeff() / white(n.accel);
  if (gyro_ratio) *gyro_ratio = rg;
  if (accel_ratio) *accel_ratio = ra;
  return rg <= factor && ra <= factor;
}

}  // namespace calbench::inmotion
