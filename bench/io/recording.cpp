#include "bench/io/recording.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>
#include <cstdio>
#include <fstream>

#include "bench/io/hdf5_recording.hpp"
#include "bench/io/sha256.hpp"
#include "bench/io/verify_recording.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/message_text.hpp"
#include "bench/io/plausible.hpp"

namespace calbench {

const char* kind_name(RecordingKind k) {
  return k == RecordingKind::bench ? "bench" : k == RecordingKind::drive ? "drive" : "multipos";
}

RecordingMeta read_meta(const fs::path& dir) {
  const fs::path file = dir / "meta.json";
  const std::string f = file.string();
  if (!fs::exists(file)) throw InputError(f, 0, "", "missing: a recording folder needs meta.json");
  const nlohmann::json j = read_json_file(file);
  if (!j.is_object()) throw InputError(f, 1, "", "expected a JSON object");
  RecordingMeta m;
  const std::string format = jstr(jreq(j, "format", f, ""), f, "format");
  if (format != "calbench-recording/1")
    throw InputError(f, 0, "format", "unsupported format '" + format + "' (expected calbench-recording/1)");
  const std::string kind = jstr(jreq(j, "kind", f, ""), f, "kind");
  if (kind == "bench") m.kind = RecordingKind::bench;
  else if (kind == "drive") m.kind = RecordingKind::drive;
  else if (kind == "multipos") m.kind = RecordingKind::multipos;
  else throw InputError(f, 0, "kind", "must be \"bench\", \"drive\" or \"multipos\", got '" + kind + "'");
  const auto& dev = jreq(j, "device", f, "");
  m.device.model = jstr(jreq(dev, "model", f, "device"), f, "device.model");
  const auto& serial = jreq(dev, "serial", f, "device");
  m.device.serial = serial.is_number_integer() ? std::to_string(serial.get<long long>()) : jstr(serial, f, "device.serial");
  m.imu_rate_hz = jnum(jreq(j, "imu_rate_hz", f, ""), f, "imu_rate_hz");
  if (m.imu_rate_hz <= 0) throw InputError(f, 0, "imu_rate_hz", "must be positive");
  if (m.imu_rate_hz > plausible::kMaxImuRate_Hz)  // 1e300 passed and broke the step checks that use 1/rate
    throw InputError(f, 0, "imu_rate_hz", number_text(m.imu_rate_hz) + " Hz is not an IMU rate (at most " +
                                              number_text(plausible::kMaxImuRate_Hz) + " Hz)");
  if (j.contains("site") || m.kind == RecordingKind::bench) {
    const auto& s = jreq(j, "site", f, "");
    Site site;
    site.lat_deg = jnum(jreq(s, "lat_deg", f, "site"), f, "site.lat_deg");
    if (m.kind == RecordingKind::multipos && !s.contains("lon_deg")) m.site_has_lon = false;  // only g and Ω·sin φ matter
    else site.lon_deg = jnum(jreq(s, "lon_deg", f, "site"), f, "site.lon_deg");
    site.h_m = jnum(jreq(s, "h_m", f, "site"), f, "site.h_m");
    if (std::abs(site.lat_deg) > 90) throw InputError(f, 0, "site.lat_deg", "latitude outside ±90°");
    if (std::abs(site.lon_deg) > 360) throw InputError(f, 0, "site.lon_deg", "longitude outside ±360°");
    if (std::abs(site.h_m) > plausible::kMaxAbsHeight_m)
      throw InputError(f, 0, "site.h_m", "height " + number_text(site.h_m) + " m is not plausible (at most ±" +
                                             number_text(plausible::kMaxAbsHeight_m) + " m)");
    m.site = site;
  }
  if (j.contains("mounting") || m.kind == RecordingKind::drive) {
    const auto& mo = jreq(j, "mounting", f, "");
    Mounting mt;
    mt.rpy_deg = jvec3(jreq(mo, "rpy_deg", f, "mounting"), f, "mounting.rpy_deg");
    mt.lever_arm_m = jvec3(jreq(mo, "lever_arm_m", f, "mounting"), f, "mounting.lever_arm_m");
    if (!(mt.lever_arm_m.norm() <= plausible::kMaxLeverArm_m))
      throw InputError(f, 0, "mounting.lever_arm_m",
                       "lever arm of " + number_text(mt.lever_arm_m.norm()) + " m is not plausible (|r| at most " +
                           number_text(plausible::kMaxLeverArm_m) + " m)");
    for (int i = 0; i < 3; ++i)
      if (!(std::abs(mt.rpy_deg(i)) <= plausible::kMaxMountingAngle_deg))
        throw InputError(f, 0, "mounting.rpy_deg[" + std::to_string(i) + "]",
                         number_text(mt.rpy_deg(i)) + "° is not a mounting angle (at most ±" +
                             number_text(plausible::kMaxMountingAngle_deg) + "°)");
    m.mounting = mt;
  }
  if (j.contains("notes") && j["notes"].is_string()) m.notes = j["notes"].get<std::string>();
  if (j.contains("status")) m.complete = j["status"] != "incomplete";
  for (auto it = j.begin(); it != j.end(); ++it) {
    static const char* known[] = {"format", "kind", "device", "site", "imu_rate_hz", "mounting", "notes", "status"};
    if (std::find(std::begin(known), std::end(known), it.key()) == std::end(known)) m.extra[it.key()] = it.value();
  }
  return m;
}

void write_meta(const fs::path& dir, const RecordingMeta& m) {
  nlohmann::json j = m.extra.is_object() ? m.extra : nlohmann::json::object();
  j["format"] = "calbench-recording/1";
  j["kind"] = kind_name(m.kind);
  j["device"] = {{"model", m.device.model}, {"serial", m.device.serial}};
  if (m.site) {
    j["site"] = {{"lat_deg", m.site->lat_deg}, {"h_m", m.site->h_m}};
    if (m.site_has_lon) j["site"]["lon_deg"] = m.site->lon_deg;
  }
  j["imu_rate_hz"] = m.imu_rate_hz;
  if (m.mounting) j["mounting"] = {{"rpy_deg", to_json(m.mounting->rpy_deg)}, {"lever_arm_m", to_json(m.mounting->lever_arm_m)}};
  j["notes"] = m.notes;
  j["status"] = m.complete ? "complete" : "incomplete";
  write_text_atomic(dir / "meta.json", j.dump(2) + "\n");
}

// ---------------------------------------------------------------------------------------------
std::unique_ptr<TableSource> open_table(const fs::path& file, bool digest) {
  if (file.extension() == ".csv") {  // NAME.csv, or else the dataset NAME of recording.h5 (table_file's rule)
    const fs::path f = table_file(file.parent_path(), file.stem().string());
    if (f.filename() == kHdf5RecordingFile) return open_hdf5_table(f, file.stem().string(), digest);
  }
  return std::make_unique<CsvReader>(file.string(), digest);
}

// Rows parsed ahead: blocks of kBatchRows, at most kQueueBatches waiting.
struct ImuReader::Batch {
  std::vector<ImuRecord> rows;
  std::vector<std::size_t> lines;
  std::exception_ptr error;  // after the rows: the input error met while parsing the next one
  bool end = false;          // the table ends after these rows
};

struct ImuReader::Queue {
  static constexpr std::size_t kBatchRows = 4096, kQueueBatches = 4;
  std::mutex m;
  std::condition_variable cv;
  std::deque<std::unique_ptr<Batch>> ready;
  bool stop = false;
  std::thread worker;
};

ImuReader::ImuReader(const fs::path& file, double nominal_rate_hz, bool digest)
    : tab_(open_table(file, digest)), nominal_dt_(1.0 / nominal_rate_hz) {
  TableSource& c = *tab_;
  t_ = c.require("t_s");
  c.set_time_slot(t_);
  if (c.has("gx_rad_s") || !c.has("dax_rad")) {
    form_ = ImuForm::rates;
    const char* g[] = {"gx_rad_s", "gy_rad_s", "gz_rad_s"};
    const char* a[] = {"ax_m_s2", "ay_m_s2", "az_m_s2"};
    for (int i = 0; i < 3; ++i) g_[i] = c.require(g_name_[i] = g[i]);
    for (int i = 0; i < 3; ++i) a_[i] = c.require(a_name_[i] = a[i]);
  } else {
    form_ = ImuForm::increments;
    const char* g[] = {"dax_rad", "day_rad", "daz_rad"};
    const char* a[] = {"dvx_m_s", "dvy_m_s", "dvz_m_s"};
    for (int i = 0; i < 3; ++i) g_[i] = c.require(g_name_[i] = g[i]);
    for (int i = 0; i < 3; ++i) a_[i] = c.require(a_name_[i] = a[i]);
  }
  temp_ = c.optional("temp_c");
  seq_ = c.optional("seq");
  q_ = std::make_unique<Queue>();
  q_->worker = std::thread([this] { produce(); });
}

ImuReader::~ImuReader() {
  {
    std::lock_guard<std::mutex> lk(q_->m);
    q_->stop = true;
  }
  q_->cv.notify_all();
  q_->worker.join();
}

void ImuReader::produce() {
  TableSource& c = *tab_;
  double last_t = 0;
  bool first = true;
  while (true) {
    auto b = std::make_unique<Batch>();
    b->rows.reserve(Queue::kBatchRows);
    b->lines.reserve(Queue::kBatchRows);
    try {
      while (b->rows.size() < Queue::kBatchRows) {
        if (!c.next()) {
          b->end = true;
          break;
        }
        ImuRecord& r = b->rows.emplace_back();
        r.t = c.value(t_);
        r.dt = first ? nominal_dt_ : r.t - last_t;
        if (!first && r.dt > plausible::kMaxImuInterval_s)
          c.fail_at("t_s", number_text(r.dt) + " s after the row before: not an IMU interval (at most " +
                               number_text(plausible::kMaxImuInterval_s) + " s; split the recording at the gap)");
        first = false;
        last_t = r.t;
        // Rates, or increments over dt (as rates): far beyond any IMU's range is not a measurement.
        const double per = form_ == ImuForm::rates ? 1.0 : 1.0 / r.dt;
        for (int i = 0; i < 3; ++i) {
          r.gyro(i) = c.value(g_[i]);
          r.accel(i) = c.value(a_[i]);
          if (!(std::abs(r.gyro(i)) * per <= plausible::kMaxAngularRate_rad_s))
            c.fail_at(g_name_[i], "angular rate " + number_text(r.gyro(i) * per) +
                                                          " rad/s is not plausible (at most " +
                                                          number_text(plausible::kMaxAngularRate_rad_s) + " rad/s)");
          if (!(std::abs(r.accel(i)) * per <= plausible::kMaxSpecificForce_m_s2))
            c.fail_at(a_name_[i], "specific force " + number_text(r.accel(i) * per) +
                                                          " m/s² is not plausible (at most " +
                                                          number_text(plausible::kMaxSpecificForce_m_s2) + " m/s²)");
        }
        r.temp_c = temp_ >= 0 ? c.value(temp_) : std::numeric_limits<double>::quiet_NaN();
        r.seq = seq_ >= 0 ? c.value(seq_) : -1;
        b->lines.push_back(c.line());
      }
    } catch (...) {
      b->error = std::current_exception();
      b->end = true;
    }
    const bool end = b->end;
    std::unique_lock<std::mutex> lk(q_->m);
    q_->cv.wait(lk, [&] { return q_->stop || q_->ready.size() < Queue::kQueueBatches; });
    if (q_->stop) return;
    q_->ready.push_back(std::move(b));
    lk.unlock();
    q_->cv.notify_all();
    if (end) return;
  }
}

bool ImuReader::next(ImuRecord& r) {
  while (!cur_ || pos_ >= cur_->rows.size()) {
    if (cur_ && cur_->error) {
      const std::exception_ptr e = cur_->error;
      cur_->error = nullptr;
      done_ = true;
      std::rethrow_exception(e);
    }
    if (done_ || (cur_ && cur_->end)) {
      done_ = true;
      return false;
    }
    std::unique_lock<std::mutex> lk(q_->m);
    q_->cv.wait(lk, [&] { return !q_->ready.empty(); });
    cur_ = std::move(q_->ready.front());
    q_->ready.pop_front();
    lk.unlock();
    q_->cv.notify_all();
    pos_ = 0;
  }
  r = cur_->rows[pos_];
  line_ = cur_->lines[pos_];
  ++pos_;
  return true;
}

std::optional<std::string> ImuReader::sha256() const {
  // The digest is complete only once the producer has read the table to its end.
  if (!done_) return std::nullopt;
  return tab_->sha256();
}

BenchRefReader::BenchRefReader(const fs::path& file) : csv_(open_table(file)) {
  t_ = csv_->require("t_s");
  csv_->set_time_slot(t_);
  const char* w[] = {"wx_rad_s", "wy_rad_s", "wz_rad_s"};
  const char* f[] = {"fx_m_s2", "fy_m_s2", "fz_m_s2"};
  for (int i = 0; i < 3; ++i) w_[i] = csv_->require(w[i]);
  for (int i = 0; i < 3; ++i) f_[i] = csv_->require(f[i]);
  step_ = csv_->require("step");
  angle_ = csv_->optional("angle_deg");
}

bool BenchRefReader::next(BenchRefRow& r) {
  if (!csv_->next()) return false;
  r.t = csv_->value(t_);
  for (int i = 0; i < 3; ++i) {
    r.w(i) = csv_->value(w_[i]);
    r.f(i) = csv_->value(f_[i]);
  }
  const double s = csv_->value(step_);
  if (s != std::floor(s) || s < -1 || s > 1e6)
    csv_->fail_at("step", "must be an integer from −1 to 1000000 (a plan step index)");
  r.step = static_cast<int>(s);
  r.angle_deg = angle_ >= 0 ? csv_->value(angle_) : std::numeric_limits<double>::quiet_NaN();
  return true;
}

namespace {
// The leading columns of a drive's reference.csv and gnss.csv: time (strictly increasing) and position.
void require_time_position(TableSource& c, int& t, int& lat, int& lon, int& h) {
  t = c.require("t_s");
  c.set_time_slot(t);
  lat = c.require("lat_deg");
  lon = c.require("lon_deg");
  h = c.require("h_m");
}
// A position off the Earth or a σ that is no σ is a broken file, not a fix: refused with file, line
// and field (the ranges of meta.json's site: latitude ±90°, height ±1e5 m; longitude −180…360°).
void check_position(TableSource& c, double lat, double lon, double h) {
  if (std::abs(lat) > 90) c.fail_at("lat_deg", "latitude outside ±90°");
  if (!(lon >= -180 && lon <= 360)) c.fail_at("lon_deg", "longitude outside −180…360°");
  if (std::abs(h) > 1e5) c.fail_at("h_m", "height outside ±1e5 m");
}
double sigma_value(TableSource& c, int slot, const char* name) {
  const double v = c.value(slot);
  if (!(v > 0)) c.fail_at(name, "a 1-sigma must be positive");
  return v;
}
}  // namespace

DriveRefReader::DriveRefReader(const fs::path& file, bool digest) : csv_(open_table(file, digest)) {
  require_time_position(*csv_, t_, lat_, lon_, h_);
  const char* v[] = {"vn_m_s", "ve_m_s", "vd_m_s"};
  const char* a[] = {"roll_deg", "pitch_deg", "yaw_deg"};
  for (int i = 0; i < 3; ++i) v_[i] = csv_->require(v[i]);
  for (int i = 0; i < 3; ++i) att_[i] = csv_->require(a[i]);
  sp_ = csv_->optional("sigma_pos_m");
  sv_ = csv_->optional("sigma_vel_m_s");
  sa_ = csv_->optional("sigma_att_deg");
}

bool DriveRefReader::next(DriveRefRow& r) {
  if (!csv_->next()) return false;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  r.t = csv_->value(t_);
  r.lat_deg = csv_->value(lat_);
  r.lon_deg = csv_->value(lon_);
  r.h_m = csv_->value(h_);
  check_position(*csv_, r.lat_deg, r.lon_deg, r.h_m);
  for (int i = 0; i < 3; ++i) {
    r.v_ned(i) = csv_->value(v_[i]);
    r.rpy_deg(i) = csv_->value(att_[i]);
  }
  r.sigma_pos_m = sp_ >= 0 ? sigma_value(*csv_, sp_, "sigma_pos_m") : nan;
  r.sigma_vel_m_s = sv_ >= 0 ? sigma_value(*csv_, sv_, "sigma_vel_m_s") : nan;
  r.sigma_att_deg = sa_ >= 0 ? sigma_value(*csv_, sa_, "sigma_att_deg") : nan;
  return true;
}

GnssReader::GnssReader(const fs::path& file, bool digest) : csv_(open_table(file, digest)) {
  require_time_position(*csv_, t_, lat_, lon_, h_);
  const char* v[] = {"vn_m_s", "ve_m_s", "vd_m_s"};
  for (int i = 0; i < 3; ++i) v_[i] = csv_->optional(v[i]);
  // Velocity is all three columns or none: a partial set is a broken file, not "no velocity".
  if ((v_[0] >= 0 || v_[1] >= 0 || v_[2] >= 0) && !(v_[0] >= 0 && v_[1] >= 0 && v_[2] >= 0))
    for (int i = 0; i < 3; ++i)
      if (v_[i] < 0)
        throw InputError(csv_->path(), 1, v[i], "missing column (a velocity needs vn_m_s, ve_m_s and vd_m_s)");
  sh_ = csv_->optional("sigma_h_m");
  sv_ = csv_->optional("sigma_v_m");
  svel_ = csv_->optional("sigma_vel_m_s");
}

bool GnssReader::next(GnssRow& r) {
  if (!csv_->next()) return false;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  r.t = csv_->value(t_);
  r.lat_deg = csv_->value(lat_);
  r.lon_deg = csv_->value(lon_);
  r.h_m = csv_->value(h_);
  check_position(*csv_, r.lat_deg, r.lon_deg, r.h_m);
  if (v_[0] >= 0 && v_[1] >= 0 && v_[2] >= 0) r.v_ned = Vec3(csv_->value(v_[0]), csv_->value(v_[1]), csv_->value(v_[2]));
  else r.v_ned.reset();
  r.sigma_h_m = sh_ >= 0 ? sigma_value(*csv_, sh_, "sigma_h_m") : nan;
  r.sigma_v_m = sv_ >= 0 ? sigma_value(*csv_, sv_, "sigma_v_m") : nan;
  r.sigma_vel_m_s = svel_ >= 0 ? sigma_value(*csv_, svel_, "sigma_vel_m_s") : nan;
  return true;
}

// ---------------------------------------------------------------------------------------------
RecordingWriter::RecordingWriter(const fs::path& dir, RecordingMeta meta, ImuForm form, bool with_temperature,
                                 bool with_seq, bool with_gnss)
    : dir_(dir), meta_(std::move(meta)), form_(form), temp_(with_temperature), seq_(with_seq) {
  fs::create_directories(dir_);
  meta_.complete = false;
  write_meta(dir_, meta_);
  std::vector<std::string> ic = {"t_s"};
  if (form_ == ImuForm::rates) ic.insert(ic.end(), {"gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"});
  else ic.insert(ic.end(), {"dax_rad", "day_rad", "daz_rad", "dvx_m_s", "dvy_m_s", "dvz_m_s"});
  if (temp_) ic.push_back("temp_c");
  if (seq_) ic.push_back("seq");
  // Each table's rows are tallied as they are written (tally_: imu, reference[, gnss]); finish()
  // reads the folder back against the tally before it marks the recording complete.
  const auto table = [&](const char* name, std::vector<std::string> cols, const char* comment) {
    tally_.emplace_back(name, cols);
    return std::make_unique<CsvWriter>((dir_ / (std::string(name) + ".csv")).string(), cols, comment);
  };
  imu_ = table("imu", ic, "MEMS IMU output, IMU axes");
  if (meta_.kind == RecordingKind::multipos) {
    // no reference table: the poses are found in the data
  } else if (meta_.kind == RecordingKind::bench) {
    ref_ = table("reference",
                 {"t_s", "wx_rad_s", "wy_rad_s", "wz_rad_s", "fx_m_s2", "fy_m_s2", "fz_m_s2", "step", "angle_deg"},
                 "what the table says the IMU experienced (nominal bench model)");
  } else {
    ref_ = table("reference",
                 {"t_s", "lat_deg", "lon_deg", "h_m", "vn_m_s", "ve_m_s", "vd_m_s", "roll_deg", "pitch_deg", "yaw_deg",
                  "sigma_pos_m", "sigma_vel_m_s", "sigma_att_deg"},
                 "reference inertial-satellite system");
    if (with_gnss)
      gnss_ = table("gnss",
                    {"t_s", "lat_deg", "lon_deg", "h_m", "vn_m_s", "ve_m_s", "vd_m_s", "sigma_h_m", "sigma_v_m",
                     "sigma_vel_m_s"},
                    "GNSS antenna fixes");
  }
  // A new recording in this folder (an overwrite): a table of an earlier one that this recording
  // does not have would be read as part of it (a drive without GNSS over one with gnss.csv).
  for (const char* t : kRecordingTables) {
    bool written = false;
    for (const auto& x : tally_) written = written || x.name() == t;
    if (!written) fs::remove(dir_ / (std::string(t) + ".csv"));
  }
}

RecordingWriter::~RecordingWriter() {
  // Not finished: keep what was captured, readable, and marked incomplete (meta already says so).
  if (!finished_) {
    try {
      if (imu_) imu_->close();
      if (ref_) ref_->close();
      if (gnss_) gnss_->close();
    } catch (...) {
    }
  }
}

void RecordingWriter::imu(const ImuRecord& r) {
  double v[9] = {r.t, r.gyro(0), r.gyro(1), r.gyro(2), r.accel(0), r.accel(1), r.accel(2)};
  std::size_t n = 7;
  if (temp_) v[n++] = r.temp_c;
  if (seq_) v[n++] = r.seq;
  imu_->row(v, n);
  tally_[0].add(v, n);
}

void RecordingWriter::bench_ref(const BenchRefRow& r) {
  if (meta_.kind != RecordingKind::bench) throw std::logic_error("RecordingWriter: not a bench recording");
  const double v[] = {r.t, r.w(0), r.w(1), r.w(2), r.f(0), r.f(1), r.f(2), static_cast<double>(r.step), r.angle_deg};
  ref_->row(v, std::size(v));
  tally_[1].add(v, std::size(v));
}

void RecordingWriter::drive_ref(const DriveRefRow& r) {
  if (meta_.kind != RecordingKind::drive) throw std::logic_error("RecordingWriter: not a drive recording");
  const double v[] = {r.t, r.lat_deg, r.lon_deg, r.h_m, r.v_ned(0), r.v_ned(1), r.v_ned(2), r.rpy_deg(0), r.rpy_deg(1),
                      r.rpy_deg(2), r.sigma_pos_m, r.sigma_vel_m_s, r.sigma_att_deg};
  ref_->row(v, std::size(v));
  tally_[1].add(v, std::size(v));
}

void RecordingWriter::gnss(const GnssRow& r) {
  if (!gnss_) throw std::logic_error("RecordingWriter: gnss.csv was not requested");
  const Vec3 v = r.v_ned.value_or(Vec3::Zero());
  const double row[] = {r.t, r.lat_deg, r.lon_deg, r.h_m, v(0), v(1), v(2), r.sigma_h_m, r.sigma_v_m, r.sigma_vel_m_s};
  gnss_->row(row, std::size(row));
  tally_[2].add(row, std::size(row));
}

void RecordingWriter::flush() {
  imu_->flush();
  if (ref_) ref_->flush();
  if (gnss_) gnss_->flush();
}

void RecordingWriter::finish() {
  imu_->close();
  if (ref_) ref_->close();
  if (gnss_) gnss_->close();
  verify_written_recording(dir_, tally_);  // read back as written, or not complete
  meta_.complete = true;
  write_meta(dir_, meta_);
  finished_ = true;
}

void RecordingWriter::share_table(const RecordingWriter& from, const std::string& name) {
  if (finished_ || !from.finished_)
    throw std::logic_error("RecordingWriter::share_table: '" + name + "' shared from an unfinished recording or into a finished one");
  std::unique_ptr<CsvWriter>& own = name == "reference" ? ref_ : name == "gnss" ? gnss_ : imu_;
  const auto is = [&](const TableTally& t) { return t.name() == name; };
  const auto mine = std::find_if(tally_.begin(), tally_.end(), is);
  const auto theirs = std::find_if(from.tally_.begin(), from.tally_.end(), is);
  if (name == "imu" || !own || mine == tally_.end() || theirs == from.tally_.end())
    throw std::logic_error("RecordingWriter::share_table: no shareable table '" + name + "'");
  own->close();
  link_or_copy(from.dir_ / (name + ".csv"), dir_ / (name + ".csv"));
  *mine = theirs->finished_copy();
}

void link_or_copy(const fs::path& target, const fs::path& link) {
  std::error_code ec;
  fs::remove(link, ec);
  fs::create_hard_link(target, link, ec);
  if (ec) fs::copy_file(target, link, fs::copy_options::overwrite_existing);
}

void sha256_add_file(Sha256& h, const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), 0, "", "cannot open");
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h.update(buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw InputError(file.string(), 0, "", "read error");
}

std::string sha256_file(const fs::path& file) {
  Sha256 h;
  sha256_add_file(h, file);
  return h.hex();
}

}  // namespace calbench

namespace calbench {
void check_same_unit(const DeviceId& d, const std::string& source, const fs::path& dir) {
  if (!fs::exists(dir / "meta.json")) return;
  const RecordingMeta m = read_meta(dir);
  const std::string meta = (dir / "meta.json").string();
  if (!m.device.serial.empty() && !d.serial.empty() && m.device.serial != d.serial)
    throw InputError(source, 0, "device.serial",
                     "the coefficient set is of unit '" + d.serial + "', the recording " + meta + " of unit '" + m.device.serial +
                         "': coefficients are used only with their own unit's recordings");
  if (!m.device.model.empty() && !d.model.empty() && m.device.model != d.model)
    throw InputError(source, 0, "device.model",
                     "the coefficient set is of a " + d.model + ", the recording " + meta + " of a " + m.device.model);
}
}  // namespace calbench
