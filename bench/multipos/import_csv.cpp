#include "bench/multipos/import_csv.hpp"

#include <algorithm>
#include <utility>

#include "bench/io/csv.hpp"
#include "bench/io/message_text.hpp"
#include "common/input_error.hpp"

namespace calbench {
namespace {

// The rows of the file, in SI, one at a time.
class CsvRows {
 public:
  explicit CsvRows(const ImportCsvArgs& a)
      : r_(a.file, false, a.delimiter),
        gyro_si_(gyro_unit_si(a.gyro_unit)),
        accel_si_(accel_unit_si(a.accel_unit)),
        time_si_(time_unit_si(a.time_unit)) {
    time_ = select("--time", a.time_col);
    for (int i = 0; i < 3; ++i) {
      gyro_[i] = select("--gyro", a.gyro_cols[static_cast<std::size_t>(i)]);
      accel_[i] = select("--accel", a.accel_cols[static_cast<std::size_t>(i)]);
    }
    // Seven different columns: one column for two quantities is a mistake in the options.
    const std::pair<const Column*, std::string> roles[7] = {
        {&time_, "--time"},      {&gyro_[0], "--gyro x"},  {&gyro_[1], "--gyro y"},  {&gyro_[2], "--gyro z"},
        {&accel_[0], "--accel x"}, {&accel_[1], "--accel y"}, {&accel_[2], "--accel z"}};
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < i; ++j)
        if (roles[i].first->index == roles[j].first->index)
          throw InputError(r_.path(), r_.line(), roles[i].second,
                           "column " + std::to_string(roles[i].first->index + 1) + " ('" +
                               field_text(r_.header()[roles[i].first->index]) + "') is given for both " +
                               roles[j].second + " and " + roles[i].second);
  }
  bool next(double& t, Vec3& f, Vec3& w) {
    if (!r_.next()) return false;
    t = r_.value(time_.slot) * time_si_;
    for (int i = 0; i < 3; ++i) {
      w(i) = r_.value(gyro_[i].slot) * gyro_si_;
      f(i) = r_.value(accel_[i].slot) * accel_si_;
      check_range(r_, gyro_[i].index, w(i), -1e3, 1e3, "gyro (rad/s or rad, after the unit)");
      check_range(r_, accel_[i].index, f(i), -1e4, 1e4, "accelerometer (m/s² or m/s, after the unit)");
    }
    return true;
  }
  const CsvReader& reader() const { return r_; }
  // Increments: the rates they make over their interval within what every reader of recordings
  // accepts (bench/io/plausible.hpp); named at this row and column.
  void check_increment_rates(const ImuRecord& rec) const {
    for (int i = 0; i < 3; ++i) {
      check_range(r_, gyro_[i].index, rec.gyro(i) / rec.dt, -plausible::kMaxAngularRate_rad_s,
                  plausible::kMaxAngularRate_rad_s, "angular rate of the increment (rad/s)");
      check_range(r_, accel_[i].index, rec.accel(i) / rec.dt, -plausible::kMaxSpecificForce_m_s2,
                  plausible::kMaxSpecificForce_m_s2, "specific force of the increment (m/s²)");
    }
  }

 private:
  struct Column {
    int slot = -1;
    std::size_t index = 0;  // 0-based, in the header
  };
  // By header name, or by 1-based index when the text is all digits.
  Column select(const char* option, const std::string& col) {
    const auto& h = r_.header();
    std::size_t idx = h.size();
    if (!col.empty() && std::all_of(col.begin(), col.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      idx = col.size() < 6 ? static_cast<std::size_t>(std::stoul(col)) : 0;
      if (idx < 1 || idx > h.size())
        throw InputError(r_.path(), r_.line(), option,
                         "column " + field_text(col) + " does not exist (the header has " + std::to_string(h.size()) +
                             " columns)");
      --idx;
    } else {
      idx = static_cast<std::size_t>(std::find(h.begin(), h.end(), col) - h.begin());
    }
    if (idx < h.size() && std::count(h.begin(), h.end(), h[idx]) > 1)
      throw InputError(r_.path(), r_.line(), option,
                       "the header names '" + field_text(h[idx]) + "' " + std::to_string(std::count(h.begin(), h.end(), h[idx])) +
                           " times: which column is meant cannot be told (rename the columns in the header line)");
    Column c;
    c.slot = r_.require(idx < h.size() ? h[idx] : col);
    c.index = idx;
    return c;
  }
  CsvReader r_;
  double gyro_si_, accel_si_, time_si_;
  Column time_, gyro_[3], accel_[3];
};

}  // namespace

ImportCsvSummary import_csv(const ImportCsvArgs& a) {
  ImportCsvSummary sum;
  const std::filesystem::path out = check_multipos_target(a);
  std::vector<double> dts;
  {
    CsvRows r(a);
    sum.rows = scan_rows([&](double& t, Vec3& f, Vec3& w) { return r.next(t, f, w); }, r.reader(), dts);
    if (sum.rows < 2) throw InputError(a.file, 0, "", "needs at least two data rows");
    sum.delimiter = r.reader().delimiter();
  }
  sum.rate_hz = multipos_rate(a, dts);
  RecordingMeta meta = multipos_meta(a, sum.rate_hz);
  meta.notes = "imported from CSV " + a.file + " (gyro " + a.gyro_unit + (a.increments ? " increments" : "") +
               ", accelerometer " + a.accel_unit + ", time " + a.time_unit + ")";
  write_multipos(out, meta, a.increments ? ImuForm::increments : ImuForm::rates, [&](RecordingWriter& wr) {
    CsvRows r(a);
    ImuRecord rec;
    double last = 0;
    for (bool first = true; r.next(rec.t, rec.accel, rec.gyro); first = false) {
      rec.dt = first ? 1.0 / sum.rate_hz : rec.t - last;
      last = rec.t;
      if (a.increments) r.check_increment_rates(rec);  // the reader's bounds apply to the rates they make
      wr.imu(rec);
    }
  });
  return sum;
}

}  // namespace calbench
