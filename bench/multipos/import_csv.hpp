// calbench import csv: one CSV with a header line, as generic loggers write it, into a multipos
// recording (../shared/spec/recording-format.md, kind "multipos"). Columns are chosen by header name
// or 1-based index; units and the delimiter (',', ';', tab or blanks; auto from the header) are
// options; rows are rates or, with `increments`, angle and velocity increments per sample.
#pragma once
#include <array>
#include <string>

#include "bench/multipos/multipos_import.hpp"

namespace calbench {

struct ImportCsvArgs : MultiposTarget {
  std::string file;
  std::string time_col = "t";
  std::array<std::string, 3> gyro_cols{"gx", "gy", "gz"}, accel_cols{"ax", "ay", "az"};
  std::string gyro_unit = "rad/s", accel_unit = "m/s2", time_unit = "s";
  bool increments = false;
  char delimiter = 0;  // 0: from the header line (CsvReader)
};

struct ImportCsvSummary {
  std::size_t rows = 0;
  double rate_hz = 0;
  char delimiter = ',';
};

// InputError naming file, line and column on anything malformed; nothing is written then.
ImportCsvSummary import_csv(const ImportCsvArgs& a);

}  // namespace calbench
