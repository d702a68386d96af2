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

  ConvertResult res{out, from, to, {}};
  StagingFolder tmp(out, "partial");
  copy_other_files(dir, tmp.path());

  if (to == "h5") {
    std::ifstream m(dir / "meta.json");
    std::stringstream meta_text;
    meta_text << m.rdbuf();
    Hdf5RecordingWriter w(tmp.path() / kHdf5RecordingFile, meta_text.str());
    for (const char* t : kRecordingTables) {
      const fs::path f = dir / (std::string(t) + ".csv");
      if (!fs::exists(f)) continue;
      CsvReader r(f.string());
      std::vector<int> slot;
      for (const std::string& c : r.header()) {
        if (r.optional(c) != static_cast<int>(slot.size()))
          throw InputError(f.string(), 1, c, "duplicated column name (a dataset's columns must be unique)");
        slot.push_back(static_cast<int>(slot.size()));
      }
      w.begin_table(t, r.header(), r.comments());
      std::vector<double> row(slot.size());
      std::size_t n = 0;
      while (r.next()) {
        for (std::size_t i = 0; i < slot.size(); ++i) row[i] = r.value(slot[i]);
        w.row(row.data());
        if (++n % 65536 == 0) check_stop(stop);
      }
      w.end_table();
      res.tables.push_back({t, n, slot.size()});
    }
    check_stop(stop);
    w.close();
    fsync_path(tmp.path() / kHdf5RecordingFile);
  } else {
    const fs::path h5 = dir / kHdf5RecordingFile;
    for (const char* t : kRecordingTables) {
      if (!recording_has_table(dir, t)) continue;
      const Hdf5TableInfo info = hdf5_table_info(h5, t);
      const auto src = open_hdf5_table(h5, t);
      std::vector<int> slot;
      for (const std::string& c : info.columns) {
        if (src->optional(c) != static_cast<int>(slot.size()))
          throw InputError(h5.string(), 0, c, "dataset /" + std::string(t) + ": duplicated column name");
        slot.push_back(static_cast<int>(slot.size()));
      }
      std::string comment;
      for (std::size_t i = 0; i < info.comments.size(); ++i) comment.append(i ? "\n# " : "").append(info.comments[i]);
      CsvWriter w((tmp.path() / (std::string(t) + ".csv")).string(), info.columns, comment);
      std::vector<double> row(slot.size());
      std::size_t n = 0;
      while (src->next()) {
        for (std::size_t i = 0; i < slot.size(); ++i) row[i] = src->value(slot[i]);
        w.row(row.data(), row.size());
        if (++n % 65536 == 0) check_stop(stop);
      }
      w.close();
      res.tables.push_back({t, n, slot.size()});
    }
  }
  check_stop(stop);
  fsync_path(tmp.path());
  fs::rename(tmp.path(), out);
  tmp.keep();
  fsync_path(out.parent_path().empty() ? fs::path(".") : out.parent_path());
  return res;
}

}  // namespace calbench
