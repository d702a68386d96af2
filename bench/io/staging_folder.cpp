#include "bench/io/staging_folder.hpp"

#include "bench/io/json_util.hpp"
#include "common/input_error.hpp"

namespace calbench {

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
