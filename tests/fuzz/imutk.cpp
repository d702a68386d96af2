// Harness: `calbench import imu-tk` (bench/multipos/import_imutk.*) and, on what it imports,
// `fit multipos`'s reader and estimator. Input: the accelerometer file and the gyro file separated
// by a line "====" (fuzz_util.hpp). Besides crashes and exceptions other than InputError, two
// findings of its own (abort): a refused import that leaves anything in the output folder's
// place, and an import that succeeds but writes a recording calbench's own reader refuses.
#include <cstdint>
#include <cstdio>

#include "bench/io/recording.hpp"
#include "bench/multipos/fit_multipos_run.hpp"
#include "bench/multipos/import_imutk.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;


extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const fs::path dir = fuzz::fresh_folder("imutk");
  const auto parts = fuzz::split_files(data, size, 2);
  ImportImuTkArgs a;
  a.acc = (dir / "acc.txt").string();
  a.gyro = (dir / "gyro.txt").string();
  a.out = (dir / "out").string();
  a.model = "Xsens MTi";
  fuzz::write_file(a.acc, parts[0]);
  fuzz::write_file(a.gyro, parts.size() > 1 ? parts[1] : std::string_view());
  try {
    import_imu_tk(a);
  } catch (const InputError& e) {
    fuzz::check_refused_import_left_nothing(dir, "out", "imutk", e.what());
    fds.verify();
    return 0;
  }
  try {  // what the import wrote, read back and fitted (a refusal is an InputError too)
    const MultiposRecording rec = read_multipos_recording(a.out, "");
    try {
      multipos::fit_multipos(rec.input, multipos::MultiposOptions{});
    } catch (const multipos::MultiposRefusal&) {
    }
  } catch (const InputError& e) {
    fuzz::finding("imutk", "the imported recording is refused by calbench's reader", e.what());
  }
  fds.verify();
  return 0;
}
