// Harness: `calbench import kf-gins` (bench/drive/import_kfgins.*). Input: the IMU file, truth.nav
// and, if present, the GNSS .pos file, separated by lines "====" (fuzz_util.hpp). Besides crashes
// and other exceptions than InputError, two findings of its own (abort): a refused import that
// leaves anything in the output folder's place (a partial recording, or its ".importing-" folder),
// and an import that succeeds but writes a recording calbench's own readers refuse.
#include <cstdint>
#include <cstdio>

#include "bench/drive/import_kfgins.hpp"
#include "common/input_error.hpp"
#include "bench/io/recording.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;


extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const fs::path dir = fuzz::fresh_folder("kf");
  const auto parts = fuzz::split_files(data, size, 3);
  ImportKfGinsArgs a;
  a.imu = (dir / "imu.txt").string();
  a.truth = (dir / "truth.nav").string();
  a.out = (dir / "out").string();
  fuzz::write_file(a.imu, parts[0]);
  fuzz::write_file(a.truth, parts.size() > 1 ? parts[1] : std::string_view());
  if (parts.size() > 2) {
    a.gnss = (dir / "gnss.pos").string();
    fuzz::write_file(a.gnss, parts[2]);
  }
  try {
    import_kf_gins(a);
  } catch (const InputError& e) {
    fuzz::check_refused_import_left_nothing(dir, "out", "kfgins", e.what());
    fds.verify();
    return 0;
  }
  try {  // what the import wrote, read back
    const RecordingMeta m = read_meta(a.out);
    ImuReader imu(fs::path(a.out) / "imu.csv", m.imu_rate_hz);
    ImuRecord r;
    while (imu.next(r)) {
    }
    DriveRefReader ref(fs::path(a.out) / "reference.csv");
    DriveRefRow rr;
    while (ref.next(rr)) {
    }
    if (!a.gnss.empty()) {
      GnssReader g(fs::path(a.out) / "gnss.csv");
      GnssRow gr;
      while (g.next(gr)) {
      }
    }
  } catch (const InputError& e) {
    fuzz::finding("kfgins", "the imported recording is refused by calbench's readers", e.what());
  }
  fds.verify();
  return 0;
}
