// calbench import kf-gins --imu IMU.txt --truth truth.nav [--gnss GNSS.pos] --out DIR
#include <iostream>

#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "bench/drive/import_kfgins.hpp"

namespace calbench::cli {
namespace {

const bool registered = add_command(95, [](CLI::App& app) {
  CLI::App* imp = app.add_subcommand("import", "Convert other data formats into the recording interchange format");
  imp->require_subcommand(1);
  auto a = std::make_shared<ImportKfGinsArgs>();
  auto rpy = std::make_shared<std::vector<double>>();
  auto lever = std::make_shared<std::vector<double>>();
  auto* k = imp->add_subcommand("kf-gins", "KF-GINS text files (IMU increments, truth.nav, GNSS .pos) -> drive recording");
  k->add_option("--imu", a->imu, "IMU file: t, dtheta xyz (rad), dvel xyz (m/s)")->required()->check(CLI::ExistingFile);
  k->add_option("--truth", a->truth, "truth.nav: week, t, lat, lon (deg), h, vn, ve, vd, roll, pitch, yaw (deg)")->required()->check(CLI::ExistingFile);
  k->add_option("--gnss", a->gnss, "GNSS .pos: t, lat, lon (deg), h, std n/e/u (m)")->check(CLI::ExistingFile);
  k->add_option("--out", a->out, "recording folder to write")->required();
  k->add_option("--rate", a->rate_hz, "IMU rate, Hz (default: from the median interval)")->check(finite_positive());
  k->add_option("--model", a->model, "device model for meta.json");
  k->add_option("--serial", a->serial, "device serial for meta.json");
  k->add_option("--mounting-rpy", *rpy, "nominal mounting roll,pitch,yaw deg (default 0,0,0: IMU = body axes)")
      ->expected(3)
      ->delimiter(',')
      ->check(finite_number(-360, 360));
  k->add_option("--lever-arm", *lever, "IMU origin in reference body axes, m (default 0,0,0)")
      ->expected(3)
      ->delimiter(',')
      ->check(finite_number(-100, 100));
  k->add_option("--ref-sigma-pos", a->ref_sigma_pos_m, "reference position 1-sigma written to reference.csv, m (0.05)")->check(finite_positive());
  k->add_option("--ref-sigma-vel", a->ref_sigma_vel_m_s, "reference velocity 1-sigma, m/s (0.01)")->check(finite_positive());
  k->add_option("--ref-sigma-att", a->ref_sigma_att_deg, "reference attitude 1-sigma, deg (0.01)")->check(finite_positive());
  k->add_flag("--force", a->force, "overwrite an existing recording in --out");
  k->callback([a, rpy, lever] {
    if (rpy->size() == 3) a->mounting_rpy_deg = Vec3((*rpy)[0], (*rpy)[1], (*rpy)[2]);
    if (lever->size() == 3) a->lever_arm_m = Vec3((*lever)[0], (*lever)[1], (*lever)[2]);
    const ImportSummary s = import_kf_gins(*a);
    std::cout << "imported " << s.imu_rows << " IMU rows (" << s.rate_hz << " Hz), " << s.ref_rows << " reference rows, "
              << s.gnss_rows << " GNSS fixes into " << a->out << std::endl;
  });
});

}  // namespace
}  // namespace calbench::cli
