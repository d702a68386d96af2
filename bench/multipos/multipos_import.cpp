#include "bench/multipos/multipos_import.hpp"

#include <cmath>
#include <initializer_list>
#include <utility>

#include "bench/io/imu_class_toml.hpp"
#include "bench/io/message_text.hpp"
#include "bench/io/staging_folder.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"

namespace calbench {

std::filesystem::path check_multipos_target(const MultiposTarget& t) {
  std::filesystem::path out = import_output_folder(t.out, t.force);
  if (t.gravity_m_s2 && !(*t.gravity_m_s2 >= 9.7 && *t.gravity_m_s2 <= 9.9))
    throw InputError("--gravity", 0, "", number_text(*t.gravity_m_s2) + " m/s² is not gravity on Earth (9.7–9.9)");
  return out;
}

double multipos_rate(const MultiposTarget& t, std::vector<double>& dts) {
  const double from_stamps = rate_from_intervals(dts);
  // An IMU samples at 1 Hz … 50 kHz: outside, the time column's unit is wrong (ms read as s gives a
  // tenth of a hertz), and the fit would refuse every pose later without saying why.
  if (!(from_stamps >= 1.0 && from_stamps <= 5e4))
    throw InputError("--time-unit", 0, "", "the time stamps give " + number_text(from_stamps) +
                                               " Hz (median interval), not an IMU's rate (1 Hz – 50 kHz): is --time-unit right?");
  if (!(t.rate_hz > 0)) return from_stamps;
  if (std::abs(t.rate_hz - from_stamps) > 0.01 * from_stamps)
    throw InputError("--rate", 0, "", number_text(t.rate_hz) + " Hz contradicts the time stamps (median interval: " +
                                         number_text(from_stamps) + " Hz; is --time-unit right?)");
  return t.rate_hz;
}

namespace {
double unit_si(const char* option, const std::string& unit,
               std::initializer_list<std::pair<const char*, double>> table) {
  std::string names;
  for (const auto& [name, si] : table) {
    if (unit == name) return si;
    names += names.empty() ? name : std::string(", ") + name;
  }
  throw InputError(option, 0, "", "unknown unit '" + field_text(unit) + "' (one of " + names + ")");
}
}  // namespace

double gyro_unit_si(const std::string& u) {
  return unit_si("--gyro-unit", u, {{"rad/s", 1.0}, {"deg/s", units::kDeg}, {"mdeg/s", 1e-3 * units::kDeg}});
}
double accel_unit_si(const std::string& u) {
  return unit_si("--accel-unit", u, {{"m/s2", 1.0}, {"g", units::kG0}, {"mg", units::kMilliG}});
}
double time_unit_si(const std::string& u) {
  return unit_si("--time-unit", u, {{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}, {"ns", 1e-9}});
}

RecordingMeta multipos_meta(const MultiposTarget& t, double rate_hz) {
  RecordingMeta meta;
  meta.kind = RecordingKind::multipos;
  meta.device = DeviceId{t.model, t.serial};
  meta.imu_rate_hz = rate_hz;
  if (t.lat_deg) {
    meta.site = Site{*t.lat_deg, 0.0, t.h_m.value_or(0.0)};
    meta.site_has_lon = false;
  }
  if (t.gravity_m_s2) meta.extra["gravity_m_s2"] = *t.gravity_m_s2;
  return meta;
}

std::string unknown_model_note(const std::string& model) {
  if (find_builtin_imu_class(model)) return {};
  return "no built-in device class is named '" + model + "': fit multipos measures the noise on the recording and takes "
         "wide drift priors; --device-class NAME|FILE gives a class (bench/imu_classes/*.toml shows the format; known: " +
         known_imu_classes_text() + ")";
}

void write_multipos(const std::filesystem::path& out, const RecordingMeta& meta, ImuForm form,
                    const std::function<void(RecordingWriter&)>& rows,
                    const std::function<void(const std::filesystem::path&)>& truth) {
  StagingFolder staging(out, "importing");
  {
    RecordingWriter wr(staging.path(), meta, form, false, false, false);
    rows(wr);
    wr.finish();  // read back against what was written before "complete"
  }
  if (!truth) {
    place_staged_recording(staging, out, {"imu.csv", "meta.json"});
    return;
  }
  truth(staging.path() / "truth.json");
  place_staged_recording(staging, out, {"imu.csv", "truth.json", "meta.json"});
}

}  // namespace calbench
