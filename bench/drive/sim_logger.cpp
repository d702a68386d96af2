#include "bench/drive/sim_logger.hpp"

#include <algorithm>
#include <cmath>

#include "calibration/ins/nav_math.hpp"
#include "common/units.hpp"

namespace calbench {

PollingLogger::PollingLogger(double read_hz, std::uint64_t seed, std::function<void(const ImuRecord&)> out)
    : read_hz_(read_hz), rng_(seed ^ 0x6c6f67676572ULL), out_(std::move(out)) {}

void PollingLogger::reads_until(double t_end) {
  std::uniform_real_distribution<double> u(0.7, 1.3);
  while (next_read_ < t_end) {
    ImuRecord r = *cur_;
    r.t = next_read_;
    out_(r);
    next_read_ += u(rng_) / read_hz_;
  }
}

void PollingLogger::sample(const ImuRecord& r) {
  if (!(read_hz_ > 0)) {
    out_(r);
    return;
  }
  if (cur_) reads_until(r.t);  // the reads while the previous sample was the newest
  if (!started_) {
    next_read_ = r.t;
    started_ = true;
  }
  cur_ = r;
}

void PollingLogger::finish(double sensor_dt) {
  if (read_hz_ > 0 && cur_) reads_until(cur_->t + sensor_dt);
}

GnssRow DifferencingReceiver::fix(const GnssRow& g) {
  if (!on_) return g;
  GnssRow out = g;
  out.v_ned.reset();
  if (prev_ && g.t > prev_->t) {
    const double dt = g.t - prev_->t, lat = 0.5 * units::kDeg * (g.lat_deg + prev_->lat_deg);
    const ins::Radii r = ins::wgs84_radii(lat);
    const double h = 0.5 * (g.h_m + prev_->h_m);
    out.v_ned = Vec3((g.lat_deg - prev_->lat_deg) * units::kDeg * (r.RM + h) / dt,
                     (g.lon_deg - prev_->lon_deg) * units::kDeg * (r.RN + h) * std::cos(lat) / dt, -(g.h_m - prev_->h_m) / dt);
    // The difference's own σ (one value per row, gnss.csv's form: the larger of the horizontal and
    // the vertical one).
    out.sigma_vel_m_s = std::sqrt(2.0) * std::max({g.sigma_h_m, g.sigma_v_m, 0.0}) / dt;
  }
  prev_ = g;
  return out;
}

}  // namespace calbench
