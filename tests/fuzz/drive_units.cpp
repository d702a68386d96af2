// Harness: units.json of a multi-unit drive (bench/drive/drive_units.*), in a drive folder whose two
// unit folders (1, 2) are whole recordings sharing reference.csv, so that the checks past the JSON run
// too. Input: units.json.
#include <cstdint>

#include "bench/drive/drive_units.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

namespace {
const std::filesystem::path& drive() {
  static const std::filesystem::path dir = [] {
    const auto d = fuzz::scratch() / "drive";
    const char* ref = "t_s,lat_deg,lon_deg,h_m,vn_m_s,ve_m_s,vd_m_s,roll_deg,pitch_deg,yaw_deg\n"
                      "0,52,13,40,0,0,0,0,0,0\n";
    const char* meta = "{\"format\": \"calbench-recording/1\", \"kind\": \"drive\", \"device\": {\"model\": \"ADIS16488A\", "
                       "\"serial\": \"F1\"}, \"imu_rate_hz\": 100, \"mounting\": {\"rpy_deg\": [0, 0, 0], "
                       "\"lever_arm_m\": [0, 0, 0]}}";
    std::filesystem::create_directories(d);
    fuzz::write_file(d / "reference.csv", ref);
    for (const char* u : {"1", "2"}) {
      std::filesystem::create_directories(d / u);
      fuzz::write_file(d / u / "reference.csv", ref);
      fuzz::write_file(d / u / "meta.json", meta);
      fuzz::write_file(d / u / "imu.csv", "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n");
    }
    return d;
  }();
  return dir;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto& d = drive();
  const fuzz::FdCheck fds;
  fuzz::write_file(d / "units.json", std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    load_drive_units(d);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
