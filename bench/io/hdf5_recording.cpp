#include "bench/io/hdf5_recording.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <mutex>
#include <stdexcept>

#include "bench/io/message_text.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"

namespace calbench {
namespace {

namespace fs = std::filesystem;

// Rows per chunk of a dataset (and per read of the reader): 8192 rows of 8–16 columns are
// 0.5–1 MiB, HDF5's default chunk cache size.
constexpr hsize_t kChunkRows = 8192;

// The HDF5 library is not thread-safe in Debian's serial build: every call into it holds this.
std::recursive_mutex& h5_mutex() {
  static std::recursive_mutex m;
  return m;
}

// HDF5 prints its error stack to stderr by default; calbench reports its own messages.
void quiet_hdf5() {
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

struct Hid {
  hid_t id = -1;
  herr_t (*close)(hid_t) = nullptr;
  Hid() = default;
  Hid(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  Hid(Hid&& o) noexcept : id(o.id), close(o.close) { o.id = -1; }
  Hid& operator=(Hid&& o) noexcept {
    reset();
    id = o.id;
    close = o.close;
    o.id = -1;
    return *this;
  }
  ~Hid() { reset(); }
  void reset() {
    if (id >= 0 && close) close(id);
    id = -1;
  }
  explicit operator bool() const { return id >= 0; }
};

// Strings in attributes are read only in fixed length. The HDF5 library keeps variable-length
// strings in a global heap, and its reader of that heap overruns its buffer on a damaged file
// (found by tests/fuzz/hdf5_table in Debian 12's libhdf5 1.10.8): calbench writes fixed-length
// strings and refuses the other kind rather than hand a damaged heap to the library.
constexpr const char* kVlenRefused =
    "variable-length strings are not read (the HDF5 library's reader of them is unsafe on damaged files): "
    "write fixed-length strings (h5py: numpy.array(names, dtype='S'))";

// A scalar string attribute; false if absent; `error` set if present but not a fixed-length string.
bool read_string_attr(hid_t obj, const char* name, std::string& out, std::string& error) {
  if (H5Aexists(obj, name) <= 0) return false;
  Hid a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  if (!a) {
    error = "cannot read the attribute";
    return true;
  }
  Hid t(H5Aget_type(a.id), H5Tclose);
  Hid sp(H5Aget_space(a.id), H5Sclose);
  if (H5Tget_class(t.id) != H5T_STRING || H5Sget_simple_extent_npoints(sp.id) != 1) {
    error = "expected a string";
    return true;
  }
  if (H5Tis_variable_str(t.id) != 0) {
    error = kVlenRefused;
    return true;
  }
  const std::size_t n = H5Tget_size(t.id);
  if (n == 0 || n > (std::size_t{64} << 20)) {
    error = "implausible string length";
    return true;
  }
  std::string b(n, '\0');
  Hid mem(H5Tcopy(t.id), H5Tclose);  // the file's fixed-length type (pad and character set as written)
  if (H5Aread(a.id, mem.id, b.data()) < 0) {
    error = "cannot read the attribute";
    return true;
  }
  out = b.substr(0, b.find('\0'));
  return true;
}

// A 1-D string-array attribute (variable or fixed length). false if absent; an error text if malformed.
bool read_string_array_attr(hid_t obj, const char* name, std::vector<std::string>& out, std::string& error) {
  if (H5Aexists(obj, name) <= 0) return false;
  Hid a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  Hid t(H5Aget_type(a.id), H5Tclose);
  Hid sp(H5Aget_space(a.id), H5Sclose);
  if (!a || !t || !sp) {
    error = "cannot read the attribute";
    return true;
  }
  if (H5Tget_class(t.id) != H5T_STRING) {
    error = "expected an array of strings";
    return true;
  }
  const int rank = H5Sget_simple_extent_ndims(sp.id);
  hsize_t n = 1;
  if (rank == 1) H5Sget_simple_extent_dims(sp.id, &n, nullptr);
  else if (rank != 0) {
    error = "expected a 1-D array of strings";
    return true;
  }
  if (n > 100000) {
    error = "implausibly many columns (" + std::to_string(n) + ")";
    return true;
  }
  out.clear();
  if (H5Tis_variable_str(t.id) != 0) {
    error = kVlenRefused;
    return true;
  }
  Hid mem(H5Tcopy(t.id), H5Tclose);  // the file's fixed-length type (pad and character set as written)
  {
    const std::size_t len = H5Tget_size(t.id);
    if (len == 0 || len > 4096) {
      error = "implausible string length";
      return true;
    }
    std::vector<char> b(len * n);
    if (H5Aread(a.id, mem.id, b.data()) < 0) {
      error = "cannot read the attribute";
      return true;
    }
    for (hsize_t i = 0; i < n; ++i) {
      std::string str(b.data() + i * len, len);
      out.push_back(str.substr(0, str.find('\0')));
    }
  }
  return true;
}

// Fixed-length, null-padded UTF-8 strings (read_string_attr says why not variable length).
void write_string_attr(hid_t obj, const char* name, const std::string& v) {
  Hid t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t.id, std::max<std::size_t>(v.size(), 1));
  H5Tset_strpad(t.id, H5T_STR_NULLPAD);
  H5Tset_cset(t.id, H5T_CSET_UTF8);
  Hid sp(H5Screate(H5S_SCALAR), H5Sclose);
  Hid a(H5Acreate2(obj, name, t.id, sp.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  std::string buf = v;
  buf.resize(std::max<std::size_t>(v.size(), 1), '\0');
  if (!a || H5Awrite(a.id, t.id, buf.data()) < 0) throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name);
}

void write_string_array_attr(hid_t obj, const char* name, const std::vector<std::string>& v) {
  std::size_t len = 1;
  for (const auto& s : v) len = std::max(len, s.size());
  Hid t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t.id, len);
  H5Tset_strpad(t.id, H5T_STR_NULLPAD);
  H5Tset_cset(t.id, H5T_CSET_UTF8);
  const hsize_t n = v.size();
  Hid sp(H5Screate_simple(1, &n, nullptr), H5Sclose);
  Hid a(H5Acreate2(obj, name, t.id, sp.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  std::vector<char> buf(len * v.size(), '\0');
  for (std::size_t i = 0; i < v.size(); ++i) std::copy(v[i].begin(), v[i].end(), buf.begin() + static_cast<std::ptrdiff_t>(i * len));
  if (!a || H5Awrite(a.id, t.id, buf.data()) < 0) throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name);
}

std::string lower_dataset(const std::string& d) { return d.empty() || d[0] != '/' ? "/" + d : d; }

// An open dataset with its checked shape and columns.
struct OpenedTable {
  Hid file, dset, space;
  hsize_t rows = 0, ncol = 0;
  std::vector<std::string> columns, comments;
};

OpenedTable open_checked(const fs::path& file, const std::string& dataset) {
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  quiet_hdf5();
  const std::string f = file.string(), ds = lower_dataset(dataset);
  OpenedTable o;
  if (!fs::exists(file)) throw InputError(f, 0, "", "cannot open: no such file");
  if (H5Fis_hdf5(f.c_str()) <= 0) throw InputError(f, 0, "", "not an HDF5 file (no HDF5 signature, or cut short)");
  o.file = Hid(H5Fopen(f.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!o.file) throw InputError(f, 0, "", "cannot open as HDF5 (damaged or truncated file)");
  if (H5Lexists(o.file.id, ds.c_str() + 1, H5P_DEFAULT) <= 0)
    throw InputError(f, 0, ds, "no dataset " + ds + " in the file");
  o.dset = Hid(H5Dopen2(o.file.id, ds.c_str(), H5P_DEFAULT), H5Dclose);
  if (!o.dset) throw InputError(f, 0, ds, "cannot open dataset " + ds + " (not a dataset, or a damaged file)");
  Hid t(H5Dget_type(o.dset.id), H5Tclose);
  if (H5Tget_class(t.id) != H5T_FLOAT || H5Tget_size(t.id) != 8)
    throw InputError(f, 0, ds, "dataset " + ds + " has the wrong type: expected 64-bit floats (H5T_IEEE_F64LE)");
  o.space = Hid(H5Dget_space(o.dset.id), H5Sclose);
  if (H5Sget_simple_extent_ndims(o.space.id) != 2)
    throw InputError(f, 0, ds, "dataset " + ds + " has the wrong shape: expected 2 dimensions (rows x columns), got " +
                                  std::to_string(H5Sget_simple_extent_ndims(o.space.id)));
  hsize_t dims[2];
  H5Sget_simple_extent_dims(o.space.id, dims, nullptr);
  o.rows = dims[0];
  o.ncol = dims[1];
  std::string err;
  if (!read_string_array_attr(o.dset.id, "columns", o.columns, err))
    throw InputError(f, 0, ds, "dataset " + ds + " has no attribute 'columns' (the column names)");
  if (!err.empty()) throw InputError(f, 0, ds, "dataset " + ds + " attribute 'columns': " + err);
  if (o.columns.size() != o.ncol)
    throw InputError(f, 0, ds, "dataset " + ds + " has the wrong shape: " + std::to_string(o.ncol) + " columns but " +
                                  std::to_string(o.columns.size()) + " names in attribute 'columns'");
  std::string c;
  if (read_string_attr(o.dset.id, "comments", c, err) && !err.empty())
    throw InputError(f, 0, ds, "dataset " + ds + " attribute 'comments': " + err);
  if (!c.empty()) {
    std::size_t p = 0;
    while (true) {
      const std::size_t n = c.find('\n', p);
      o.comments.push_back(c.substr(p, n == std::string::npos ? std::string::npos : n - p));
      if (n == std::string::npos) break;
      p = n + 1;
    }
  }
  return o;
}

class Hdf5Table final : public TableSource {
 public:
  Hdf5Table(const fs::path& file, const std::string& dataset, bool digest)
      : path_(file.string()), ds_(lower_dataset(dataset)), t_(open_checked(file, dataset)) {
    slot_of_col_.assign(t_.ncol, -1);
    if (digest) digest_ = std::async(std::launch::async, [f = file] { return sha256_file(f); });
  }
  ~Hdf5Table() override {
    if (digest_.valid()) digest_.wait();
    std::lock_guard<std::recursive_mutex> lk(h5_mutex());
    t_.space.reset();
    t_.dset.reset();
    t_.file.reset();
  }
  int optional(std::string_view name) override {
    for (std::size_t i = 0; i < t_.columns.size(); ++i)
      if (t_.columns[i] == name) {
        if (slot_of_col_[i] >= 0) return slot_of_col_[i];
        slot_of_col_[i] = static_cast<int>(cols_.size());
        cols_.push_back(i);
        values_.push_back(0.0);
        return slot_of_col_[i];
      }
    return -1;
  }
  int require(std::string_view name) override {
    const int s = optional(name);
    if (s < 0) throw InputError(path_, 0, std::string(name), "dataset " + ds_ + ": missing required column (not in attribute 'columns')");
    return s;
  }
  bool has(std::string_view name) const override {
    for (const auto& c : t_.columns)
      if (c == name) return true;
    return false;
  }
  void set_time_slot(int slot) override { time_slot_ = slot; }
  bool next() override {
    if (row_ >= t_.rows) {
      if (t_.rows == 0) fail_at("", "no data rows");
      return false;
    }
    if (row_ >= block0_ + block_rows_) read_block();
    const double* r = buf_.data() + (row_ - block0_) * t_.ncol;
    ++row_;
    for (std::size_t s = 0; s < cols_.size(); ++s) {
      const double v = r[cols_[s]];
      if (!std::isfinite(v)) fail_at(t_.columns[cols_[s]], "NaN or infinity is not allowed");
      values_[s] = v;
    }
    if (time_slot_ >= 0) {
      const double tv = values_[static_cast<std::size_t>(time_slot_)];
      const std::string& name = t_.columns[cols_[static_cast<std::size_t>(time_slot_)]];
      if (row_ > 1) {
        if (tv == last_time_) fail_at(name, "duplicated time " + number_text(tv));
        if (tv < last_time_) fail_at(name, "time goes backwards");
      }
      last_time_ = tv;
    }
    return true;
  }
  double value(int slot) const override { return values_[static_cast<std::size_t>(slot)]; }
  const std::string& path() const override { return path_; }
  std::size_t line() const override { return row_; }
  [[noreturn]] void fail_at(const std::string& column, const std::string& msg) const override {
    throw InputError(path_, 0, column, "dataset " + ds_ + (row_ > 0 ? ", row " + std::to_string(row_) : "") + ": " + msg);
  }
  std::optional<std::string> sha256() const override {
    if (!digest_.valid()) return std::nullopt;
    if (!digest_done_) {
      digest_value_ = digest_.get();
      digest_done_ = true;
    }
    return digest_value_;
  }

 private:
  void read_block() {
    std::lock_guard<std::recursive_mutex> lk(h5_mutex());
    block0_ = row_;
    block_rows_ = std::min<hsize_t>(kChunkRows, t_.rows - row_);
    buf_.resize(block_rows_ * t_.ncol);
    const hsize_t start[2] = {block0_, 0}, count[2] = {block_rows_, t_.ncol};
    H5Sselect_hyperslab(t_.space.id, H5S_SELECT_SET, start, nullptr, count, nullptr);
    Hid mem(H5Screate_simple(2, count, nullptr), H5Sclose);
    if (H5Dread(t_.dset.id, H5T_NATIVE_DOUBLE, mem.id, t_.space.id, H5P_DEFAULT, buf_.data()) < 0)
      throw InputError(path_, 0, ds_,
                       "dataset " + ds_ + ", rows " + std::to_string(block0_ + 1) + "-" + std::to_string(block0_ + block_rows_) +
                           ": cannot read (the file is truncated or damaged)");
  }

  std::string path_, ds_;
  OpenedTable t_;
  std::vector<int> slot_of_col_;
  std::vector<std::size_t> cols_;
  std::vector<double> values_, buf_;
  hsize_t row_ = 0, block0_ = 0, block_rows_ = 0;
  int time_slot_ = -1;
  double last_time_ = 0;
  mutable std::shared_future<std::string> digest_;
  mutable std::string digest_value_;
  mutable bool digest_done_ = false;
};

}  // namespace

std::unique_ptr<TableSource> open_hdf5_table(const fs::path& file, const std::string& dataset, bool digest) {
  return std::make_unique<Hdf5Table>(file, dataset, digest);
}

bool recording_has_table(const fs::path& dir, const std::string& name) {
  if (fs::exists(dir / (name + ".csv"))) return true;
  const fs::path h5 = dir / kHdf5RecordingFile;
  if (!fs::exists(h5)) return false;
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  quiet_hdf5();
  if (H5Fis_hdf5(h5.string().c_str()) <= 0) return false;
  Hid f(H5Fopen(h5.string().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  return f && H5Lexists(f.id, name.c_str(), H5P_DEFAULT) > 0;
}

fs::path table_file(const fs::path& dir, const std::string& name) {
  const fs::path csv = dir / (name + ".csv");
  if (fs::exists(csv) || !fs::exists(dir / kHdf5RecordingFile)) return csv;
  return dir / kHdf5RecordingFile;
}

Hdf5TableInfo hdf5_table_info(const fs::path& file, const std::string& dataset) {
  OpenedTable o = open_checked(file, dataset);
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  Hdf5TableInfo i{o.columns, o.comments, static_cast<std::size_t>(o.rows)};
  o.space.reset();
  o.dset.reset();
  o.file.reset();
  return i;
}

// ---------------------------------------------------------------------------------------------
Hdf5RecordingWriter::Hdf5RecordingWriter(const fs::path& file, const std::string& meta_json) : file_(file) {
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  quiet_hdf5();
  fid_ = H5Fcreate(file.string().c_str(), H5F_ACC_EXCL, H5P_DEFAULT, H5P_DEFAULT);
  if (fid_ < 0) throw std::runtime_error(file.string() + ": cannot create the HDF5 file");
  write_string_attr(fid_, "format", kHdf5RecordingFormat);
  write_string_attr(fid_, "meta_json", meta_json);
}

Hdf5RecordingWriter::~Hdf5RecordingWriter() {
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  if (did_ >= 0) H5Dclose(did_);
  if (fid_ >= 0) H5Fclose(fid_);
}

void Hdf5RecordingWriter::begin_table(const std::string& name, const std::vector<std::string>& columns,
                                      const std::vector<std::string>& comments) {
  // The dataset is created with the first block of rows: a table shorter than a chunk gets chunks
  // of its own length (a small file stays small).
  table_ = name;
  columns_ = columns;
  comments_ = comments;
  ncol_ = columns.size();
  rows_ = 0;
  pending_.clear();
}

void Hdf5RecordingWriter::create_dataset(unsigned long long chunk_rows) {
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  const hsize_t dims[2] = {0, ncol_}, maxd[2] = {H5S_UNLIMITED, ncol_}, chunk[2] = {std::max<hsize_t>(chunk_rows, 1), std::max<hsize_t>(ncol_, 1)};
  Hid sp(H5Screate_simple(2, dims, maxd), H5Sclose);
  Hid pl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_chunk(pl.id, 2, chunk);
  did_ = H5Dcreate2(fid_, ("/" + table_).c_str(), H5T_IEEE_F64LE, sp.id, H5P_DEFAULT, pl.id, H5P_DEFAULT);
  if (did_ < 0) throw std::runtime_error(file_.string() + ": cannot create dataset /" + table_);
  write_string_array_attr(did_, "columns", columns_);
  std::string c;
  for (std::size_t i = 0; i < comments_.size(); ++i) c.append(i ? "\n" : "").append(comments_[i]);
  write_string_attr(did_, "comments", c);
}

void Hdf5RecordingWriter::row(const double* v) {
  pending_.insert(pending_.end(), v, v + ncol_);
  if (pending_.size() >= kChunkRows * ncol_) flush_rows();
}

void Hdf5RecordingWriter::flush_rows() {
  if (did_ < 0 && !table_.empty()) create_dataset(ncol_ ? pending_.size() / ncol_ : 0);
  if (pending_.empty()) return;
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  const hsize_t n = pending_.size() / ncol_;
  const hsize_t dims[2] = {rows_ + n, ncol_};
  if (H5Dset_extent(did_, dims) < 0) throw std::runtime_error(file_.string() + ": cannot extend a dataset");
  Hid fs_(H5Dget_space(did_), H5Sclose);
  const hsize_t start[2] = {rows_, 0}, count[2] = {n, ncol_};
  H5Sselect_hyperslab(fs_.id, H5S_SELECT_SET, start, nullptr, count, nullptr);
  Hid mem(H5Screate_simple(2, count, nullptr), H5Sclose);
  if (H5Dwrite(did_, H5T_NATIVE_DOUBLE, mem.id, fs_.id, H5P_DEFAULT, pending_.data()) < 0)
    throw std::runtime_error(file_.string() + ": write failed");
  rows_ += n;
  pending_.clear();
}

void Hdf5RecordingWriter::end_table() {
  flush_rows();
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  if (did_ >= 0) H5Dclose(did_);
  did_ = -1;
  table_.clear();
}

void Hdf5RecordingWriter::close() {
  end_table();
  std::lock_guard<std::recursive_mutex> lk(h5_mutex());
  if (fid_ >= 0) {
    if (H5Fflush(fid_, H5F_SCOPE_GLOBAL) < 0) throw std::runtime_error(file_.string() + ": flush failed");
    const herr_t rc = H5Fclose(fid_);
    fid_ = -1;
    if (rc < 0) throw std::runtime_error(file_.string() + ": close failed");
  }
}

}  // namespace calbench
