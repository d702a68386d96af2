#include "bench/drive/drive_stream.hpp"

#include "calibration/effects/effect_registry.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"

namespace calbench {

inmotion::RefObs to_ref_obs(const DriveRefRow& r) {
  inmotion::RefObs o;
  o.t = r.t;
  o.lat = r.lat_deg * units::kDeg;
  o.lon = r.lon_deg * units::kDeg;
  o.h = r.h_m;
  o.v_ned = r.v_ned;
  o.rpy = r.rpy_deg * units::kDeg;
  o.sigma_pos = std::isfinite(r.sigma_pos_m) ? r.sigma_pos_m : 0.0;
  o.sigma_vel = std::isfinite(r.sigma_vel_m_s) ? r.sigma_vel_m_s : 0.0;
  o.sigma_att = std::isfinite(r.sigma_att_deg) ? r.sigma_att_deg * units::kDeg : 0.0;
  return o;
}

inmotion::RefObs to_ref_obs(const GnssRow& r) {
  const auto nz = [](double v) { return std::isfinite(v) ? v : 0.0; };
  return inmotion::gnss_fix_obs(r.t, r.lat_deg * units::kDeg, r.lon_deg * units::kDeg, r.h_m, r.v_ned ? &*r.v_ned : nullptr,
                                nz(r.sigma_h_m), nz(r.sigma_v_m), r.sigma_vel_m_s);
}

std::shared_ptr<const SharedReference> load_shared_reference(const fs::path& file) {
  auto s = std::make_shared<SharedReference>();
  s->file = file;
  DriveRefReader r(file);
  DriveRefRow row;
  while (r.next(row)) s->rows.push_back(row);
  s->sha256 = sha256_file(file);
  return s;
}

DriveStream::DriveStream(const fs::path& dir, const std::optional<SensorErrors>& pre, const EffectTerms* effects, Aiding aiding,
                         std::shared_ptr<const SharedReference> shared, bool digest)
    : dir_(dir), shared_(aiding == Aiding::gnss ? nullptr : std::move(shared)) {
  meta_ = read_meta(dir);
  if (meta_.kind != RecordingKind::drive)
    throw InputError((dir / "meta.json").string(), 0, "kind", "expected a drive recording (kind \"drive\")");
  if (!meta_.mounting) throw InputError((dir / "meta.json").string(), 0, "mounting", "a drive recording needs a mounting");
  if (!(meta_.imu_rate_hz > 0)) throw InputError((dir / "meta.json").string(), 0, "imu_rate_hz", "must be > 0");
  imu_ = std::make_unique<ImuReader>(dir / "imu.csv", meta_.imu_rate_hz, digest);
  if (aiding == Aiding::gnss) gnss_ = std::make_unique<GnssReader>(dir / "gnss.csv", digest);
  else if (!shared_) ref_ = std::make_unique<DriveRefReader>(dir / "reference.csv", digest);
  if (pre) {
    cg_ = TriadCorrector(pre->gyro);
    ca_ = TriadCorrector(pre->accel);
  }
  if (effects && (effects->any_sensor_side() || time_stamp_offset(*effects) != 0))
    comp_.emplace(*effects, pre ? *pre : SensorErrors{});
  have_ref_ = read_epoch();
}

bool DriveStream::read_epoch() {
  if (gnss_) {
    if (!gnss_->next(pending_gnss_)) {
      gnss_done_ = true;
      return false;
    }
    pending_ = to_ref_obs(pending_gnss_);
    return true;
  }
  if (shared_) {
    if (shared_next_ >= shared_->rows.size()) return false;
    pending_row_ = shared_->rows[shared_next_++];
    pending_ = to_ref_obs(pending_row_);
    return true;
  }
  if (!ref_->next(pending_row_)) {
    ref_done_ = true;
    return false;
  }
  pending_ = to_ref_obs(pending_row_);
  return true;
}

std::optional<std::string> DriveStream::aiding_sha256() const {
  if (shared_) return shared_->sha256.empty() ? std::nullopt : std::optional<std::string>(shared_->sha256);
  if (gnss_) return gnss_done_ ? gnss_->sha256() : std::nullopt;
  return ref_done_ ? ref_->sha256() : std::nullopt;
}

Mat3 DriveStream::nominal_mounting() const { return ins::dcm_from_rpy(meta_.mounting->rpy_deg * units::kDeg); }
Vec3 DriveStream::lever_arm() const { return meta_.mounting->lever_arm_m; }

bool DriveStream::next(Event& e) {
  // A pending reference epoch that the IMU has reached goes first.
  if (have_ref_ && (pending_.t <= last_imu_t_ + 1e-9 || imu_done_)) {
    e.is_ref = true;
    e.t = pending_.t;
    e.ref = pending_;
    if (gnss_) gnss_out_ = pending_gnss_;
    else row_out_ = pending_row_;
    have_row_ = true;
    have_ref_ = read_epoch();
    return true;
  }
  if (have_rest_) {  // the remainder of a split interval
    e = rest_;
    have_rest_ = false;
  } else {
    if (imu_done_) return false;
    ImuRecord r;
    for (;;) {
      if (!imu_->next(r)) {
        imu_done_ = true;
        return next(e);
      }
      // A second read of the sample already read: its interval joins the next distinct sample's.
      if (drop_repeats_ && imu_->form() == ImuForm::rates && have_raw_ && r.gyro == raw_g_ && r.accel == raw_a_) {
        skipped_dt_ += r.dt;
        ++dropped_;
        continue;
      }
      break;
    }
    raw_g_ = r.gyro;
    raw_a_ = r.accel;
    have_raw_ = true;
    r.dt += skipped_dt_;
    skipped_dt_ = 0;
    e.is_ref = false;
    e.t = r.t;
    e.dt = r.dt;
    e.temp_c = r.temp_c;
    if (std::isfinite(r.temp_c)) ++rows_temp_;
    if (comp_) {
      e.t = comp_->corrected_time(r.t);
      if (imu_->form() == ImuForm::rates) comp_->rates(r.gyro, r.accel, r.dt, r.temp_c);
      else comp_->increments(r.gyro, r.accel, r.dt, r.temp_c);
    }
    if (imu_->form() == ImuForm::rates) integ_(r.gyro, r.accel, r.dt, e.dtheta, e.dv);
    else {
      e.dtheta = r.gyro;
      e.dv = r.accel;
    }
    if (cg_) {
      e.dtheta = cg_->increment(e.dtheta, r.dt);
      e.dv = ca_->increment(e.dv, r.dt);
    }
  }
  // Time stamps moved by a time offset, or intervals merged over second reads, no longer fall on
  // the reference epochs (which they typically do in a recording): split the interval that
  // straddles the next epoch there, increments in proportion, so that the epoch is compared at its
  // own time as before.
  if (((comp_ && comp_->time_offset_s() != 0) || drop_repeats_) && have_ref_ && e.dt > 0 && pending_.t > e.t - e.dt + 1e-9 &&
      pending_.t < e.t - 1e-9) {
    const double a = (pending_.t - (e.t - e.dt)) / e.dt;
    rest_ = e;
    rest_.dt = e.dt * (1 - a);
    rest_.dtheta = e.dtheta * (1 - a);
    rest_.dv = e.dv * (1 - a);
    have_rest_ = true;
    e.t = pending_.t;
    e.dt *= a;
    e.dtheta *= a;
    e.dv *= a;
  }
  last_imu_t_ = e.t;
  return true;
}

}  // namespace calbench
