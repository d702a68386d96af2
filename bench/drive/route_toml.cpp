#include "bench/drive/route_toml.hpp"

#include <cmath>
#include <random>
#include <toml++/toml.h>

#include "bench/io/toml_read.hpp"
#include "bench/io/toml_text.hpp"
#include "common/input_error.hpp"
#include "bench/io/message_text.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using Ctx = TomlReader;

}  // namespace

RouteFile load_route(const std::filesystem::path& file) {
  Ctx c{file.string()};
  const toml::table root = parse_toml_file(file);
  using units::kDeg;
  RouteFile rf;
  c.check_keys(root, "", {"name", "description", "start", "mounting", "imu", "reference", "gnss", "vehicle", "segment"});
  if (auto n = root.get("name")) rf.route.name = n->value<std::string>().value_or("");
  if (auto n = root.get("description")) rf.route.description = n->value<std::string>().value_or("");
  const toml::table* st = root["start"].as_table();
  if (!st) c.fail(&root, "start", "missing table [start]");
  c.check_keys(*st, "start.", {"lat_deg", "lon_deg", "h_m", "heading_deg"});
  rf.route.lat = c.num(*st, "start.", "lat_deg", std::nullopt, -85, 85) * kDeg;
  rf.route.lon = c.num(*st, "start.", "lon_deg", std::nullopt, -180, 360) * kDeg;
  rf.route.h = c.num(*st, "start.", "h_m", 0.0, -500, 9000);
  rf.route.heading = c.num(*st, "start.", "heading_deg", 0.0, -360, 360) * kDeg;
  if (const toml::table* m = root["mounting"].as_table()) {
    c.check_keys(*m, "mounting.", {"rpy_deg", "lever_arm_m", "misalignment_sigma_deg"});
    rf.mounting_rpy_deg = c.vec3(*m, "mounting.", "rpy_deg", Vec3::Zero());
    rf.lever_arm_m = c.vec3(*m, "mounting.", "lever_arm_m", Vec3::Zero());
    rf.misalignment_sigma_deg = c.num(*m, "mounting.", "misalignment_sigma_deg", 0.5, 0, 10);
  }
  if (const toml::table* m = root["imu"].as_table()) {
    c.check_keys(*m, "imu.", {"rate_hz"});
    rf.imu_rate_hz = c.num(*m, "imu.", "rate_hz", 2460.0, 50, 10000);
  }
  if (const toml::table* m = root["vehicle"].as_table()) {
    c.check_keys(*m, "vehicle.", {"roll_deg_per_m_s2", "pitch_deg_per_m_s2"});
    rf.route.roll_per_lat_accel = c.num(*m, "vehicle.", "roll_deg_per_m_s2", units::deg(rf.route.roll_per_lat_accel), 0, 10) * kDeg;
    rf.route.pitch_per_long_accel = c.num(*m, "vehicle.", "pitch_deg_per_m_s2", units::deg(rf.route.pitch_per_long_accel), 0, 10) * kDeg;
  }
  if (const toml::table* m = root["reference"].as_table()) {
    c.check_keys(*m, "reference.", {"rate_hz", "sigma_pos_m", "sigma_vel_m_s", "sigma_att_deg"});
    rf.reference.rate_hz = c.num(*m, "reference.", "rate_hz", rf.reference.rate_hz, 1, 1000);
    rf.reference.sigma_pos_m = c.num(*m, "reference.", "sigma_pos_m", rf.reference.sigma_pos_m, 0, 100);
    rf.reference.sigma_vel_m_s = c.num(*m, "reference.", "sigma_vel_m_s", rf.reference.sigma_vel_m_s, 0, 10);
    rf.reference.sigma_att_rad = c.num(*m, "reference.", "sigma_att_deg", units::deg(rf.reference.sigma_att_rad), 0, 10) * kDeg;
  }
  if (const toml::table* m = root["gnss"].as_table()) {
    c.check_keys(*m, "gnss.", {"rate_hz", "sigma_h_m", "sigma_v_m", "sigma_vel_m_s"});
    rf.gnss.rate_hz = c.num(*m, "gnss.", "rate_hz", rf.gnss.rate_hz, 0, 100);
    rf.gnss.sigma_h_m = c.num(*m, "gnss.", "sigma_h_m", rf.gnss.sigma_h_m, 0, 100);
    rf.gnss.sigma_v_m = c.num(*m, "gnss.", "sigma_v_m", rf.gnss.sigma_v_m, 0, 100);
    rf.gnss.sigma_vel_m_s = c.num(*m, "gnss.", "sigma_vel_m_s", rf.gnss.sigma_vel_m_s, 0, 10);
  }
  const toml::array* segs = root["segment"].as_array();
  if (!segs || segs->empty()) c.fail(&root, "segment", "a route needs at least one [[segment]]");
  for (std::size_t i = 0; i < segs->size(); ++i) {
    const toml::table* t = (*segs)[i].as_table();
    const std::string p = "segment[" + std::to_string(i) + "].";
    if (!t) c.fail(&(*segs)[i], p, "expected a table");
    drivesim::Segment s;
    s.line = static_cast<int>(t->source().begin.line);
    const auto type = (*t)["type"].value<std::string>();
    if (!type) c.fail(t, p + "type", "missing or not a string");
    if (*type == "accelerate") {
      c.check_keys(*t, p, {"type", "to_kmh", "duration_s"});
      s.kind = drivesim::SegmentKind::accelerate;
      s.to_speed = c.num(*t, p, "to_kmh", std::nullopt, 0, 250) / 3.6;
      s.duration_s = c.num(*t, p, "duration_s", 0.0, 0, 3600);
    } else if (*type == "cruise") {
      c.check_keys(*t, p, {"type", "duration_s"});
      s.kind = drivesim::SegmentKind::cruise;
      s.duration_s = c.num(*t, p, "duration_s", std::nullopt, 0.01, 36000);
    } else if (*type == "stop") {
      c.check_keys(*t, p, {"type", "duration_s"});
      s.kind = drivesim::SegmentKind::stop;
      s.duration_s = c.num(*t, p, "duration_s", std::nullopt, 0, 36000);
    } else if (*type == "turn") {
      c.check_keys(*t, p, {"type", "angle_deg", "radius_m", "ramp_s"});
      s.kind = drivesim::SegmentKind::turn;
      s.angle = c.num(*t, p, "angle_deg", std::nullopt, -3600, 3600) * kDeg;
      if (s.angle == 0) c.fail(t->get("angle_deg"), p + "angle_deg", "must be non-zero (+ right, − left)");
      s.radius = c.num(*t, p, "radius_m", std::nullopt, 1, 100000);
      s.ramp_s = c.num(*t, p, "ramp_s", 0.0, 0, 60);
    } else if (*type == "climb" || *type == "descend") {
      c.check_keys(*t, p, {"type", "grade_pct", "duration_s", "ramp_s"});
      s.kind = drivesim::SegmentKind::climb;
      const double g = c.num(*t, p, "grade_pct", std::nullopt, 0, 40);
      s.grade = std::atan(g / 100.0) * (*type == "descend" ? -1 : 1);
      s.duration_s = c.num(*t, p, "duration_s", std::nullopt, 0.1, 36000);
      s.ramp_s = c.num(*t, p, "ramp_s", 0.0, 0, 60);
    } else if (*type == "lane_change") {
      c.check_keys(*t, p, {"type", "width_m", "duration_s"});
      s.kind = drivesim::SegmentKind::lane_change;
      s.width = c.num(*t, p, "width_m", 3.5, -20, 20);
      s.duration_s = c.num(*t, p, "duration_s", 4.0, 1, 60);
    } else {
      c.fail(t->get("type"), p + "type",
             "unknown segment type '" + *type + "' (accelerate, cruise, stop, turn, climb, descend, lane_change)");
    }
    rf.route.segments.push_back(s);
  }
  try {
    drivesim::RouteProfile check(rf.route);
  } catch (const std::invalid_argument& e) {
    // The message names the segment's line.
    throw InputError(file.string(), 0, "segment", e.what());
  }
  return rf;
}

Vec3 draw_true_mounting_rpy_deg(const RouteFile& rf, std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x6d6f756e74ULL);
  std::normal_distribution<double> n(0.0, rf.misalignment_sigma_deg);
  Vec3 rpy = rf.mounting_rpy_deg;
  for (int i = 0; i < 3; ++i) rpy(i) += n(rng);
  return rpy;
}

}  // namespace calbench
