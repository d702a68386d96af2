// Shared by the harnesses of tests/fuzz (README.md there): a scratch folder per process, files
// written from the fuzz input, and the split of one input into several files.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

namespace calbench::fuzz {

// A folder of its own for this process (under $TMPDIR, scripts/fuzz points that at /dev/shm),
// removed at exit. Parsers' warnings (std::cerr) are silenced: they are expected output.
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::cerr.rdbuf(nullptr);
    std::string tmpl = (std::filesystem::temp_directory_path() / "calbench-fuzz-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
      std::perror("calbench fuzz: mkdtemp");
      std::abort();
    }
    std::atexit([] { std::error_code ec; std::filesystem::remove_all(scratch(), ec); });
    return std::filesystem::path(tmpl);
  }();
  return dir;
}

// scratch()/name, emptied: the folder one input's files are written to.
inline std::filesystem::path fresh_folder(const char* name) {
  const std::filesystem::path dir = scratch() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_file(const std::filesystem::path& p, std::string_view bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    std::perror("calbench fuzz: write");
    std::abort();
  }
}

// Open file descriptors of the process. A reader that loses its FILE* (an exception between fopen
// and the owner taking it) keeps one open; LeakSanitizer does not see that, as glibc still lists
// the FILE. Harnesses that open files count before and after (FdCheck): a difference is a finding.
inline std::size_t open_fds() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) ++n;
  return n;
}
class FdCheck {
 public:
  FdCheck() : before_(open_fds()) {}
  void verify() const {
    const std::size_t after = open_fds();
    if (after != before_) {
      std::fprintf(stderr, "calbench fuzz: %zu file descriptor(s) leaked by this input\n", after - before_);
      std::abort();
    }
  }

 private:
  std::size_t before_;
};

// The separator of the files in one input: a line holding only "====". Each part keeps its own
// line ends (the separator's leading newline ends the part before it); an input that starts with
// "====\n" has an empty first part. At most `max_parts` parts: the last one takes the rest.
inline std::vector<std::string_view> split_files(const std::uint8_t* data, std::size_t size, std::size_t max_parts) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view sep = "====\n";
  std::vector<std::string_view> parts;
  std::size_t begin = 0;
  while (parts.size() + 1 < max_parts) {
    std::size_t at = std::string_view::npos;
    for (std::size_t p = begin; (p = in.find(sep, p)) != std::string_view::npos; ++p)
      if (p == begin || in[p - 1] == '\n') {
        at = p;
        break;
      }
    if (at == std::string_view::npos) break;
    parts.push_back(in.substr(begin, at - begin));
    begin = at + sep.size();
  }
  parts.push_back(in.substr(begin));
  return parts;
}

// A finding of a harness's own (beyond crashes and unexpected exceptions): said on stderr, aborts.
[[noreturn]] inline void finding(const char* harness, const char* what, const std::string& detail) {
  std::fprintf(stderr, "%s harness: %s: %s\n", harness, what, detail.c_str());
  std::abort();
}

// An importer's refusal must leave nothing in the output folder's place under `dir`: neither the
// folder `out_name` nor its staging folder (".OUT.importing-PID").
inline void check_refused_import_left_nothing(const std::filesystem::path& dir, const std::string& out_name,
                                              const char* harness, const std::string& why) {
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name == out_name || name.rfind("." + out_name + ".importing-", 0) == 0)
      finding(harness, "refused import left output behind", name + " after: " + why);
  }
}

}  // namespace calbench::fuzz
