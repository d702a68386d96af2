#include "bench/drive/import_kfgins.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <vector>

#include "bench/drive/kfgins_columns.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/message_text.hpp"
#include "common/number_parse.hpp"
#include "bench/io/plausible.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/staging_folder.hpp"
#include "bench/io/text_rows.hpp"

namespace calbench {
namespace {

namespace I = kfgins::imu_col;
namespace G = kfgins::gnss_col;
namespace N = kfgins::nav_col;

void write_recording(const ImportKfGinsArgs& a, const RecordingMeta& meta, const fs::path& out, ImportSummary& sum,
                     std::vector<double>& v);

}  // namespace

ImportSummary import_kf_gins(const ImportKfGinsArgs& a) {
  ImportSummary sum;
  const fs::path out = import_output_folder(a.out, a.force);
  std::vector<double> v;
  // IMU rate: given, or the median interval of the first rows.
  double rate = a.rate_hz;
  if (!(rate > 0)) {
    TextRows r(a.imu, I::count);
    std::vector<double> dts;
    double last = 0;
    bool first = true;
    while (dts.size() < 1000 && r.next(v)) {
      if (!first) dts.push_back(v[I::t] - last);
      check_time(r, v[I::t], last, first);
    }
    if (dts.empty()) throw InputError(a.imu, 0, "", "needs at least two IMU rows");
    rate = rate_from_intervals(dts);
  }
  sum.rate_hz = rate;
  RecordingMeta meta;
  meta.kind = RecordingKind::drive;
  meta.device = DeviceId{a.model, a.serial};
  meta.imu_rate_hz = rate;
  meta.mounting = Mounting{a.mounting_rpy_deg, a.lever_arm_m};
  meta.notes = "imported from KF-GINS text files: IMU " + a.imu + ", reference " + a.truth +
               (a.gnss.empty() ? std::string() : ", GNSS " + a.gnss);
  // Written into a folder beside --out and renamed into place at the end: an import that fails
  // (bad input, a full disk) or is killed leaves no half-written recording under --out.
  StagingFolder staging(out, "importing");
  write_recording(a, meta, staging.path(), sum, v);
  place_staged_recording(staging, out, {"imu.csv", "reference.csv", "gnss.csv", "meta.json"});
  return sum;
}

namespace {
void write_recording(const ImportKfGinsArgs& a, const RecordingMeta& meta, const fs::path& out, ImportSummary& sum,
                     std::vector<double>& v) {
  RecordingWriter w(out, meta, ImuForm::increments, false, false, !a.gnss.empty());
  {
    TextRows r(a.imu, I::count);
    double last = 0;
    bool first = true;
    while (r.next(v)) {
      check_time(r, v[I::t], last, first);
      for (std::size_t k = I::dtheta; k < I::count; ++k) check_range(r, k, v[k], -1e6, 1e6, "increment");
      ImuRecord rec;
      rec.t = v[I::t];
      rec.gyro = Vec3(v[I::dtheta], v[I::dtheta + 1], v[I::dtheta + 2]);
      rec.accel = Vec3(v[I::dvel], v[I::dvel + 1], v[I::dvel + 2]);
      w.imu(rec);
      ++sum.imu_rows;
    }
  }
  {
    TextRows r(a.truth, N::count);
    double last = 0;
    bool first = true;
    while (r.next(v)) {
      check_time(r, v[N::t], last, first);
      check_range(r, N::lat, v[N::lat], -90, 90, "latitude (deg)");
      check_range(r, N::lon, v[N::lon], -360, 360, "longitude (deg)");
      check_range(r, N::h, v[N::h], -1e5, 1e7, "height (m)");
      for (std::size_t k = N::vel; k < N::vel + 3; ++k) check_range(r, k, v[k], -1e4, 1e4, "velocity (m/s)");
      for (std::size_t k = N::rpy; k < N::rpy + 3; ++k) check_range(r, k, v[k], -720, 720, "attitude angle (deg)");
      DriveRefRow row;
      row.t = v[N::t];
      row.lat_deg = v[N::lat];
      row.lon_deg = v[N::lon];
      row.h_m = v[N::h];
      row.v_ned = Vec3(v[N::vel], v[N::vel + 1], v[N::vel + 2]);
      row.rpy_deg = Vec3(v[N::rpy], v[N::rpy + 1], v[N::rpy + 2]);
      row.sigma_pos_m = a.ref_sigma_pos_m;
      row.sigma_vel_m_s = a.ref_sigma_vel_m_s;
      row.sigma_att_deg = a.ref_sigma_att_deg;
      w.drive_ref(row);
      ++sum.ref_rows;
    }
    // A drive recording without its reference is no recording (the import went "fine" with 0 rows).
    if (sum.ref_rows == 0) throw InputError(a.truth, 0, "", "no truth rows (week, t, lat, lon, h, vn, ve, vd, roll, pitch, yaw)");
  }
  // A file without data rows would give a recording calbench's readers refuse ("no data rows").
  if (sum.imu_rows == 0) throw InputError(a.imu, 0, "", "no data rows (IMU increments: t, dθ x/y/z, dv x/y/z)");
  if (!a.gnss.empty()) {
    TextRows r(a.gnss, G::count);
    double last = 0;
    bool first = true;
    while (r.next(v)) {
      check_time(r, v[G::t], last, first, std::numeric_limits<double>::infinity());  // fixes may pause for long
      check_range(r, G::lat, v[G::lat], -90, 90, "latitude (deg)");
      check_range(r, G::lon, v[G::lon], -360, 360, "longitude (deg)");
      check_range(r, G::h, v[G::h], -1e5, 1e7, "height (m)");
      for (std::size_t k = G::sigma_n; k <= G::sigma_d; ++k) check_range(r, k, v[k], 0, 1e6, "standard deviation (m)");
      GnssRow g;
      g.t = v[G::t];
      g.lat_deg = v[G::lat];
      g.lon_deg = v[G::lon];
      g.h_m = v[G::h];
      // The horizontal σ per axis (RMS of north and east); equal σ taken as they are, so that an
      // exported .pos file reads back to the values written (hypot/√2 is off by an ulp).
      g.sigma_h_m = v[G::sigma_n] == v[G::sigma_e] ? v[G::sigma_n] : std::hypot(v[G::sigma_n], v[G::sigma_e]) / std::sqrt(2.0);
      g.sigma_v_m = v[G::sigma_d];
      // .pos files carry no velocity; RecordingWriter always writes the velocity columns, so it
      // is written as 0 with sigma_vel_m_s = 1e6 (unknown).
      g.sigma_vel_m_s = 1e6;
      w.gnss(g);
      ++sum.gnss_rows;
    }
    if (sum.gnss_rows == 0) throw InputError(a.gnss, 0, "", "no GNSS fixes (t, lat, lon, h, std n/e/u); leave out --gnss for none");
  }
  w.finish();
}
}  // namespace

}  // namespace calbench
