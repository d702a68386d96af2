// Harness: `calbench import imu-tk` (bench/multipos/import_imutk.*) and, on what it imports,
// `fit multipos`'s reader and estimator. Input: the accelerometer file and the gyro file separated
// by a line "====" (fuzz_util.hpp). Checks: tests/fuzz/multipos_import_check.hpp.
#include <cstdint>

#include "bench/multipos/import_imutk.hpp"
#include "tests/fuzz/multipos_import_check.hpp"

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
  fuzz::check_multipos_import("imutk", dir, [&] { import_imu_tk(a); });
  fds.verify();
  return 0;
}
