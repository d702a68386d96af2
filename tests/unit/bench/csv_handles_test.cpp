// The CSV reader owns its file handle: a constructor that throws after opening (an empty file, no
// header) closes it. Before, each such file leaked a FILE* and a long-running process ran out of
// descriptors after a few hundred (issue 17, fuzzing).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "bench/io/csv.hpp"
#include "common/input_error.hpp"

namespace fs = std::filesystem;
using namespace calbench;

namespace {
std::size_t open_descriptors() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator("/proc/self/fd")) ++n;
  return n;
}
}  // namespace

TEST(CsvHandles, ReaderThatRefusesItsFileClosesIt) {
  const fs::path dir = fs::temp_directory_path() / ("calbench-csv-handles-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "empty.csv").close();
  std::ofstream(dir / "comments.csv") << "# only a comment\n\n";
  const std::size_t before = open_descriptors();
  int refused = 0;
  for (int i = 0; i < 300; ++i) {
    for (const char* f : {"empty.csv", "comments.csv"}) {
      try {
        CsvReader r((dir / f).string());
      } catch (const InputError& e) {
        ++refused;
        EXPECT_NE(std::string(e.what()).find("no header line"), std::string::npos) << e.what();
      }
    }
  }
  EXPECT_EQ(refused, 600);
  EXPECT_EQ(open_descriptors(), before);
  fs::remove_all(dir);
}
