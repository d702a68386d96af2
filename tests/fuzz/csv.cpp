// Harness: the CSV reader alone (bench/io/csv.*), as `calbench identify INPUT` and every recording
// reader use it. Input: the file. Every column of the header is selected, "t_s" (if present) as
// the strictly increasing time.
#include <cstdint>

#include "bench/io/csv.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const auto file = fuzz::scratch() / "data.csv";
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    CsvReader r(file.string());
    const std::vector<std::string> header = r.header();
    std::vector<int> slots;
    for (const auto& h : header) slots.push_back(r.optional(h));
    const int t = r.optional("t_s");
    if (t >= 0) r.set_time_slot(t);
    volatile double sum = 0;
    while (r.next())
      for (const int s : slots)
        if (s >= 0) sum = sum + r.value(s);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
