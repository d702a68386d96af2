#include "bench/io/recording_location.hpp"

#include <unistd.h>

#include <algorithm>
#include <vector>

#include "bench/io/recording.hpp"
#include "bench/io/sha256.hpp"
#include "common/input_error.hpp"
#include "common/percent_encode.hpp"

namespace calbench {
namespace fs = std::filesystem;

std::string file_uri(const fs::path& p) {
  char host[256] = {};
  const std::string h = ::gethostname(host, sizeof host - 1) == 0 && host[0] ? host : "localhost";
  const std::string path = fs::weakly_canonical(fs::absolute(p)).generic_string();
  return "file://" + h + percent_encode(path, "/");
}

std::string folder_digest(const fs::path& folder) {
  std::error_code ec;
  std::vector<std::string> files;
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) files.push_back(fs::relative(it->path(), folder, ec).generic_string());
  if (ec) throw InputError(folder.string(), 0, "", "cannot list the recording folder (" + ec.message() + ")");
  std::sort(files.begin(), files.end());
  Sha256 h;
  for (const auto& f : files) {
    const std::string size = std::to_string(fs::file_size(folder / f));
    h.update(f.data(), f.size() + 1);  // with its NUL
    h.update(size.data(), size.size() + 1);
    sha256_add_file(h, folder / f);
  }
  return h.hex();
}

void describe_recording(db::BenchRunInput& run, const fs::path& folder) {
  run.recording_path = folder.string();
  run.recording_uri = file_uri(folder);
  run.recording_digest = fs::is_directory(folder) ? folder_digest(folder) : "";
}

}  // namespace calbench
