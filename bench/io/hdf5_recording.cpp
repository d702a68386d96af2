#include "bench/io/hdf5_recording.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <new>
#include <map>
#include <sys/stat.h>
#include <cstdio>
#include <cstring>

#include <algorithm>
#include <bit>
#include <cmath>
#include <future>
#include <mutex>
#include <stdexcept>

#include "bench/io/message_text.hpp"
#include "bench/io/plausible.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"
#include <nlohmann/json.hpp>

namespace calbench {
namespace {

namespace fs = std::filesystem;
// The reader takes the stored little-endian doubles as they are.
static_assert(std::endian::native == std::endian::little, "HDF5 recordings are read on little-endian machines");

// Rows per chunk of a dataset (and per read of the reader): 8192 rows of 8–16 columns are
// 0.5–1 MiB, HDF5's default chunk cache size.
constexpr hsize_t kChunkRows = 8192;

// The HDF5 library is not thread-safe in Debian's serial build: every call into it holds this.
std::recursive_mutex& h5_mutex() {
  static std::recursive_mutex m;
  return m;
}

// HDF5 prints its error stack to stderr by default; calbench reports its own messages. Debian's
// library is built thread-safe, where that setting is each thread's own: every thread that calls
// into the library turns it off first.
void quiet_hdf5() {
  thread_local bool done = false;
  if (done) return;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  done = true;
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

// What a reader needs of one dataset, found by the HDF5 library in a child process (survey()):
// shape, names, comments, and where every block of values lies in the file. The values themselves
// are read by calbench (pread), never by the library.
struct TableMeta {
  bool present = false;
  std::string error_field, error;  // set: the dataset is refused (InputError: field, message)
  std::uint64_t rows = 0, ncol = 0, chunk_rows = 0, offset = 0;  // chunk_rows 0: contiguous at offset
  std::vector<std::string> columns, comments;
  std::vector<std::uint64_t> chunk_addr;  // chunk k holds rows [k·chunk_rows, (k+1)·chunk_rows)
  bool side = false;  // the values were read by the library into the side file, contiguous at offset
};
struct FileMeta {
  std::string error;  // set: the file is refused as a whole
  std::map<std::string, TableMeta> tables;
  std::shared_ptr<std::FILE> side;  // the side file (in the parent; survey())
};

// A dataset of many small chunks (h5py's chunks=(1, n), say) is not located chunk by chunk: the
// library's H5Dget_chunk_info_by_coord walks the whole chunk index on every call, so that time grew
// with the square of the chunks (75,807 one-row chunks: 79 s, issue 35). Beyond this many chunks
// the child reads the values itself (H5Dread of kChunkRows rows at a time: one index walk) into a
// temporary side file that the reader then reads as a contiguous block.
constexpr std::uint64_t kMaxLocatedChunks = 1024;

// In the child: the values of a dataset of many chunks (kMaxLocatedChunks), read by the library
// kChunkRows rows at a time and appended to the side file; m then says where they lie there.
TableMeta read_to_side(hid_t d, TableMeta m, const std::string& ds, int side_fd, std::uint64_t& side_end) {
  const auto damaged = [&](std::uint64_t r0, const std::string& why) {
    m.error_field = ds;
    m.error = "dataset " + ds + ", rows from " + std::to_string(r0 + 1) + ": " + why;
    return m;
  };
  const std::uint64_t nchunks = (m.rows + m.chunk_rows - 1) / m.chunk_rows;
  hsize_t allocated = 0;
  Hid all(H5Dget_space(d), H5Sclose);
  if (!all || H5Dget_num_chunks(d, all.id, &allocated) < 0 || allocated != nchunks)
    return damaged(0, "their values are not all stored (" + std::to_string(allocated) + " of " + std::to_string(nchunks) +
                          " chunks: truncated or damaged)");
  if (side_fd < 0) return damaged(0, "no temporary file to read them into");
  m.offset = side_end;
  m.side = true;
  m.chunk_rows = 0;
  Hid fsp(H5Dget_space(d), H5Sclose);
  std::vector<double> buf;
  for (std::uint64_t r0 = 0; r0 < m.rows; r0 += kChunkRows) {
    const hsize_t start[2] = {r0, 0}, count[2] = {std::min<std::uint64_t>(kChunkRows, m.rows - r0), m.ncol};
    buf.resize(count[0] * count[1]);
    Hid mem(H5Screate_simple(2, count, nullptr), H5Sclose);
    if (!fsp || H5Sselect_hyperslab(fsp.id, H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
        H5Dread(d, H5T_IEEE_F64LE, mem.id, fsp.id, H5P_DEFAULT, buf.data()) < 0)
      return damaged(r0, "cannot read (the file is truncated or damaged)");
    const char* p = reinterpret_cast<const char*>(buf.data());
    std::size_t left = buf.size() * sizeof(double);
    while (left > 0) {
      const ssize_t n = ::pwrite(side_fd, p, left, static_cast<off_t>(side_end));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return damaged(r0, std::string("cannot hold the values in a temporary file: ") + std::strerror(errno));
      p += n;
      left -= static_cast<std::size_t>(n);
      side_end += static_cast<std::uint64_t>(n);
    }
  }
  return m;
}

// In the child: one table, checked as the format says. Errors are returned, not thrown.
TableMeta survey_table(hid_t file, const std::string& name, std::uintmax_t file_size, int side_fd, std::uint64_t& side_end) {
  TableMeta m;
  const std::string ds = "/" + name;
  auto fail = [&](const std::string& field, const std::string& msg) {
    m.error_field = field;
    m.error = msg;
    return m;
  };
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) return m;
  m.present = true;
  Hid d(H5Dopen2(file, ds.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d) return fail(ds, "cannot open dataset " + ds + " (not a dataset, or a damaged file)");
  Hid t(H5Dget_type(d.id), H5Tclose);
  if (!t || H5Tget_class(t.id) != H5T_FLOAT || H5Tget_size(t.id) != 8 || H5Tequal(t.id, H5T_IEEE_F64LE) <= 0)
    return fail(ds, "dataset " + ds + " has the wrong type: expected 64-bit floats (H5T_IEEE_F64LE)");
  Hid sp(H5Dget_space(d.id), H5Sclose);
  const int rank = sp ? H5Sget_simple_extent_ndims(sp.id) : -1;
  if (rank != 2)
    return fail(ds, "dataset " + ds + " has the wrong shape: expected 2 dimensions (rows x columns), got " + std::to_string(rank));
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(sp.id, dims, nullptr);
  m.rows = dims[0];
  m.ncol = dims[1];
  std::string err;
  if (!read_string_array_attr(d.id, "columns", m.columns, err))
    return fail(ds, "dataset " + ds + " has no attribute 'columns' (the column names)");
  if (!err.empty()) return fail(ds, "dataset " + ds + " attribute 'columns': " + err);
  if (m.columns.size() != m.ncol)
    return fail(ds, "dataset " + ds + " has the wrong shape: " + std::to_string(m.ncol) + " columns but " +
                        std::to_string(m.columns.size()) + " names in attribute 'columns'");
  if (m.ncol == 0 || m.ncol > 4096)
    return fail(ds, "dataset " + ds + " has the wrong shape: " + std::to_string(m.ncol) + " columns (1 to 4096)");
  std::string c;
  if (read_string_attr(d.id, "comments", c, err) && !err.empty()) return fail(ds, "dataset " + ds + " attribute 'comments': " + err);
  if (!c.empty()) {
    std::size_t p = 0;
    while (true) {
      const std::size_t n = c.find('\n', p);
      m.comments.push_back(c.substr(p, n == std::string::npos ? std::string::npos : n - p));
      if (n == std::string::npos) break;
      p = n + 1;
    }
  }
  // Storage: no filter (the values as they are), chunks of whole rows, or one contiguous block.
  Hid dcpl(H5Dget_create_plist(d.id), H5Pclose);
  if (!dcpl || H5Pget_nfilters(dcpl.id) != 0)
    return fail(ds, "dataset " + ds + " is compressed or filtered: the format stores the values as they are (no filters)");
  const std::uint64_t row_bytes = m.ncol * 8;
  const H5D_layout_t layout = H5Pget_layout(dcpl.id);
  const auto damaged = [&](std::uint64_t r0) {
    return fail(ds, "dataset " + ds + ", rows from " + std::to_string(r0 + 1) + ": their values lie outside the file or are "
                    "not stored (truncated or damaged)");
  };
  if (layout == H5D_CHUNKED) {
    hsize_t cd[2] = {0, 0};
    if (H5Pget_chunk(dcpl.id, 2, cd) != 2 || cd[1] != m.ncol || cd[0] == 0 || cd[0] * m.ncol > (hsize_t{1} << 25))
      return fail(ds, "dataset " + ds + " has the wrong chunk shape: expected chunks of whole rows (every column), at most 2^25 values each");
    m.chunk_rows = cd[0];
    if ((m.rows + m.chunk_rows - 1) / m.chunk_rows > kMaxLocatedChunks) return read_to_side(d.id, m, ds, side_fd, side_end);
    for (std::uint64_t r0 = 0; r0 < m.rows; r0 += m.chunk_rows) {
      const hsize_t at[2] = {r0, 0};
      unsigned mask = 0;
      haddr_t addr = HADDR_UNDEF;
      hsize_t size = 0;
      if (H5Dget_chunk_info_by_coord(d.id, at, &mask, &addr, &size) < 0 || addr == HADDR_UNDEF ||
          size != m.chunk_rows * row_bytes || addr > file_size || size > file_size - addr)
        return damaged(r0);
      m.chunk_addr.push_back(addr);
    }
  } else if (layout == H5D_CONTIGUOUS) {
    const haddr_t off = H5Dget_offset(d.id);
    if (m.rows > 0 && (off == HADDR_UNDEF || off > file_size || m.rows > (file_size - off) / row_bytes)) return damaged(0);
    m.offset = off == HADDR_UNDEF ? 0 : off;
  } else {
    return fail(ds, "dataset " + ds + " has a layout calbench does not read (chunked or contiguous expected)");
  }
  return m;
}

nlohmann::json to_json(const FileMeta& f) {
  nlohmann::json j = {{"error", f.error}, {"tables", nlohmann::json::object()}};
  for (const auto& [name, m] : f.tables)
    j["tables"][name] = {{"present", m.present}, {"error_field", m.error_field}, {"error", m.error}, {"rows", m.rows},
                         {"ncol", m.ncol}, {"chunk_rows", m.chunk_rows}, {"offset", m.offset}, {"columns", m.columns},
                         {"comments", m.comments}, {"chunk_addr", m.chunk_addr}, {"side", m.side}};
  return j;
}

FileMeta from_json(const nlohmann::json& j) {
  FileMeta f;
  f.error = j.at("error").get<std::string>();
  for (const auto& [name, t] : j.at("tables").items()) {
    TableMeta m;
    m.present = t.at("present").get<bool>();
    m.error_field = t.at("error_field").get<std::string>();
    m.error = t.at("error").get<std::string>();
    m.rows = t.at("rows").get<std::uint64_t>();
    m.ncol = t.at("ncol").get<std::uint64_t>();
    m.chunk_rows = t.at("chunk_rows").get<std::uint64_t>();
    m.offset = t.at("offset").get<std::uint64_t>();
    m.columns = t.at("columns").get<std::vector<std::string>>();
    m.comments = t.at("comments").get<std::vector<std::string>>();
    m.chunk_addr = t.at("chunk_addr").get<std::vector<std::uint64_t>>();
    m.side = t.at("side").get<bool>();
    f.tables[name] = std::move(m);
  }
  return f;
}

// In the child: the whole file.
FileMeta survey_file(const fs::path& file, int side_fd) {
  FileMeta f;
  quiet_hdf5();
  const std::string p = file.string();
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(file, ec);
  if (H5Fis_hdf5(p.c_str()) <= 0) {
    f.error = "not an HDF5 file (no HDF5 signature, or cut short)";
    return f;
  }
  Hid h(H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!h) {
    f.error = "cannot open as HDF5 (damaged or truncated file)";
    return f;
  }
  std::uint64_t side_end = 0;
  for (const char* t : kRecordingTables) f.tables[t] = survey_table(h.id, t, size, side_fd, side_end);
  return f;
}

// The HDF5 library (Debian 12's 1.10.8) overruns its buffers on some damaged files, inside its own
// parsing of object headers, attribute messages and chunk indexes (found by tests/fuzz/hdf5_table),
// where no check of calbench's can come first. So the library reads a file's structure in a child
// process (fork) and hands over what the readers need as JSON through a pipe; a crash there ends
// the child and the file is reported damaged (exit 2). This process never gives the library a file
// it reads; the values are read from the offsets the child found, checked against the file's size.
// Once per file (path, size, modification time) and process.
// A file as it is now: its path, size and modification time (what the caches below key on).
std::string file_key(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (ec) throw InputError(file.string(), 0, "", "cannot open: " + ec.message());
  const auto mtime = fs::last_write_time(file, ec).time_since_epoch().count();
  return file.string() + "|" + std::to_string(size) + "|" + std::to_string(mtime);
}

// The SHA-256 of a file, computed once on a thread of its own however many of its tables ask.
std::shared_future<std::string> file_digest(const fs::path& file) {
  const std::string key = file_key(file);
  static std::mutex m;
  static std::map<std::string, std::shared_future<std::string>> started;
  std::lock_guard<std::mutex> lk(m);
  auto it = started.find(key);
  if (it == started.end())
    it = started.emplace(key, std::async(std::launch::async, [f = file] { return sha256_file(f); }).share()).first;
  return it->second;
}

// The surveys of this process, by file_key(). An entry whose tables were read into a side file holds
// that file open until the last table reading from it is gone (release_side()).
struct SurveyCache {
  std::mutex m;
  std::map<std::string, FileMeta> done;
};
SurveyCache& survey_cache() {
  static SurveyCache c;
  return c;
}

void release_side(const std::string& key) {
  SurveyCache& c = survey_cache();
  std::lock_guard<std::mutex> lk(c.m);
  const auto it = c.done.find(key);
  if (it != c.done.end() && it->second.side && it->second.side.use_count() == 1) c.done.erase(it);  // the cache's own
}

}  // namespace

void hdf5_drop_unused_surveys() {
  SurveyCache& c = survey_cache();
  std::lock_guard<std::mutex> lk(c.m);
  for (auto it = c.done.begin(); it != c.done.end();)
    it = !it->second.side || it->second.side.use_count() == 1 ? c.done.erase(it) : std::next(it);
}

namespace {

const FileMeta& survey(const fs::path& file) {
  const std::string key = file_key(file);
  SurveyCache& cache = survey_cache();
  std::mutex& m = cache.m;
  std::map<std::string, FileMeta>& done = cache.done;
  std::lock_guard<std::mutex> lk(m);
  const auto it = done.find(key);
  if (it != done.end()) return it->second;
  // The side file (kMaxLocatedChunks): unnamed, in TMPDIR, gone when closed.
  std::shared_ptr<std::FILE> side(std::tmpfile(), [](std::FILE* p) {
    if (p) std::fclose(p);
  });
  const int side_fd = side ? ::fileno(side.get()) : -1;
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error(std::string("cannot make a pipe: ") + std::strerror(errno));
  pid_t pid = -1;
  {
    std::lock_guard<std::recursive_mutex> h5(h5_mutex());  // no thread of ours inside the library while forking
    pid = ::fork();
  }
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(file.string() + ": cannot fork to read the HDF5 structure: " + std::strerror(errno));
  }
  if (pid == 0) {  // the child: one thread; our lock of the library re-made (the parent's thread holds its copy)
    ::close(fds[0]);
    new (&h5_mutex()) std::recursive_mutex();
    std::string out;
    try {
      out = to_json(survey_file(file, side_fd)).dump();
    } catch (...) {
      ::_exit(3);
    }
    std::size_t w = 0;
    while (w < out.size()) {
      const ssize_t n = ::write(fds[1], out.data() + w, out.size() - w);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) ::_exit(4);
      w += static_cast<std::size_t>(n);
    }
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string in;
  char buf[65536];
  while (true) {
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    in.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw InputError(file.string(), 0, "",
                     "damaged HDF5 file: the HDF5 library failed while reading its structure" +
                         (WIFSIGNALED(status) ? " (signal " + std::to_string(WTERMSIG(status)) + ")" : std::string()) +
                         "; nothing read from it");
  FileMeta f;
  try {
    f = from_json(nlohmann::json::parse(in));
  } catch (const std::exception& e) {
    throw std::runtime_error(file.string() + ": the HDF5 survey's answer is unreadable: " + e.what());
  }
  // The side file stays open (with the survey, for the tables read from it) only when a table was
  // read into it; otherwise it is closed here.
  bool used = false;
  for (const auto& t : f.tables) used = used || t.second.side;
  if (used) f.side = std::move(side);
  return done[key] = std::move(f);
}

// The table `dataset` of a surveyed file, or the InputError the survey found.
const TableMeta& table_meta(const fs::path& file, const std::string& dataset) {
  const std::string f = file.string(), name = dataset.empty() || dataset[0] != '/' ? dataset : dataset.substr(1);
  if (!fs::exists(file)) throw InputError(f, 0, "", "cannot open: no such file");
  const FileMeta& fm = survey(file);
  if (!fm.error.empty()) throw InputError(f, 0, "", fm.error);
  const auto it = fm.tables.find(name);
  if (it == fm.tables.end() || !it->second.present) throw InputError(f, 0, "/" + name, "no dataset /" + name + " in the file");
  if (!it->second.error.empty()) throw InputError(f, 0, it->second.error_field, it->second.error);
  return it->second;
}

class Hdf5Table final : public TableSource {
 public:
  Hdf5Table(const fs::path& file, const std::string& dataset, bool digest)
      : path_(file.string()), ds_(lower_dataset(dataset)), t_(table_meta(file, dataset)) {
    slot_of_col_.assign(t_.ncol, -1);
    if (t_.side) {  // the values as the survey read them (kMaxLocatedChunks)
      side_key_ = file_key(file);
      side_ = survey(file).side;
      fd_ = side_ ? ::dup(::fileno(side_.get())) : -1;
    } else {
      fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    }
    if (fd_ < 0) throw InputError(path_, 0, "", std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    file_size_ = ::fstat(fd_, &st) == 0 ? static_cast<std::uint64_t>(st.st_size) : 0;
    if (digest) digest_ = file_digest(file);
  }
  ~Hdf5Table() override {
    if (fd_ >= 0) ::close(fd_);
    if (side_) {  // the last table of a side file closes it (the survey is redone if the file is read again)
      side_.reset();
      release_side(side_key_);
    }
    // No hashing thread outlives the tables that asked for it (at exit, OpenSSL is torn down).
    if (digest_.valid()) digest_.wait();
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
  const std::vector<std::string>& columns() const override { return t_.columns; }
  void set_time_slot(int slot) override { time_slot_ = slot; }
  bool next() override {
    if (row_ >= t_.rows) {
      if (t_.rows == 0) fail_at("", "no data rows");
      return false;
    }
    if (row_ >= block0_ + block_rows_ || row_ < block0_) read_block();
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
      plausible::check_row_time(*this, name, tv, row_ > 1, last_time_);
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
    return digest_.get();
  }

 private:
  // The block of rows holding row_: a chunk (at the address the survey found), or kChunkRows rows of
  // the contiguous block; read with pread, each range checked against the file's size again.
  void read_block() {
    const std::uint64_t row_bytes = t_.ncol * 8;
    std::uint64_t addr = 0;
    if (t_.chunk_rows > 0) {
      const std::uint64_t k = row_ / t_.chunk_rows;
      block0_ = k * t_.chunk_rows;
      block_rows_ = std::min<std::uint64_t>(t_.chunk_rows, t_.rows - block0_);
      if (k >= t_.chunk_addr.size()) damaged();
      addr = t_.chunk_addr[k];
    } else {
      block0_ = row_;
      block_rows_ = std::min<std::uint64_t>(kChunkRows, t_.rows - block0_);
      addr = t_.offset + block0_ * row_bytes;
    }
    const std::uint64_t want = block_rows_ * row_bytes;
    if (addr > file_size_ || want > file_size_ - addr) damaged();
    buf_.resize(block_rows_ * t_.ncol);
    std::uint64_t got = 0;
    while (got < want) {
      const ssize_t n = ::pread(fd_, reinterpret_cast<char*>(buf_.data()) + got, want - got, static_cast<off_t>(addr + got));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) damaged();
      got += static_cast<std::uint64_t>(n);
    }
  }
  [[noreturn]] void damaged() const {
    throw InputError(path_, 0, ds_,
                     "dataset " + ds_ + ", rows " + std::to_string(block0_ + 1) + "-" +
                         std::to_string(block0_ + std::max<std::uint64_t>(block_rows_, 1)) +
                         ": cannot read (the file is truncated or damaged)");
  }

  std::string path_, ds_;
  TableMeta t_;
  std::shared_ptr<std::FILE> side_;  // the side file, when t_.side
  std::string side_key_;              // its survey's key (release_side())
  int fd_ = -1;
  std::uint64_t file_size_ = 0;
  std::vector<int> slot_of_col_;
  std::vector<std::size_t> cols_;
  std::vector<double> values_, buf_;
  std::uint64_t row_ = 0, block0_ = 0, block_rows_ = 0;
  int time_slot_ = -1;
  double last_time_ = 0;
  std::shared_future<std::string> digest_;
};

}  // namespace

std::unique_ptr<TableSource> open_hdf5_table(const fs::path& file, const std::string& dataset, bool digest) {
  return std::make_unique<Hdf5Table>(file, dataset, digest);
}

bool recording_has_table(const fs::path& dir, const std::string& name) {
  if (fs::exists(dir / (name + ".csv"))) return true;
  const fs::path h5 = dir / kHdf5RecordingFile;
  if (!fs::exists(h5)) return false;
  try {
    const FileMeta& fm = survey(h5);
    const auto it = fm.tables.find(name);
    return fm.error.empty() && it != fm.tables.end() && it->second.present;
  } catch (const InputError&) {
    return false;  // a damaged file: its reader says so
  }
}

bool hdf5_has_dataset(const fs::path& file, const std::string& name) {
  if (!fs::exists(file)) throw InputError(file.string(), 0, "", "cannot open: no such file");
  const FileMeta& fm = survey(file);
  if (!fm.error.empty()) throw InputError(file.string(), 0, "", fm.error);
  const auto it = fm.tables.find(name);
  return it != fm.tables.end() && it->second.present;
}

std::string imu_table_file_name(const fs::path& dir) {
  try {
    if (dir.empty()) return "";
    const fs::path f = table_file(dir, "imu");
    return fs::is_regular_file(f) ? f.filename().string() : "";
  } catch (const std::exception&) {
    return "";
  }
}

std::string imu_table_file_label(const fs::path& dir) {
  const std::string n = imu_table_file_name(dir);
  return n.empty() ? "the IMU table's file (imu.csv, or recording.h5 for an HDF5 recording)" : n;
}

fs::path table_file(const fs::path& dir, const std::string& name) {
  const fs::path csv = dir / (name + ".csv");
  if (fs::exists(csv) || !fs::exists(dir / kHdf5RecordingFile)) return csv;
  return dir / kHdf5RecordingFile;
}

Hdf5TableInfo hdf5_table_info(const fs::path& file, const std::string& dataset) {
  const TableMeta& m = table_meta(file, dataset);
  return Hdf5TableInfo{m.columns, m.comments, static_cast<std::size_t>(m.rows)};
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
