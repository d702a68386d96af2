// The recording interchange format (../shared/spec/recording-format.md): a folder with meta.json,
// imu.csv, reference.csv and, for drives, an optional gnss.csv. Readers stream row by row;
// writers write as they go and mark meta.json "complete" only when finished, so an interrupted
// writer leaves a readable recording marked incomplete.
#pragma once
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "bench/io/csv.hpp"
#include "bench/io/verify_recording.hpp"
#include "calibration/bench_plan.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

namespace fs = std::filesystem;

// multipos: a unit turned between static poses, no reference (spec, kind "multipos").
enum class RecordingKind { bench, drive, multipos };

struct Mounting {
  Vec3 rpy_deg = Vec3::Zero();      // MEMS IMU frame -> reference body frame
  Vec3 lever_arm_m = Vec3::Zero();  // MEMS IMU origin in reference body frame
};

struct RecordingMeta {
  RecordingKind kind = RecordingKind::bench;
  DeviceId device;
  std::optional<Site> site;          // required for bench; multipos: lat/h only (lon optional)
  bool site_has_lon = true;          // false for a multipos site given without lon_deg
  double imu_rate_hz = 0;
  std::optional<Mounting> mounting;  // required for drive
  std::string notes;
  bool complete = true;              // calbench's own key "status": "complete" | "incomplete"
  nlohmann::json extra = nlohmann::json::object();  // keys calbench does not interpret, kept
};

RecordingMeta read_meta(const fs::path& dir);
// Atomic: written to a temporary file and renamed into place.
void write_meta(const fs::path& dir, const RecordingMeta& meta);
const char* kind_name(RecordingKind k);

// One IMU row. `rates` form: gyro in rad/s, accel in m/s². `increments` form: gyro = Δθ (rad),
// accel = Δv (m/s) over the interval of length dt that ends at t.
struct ImuRecord {
  double t = 0;
  double dt = 0;
  Vec3 gyro = Vec3::Zero();
  Vec3 accel = Vec3::Zero();
  double temp_c = std::numeric_limits<double>::quiet_NaN();
  double seq = -1;  // device sample counter, −1 if absent
};

enum class ImuForm { rates, increments };

// A table of the recording: `file` (dir/NAME.csv) when it exists, else the dataset NAME of
// dir/recording.h5 when that file exists (hdf5_recording.hpp). digest: SHA-256 of the file read
// alongside (TableSource::sha256()).
std::unique_ptr<TableSource> open_table(const fs::path& file, bool digest = false);

// IMU rows, parsed ahead on a thread of their own into a bounded queue (a few blocks of rows), so
// that the consumer (the filter) does not wait for parsing when a second core is free. An input
// error is raised at the row where it was found, after the rows before it.
class ImuReader {
 public:
  // nominal_rate_hz gives dt of the first row.
  ImuReader(const fs::path& file, double nominal_rate_hz, bool digest = false);
  ~ImuReader();
  ImuReader(const ImuReader&) = delete;
  ImuReader& operator=(const ImuReader&) = delete;
  bool next(ImuRecord& r);
  ImuForm form() const { return form_; }
  bool has_temperature() const { return temp_ >= 0; }
  const std::string& path() const { return tab_->path(); }
  std::size_t line() const { return line_; }  // line (CSV) or row (HDF5) of the row last returned
  // SHA-256 of the file once read to its end with digest requested; nullopt otherwise.
  std::optional<std::string> sha256() const;

 private:
  struct Batch;
  struct Queue;
  void produce();
  std::unique_ptr<TableSource> tab_;
  ImuForm form_ = ImuForm::rates;
  int t_, g_[3], a_[3], temp_, seq_;
  const char* g_name_[3] = {};  // the columns of g_ and a_, for messages
  const char* a_name_[3] = {};
  double nominal_dt_;
  std::unique_ptr<Queue> q_;
  std::unique_ptr<Batch> cur_;
  std::size_t pos_ = 0, line_ = 0;
  bool done_ = false;
};

