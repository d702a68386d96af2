// `calbench convert`: a recording folder from CSV (imu.csv, reference.csv, gnss.csv) to HDF5
// (recording.h5, docs/recording-hdf5.md) or back. Every value is carried bit for bit (CSV numbers
// are written with 17 significant digits, which read back to the same double), the column names,
// the order of the columns and the '#' comments with it; meta.json and every other file of the
// folder are copied as they are. The new folder appears only when complete: it is written under a
// temporary name beside it and renamed into place, so an interrupted conversion leaves nothing.
#pragma once
#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

namespace calbench {

struct ConvertedTable {
  std::string name;
  std::size_t rows = 0, columns = 0;
};

struct ConvertResult {
  std::filesystem::path out;
  std::string from, to;  // "csv" or "h5"
  std::vector<ConvertedTable> tables;
};

// to: "h5" or "csv"; out: the new folder (must not exist; empty: DIR-h5 or DIR-csv beside DIR).
// stop: checked between blocks of rows (an interrupt); when set, the conversion is abandoned.
ConvertResult convert_recording(const std::filesystem::path& dir, const std::string& to, std::filesystem::path out,
                                const std::atomic<bool>* stop = nullptr);

}  // namespace calbench
