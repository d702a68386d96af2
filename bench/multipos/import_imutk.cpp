#include "bench/multipos/import_imutk.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "bench/io/json_util.hpp"
#include "bench/io/message_text.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/text_rows.hpp"
#include "common/input_error.hpp"

namespace calbench {
namespace {

nlohmann::json counts_json(const CountsConversion& c) {
  return {{"offset", {c.offset(0), c.offset(1), c.offset(2)}}, {"scale", {c.scale(0), c.scale(1), c.scale(2)}}};
}

// The two files advance together, row by row, with the same time stamps (IMU-TK's format).
struct PairReader {
  TextRows acc, gyro;
  std::vector<double> va, vg;
  std::size_t rows_ = 0;
  double time_si;  // seconds per unit of the files' time column
  PairReader(const ImportImuTkArgs& a)
      : acc(a.acc, 4, 4), gyro(a.gyro, 4, 4), time_si(time_unit_si(a.time_unit)) {}  // t x y z, nothing else
  bool next(const ImportImuTkArgs& a, double& t, Vec3& f, Vec3& w) {
    const bool ha = acc.next(va), hg = gyro.next(vg);
    if (ha != hg) {
      const TextRows& shorter = ha ? gyro : acc;
      TextRows& longer = ha ? acc : gyro;
      // The shorter file's last line was cut (dropped with a warning): its pair in the other file goes
      // too, when it is that file's last row.
      if (std::vector<double> extra; shorter.truncated() && !longer.next(extra)) {
        input_warning(longer.path(), longer.line(), "last row left out with the truncated last line of " + shorter.path());
        return false;
      }
      if (rows_ == 0) throw InputError(shorter.path(), shorter.line(), "", "no data rows (t x y z)");
      throw InputError(shorter.path(), shorter.line(), "",
                       "ends before " + (ha ? acc : gyro).path() + " (line " + std::to_string((ha ? acc : gyro).line()) +
                           "): the two files must have the same rows");
    }
    if (!ha) return false;
    ++rows_;
    t = va[0] * time_si;
    const double tg = vg[0] * time_si;
    if (!(std::abs(t - tg) <= 1e-6 * std::max(1.0, std::abs(t))))
      throw InputError(gyro.path(), gyro.line(), "column 1",
                       "time " + number_text(tg) + " s differs from " + acc.path() + " line " + std::to_string(acc.line()) +
                           " (" + number_text(t) + " s): the two files must share their time stamps");
    for (int i = 0; i < 3; ++i) {
      f(i) = (va[1 + i] - a.acc_counts.offset(i)) * a.acc_counts.scale(i);
      w(i) = (vg[1 + i] - a.gyro_counts.offset(i)) * a.gyro_counts.scale(i);
    }
    for (int i = 0; i < 3; ++i) {
      // Raw counts read as SI land here: say which options convert them (issue 56 item 14).
      check_range(acc, 1 + i, f(i), -1e4, 1e4,
                  a.acc_counts.given ? "specific force (m/s², after --acc-offset/--acc-scale)"
                                     : "specific force (m/s²; raw counts need --acc-offset and --acc-scale)");
      check_range(gyro, 1 + i, w(i), -1e3, 1e3,
                  a.gyro_counts.given ? "angular rate (rad/s, after --gyro-offset/--gyro-scale)"
                                      : "angular rate (rad/s; raw counts need --gyro-offset and --gyro-scale)");
    }
    return true;
  }
};

}  // namespace

ImportImuTkSummary import_imu_tk(const ImportImuTkArgs& a) {
  ImportImuTkSummary sum;
  const std::filesystem::path out = check_multipos_target(a);
  std::vector<double> dts;
  {
    PairReader r(a);
    sum.rows = scan_rows([&](double& t, Vec3& f, Vec3& w) { return r.next(a, t, f, w); }, r.acc, dts);
    if (sum.rows < 2) throw InputError(a.acc, 0, "", "needs at least two rows");
  }
  sum.rate_hz = multipos_rate(a, dts);
  RecordingMeta meta = multipos_meta(a, sum.rate_hz);
  if (a.acc_counts.given || a.gyro_counts.given)
    meta.extra["source_counts"] = {{"gyro", counts_json(a.gyro_counts)}, {"accel", counts_json(a.acc_counts)}};
  meta.notes = "imported from IMU-TK text files: accelerometer " + a.acc + ", gyro " + a.gyro + " (time unit " +
               a.time_unit + ")";
  write_multipos(out, meta, ImuForm::rates, [&](RecordingWriter& wr) {
    PairReader r(a);
    ImuRecord rec;
    while (r.next(a, rec.t, rec.accel, rec.gyro)) wr.imu(rec);
  });
  return sum;
}

}  // namespace calbench
