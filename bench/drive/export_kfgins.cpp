#include "bench/drive/export_kfgins.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "bench/drive/kfgins_columns.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/staging_folder.hpp"
#include "bench/io/verify_recording.hpp"
#include "calibration/inmotion/priors.hpp"
#include "calibration/ins/nav_math.hpp"
#include "common/input_error.hpp"
#include "common/noise_spec.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using namespace units;

// One line of whitespace-separated numbers, each with kfgins::kDigits significant digits.
class Line {
 public:
  Line& operator<<(double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%.*g", kfgins::kDigits, x);
    if (!s_.empty()) s_ += ' ';
    s_ += b;
    return *this;
  }
  Line& operator<<(const Vec3& v) { return *this << v(0) << v(1) << v(2); }
  void to(std::ostream& os) {
    os << s_ << '\n';
    s_.clear();
  }
  void to(std::ostream& os, TextTally& tally) {  // and tallied, for the check of what was written
    s_ += '\n';
    os << s_;
    tally.add(s_);
    s_.clear();
  }

 private:
  std::string s_;
};

// Closes f and reads the file back against what was written to it.
void check_written(std::ofstream& f, const fs::path& p, TextTally& tally) {
  f.close();
  if (!f) throw std::runtime_error(p.string() + ": cannot write the file");
  verify_written_text(p, tally);
}

std::string yaml_vec(const Vec3& v) {
  Line l;
  l << v;
  std::ostringstream os;
  l.to(os);
  std::string s = os.str();
  s.pop_back();
  for (auto& c : s)
    if (c == ' ') c = ',';
  return "[" + s + "]";
}

std::string yaml_string(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

// The rows below are written in the column order of kfgins_columns.hpp (the reader's positions).
namespace I = kfgins::imu_col;
namespace G = kfgins::gnss_col;
namespace N = kfgins::nav_col;
static_assert(I::t == 0 && I::dtheta == 1 && I::dvel == 4 && I::count == 7, "imu.txt: t, dtheta xyz, dvel xyz");
static_assert(G::t == 0 && G::lat == 1 && G::lon == 2 && G::h == 3 && G::sigma_n == 4 && G::sigma_e == 5 && G::sigma_d == 6 &&
                  G::count == 7,
              "gnss.pos: t, lat, lon, h, sigma n e d");
static_assert(N::week == 0 && N::t == 1 && N::lat == 2 && N::lon == 3 && N::h == 4 && N::vel == 5 && N::rpy == 8 && N::count == 11,
              "truth.nav: week, t, lat, lon, h, v ned, roll pitch yaw");

// A geodetic position in degrees moved by a small NED displacement (m).
void move_deg(double& lat_deg, double& lon_deg, double& h, const Vec3& d_ned) {
  double lat = lat_deg * kDeg, lon = lon_deg * kDeg;
  ins::geodetic_add_ned(lat, lon, h, d_ned);
  lat_deg = lat / kDeg;
  lon_deg = lon / kDeg;
}

// The state KF-GINS starts from: position and velocity of its IMU, attitude of its IMU frame, σ.
struct Start {
  double t = 0, lat = 0, lon = 0, h = 0;
  Vec3 v = Vec3::Zero(), rpy_deg = Vec3::Zero();
  Vec3 sigma_pos = Vec3::Zero(), sigma_vel = Vec3::Zero(), sigma_att_deg = Vec3::Zero();
};

}  // namespace

