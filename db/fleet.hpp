// Fleet statistics: the distribution of each coefficient over devices (newest non-revoked set of
// each), with outliers flagged by the robust z-score z = 0.6745·(x − median)/MAD (Iglewicz &
// Hoaglin), |z| > 3.5 an outlier.
#pragma once
#include <string>
#include <vector>

#include "common/statistics.hpp"  // median_of
#include "db/store.hpp"

namespace calbench::db {

inline constexpr double kOutlierZ = 3.5;
// Fewer units than this are no distribution to be an outlier of (a MAD of 4 values flags the ends):
// the coefficient is listed, and not judged (CoefficientStats::judged false; issue 56 item 14).
inline constexpr std::size_t kOutlierMinUnits = 8;

struct CoefficientStats {
  std::string name;     // e.g. "gyro.bias.x"
  std::string unit;     // display unit: "deg/h", "mg" or "ppm"
  double to_display = 1;  // multiply SI by this for the display unit
  std::size_t n = 0;
  bool judged = false;  // n ≥ kOutlierMinUnits: outliers flagged; else none (too few units)
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
std::vector<CoefficientStats> fleet_stats(const std::vector<FleetValue>& values);

// Per station: do its units agree with the other stations' units? A table or fixture fault moves
// every unit calibrated on it the same way (a tilted table: accelerometer biases and skews; a
// table-rate error: gyro scale factors), which no single unit shows as an outlier. For each
// coefficient, the station's median against the other stations' median, in units of the standard
// error of the difference of two medians, 1.2533·√(σ_s²/n_s + σ_o²/n_o) with σ = 1.4826·MAD of each
// group (Welch's form: a station whose units merely scatter more is not also called offset):
// |z| > kStationZ flags it. Also its spread: MAD of the station over MAD of the others > kStationSpread
// (with at least kStationSpreadMinUnits units). A station needs ≥ 2 units and the others ≥ 3.
inline constexpr double kStationZ = 3.5;
inline constexpr double kStationSpread = 3.0;
inline constexpr std::size_t kStationSpreadMinUnits = 5;
struct StationCoefficient {
  std::string name, unit;
  double to_display = 1;
  std::size_t n = 0, n_others = 0;
  double median = 0, median_others = 0, z = 0, spread_ratio = 0;  // SI medians
  bool offset_flag = false, spread_flag = false;
};
struct StationStats {
  std::string station;  // "" : sets without a known station
  std::size_t devices = 0;
  std::size_t others = 0;  // units of the other stations
  bool tested = false;  // enough units here and elsewhere to compare
  bool flagged = false;
  std::vector<StationCoefficient> coefficients;  // every coefficient when tested
  std::vector<std::string> serials;
};
std::vector<StationStats> station_stats(const std::vector<FleetValue>& values);
// "consistent", "DRIFTS APART: check its table and fixture", "not compared (no other station to
// compare with)" or "not compared (too few units: …)".
std::string station_verdict(const StationStats& s);

}  // namespace calbench::db
