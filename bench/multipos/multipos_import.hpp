// What every importer into a multipos recording shares (import imu-tk, import csv): the meta.json
// of the kind (device, rate, gravity or site), the checks before anything is written, and the
// atomic write (staging folder, RecordingWriter read-back, then the rename).
#pragma once
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bench/io/recording.hpp"
#include "bench/io/text_rows.hpp"

namespace calbench {

struct MultiposTarget {
  std::string out;
  std::string model = "unknown", serial = "unknown";
  double rate_hz = 0;  // 0: from the median interval
  std::optional<double> gravity_m_s2;
  std::optional<double> lat_deg, h_m;
  bool force = false;
};

// The output folder (import_output_folder: refused when it holds a recording, unless force); refuses
// a gravity not on Earth. Call before reading anything.
std::filesystem::path check_multipos_target(const MultiposTarget& t);

// The first pass over an importer's rows: next(t, f, w) until false, time checked at reader's line
// (check_time), the intervals into dts; returns the number of rows.
template <class Next, class Reader>
std::size_t scan_rows(Next next, const Reader& reader, std::vector<double>& dts) {
  double t = 0, last = 0;
  bool first = true;
  Vec3 f, w;
  std::size_t rows = 0;
  while (next(t, f, w)) {
    if (!first) dts.push_back(t - last);
    check_time(reader, t, last, first);
    ++rows;
  }
  return rows;
}

// The rate: 1 / the median of the intervals (dts is reordered), or t.rate_hz when given and within 1 %
// of it (else an InputError naming --rate: a wrong time unit is the usual cause); a rate outside
// 1 Hz – 50 kHz is an InputError naming --time-unit.
double multipos_rate(const MultiposTarget& t, std::vector<double>& dts);

RecordingMeta multipos_meta(const MultiposTarget& t, double rate_hz);

// "" when a built-in device class has the name or alias `model`; else the note the writers of a
// multipos recording print: the model is fine, but fit multipos will need --device-class.
std::string unknown_model_note(const std::string& model);

// SI per unit of the importers' unit options (--gyro-unit rad/s|deg/s|mdeg/s, --accel-unit
// m/s2|g|mg, --time-unit s|ms|us|ns); an InputError naming the option for anything else.
double gyro_unit_si(const std::string& unit);
double accel_unit_si(const std::string& unit);
double time_unit_si(const std::string& unit);

// Writes the recording into a staging folder with `rows`, reads it back (RecordingWriter::finish),
// then places it at `out` (place_staged_recording). `truth`, when given, writes a simulated
// recording's truth.json (the convention of every simulate command: beside meta.json) at the path
// it is handed, in the staging folder, after `rows`: it is placed with the recording, or not at all.
void write_multipos(const std::filesystem::path& out, const RecordingMeta& meta, ImuForm form,
                    const std::function<void(RecordingWriter&)>& rows,
                    const std::function<void(const std::filesystem::path&)>& truth = {});

}  // namespace calbench
