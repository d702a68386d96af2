// Harness: `calbench import csv` (bench/multipos/import_csv.cpp with bench/io/csv.cpp's reader and
// its delimiters), then the imported recording read back (`read_multipos_recording`) and fitted
// (`fit_multipos`). Input: one option byte, then the CSV file. The option byte picks the delimiter
// (bits 0-1: auto, comma, semicolon, blanks), columns by name or by index (bit 2), increments
// (bit 3) and units (bits 4-6). Checks: tests/fuzz/multipos_import_check.hpp.
#include <cstdint>

#include "bench/multipos/import_csv.hpp"
#include "tests/fuzz/multipos_import_check.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const fuzz::FdCheck fds;
  const fs::path dir = fuzz::fresh_folder("csvimport");
  const std::uint8_t opt = data[0];
  ImportCsvArgs a;
  a.file = (dir / "log.csv").string();
  a.out = (dir / "out").string();
  a.model = "Xsens MTi";
  a.delimiter = "\0,; "[opt & 3];
  if (opt & 4) {
    a.time_col = "1";
    a.gyro_cols = {"2", "3", "4"};
    a.accel_cols = {"5", "6", "7"};
  }
  a.increments = (opt & 8) != 0;
  a.gyro_unit = (opt & 16) ? "deg/s" : "rad/s";
  a.accel_unit = (opt & 32) ? "g" : "m/s2";
  a.time_unit = (opt & 64) ? "ms" : "s";
  fuzz::write_file(a.file, std::string_view(reinterpret_cast<const char*>(data + 1), size - 1));
  fuzz::check_multipos_import("csvimport", dir, [&] { import_csv(a); });
  fds.verify();
  return 0;
}
