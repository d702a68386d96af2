// The observability rules of the multi-position fit and their refusals (multipos_observability.hpp;
// the rules are explained in docs/multipos.md, "What the recording must hold").
#include "calibration/multipos/multipos_observability.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "common/units.hpp"

namespace calbench::multipos {
namespace {

const char* axis_name(int i) { return i == 0 ? "x" : i == 1 ? "y" : "z"; }

// "; 12 more still intervals were shorter than a pose's 0.75 s, the longest 0.52 s", or nothing.
std::string too_short_text(const MultiposFit& fit, const MultiposOptions& opt) {
  if (fit.too_short_s.empty()) return {};
  std::ostringstream os;
  os.precision(2);
  os << "; " << fit.too_short_s.size() << (fit.statics.empty() ? "" : " more") << " still interval" << (fit.too_short_s.size() == 1 ? " was" : "s were")
     << " shorter than a pose's " << opt.min_static_s << " s, the longest "
     << *std::max_element(fit.too_short_s.begin(), fit.too_short_s.end()) << " s";
  return os.str();
}

void noise_text(std::ostream& os, const NoiseLevel& n, bool gyro) {
  os << (gyro ? "gyro " : "accelerometer ") << (gyro ? n.used_sigma / units::kDeg : n.used_sigma) << (gyro ? " °/s" : " m/s²")
     << " per sample, from the " << n.source;
}

}  // namespace

void refuse_no_poses(const MultiposFit& fit, const MultiposOptions& opt) {
  std::ostringstream os;
  os << "no static pose found: no interval of " << opt.min_static_s << " s or more is still by the static test"
     << too_short_text(fit, opt) << " ("
     << opt.window_s << "-s windows whose variance stays within " << opt.margin
     << "× the χ² bound of the recording's own white noise: ";
  noise_text(os, fit.gyro_noise, true);
  os << "; ";
  noise_text(os, fit.accel_noise, false);
  os << "). Either the unit never held still, or the conversion to SI is wrong, or the accelerometer and gyro "
        "files are swapped (import imu-tk --acc-scale/--gyro-scale, import csv --accel-unit/--gyro-unit and the columns)";
  throw MultiposRefusal(os.str());
}

void check_gravity_units(const std::vector<StaticInterval>& st, double gravity) {
  std::vector<double> mags;
  for (const auto& s : st) mags.push_back(s.f_mean.norm());
  std::nth_element(mags.begin(), mags.begin() + static_cast<long>(mags.size() / 2), mags.end());
  const double ratio = mags[mags.size() / 2] / gravity;
  if (!(ratio > 0.5 && ratio < 2.0))
    throw MultiposRefusal("the static poses measure |f| = " + std::to_string(mags[mags.size() / 2]) + " m/s² (median of " +
                          std::to_string(st.size()) + " poses), " + std::to_string(ratio) + "× gravity (" +
                          std::to_string(gravity) +
                          " m/s²): the accelerometer values are not in m/s² — check the conversion to SI "
                          "(import imu-tk --acc-offset / --acc-scale, import csv --accel-unit), that the accelerometer "
                          "columns are the right ones, and that the accelerometer and gyro files are not swapped");
}

std::size_t count_distinct_directions(const std::vector<StaticInterval>& st, const std::vector<int>& used) {
  std::vector<Vec3> dirs;
  const double c = std::cos(kDistinctDirectionDeg * units::kDeg);
  for (int k : used) {
    const Vec3 u = st[k].f_mean.normalized();
    if (std::none_of(dirs.begin(), dirs.end(), [&](const Vec3& d) { return u.dot(d) > c; })) dirs.push_back(u);
  }
  return dirs.size();
}

void check_accel_observability(const MultiposFit& fit, const std::vector<int>& used, const MultiposOptions& opt) {
  const auto& st = fit.statics;
  std::vector<std::string> missing;
  if (used.size() < opt.min_poses)
    missing.push_back(std::to_string(used.size()) + (used.size() == 1 ? " static pose" : " static poses") + " used (" +
                      std::to_string(st.size()) + " found" +
                      (used.size() < st.size() ? ", " + std::to_string(st.size() - used.size()) + " left out" : std::string()) +
                      too_short_text(fit, opt) + "), at least " + std::to_string(opt.min_poses) +
                      " needed (9 accelerometer parameters; 12 or more recommended)");
  Vec3 up_max = Vec3::Constant(-2), up_min = Vec3::Constant(2);
  for (int k : used) {
    const Vec3 u = st[k].f_mean.normalized();
    up_max = up_max.cwiseMax(u);
    up_min = up_min.cwiseMin(u);
  }
  // Bias and scale of axis i separate only when its share of gravity takes clearly different values
  // over the poses: a spread of at least 1 (e.g. down and level, or ±30°).
  for (int i = 0; i < 3 && !used.empty(); ++i)
    if (up_max(i) - up_min(i) < 1.0) {
      std::ostringstream os;
      const bool lacks_up = 1 - up_min(i) >= up_max(i) + 1;
      const long most = std::lround(100 * (lacks_up ? up_max(i) : -up_min(i)));  // its share the missing way
      os << "the " << axis_name(i) << " axis's share of gravity spans only " << std::lround(100 * up_min(i)) << "…"
         << std::lround(100 * up_max(i)) << " % over the " << used.size() << (used.size() == 1 ? " pose" : " poses")
         << " (at least 100 % apart needed): no pose has the " << axis_name(i) << " axis pointing "
         << (lacks_up ? "up" : "down");
      if (most > 0) os << " by more than " << most << " %";
      missing.push_back(os.str());
    }
  // The skews need tilted poses: the six faces give 6 distinct equations for 9 unknowns however often
  // they are repeated.
  const std::size_t dirs = count_distinct_directions(st, used);
  if (dirs < 9)
    missing.push_back("only " + std::to_string(dirs) + (dirs == 1 ? " distinct gravity direction" : " distinct gravity directions") +
                      " among the " + std::to_string(used.size()) + (used.size() == 1 ? " pose" : " poses") +
                      " (directions within 10° count once), at least 9 needed for the 9 accelerometer parameters: "
                      "the skews need poses tilted between the faces (on an edge or a corner of the unit)");
  if (missing.empty()) return;
  std::ostringstream os;
  os << "the poses do not determine the accelerometer coefficients:";
  for (const auto& m : missing) os << "\n  - " << m;
  os << "\n  (static poses: " << opt.min_static_s << " s or more still; noise per sample from the " << fit.accel_noise.source
     << ")";
  throw MultiposRefusal(os.str());
}

void check_gyro_units(const MultiposInput& in, const MultiposFit& fit, const std::vector<Vec3>& up, const Vec3& b0,
                      const std::vector<int>& rused) {
  // The turn's path length ∫|ω − b|dt can never be shorter than the angle gravity turned through in
  // the body, and for a hand-turned unit it is seldom more than twice it: rates in the wrong unit
  // (deg/s read as rad/s: 57×) show here before they ruin the fit.
  std::vector<double> ratio;
  for (int k : rused) {
    const auto& ru = fit.rotations[k];
    const double alpha = std::acos(std::clamp(up[ru.from].dot(up[ru.to]), -1.0, 1.0));
    if (alpha < 30 * units::kDeg) continue;
    double path = 0;
    for (std::size_t i = ru.i0; i < ru.i1; ++i)
      path += (in.gyro[i] - b0).norm() * (i + 1 < in.t.size() ? in.t[i + 1] - in.t[i] : 1 / in.rate_hz);
    ratio.push_back(path / alpha);
  }
  if (ratio.size() < 3) return;
  std::nth_element(ratio.begin(), ratio.begin() + static_cast<long>(ratio.size() / 2), ratio.end());
  const double med = ratio[ratio.size() / 2];
  if (med > 0.7 && med < 5) return;
  std::ostringstream os;
  os << "the gyro rates integrate to " << med << "× the angle gravity turned through in the rotations (median over "
     << ratio.size() << " rotations of 30° or more; 1–2 for rates in rad/s): the gyro values are not in rad/s — "
     << "check the conversion to SI (import csv --gyro-unit, import imu-tk --gyro-scale) and the gyro columns";
  throw MultiposRefusal(os.str());
}

void check_rotation_observability(const MultiposFit& fit, const std::vector<int>& rused, const MultiposOptions& opt) {
  std::vector<std::string> miss;
  if (rused.size() < opt.min_rotations)
    miss.push_back(std::to_string(rused.size()) + " rotations between static poses, at least " +
                   std::to_string(opt.min_rotations) + " needed (12 gyro parameters, 2 per rotation)");
  for (int i = 0; i < 3; ++i) {
    double best = 0;
    for (int k : rused) best = std::max(best, std::abs(fit.rotations[k].angle_raw(i)));
    if (best < units::kPi / 4)
      miss.push_back(std::string("no rotation of 45° or more about the ") + axis_name(i) + " axis among the " +
                     std::to_string(rused.size()) + " rotations (largest " +
                     std::to_string(static_cast<int>(std::lround(best / units::kDeg))) + "°)");
  }
  if (miss.empty()) return;
  std::ostringstream os;
  os << "the rotations do not determine the gyro coefficients:";
  for (const auto& m : miss) os << "\n  - " << m;
  throw MultiposRefusal(os.str());
}

}  // namespace calbench::multipos
