// Fleet statistics: the distribution of each coefficient over devices (newest non-revoked set of
// each), with outliers flagged by the robust z-score z = 0.6745·(x − median)/MAD (Iglewicz &
// Hoaglin), |z| > 3.5 an outlier.
#pragma once
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::db {

inline constexpr double kOutlierZ = 3.5;

struct CoefficientStats {
  std::string name;     // e.g. "gyro.bias.x"
  std::string unit;     // display unit: "deg/h", "mg" or "ppm"
  double to_display = 1;  // multiply SI by this for the display unit
  std::size_t n = 0;
  double median = 0, mad = 0, min = 0, max = 0, mean = 0, stddev = 0;  // SI
  struct Point {
    std::string serial;
    std::int64_t set_id;
    double value, sigma, z;
    bool outlier;
  };
  std::vector<Point> points;  // one per device
};

// Display unit of a coefficient name: gyro bias °/h, accelerometer bias mg, M ppm.
void display_unit(const std::string& name, std::string& unit, double& to_display);
double median_of(std::vector<double> v);
std::vector<CoefficientStats> fleet_stats(const std::vector<FleetValue>& values);

}  // namespace calbench::db
