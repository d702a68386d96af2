// A temporary folder for a unit test, removed with it.
#pragma once
#include <stdlib.h>

#include <filesystem>

namespace calbench::test {

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/calbench-test-XXXXXX";
    path_ = ::mkdtemp(tmpl);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace calbench::test