ExportSummary export_kf_gins(const ExportKfGinsArgs& a) {
  ExportSummary sum;
  const fs::path dir(a.dir);
  const RecordingMeta meta = read_meta(dir);
  if (meta.kind != RecordingKind::drive || !meta.mounting)
    throw InputError((dir / "meta.json").string(), 0, "kind", "not a drive recording (KF-GINS needs a drive with its mounting)");
  if (!recording_has_table(dir, "gnss"))
    throw InputError((dir / "gnss.csv").string(), 0, "", "cannot open: KF-GINS is aided by GNSS fixes, the recording has none");
  const bool has_ref = recording_has_table(dir, "reference");
  fs::path out(a.out);
  if (out.filename().empty()) out = out.parent_path();
  if (fs::exists(out / "kf-gins.yaml") && !a.force)
    throw InputError(a.out, 0, "", "already holds a KF-GINS export (use --force to overwrite)");
  check_output_folder(out);
  fs::create_directories(out.has_parent_path() ? out.parent_path() : fs::path("."));
  const fs::path final_dir = fs::absolute(out);

  const Mat3 C_mb = ins::dcm_from_rpy(meta.mounting->rpy_deg * kDeg);  // MEMS axes -> body (FRD) axes
  const Vec3 lever = meta.mounting->lever_arm_m;                        // MEMS origin in body axes

  StagingFolder staging(out, "exporting");
  const fs::path& tmp = staging.path();
  double t_imu0 = NAN, t_imu1 = NAN;
  // The opening standstill (--standstill): sums of the increments in the IMU frame over it.
  Vec3 still_dtheta = Vec3::Zero(), still_f_sum = Vec3::Zero(), still_f_sq = Vec3::Zero();
  double still_t = 0;
  long still_n = 0;
  {
    std::ofstream f(tmp / "imu.txt");
    TextTally tally;
    ImuReader r(dir / "imu.csv", meta.imu_rate_hz);
    const bool rates = r.form() == ImuForm::rates;
    ImuRecord rec;
    Line l;
    while (r.next(rec)) {
      const double k = rates ? rec.dt : 1.0;
      const Vec3 dth = C_mb * (rec.gyro * k), dv = C_mb * (rec.accel * k);
      l << rec.t << dth << dv;
      l.to(f, tally);
      if (sum.imu_rows++ == 0) t_imu0 = rec.t;
      t_imu1 = rec.t;
      const double from = a.start_s >= 0 ? a.start_s : t_imu0;
      if (a.standstill_s > 0 && rec.t - rec.dt >= from - 1e-9 && rec.t <= from + a.standstill_s + 1e-9 && rec.dt > 0) {
        still_dtheta += dth;
        still_t += rec.dt;
        const Vec3 fs = dv / rec.dt;
        still_f_sum += fs;
        still_f_sq += fs.cwiseProduct(fs);
        ++still_n;
      }
    }
    check_written(f, tmp / "imu.txt", tally);
  }
  if (sum.imu_rows < 2) throw InputError((dir / "imu.csv").string(), 0, "", "fewer than two IMU rows");
  const double t_from = a.start_s >= 0 ? a.start_s : t_imu0;
  if (t_from > t_imu1)
    throw InputError("--start", 0, "", "after the last IMU sample (" + std::to_string(t_imu1) + " s)");
  std::optional<Start> start;
  {
    std::ofstream f(tmp / "gnss.pos");
    TextTally tally;
    GnssReader r(dir / "gnss.csv");
    GnssRow g;
    Line l;
    while (r.next(g)) {
      const double sh = std::isfinite(g.sigma_h_m) ? g.sigma_h_m : 2.0, sv = std::isfinite(g.sigma_v_m) ? g.sigma_v_m : 2 * sh;
      l << g.t << g.lat_deg << g.lon_deg << g.h_m << sh << sh << sv;
      l.to(f, tally);
      ++sum.gnss_rows;
      if (!has_ref && !start && g.t >= t_from) {  // no reference: the first fix, level, heading from its velocity
        Start s;
        s.t = g.t;
        s.lat = g.lat_deg;
        s.lon = g.lon_deg;
        s.h = g.h_m;
        const bool vel = g.v_ned.has_value();
        s.v = vel ? *g.v_ned : Vec3::Zero();
        const bool moving = vel && std::hypot(s.v(0), s.v(1)) > 2.0;
        s.rpy_deg = Vec3(0, 0, moving ? std::atan2(s.v(1), s.v(0)) / kDeg : 0.0);
        s.sigma_pos = Vec3(sh, sh, sv);
        s.sigma_vel.setConstant(vel && std::isfinite(g.sigma_vel_m_s) ? g.sigma_vel_m_s : 1.0);
        s.sigma_att_deg = Vec3(5, 5, moving ? 10 : 180);
        // The fix is of the antenna (body origin); KF-GINS starts at its IMU: the lever arm in the
        // horizontal plane is turned by the heading only.
        move_deg(s.lat, s.lon, s.h, ins::dcm_from_rpy(s.rpy_deg * kDeg) * lever);
        start = s;
      }
    }
    check_written(f, tmp / "gnss.pos", tally);
  }
  if (sum.gnss_rows == 0) throw InputError((dir / "gnss.csv").string(), 0, "", "no GNSS fixes");
  if (has_ref) {
    std::ofstream f(tmp / "truth.nav");
    TextTally tally;
    DriveRefReader r(dir / "reference.csv");
    DriveRefRow row;
    Line l;
    const Vec3 mount_sigma = inmotion::datasheet_priors().mount / kDeg;
    while (r.next(row)) {
      l << 0.0 << row.t << row.lat_deg << row.lon_deg << row.h_m << row.v_ned << row.rpy_deg;
      l.to(f, tally);
      ++sum.truth_rows;
      if (!start && row.t >= t_from - 1e-9) {
        Start s;
        s.t = row.t;
        s.lat = row.lat_deg;
        s.lon = row.lon_deg;
        s.h = row.h_m;
        s.v = row.v_ned;
        s.rpy_deg = row.rpy_deg;
        // KF-GINS's IMU sits at the lever arm from the body origin.
        move_deg(s.lat, s.lon, s.h, ins::dcm_from_rpy(row.rpy_deg * kDeg) * lever);
        const double sp = std::isfinite(row.sigma_pos_m) ? row.sigma_pos_m : 0.1;
        const double sv = std::isfinite(row.sigma_vel_m_s) ? row.sigma_vel_m_s : 0.02;
        const double sa = std::isfinite(row.sigma_att_deg) ? row.sigma_att_deg : 0.01;
        s.sigma_pos.setConstant(sp);
        s.sigma_vel.setConstant(sv);
        // The IMU frame is the body frame only through the nominal mounting: its misalignment
        // (the installation tolerance, 1° per axis) is an attitude error to KF-GINS.
        for (int i = 0; i < 3; ++i) s.sigma_att_deg(i) = std::hypot(sa, mount_sigma(i));
        start = s;
      }
    }
    check_written(f, tmp / "truth.nav", tally);
    if (sum.truth_rows == 0) throw InputError((dir / "reference.csv").string(), 0, "", "no reference rows");
  }
  if (!start) throw InputError("--start", 0, "", "no " + std::string(has_ref ? "reference epoch" : "GNSS fix") + " at or after " + std::to_string(t_from) + " s");
  sum.start_s = start->t;
  sum.init_from_reference = has_ref;

  // The data-sheet class the filter uses for raw data (noise_spec.hpp, priors.hpp), in KF-GINS units.
  // The recording's device class (meta.json device.model), or the ADIS16488A class where the model
  // is none of the built-in classes (the export does not refuse a recording the fit would: the
  // YAML says which class its noise figures are of).
  const ImuClass* cls = nullptr;
  try {
    cls = &builtin_imu_class(meta.device.model);
  } catch (const std::out_of_range&) {
    cls = &builtin_imu_class("ADIS16488A");
  }
  const NoiseSpec n = cls->noise;
  const inmotion::ParameterPriors pri = cls->priors;
  Vec3 bg_sigma = pri.gyro_bias / kDegPerHour;
  if (a.standstill_s > 0) {
    if (still_n < 10 || still_t < 0.5 * a.standstill_s)
      throw InputError("--standstill", 0, "", "the recording has too few IMU samples in the " + std::to_string(a.standstill_s) + " s after the start");
    // A vehicle that moves shows it in the specific force; standing, its spread is the sensor noise.
    const Vec3 mean = still_f_sum / still_n;
    const Vec3 sd = (still_f_sq / still_n - mean.cwiseProduct(mean)).cwiseMax(0.0).cwiseSqrt();
    if (sd.maxCoeff() > 0.2)
      throw InputError("--standstill", 0, "", "not a standstill: the specific force varies by " + std::to_string(sd.maxCoeff()) +
                                                  " m/s² (1σ) over the window (more than 0.2)");
    const Mat3 C_nb = ins::dcm_from_rpy(start->rpy_deg * kDeg);
    const Vec3 w_ie_b = C_nb.transpose() * ins::earth_rate_ned_at(start->lat * kDeg);
    sum.gyro_bias_dph = (still_dtheta / still_t - w_ie_b) / kDegPerHour;
    const double s = std::hypot(n.gyro.white_density / std::sqrt(still_t), n.gyro.drift_sigma) / kDegPerHour;
    bg_sigma.setConstant(s);
  }

  const inmotion::StabilityAllowance* allow = &cls->allowance;
  const double mgal = 1e-5;  // m/s² per mGal
  const double tau_h = n.gyro.drift_tau_s / 3600.0;
  std::ostringstream y;
  y << "# KF-GINS configuration written by `calbench export kf-gins` from " << dir.string() << "\n"
    << "# IMU frame = calbench's reference body frame (forward-right-down) through the nominal mounting\n"
    << "# rpy " << yaml_vec(meta.mounting->rpy_deg) << " deg of meta.json; initial state "
    << (has_ref ? "from reference.csv (position moved to the IMU by the lever arm)" : "from the first fix (level; heading from its velocity)")
    << "\n# IMU noise: " << cls->name << " data-sheet class (" << cls->file << ")\n"
    << "imupath: " << yaml_string((final_dir / "imu.txt").string()) << "\n"
    << "gnsspath: " << yaml_string((final_dir / "gnss.pos").string()) << "\n"
    << "outputpath: " << yaml_string(final_dir.string()) << "\n"
    << "imudatalen: " << I::count << "\n"
    << "imudatarate: " << std::lround(meta.imu_rate_hz) << "\n";
  Line l;
  auto put = [&](const char* key, double v) {
    l << v;
    y << key << ": ";
    l.to(y);
  };
  put("starttime", start->t);
  y << "endtime: -1\n"
    << "initpos: " << yaml_vec(Vec3(start->lat, start->lon, start->h)) << "\n"
    << "initvel: " << yaml_vec(start->v) << "\n"
    << "initatt: " << yaml_vec(start->rpy_deg) << "\n"
    << "initgyrbias: " << yaml_vec(sum.gyro_bias_dph)
    << (a.standstill_s > 0 ? "  # mean rate over the opening standstill less the Earth rate\n" : "\n")
    << "initaccbias: [0, 0, 0]\ninitgyrscale: [0, 0, 0]\ninitaccscale: [0, 0, 0]\n"
    << "initposstd: " << yaml_vec(start->sigma_pos) << "\n"
    << "initvelstd: " << yaml_vec(start->sigma_vel) << "\n"
    << "initattstd: " << yaml_vec(start->sigma_att_deg) << "\n"
    << "# initial sensor-error spread: calbench's raw-data priors (bias, scale = diagonal of M; KF-GINS has no skew state)\n"
    << "initbgstd: " << yaml_vec(bg_sigma) << "\n"
    << "initbastd: " << yaml_vec(pri.accel_bias / mgal) << "\n"
    << "initsgstd: " << yaml_vec(pri.gyro_M.diagonal() / kPpm) << "\n"
    << "initsastd: " << yaml_vec(pri.accel_M.diagonal() / kPpm) << "\n"
    << "# in-run: white noise, bias instability (Gauss-Markov), scale stability allowance\n"
    << "imunoise:\n"
    << "  arw: " << yaml_vec(Vec3::Constant(n.gyro.white_density / kDeg * kSqrtHour)) << "\n"
    << "  vrw: " << yaml_vec(Vec3::Constant(n.accel.white_density * kSqrtHour)) << "\n"
    << "  gbstd: " << yaml_vec(Vec3::Constant(n.gyro.drift_sigma / kDegPerHour)) << "\n"
    << "  abstd: " << yaml_vec(Vec3::Constant(n.accel.drift_sigma / mgal)) << "\n"
    << "  gsstd: " << yaml_vec(Vec3::Constant((allow ? allow->gyro_scale : 300 * kPpm) / kPpm)) << "\n"
    << "  asstd: " << yaml_vec(Vec3::Constant((allow ? allow->accel_scale : 300 * kPpm) / kPpm)) << "\n"
    << "  corrtime: ";
  l << tau_h;
  l.to(y);
  y << "antlever: " << yaml_vec(-lever) << "\n";
  write_text_atomic(tmp / "kf-gins.yaml", y.str());

  if (!fs::exists(out)) {
    fs::rename(tmp, out);
    staging.keep();
  } else {  // --force, or an existing folder: replace the export's files, the configuration last
    for (const char* f : {"imu.txt", "gnss.pos", "truth.nav", "kf-gins.yaml"})
      if (fs::exists(tmp / f)) fs::rename(tmp / f, out / f);
      else if (std::string(f) == "truth.nav") fs::remove(out / f);
  }
  return sum;
}

}  // namespace calbench
