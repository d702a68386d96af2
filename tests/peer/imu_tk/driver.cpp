// Runs IMU-TK's MultiPosCalibration (Tedaldi, Pretto & Menegatti, ICRA 2014) on a pair of its text
// files and writes its result as JSON for calbench's comparison (bench/multipos/peer_imu_tk.py):
// the misalignment matrix T, scale matrix K and bias b of each triad, in IMU-TK's own convention
// (calibrated = T·K·(raw − b), raw in the files' units), and the static intervals it used.
//   imu_tk_driver ACC GYRO OUT.json [--acc-only] [--init-static S] [--gravity G]
//                 [--acc-bias-init B] [--gyro-scale-init K] [--verbose]
// The settings default to IMU-TK's own example for its xsens recording (apps/test_imu_calib.cpp).
// --verbose turns on IMU-TK's own verbose output on stdout (the static intervals it extracted per
// threshold multiplier and the one it kept; its plots are stubbed out by viewer_off.cpp); it changes
// no result.
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "imu_tk/calibration.h"
#include "imu_tk/io_utils.h"

using namespace imu_tk;

static nlohmann::json triad(const CalibratedTriad& c) {
  nlohmann::json j;
  const auto& T = c.getMisalignmentMatrix();
  const auto& K = c.getScaleMatrix();
  const auto& b = c.getBiasVector();
  for (int i = 0; i < 3; ++i) {
    j["T"].push_back({T(i, 0), T(i, 1), T(i, 2)});
    j["K"].push_back({K(i, 0), K(i, 1), K(i, 2)});
    j["b"].push_back(b(i));
  }
  return j;
}

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: imu_tk_driver ACC GYRO OUT.json [--acc-only] [--init-static S] [--gravity G] "
                 "[--acc-bias-init B] [--gyro-scale-init K] [--verbose]\n";
    return 2;
  }
  bool acc_only = false, verbose = false;
  double init_static = 50.0, g = 9.81744, acc_bias = 32768, gyro_scale = 1.0 / 6258.0;
  for (int i = 4; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&] { return std::atof(argv[++i]); };
    if (a == "--acc-only") acc_only = true;
    else if (a == "--verbose") verbose = true;
    else if (a == "--init-static") init_static = val();
    else if (a == "--gravity") g = val();
    else if (a == "--acc-bias-init") acc_bias = val();
    else if (a == "--gyro-scale-init") gyro_scale = val();
    else { std::cerr << "unknown option " << a << "\n"; return 2; }
  }
  std::vector<TriadData> acc, gyro;
  importAsciiData(argv[1], acc, TIMESTAMP_UNIT_SEC);
  importAsciiData(argv[2], gyro, TIMESTAMP_UNIT_SEC);
  CalibratedTriad init_acc, init_gyro;
  init_acc.setBias(Eigen::Vector3d::Constant(acc_bias));
  init_gyro.setScale(Eigen::Vector3d::Constant(gyro_scale));
  MultiPosCalibration mp;
  mp.setInitStaticIntervalDuration(init_static);
  mp.setInitAccCalibration(init_acc);
  mp.setInitGyroCalibration(init_gyro);
  mp.setGravityMagnitude(g);
  mp.enableVerboseOutput(verbose);
  mp.enableAccUseMeans(false);
  const bool ok = acc_only ? mp.calibrateAcc(acc) : mp.calibrateAccGyro(acc, gyro);
  nlohmann::json out;
  out["ok"] = ok;
  out["tool"] = "IMU-TK MultiPosCalibration";
  out["settings"] = {{"init_static_s", init_static}, {"gravity", g}, {"acc_bias_init", acc_bias},
                     {"gyro_scale_init", gyro_scale}, {"acc_only", acc_only}};
  if (ok) {
    out["acc"] = triad(mp.getAccCalib());
    if (!acc_only) out["gyro"] = triad(mp.getGyroCalib());
  }
  std::ofstream(argv[3]) << out.dump(2) << "\n";
  return ok ? 0 : 1;
}
