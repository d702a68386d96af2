#include "db/fleet.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/units.hpp"

namespace calbench::db {

void display_unit(const std::string& name, std::string& unit, double& to_display) {
  using namespace calbench::units;
  if (name.rfind("gyro.bias", 0) == 0) {
    unit = "deg/h";
    to_display = 1.0 / kDegPerHour;
  } else if (name.rfind("accel.bias", 0) == 0) {
    unit = "mg";
    to_display = 1.0 / kMilliG;
  } else {
    unit = "ppm";
    to_display = 1.0 / kPpm;
  }
}

std::vector<CoefficientStats> fleet_stats(const std::vector<FleetValue>& values) {
  std::map<std::string, CoefficientStats> by;
  for (const auto& name : coefficient_names()) {
    auto& s = by[name];
    s.name = name;
    display_unit(name, s.unit, s.to_display);
  }
  for (const auto& v : values) {
    auto it = by.find(v.name);
    if (it == by.end()) continue;
    it->second.points.push_back({v.serial, v.set_id, v.value, v.sigma, 0, false});
  }
  std::vector<CoefficientStats> out;
  for (const auto& name : coefficient_names()) {
    CoefficientStats s = by[name];
    s.n = s.points.size();
    s.judged = s.n >= kOutlierMinUnits;
    if (s.n) {
      std::vector<double> x;
      for (const auto& p : s.points) x.push_back(p.value);
      s.median = median_of(x);
      std::vector<double> dev;
      for (double xi : x) dev.push_back(std::abs(xi - s.median));
      s.mad = median_of(dev);
      s.min = *std::min_element(x.begin(), x.end());
      s.max = *std::max_element(x.begin(), x.end());
      double sum = 0, sq = 0;
      for (double xi : x) sum += xi;
      s.mean = sum / static_cast<double>(s.n);
      for (double xi : x) sq += (xi - s.mean) * (xi - s.mean);
      s.stddev = s.n > 1 ? std::sqrt(sq / static_cast<double>(s.n - 1)) : 0;
      for (auto& p : s.points) {
        // MAD = 0 (more than half identical): any value off the median is an outlier.
        const double d = p.value - s.median;
        p.z = s.mad > 0 ? 0.6745 * d / s.mad : (d == 0 ? 0 : std::copysign(INFINITY, d));
        p.outlier = s.n >= kOutlierMinUnits && std::abs(p.z) > kOutlierZ;
      }
    }
    out.push_back(std::move(s));
  }
  return out;
}

std::string station_verdict(const StationStats& s) {
  if (s.tested) return s.flagged ? "DRIFTS APART: check its table and fixture" : "consistent";
  if (s.others == 0) return "not compared (no other station to compare with)";
  return "not compared (too few units: " + std::to_string(s.devices) + " here, " + std::to_string(s.others) +
         " elsewhere; it needs 2 here and 3 elsewhere)";
}

std::vector<StationStats> station_stats(const std::vector<FleetValue>& values) {
  // station → coefficient → values; station → serials
  std::map<std::string, std::map<std::string, std::vector<double>>> by;
  std::map<std::string, std::vector<std::string>> serials;
  std::map<std::string, std::set<std::string>> seen;  // (a linear search here was quadratic: 90 s for 10^5 devices)
  for (const auto& v : values) {
    by[v.station][v.name].push_back(v.value);
    if (seen[v.station].insert(v.serial).second) serials[v.station].push_back(v.serial);
  }
  std::vector<StationStats> out;
  for (const auto& [station, coeffs] : by) {
    StationStats st;
    st.station = station;
    st.serials = serials[station];
    st.devices = st.serials.size();
    for (const auto& [o, os] : serials)
      if (o != station) st.others += os.size();
    for (const auto& name : coefficient_names()) {
      const auto it = coeffs.find(name);
      if (it == coeffs.end()) continue;
      std::vector<double> others;
      for (const auto& [o, oc] : by)
        if (o != station)
          if (const auto j = oc.find(name); j != oc.end()) others.insert(others.end(), j->second.begin(), j->second.end());
      const std::vector<double>& mine = it->second;
      if (mine.size() < 2 || others.size() < 3) continue;
      StationCoefficient c;
      c.name = name;
      display_unit(name, c.unit, c.to_display);
      c.n = mine.size();
      c.n_others = others.size();
      c.median = median_of(mine);
      c.median_others = median_of(others);
      std::vector<double> dev_o, dev_m;
      for (double x : others) dev_o.push_back(std::abs(x - c.median_others));
      for (double x : mine) dev_m.push_back(std::abs(x - c.median));
      const double mad_o = median_of(dev_o), mad_m = median_of(dev_m);
      const double sigma_o = 1.4826 * mad_o, sigma_m = 1.4826 * mad_m;
      const double se = 1.2533 * std::sqrt(sigma_m * sigma_m / static_cast<double>(c.n) +
                                           sigma_o * sigma_o / static_cast<double>(c.n_others));
      const double d = c.median - c.median_others;
      c.z = se > 0 ? d / se : (d == 0 ? 0 : std::copysign(INFINITY, d));
      c.spread_ratio = mad_o > 0 ? mad_m / mad_o : (mad_m == 0 ? 1 : INFINITY);
      c.offset_flag = std::abs(c.z) > kStationZ;
      c.spread_flag = c.n >= kStationSpreadMinUnits && c.spread_ratio > kStationSpread;
      st.tested = true;
      st.flagged = st.flagged || c.offset_flag || c.spread_flag;
      st.coefficients.push_back(c);
    }
    out.push_back(std::move(st));
  }
  return out;
}

}  // namespace calbench::db
