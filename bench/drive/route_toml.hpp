// Route files (TOML) for the drive simulator; format in docs/in-motion.md. Every defect is an
// InputError naming the file, line and key.
#pragma once
#include <filesystem>

#include "calibration/drive_sim/drive_simulator.hpp"

namespace calbench {

struct RouteFile {
  drivesim::Route route;
  Vec3 mounting_rpy_deg = Vec3::Zero();  // nominal MEMS → reference body (meta.json)
  Vec3 lever_arm_m = Vec3::Zero();       // MEMS origin in reference body axes
  double misalignment_sigma_deg = 0.5;   // --truth random: true mounting = nominal + N(0, σ²) per angle
  double imu_rate_hz = 2460;
  drivesim::ReferenceErrors reference;
  drivesim::GnssErrors gnss;
};

RouteFile load_route(const std::filesystem::path& file);

// The true mounting `simulate drive --truth random --seed N` draws: nominal + N(0, σ²) per angle, deg.
Vec3 draw_true_mounting_rpy_deg(const RouteFile& rf, std::uint64_t seed);

}  // namespace calbench
