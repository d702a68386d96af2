// A folder written beside its final place under a hidden name (.NAME.TAG-PID) and renamed into
// place only when complete, so that a writer that fails or is killed leaves nothing half written
// under NAME: removed with this object unless kept.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <initializer_list>
#include <string>

namespace calbench {

// Removes the staging folders `parent`/PREFIX<pid> whose process is gone (killed by Ctrl-C or a
// power cut: no destructor ran), so that an interrupted writer's hidden copy does not stay.
void remove_stale_staging(const std::filesystem::path& parent, const std::string& prefix);

class StagingFolder {
 public:
  // out: the final folder; its parent must exist. Any stale staging folder of this process, or of a
  // process that no longer runs, goes.
  StagingFolder(const std::filesystem::path& out, const char* tag) {
    const std::filesystem::path parent = out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
    std::string name(".");  // built with append(): GCC 12 warns falsely (-Wrestrict) on chained operator+
    name.append(out.filename().string()).append(".").append(tag).append("-").append(std::to_string(::getpid()));
    path_ = parent / name;
    remove_stale_staging(parent, name.substr(0, name.size() - std::to_string(::getpid()).size()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directory(path_);
  }
  ~StagingFolder() {
    if (kept_) return;
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  StagingFolder(const StagingFolder&) = delete;
  StagingFolder& operator=(const StagingFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }
  void keep() { kept_ = true; }  // it was renamed or emptied: nothing to remove

 private:
  std::filesystem::path path_;
  bool kept_ = false;
};

// An importer's output folder: `out` as given ("rec/" → "rec"), refused when it already holds a
// recording unless `force`, its parent created.
std::filesystem::path import_output_folder(const std::string& out, bool force);
// The importer's last step: the staged recording becomes `out`; with --force into an existing folder
// the recording's `files` replace those there (meta.json last, so it is listed last), the rest kept.
void place_staged_recording(StagingFolder& staging, const std::filesystem::path& out,
                            std::initializer_list<const char*> files);

}  // namespace calbench
