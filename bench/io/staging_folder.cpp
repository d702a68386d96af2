#include "bench/io/staging_folder.hpp"

#include <signal.h>

#include <cerrno>

#include "bench/io/json_util.hpp"
#include "common/input_error.hpp"

namespace calbench {

void remove_stale_staging(const std::filesystem::path& parent, const std::string& prefix) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(parent, ec)) {
    const std::string n = e.path().filename().string();
    if (n.size() <= prefix.size() || n.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string pid = n.substr(prefix.size());
    if (pid.find_first_not_of("0123456789") != std::string::npos || pid.size() > 9) continue;
    const long p = std::stol(pid);
    if (p == ::getpid() || ::kill(static_cast<pid_t>(p), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to tell)
    std::filesystem::remove_all(e.path(), ec);
  }
}

std::filesystem::path import_output_folder(const std::string& out_arg, bool force) {
  std::filesystem::path out(out_arg);
  if (out.filename().empty()) out = out.parent_path();  // "rec/"
  if (std::filesystem::exists(out / "meta.json") && !force)
    throw InputError(out_arg, 0, "", "already holds a recording (use --force to overwrite)");
  check_output_folder(out);
  std::filesystem::create_directories(out.has_parent_path() ? out.parent_path() : std::filesystem::path("."));
  return out;
}

void place_staged_recording(StagingFolder& staging, const std::filesystem::path& out,
                            std::initializer_list<const char*> files) {
  if (!std::filesystem::exists(out)) {
    std::filesystem::rename(staging.path(), out);
    staging.keep();
    return;
  }
  for (const char* f : files)
    if (std::filesystem::exists(staging.path() / f)) std::filesystem::rename(staging.path() / f, out / f);
}

}  // namespace calbench
