// HDF5 recordings (docs/recording-hdf5.md): the tables of the interchange format (imu, reference,
// gnss) as datasets of one file, recording.h5, beside meta.json in the recording folder. Each
// dataset is a 2-D array of 64-bit floats, rows × columns, with the CSV's column names in its
// attribute "columns"; chunked by rows, so that a reader streams it. calbench reads either form
// wherever it reads a recording (recording.hpp opens the CSV when it is there, else the dataset).
#pragma once
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "bench/io/table_source.hpp"

namespace calbench {

inline constexpr const char* kHdf5RecordingFile = "recording.h5";
inline constexpr const char* kHdf5RecordingFormat = "calbench-recording-hdf5/1";
// The tables of a recording, by name: NAME.csv, or the dataset /NAME of recording.h5.
inline constexpr const char* kRecordingTables[] = {"imu", "reference", "gnss"};

// One dataset of recording.h5 as a table. Its shape, type and "columns" are checked at open: a
// missing dataset, a wrong rank, type or column count, a file that is not HDF5 or is cut short
// are InputErrors naming the file, the dataset and (where there is one) the column.
// digest: SHA-256 of the file's bytes (sha256()), read alongside on a thread of its own, once per
// file however many of its tables ask.
std::unique_ptr<TableSource> open_hdf5_table(const std::filesystem::path& file, const std::string& dataset, bool digest = false);

// Does recording.h5 `file` hold dataset `name`? A file that cannot be read at all (not HDF5, cut
// short, damaged) is an InputError naming it, not a file without datasets.
bool hdf5_has_dataset(const std::filesystem::path& file, const std::string& name);
// Does the recording folder hold table `name` ("imu", "reference", "gnss"), as name.csv or as a
// dataset of recording.h5?
bool recording_has_table(const std::filesystem::path& dir, const std::string& name);
// The file a table is read from: dir/name.csv if present, else dir/recording.h5 if it holds the
// dataset, else dir/name.csv (which then does not exist: the reader says so).
std::filesystem::path table_file(const std::filesystem::path& dir, const std::string& name);
// The file the IMU digest of a stored run is of: "imu.csv" or "recording.h5" (table_file of "imu"),
// or "" when the recording folder is not at hand (moved, another machine) or unreadable.
std::string imu_table_file_name(const std::filesystem::path& dir);
// How a report names that file: imu_table_file_name(), or both choices when it is not at hand.
std::string imu_table_file_label(const std::filesystem::path& dir);

// Writes recording.h5 table by table. create() makes the file (root attributes: format and the
// meta.json text); table() streams one dataset, appending rows in chunks.
class Hdf5RecordingWriter {
 public:
  Hdf5RecordingWriter(const std::filesystem::path& file, const std::string& meta_json);
  ~Hdf5RecordingWriter();
  Hdf5RecordingWriter(const Hdf5RecordingWriter&) = delete;
  Hdf5RecordingWriter& operator=(const Hdf5RecordingWriter&) = delete;
  // Begins dataset `name`; rows follow with row(), until end_table().
  void begin_table(const std::string& name, const std::vector<std::string>& columns, const std::vector<std::string>& comments);
  void row(const double* v);
  void end_table();
  void close();  // flush and close; throws on a write error

 private:
  void flush_rows();
  void create_dataset(unsigned long long chunk_rows);
  std::filesystem::path file_;
  std::string table_;
  std::vector<std::string> columns_, comments_;
  long long fid_ = -1, did_ = -1;
  std::size_t ncol_ = 0, rows_ = 0;
  std::vector<double> pending_;
};

// Reads a whole dataset's column names and comments (for conversion).
struct Hdf5TableInfo {
  std::vector<std::string> columns, comments;
  std::size_t rows = 0;
};
Hdf5TableInfo hdf5_table_info(const std::filesystem::path& file, const std::string& dataset);
// Forget the cached surveys no table is reading from (their side files are closed). The readers
// keep a file's survey for the process, and a side file (a dataset of many small chunks read into
// an unnamed temporary file) open while a table reads from it; the fuzz harness calls this before
// counting open descriptors.
void hdf5_drop_unused_surveys();

}  // namespace calbench
