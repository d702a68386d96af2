#include "calibration/diagnosis/diag_data.hpp"

#include <algorithm>
#include <cmath>

namespace calbench {

namespace {
constexpr double kAxisChunkS = 0.05;          // rows summed before judging the motion
constexpr double kAxisMinRate = 0.0872665;    // 5 °/s: the Earth rate is < 0.1 % of it
constexpr double kAxisOnlyTol = 2e-3;         // |ω| = |θ̇| within this: no other axis turns
constexpr double kAxisMinTurn = 0.5;          // rad of qualifying rotation per stretch
constexpr double kAxisAgreement = 0.998;      // |Σ ω·Δθ| / Σ |ω|·|Δθ|: the rows agree on one axis
}  // namespace

void DiagDataBuilder::track_axis(const DiagSample& s, bool gap) {
  if (!have_prev_ || gap) {
    stretches_.emplace_back();
    ch_wh_.setZero();
    ch_dth_ = ch_h_ = 0;
  } else if (std::isfinite(s.angle_deg) && std::isfinite(prev_angle_) && s.t > prev_t_) {
    const double h = s.t - prev_t_;
    ch_dth_ += std::remainder((s.angle_deg - prev_angle_) * M_PI / 180.0, 2 * M_PI);
    ch_wh_ += 0.5 * (s.w + prev_w_) * h;
    ch_h_ += h;
    if (ch_h_ >= kAxisChunkS) {
      const double rate = std::abs(ch_dth_) / ch_h_;
      const Vec3 w = ch_wh_ / ch_h_;
      if (rate > kAxisMinRate && std::abs(w.norm() - rate) <= kAxisOnlyTol * rate) {
        Stretch& st = stretches_.back();
        st.w_dth += w * ch_dth_;
        st.w_abs_dth += w.norm() * std::abs(ch_dth_);
        st.turn += std::abs(ch_dth_);
      }
      ch_wh_.setZero();
      ch_dth_ = ch_h_ = 0;
    }
  }
  have_prev_ = true;
  prev_t_ = s.t;
  prev_angle_ = s.angle_deg;
  prev_w_ = s.w;
}

void DiagDataBuilder::add(const DiagSample& s) {
  if (open_) {
    const bool gap = (s.t - t_last_) > 1.5 * std::max(s.dt, dt_last_) + 1e-9;
    if (s.step != cur_.step || gap || (s.t - t0_) >= sub_s_ - 0.5 * s.dt) close_sub();
  }
  // A stretch ends where rows are missing (a remount is not recorded): judged against the previous
  // row's interval, as a reader of a file gives dt = the time since the previous row.
  track_axis(s, have_prev_ && (s.t - t_last_) > 1.5 * dt_last_ + 1e-9);
  t_last_ = s.t;
  dt_last_ = s.dt;
  if (s.step < 0) return;
  ++samples_;
  rate_sum_ += s.dt > 0 ? 1.0 / s.dt : 0.0;
  if (!open_) {
    open_ = true;
    cur_ = SubBlock{};
    cur_.step = s.step;
    t0_ = s.t - s.dt;
    t_first_ = s.t;
    w_first_ = s.w;
    f_first_ = s.f;
    rg_.setZero();
    ra_.setZero();
    temp_sum_ = ang_sum_ = 0;
    temp_n_ = ang_n_ = 0;
  }
  const int n = ++cur_.n;
  cur_.gyro += (s.gyro - cur_.gyro) / n;
  cur_.accel += (s.accel - cur_.accel) / n;
  cur_.w += (s.w - cur_.w) / n;
  cur_.f += (s.f - cur_.f) / n;
  const Vec3 rg = s.gyro - s.w, ra = s.accel - s.f;
  const Vec3 dg = rg - rg_, da = ra - ra_;
  rg_ += dg / n;
  ra_ += da / n;
  cur_.gyro_ss += dg.cwiseProduct(rg - rg_);
  cur_.accel_ss += da.cwiseProduct(ra - ra_);
  w_last_ = s.w;
  f_last_ = s.f;
  if (std::isfinite(s.temp_c)) {
    temp_sum_ += s.temp_c;
    ++temp_n_;
  }
  if (std::isfinite(s.angle_deg)) {
    const double a = s.angle_deg * M_PI / 180.0;
    if (ang_n_ == 0) {
      a0_ = a;
      a_first_ = a;
    }
    const double u = a0_ + std::remainder(a - a0_, 2 * M_PI);  // unwrapped relative to the previous
    a0_ = u;
    a_last_ = u;
    ang_sum_ += u;
    ++ang_n_;
  }
  cur_.duration = s.t - t0_;
  cur_.t_mid = t0_ + 0.5 * cur_.duration;
}

void DiagDataBuilder::close_sub() {
  if (!open_) return;
  open_ = false;
  if (cur_.n < 2) return;
  const double span = t_last_ - t_first_;
  if (span > 0) {
    cur_.dw = (w_last_ - w_first_) / span;
    cur_.df = (f_last_ - f_first_) / span;
  }
  cur_.temp_c = temp_n_ > 0 ? temp_sum_ / temp_n_ : std::numeric_limits<double>::quiet_NaN();
  if (ang_n_ > 0) {
    cur_.angle = ang_sum_ / ang_n_;
    cur_.angle_rate = (ang_n_ > 1 && span > 0) ? (a_last_ - a_first_) / span : 0.0;
  }
  d_.subs.push_back(cur_);
  sub_stretch_.push_back(static_cast<int>(stretches_.size()) - 1);
}

DiagData DiagDataBuilder::finish() {
  close_sub();
  d_.sample_rate_hz = samples_ > 0 ? rate_sum_ / static_cast<double>(samples_) : 0.0;
  auto& subs = d_.subs;
  for (const Stretch& st : stretches_) {
    const double n = st.w_dth.norm();
    d_.stretch_axes.push_back(st.turn >= kAxisMinTurn && n >= kAxisAgreement * st.w_abs_dth ? Vec3(st.w_dth / n)
                                                                                              : Vec3::Zero());
  }
  for (std::size_t k = 0; k < subs.size(); ++k) subs[k].inner_axis = d_.stretch_axes[sub_stretch_[k]];
  if (max_parents_ > 0) {
    double total = 0;
    for (const auto& s : subs) total += s.duration;
    parent_s_ = std::max(parent_s_, total / max_parents_);
  }
  // Parents: consecutive sub-blocks of one step, about parent_s long.
  for (std::size_t k = 0; k < subs.size(); ++k) {
    const SubBlock& s = subs[k];
    bool open_new = d_.parents.empty();
    if (!open_new) {
      const ParentBlock& p = d_.parents.back();
      const SubBlock& prev = subs[k - 1];
      open_new = s.step != p.step || (s.t_mid - 0.5 * s.duration) - (subs[p.first].t_mid - 0.5 * subs[p.first].duration) >=
                                         parent_s_ - 1e-6 ||
                 (s.t_mid - prev.t_mid) > 1.5 * (s.duration + prev.duration);
    }
    if (open_new) {
      ParentBlock p;
      p.step = s.step;
      p.first = static_cast<int>(k);
      d_.parents.push_back(p);
    }
    ParentBlock& p = d_.parents.back();
    ++p.count;
    subs[k].parent = static_cast<int>(d_.parents.size()) - 1;
  }
  for (auto& p : d_.parents) {
    double tw = 0, temp = 0, tn = 0, t0 = 1e300, t1 = -1e300;
    for (int k = p.first; k < p.first + p.count; ++k) {
      const SubBlock& s = subs[k];
      p.n += s.n;
      tw += s.n * s.t_mid;
      p.w += s.n * s.w;
      p.f += s.n * s.f;
      if (std::isfinite(s.temp_c)) {
        temp += s.n * s.temp_c;
        tn += s.n;
      }
      t0 = std::min(t0, s.t_mid - 0.5 * s.duration);
      t1 = std::max(t1, s.t_mid + 0.5 * s.duration);
    }
    p.t_mid = tw / p.n;
    p.w /= p.n;
    p.f /= p.n;
    p.duration = t1 - t0;
    p.temp_c = tn > 0 ? temp / tn : std::numeric_limits<double>::quiet_NaN();
    d_.has_temperature = d_.has_temperature || tn > 0;
  }
  for (const auto& s : subs) d_.has_angle = d_.has_angle || std::isfinite(s.angle);
  // dT/dt: least-squares slope over blocks within ±kHalf s (the temperature readout is quantised:
  // a slope over tens of seconds; short enough to follow the corners of a chamber ramp).
  constexpr double kHalf = 15.0;
  const auto& ps = d_.parents;
  for (std::size_t k = 0; k < ps.size(); ++k) {
    double st = 0, sT = 0, stt = 0, stT = 0, n = 0;
    for (std::size_t l = 0; l < ps.size(); ++l) {
      if (std::abs(ps[l].t_mid - ps[k].t_mid) > kHalf || !std::isfinite(ps[l].temp_c)) continue;
      const double t = ps[l].t_mid - ps[k].t_mid;
      st += t;
      sT += ps[l].temp_c;
      stt += t * t;
      stT += t * ps[l].temp_c;
      ++n;
    }
    const double den = n * stt - st * st;
    d_.parents[k].dtemp = (n > 2 && den > 0) ? (n * stT - st * sT) / den : 0.0;
  }
  for (auto& s : subs) s.dtemp = s.parent >= 0 ? d_.parents[s.parent].dtemp : 0.0;
  return std::move(d_);
}

}  // namespace calbench
