// Harness: recording.h5 of an HDF5 recording (bench/io/hdf5_recording.cpp, docs/recording-hdf5.md):
// every table opened as the recording readers open it (imu, reference, gnss; shape, type and the
// "columns" attribute checked), every column selected and every row read, and the conversion
// summary of each (hdf5_table_info). Input: the file's bytes (the corpus holds a small valid one,
// which the fuzzer damages).
#include <cstdint>

#include "bench/io/hdf5_recording.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto dir = fuzz::fresh_folder("h5");
  const auto file = dir / kHdf5RecordingFile;
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  const fuzz::FdCheck fds;
  for (const char* t : {"imu", "reference", "gnss"}) {
    try {
      const Hdf5TableInfo info = hdf5_table_info(file, t);
      const auto tab = open_hdf5_table(file, t);
      std::vector<int> slots;
      for (const auto& c : info.columns) slots.push_back(tab->optional(c));
      if (!slots.empty() && slots[0] >= 0) tab->set_time_slot(slots[0]);
      double sum = 0;
      while (tab->next())
        for (int s : slots)
          if (s >= 0) sum += tab->value(s);
      (void)sum;
    } catch (const InputError&) {
    }
  }
  (void)recording_has_table(dir, "imu");
  hdf5_drop_unused_surveys();  // the readers' survey cache, not a leak
  fds.verify();
  return 0;
}
