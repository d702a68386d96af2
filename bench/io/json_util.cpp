#include "bench/io/json_util.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "bench/io/verify_recording.hpp"
#include "common/input_error.hpp"
#include "common/json_parse.hpp"

namespace calbench {

nlohmann::json read_json_file(const std::filesystem::path& file) { return parse_json_text(read_json_text(file), file.string()); }

void check_output_path(const std::filesystem::path& file) {
  // Named by the path the user gave (the temporary file beside it is an implementation detail).
  if (std::filesystem::is_directory(file)) throw InputError(file.string(), 0, "", "is a folder: give a file name to write");
  const auto parent = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(parent))
    throw InputError(file.string(), 0, "", "cannot write: the folder " + parent.string() + " does not exist");
  if (::access(parent.c_str(), W_OK) != 0)
    throw InputError(file.string(), 0, "", "cannot write into the folder " + parent.string() + ": " + std::strerror(errno) +
                                               " (give another path)");
}

void check_output_folder(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (fs::exists(dir) && !fs::is_directory(dir))
    throw InputError(dir.string(), 0, "", "is a file, not a folder: give a folder to write into");
  // The nearest folder that exists must take new entries (the rest is created below it).
  fs::path p = dir;
  while (!p.empty() && !fs::exists(p)) p = p.parent_path();
  if (p.empty()) p = ".";
  if (!fs::is_directory(p)) throw InputError(dir.string(), 0, "", "cannot create the folder: " + p.string() + " is a file");
  if (::access(p.c_str(), W_OK) != 0)
    throw InputError(dir.string(), 0, "", "cannot write into " + p.string() + ": " + std::strerror(errno) + " (give another folder)");
}

void write_text_atomic(const std::filesystem::path& file, const std::string& text) {
  check_output_path(file);
  const auto tmp = file.string() + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    const int e = errno;  // a place that takes no files is the user's choice (bad input); anything else a failure
    if (e == EACCES || e == EPERM || e == EROFS) throw InputError(file.string(), 0, "", std::string("cannot write: ") + std::strerror(e));
    throw std::runtime_error(file.string() + ": cannot write: " + std::strerror(e));
  }
  std::size_t off = 0;
  while (off < text.size()) {
    const ssize_t n = ::write(fd, text.data() + off, text.size() - off);
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error(file.string() + ": write failed: " + std::strerror(errno));
    }
    off += static_cast<std::size_t>(n);
  }
  ::fsync(fd);
  ::close(fd);
  try {  // renamed into place only once it reads back as written
    TextTally tally;
    tally.add(text);
    verify_written_text(tmp, tally);
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    ::unlink(tmp.c_str());
    throw std::runtime_error(file.string() + ": rename failed: " + std::strerror(errno));
  }
}

}  // namespace calbench