struct BenchRefRow {
  double t = 0;
  Vec3 w = Vec3::Zero();  // rad/s, IMU axes, w.r.t. inertial space
  Vec3 f = Vec3::Zero();  // m/s², specific force in IMU axes
  int step = -1;
  double angle_deg = std::numeric_limits<double>::quiet_NaN();
};

class BenchRefReader {
 public:
  explicit BenchRefReader(const fs::path& file);
  bool next(BenchRefRow& r);
  bool has_angle() const { return angle_ >= 0; }

 private:
  std::unique_ptr<TableSource> csv_;
  int t_, w_[3], f_[3], step_, angle_;
};

struct DriveRefRow {
  double t = 0;
  double lat_deg = 0, lon_deg = 0, h_m = 0;
  Vec3 v_ned = Vec3::Zero();
  Vec3 rpy_deg = Vec3::Zero();  // roll, pitch, yaw of the reference body (forward-right-down)
  double sigma_pos_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_vel_m_s = std::numeric_limits<double>::quiet_NaN();
  double sigma_att_deg = std::numeric_limits<double>::quiet_NaN();
};

class DriveRefReader {
 public:
  explicit DriveRefReader(const fs::path& file, bool digest = false);
  bool next(DriveRefRow& r);
  std::optional<std::string> sha256() const { return csv_->sha256(); }

 private:
  std::unique_ptr<TableSource> csv_;
  int t_, lat_, lon_, h_, v_[3], att_[3], sp_, sv_, sa_;
};

struct GnssRow {
  double t = 0;
  double lat_deg = 0, lon_deg = 0, h_m = 0;
  std::optional<Vec3> v_ned;
  double sigma_h_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_v_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_vel_m_s = std::numeric_limits<double>::quiet_NaN();
};

class GnssReader {
 public:
  explicit GnssReader(const fs::path& file, bool digest = false);
  bool next(GnssRow& r);
  std::optional<std::string> sha256() const { return csv_->sha256(); }

 private:
  std::unique_ptr<TableSource> csv_;
  int t_, lat_, lon_, h_, v_[3], sh_, sv_, svel_;
};

// Writes a recording folder. meta.json is written first with status "incomplete" and rewritten
// as "complete" by finish(), once the tables read back as written (verify_written_recording). Rows are buffered and flushed every `flush_every` seconds of data.
class RecordingWriter {
 public:
  RecordingWriter(const fs::path& dir, RecordingMeta meta, ImuForm form = ImuForm::rates,
                  bool with_temperature = true, bool with_seq = false, bool with_gnss = false);
  ~RecordingWriter();
  void imu(const ImuRecord& r);
  void bench_ref(const BenchRefRow& r);
  void drive_ref(const DriveRefRow& r);
  void gnss(const GnssRow& r);
  void flush();
  void finish();  // close files, mark complete
  // Units of one drive share its reference (and GNSS) file: before finish(), this recording's
  // table `name` ("reference" or "gnss") becomes the file `from` wrote (link_or_copy; `from` has
  // finished), and finish() checks what this folder then holds against what `from` wrote.
  void share_table(const RecordingWriter& from, const std::string& name);
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
  RecordingMeta meta_;
  ImuForm form_;
  bool temp_, seq_;
  std::unique_ptr<CsvWriter> imu_, ref_, gnss_;
  std::vector<TableTally> tally_;
  bool finished_ = false;
};

// Replaces `link` by a hard link to `target` (the same file, no second copy), or by a copy where the
// file system has no hard links.
void link_or_copy(const fs::path& target, const fs::path& link);

// SHA-256 of a file, hex; sha256_add_file feeds a file's bytes into a digest being computed.
std::string sha256_file(const fs::path& file);
class Sha256;
void sha256_add_file(Sha256& h, const fs::path& file);

// Provenance at a hand-over: a coefficient set (from `source`, a file or an option) used with the
// recording in `dir` must be of the recording's unit — same serial and model as its meta.json (an
// empty serial or model on either side is not compared). InputError naming both otherwise.
void check_same_unit(const DeviceId& set_device, const std::string& source, const fs::path& dir);

}  // namespace calbench
