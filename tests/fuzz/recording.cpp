// Harness: a recording folder (bench/io/recording.*, bench/io/csv.*, bench/bench_recording.*).
// Input: meta.json, imu.csv, reference.csv and gnss.csv separated by lines "====" (fuzz_util.hpp);
// a file whose part is absent is not there. Read as `fit bench` reads a bench recording
// (load_bench_blocks), a drive with the readers of imu.csv, reference.csv and gnss.csv.
#include <cstdint>

#include "bench/bench_recording.hpp"
#include "common/input_error.hpp"
#include "bench/io/recording.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const fs::path dir = fuzz::fresh_folder("rec");
  const auto parts = fuzz::split_files(data, size, 4);
  static const char* names[] = {"meta.json", "imu.csv", "reference.csv", "gnss.csv"};
  for (std::size_t i = 0; i < parts.size(); ++i) fuzz::write_file(dir / names[i], parts[i]);
  try {
    const RecordingMeta m = read_meta(dir);
    if (m.kind == RecordingKind::bench) {
      try {
        load_bench_blocks(dir);
      } catch (const InputError&) {
      }
      BenchRefReader ref(dir / "reference.csv");
      BenchRefRow r;
      while (ref.next(r)) {
      }
    } else {
      try {
        ImuReader imu(dir / "imu.csv", m.imu_rate_hz);
        ImuRecord r;
        while (imu.next(r)) {
        }
      } catch (const InputError&) {
      }
      try {
        DriveRefReader ref(dir / "reference.csv");
        DriveRefRow r;
        while (ref.next(r)) {
        }
      } catch (const InputError&) {
      }
      if (fs::exists(dir / "gnss.csv")) {
        GnssReader g(dir / "gnss.csv");
        GnssRow r;
        while (g.next(r)) {
        }
      }
    }
  } catch (const InputError&) {
    // bad input, refused with a message: not a finding
  }
  fds.verify();
  return 0;
}
