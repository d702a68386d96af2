#include "bench/io/convert_recording.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "bench/io/csv.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/staging_folder.hpp"
#include "bench/io/verify_recording.hpp"
#include "common/input_error.hpp"

namespace calbench {
namespace {

namespace fs = std::filesystem;

bool is_table_file(const fs::path& name) {
  if (name == kHdf5RecordingFile) return true;
  for (const char* t : kRecordingTables)
    if (name == std::string(t) + ".csv") return true;
  return false;
}

void check_stop(const std::atomic<bool>* stop) {
  if (stop && stop->load()) throw std::runtime_error("interrupted: nothing written");
}

void fsync_path(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

void copy_other_files(const fs::path& dir, const fs::path& tmp) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const fs::path name = e.path().filename();
    if (is_table_file(name)) continue;
    fs::copy(e.path(), tmp / name, fs::copy_options::recursive);
  }
}

}  // namespace

ConvertResult convert_recording(const fs::path& dir, const std::string& to, fs::path out, const std::atomic<bool>* stop) {
  if (to != "h5" && to != "csv") throw InputError("--to", 0, "", "expected h5 or csv, got '" + to + "'");
  if (!fs::is_directory(dir)) throw InputError(dir.string(), 0, "", "not a recording folder (no such directory)");
  if (fs::exists(dir / "units.json"))
    throw InputError((dir / "units.json").string(), 0, "",
                     "a multi-unit drive (units.json): convert each unit's folder and the shared reference is not "
                     "supported; convert a single-unit recording");
  const RecordingMeta meta = read_meta(dir);  // a recording at all: meta.json valid
  (void)meta;
  const bool has_csv = fs::exists(dir / "imu.csv"), has_h5 = fs::exists(dir / kHdf5RecordingFile);
  if (!has_csv && !has_h5) throw InputError((dir / "imu.csv").string(), 0, "", "no imu.csv and no recording.h5: not a recording");
  const std::string from = has_csv ? "csv" : "h5";
  if (from == to)
    throw InputError(dir.string(), 0, "", "the recording is already " + std::string(to == "h5" ? "HDF5 (imu.csv absent, recording.h5 present)" : "CSV (imu.csv present)"));
  if (out.empty()) {  // DIR-h5 or DIR-csv beside DIR (built with append(): GCC 12 warns falsely on operator+ here)
    std::string name = fs::path(dir).lexically_normal().string();
    while (name.size() > 1 && name.back() == '/') name.pop_back();
    out = fs::path(name.append("-").append(to));
  }
  if (fs::exists(out)) throw InputError("--out", 0, "", out.string() + " exists: choose a new folder");
  if (!out.parent_path().empty() && !fs::is_directory(out.parent_path()))
    throw InputError("--out", 0, "", "no such directory: " + out.parent_path().string());

  // The source's tables: each read to its end before anything is marked done. A recording.h5 that
  // cannot be read (cut short, empty, damaged) is refused here, naming the file and what is wrong,
  // not skipped as a folder without tables.
  const fs::path h5 = dir / kHdf5RecordingFile;
  if (from == "h5") hdf5_table_info(h5, "imu");  // the file as a whole, and the table every recording has
  std::vector<const char*> tables;
  for (const char* t : kRecordingTables)
    if (from == "h5" ? hdf5_has_dataset(h5, t) : fs::exists(dir / (std::string(t) + ".csv"))) tables.push_back(t);

  ConvertResult res{out, from, to, {}};
  StagingFolder tmp(out, "partial");
  copy_other_files(dir, tmp.path());
  std::unique_ptr<Hdf5RecordingWriter> h5w;
  if (to == "h5") {
    std::ifstream m(dir / "meta.json");
    std::stringstream meta_text;
    meta_text << m.rdbuf();
    h5w = std::make_unique<Hdf5RecordingWriter>(tmp.path() / kHdf5RecordingFile, meta_text.str());
  }
  std::vector<TableTally> tally;
  for (const char* t : tables) {
    // The source table, read with the readers' own checks: every value a number, time ("t_s")
    // strictly increasing (TableSource::set_time_slot, as every reader of a recording).
    std::unique_ptr<TableSource> src;
    std::vector<std::string> comments;
    if (from == "csv") {
      auto csv = std::make_unique<CsvReader>((dir / (std::string(t) + ".csv")).string());
      csv->refuse_cut_last_line();  // a copy is complete or not made (issue 35 sign-off)
      comments = csv->comments();
      src = std::move(csv);
    } else {
      comments = hdf5_table_info(h5, t).comments;
      src = open_hdf5_table(h5, t);
    }
    const std::vector<std::string> columns = src->columns();
    std::vector<int> slot;
    for (const std::string& c : columns) {
      if (src->optional(c) != static_cast<int>(slot.size()))
        throw InputError(src->path(), from == "csv" ? 1 : 0, c, "table " + std::string(t) + ": duplicated column name (a table's columns must be unique)");
      slot.push_back(static_cast<int>(slot.size()));
    }
    src->set_time_slot(src->require("t_s"));
    std::unique_ptr<CsvWriter> cw;
    if (h5w) {
      h5w->begin_table(t, columns, comments);
    } else {
      std::string comment;
      for (std::size_t i = 0; i < comments.size(); ++i) comment.append(i ? "\n# " : "").append(comments[i]);
      cw = std::make_unique<CsvWriter>((tmp.path() / (std::string(t) + ".csv")).string(), columns, comment);
    }
    tally.emplace_back(t, columns);
    std::vector<double> row(slot.size());
    while (src->next()) {
      for (std::size_t i = 0; i < slot.size(); ++i) row[i] = src->value(slot[i]);
      if (h5w) h5w->row(row.data());
      else cw->row(row.data(), row.size());
      tally.back().add(row.data(), row.size());
      if (tally.back().rows() % 65536 == 0) check_stop(stop);
    }
    if (h5w) h5w->end_table();
    else cw->close();
    res.tables.push_back({t, tally.back().rows(), slot.size()});
  }
  check_stop(stop);
  if (h5w) {
    h5w->close();
    fsync_path(tmp.path() / kHdf5RecordingFile);
  }
  // Complete only when the new folder reads back as the source was read: the same tables, columns,
  // rows and values bit for bit.
  verify_written_recording(tmp.path(), tally);
  check_stop(stop);
  fsync_path(tmp.path());
  fs::rename(tmp.path(), out);
  tmp.keep();
  fsync_path(out.parent_path().empty() ? fs::path(".") : out.parent_path());
  return res;
}

}  // namespace calbench
