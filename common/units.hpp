// Unit conversions. Everything inside calbench is SI; these are used only at the edges.
#pragma once
#include <numbers>

namespace calbench::units {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDeg = kPi / 180.0;          // rad per degree
inline constexpr double kDegPerHour = kDeg / 3600.0;  // rad/s per °/h
inline constexpr double kG0 = 9.80665;                // m/s² per g (standard gravity)
inline constexpr double kMilliG = kG0 * 1e-3;         // m/s² per mg
inline constexpr double kPpm = 1e-6;
inline constexpr double kSqrtHour = 60.0;             // √s per √h
// Earth rotation rate (WGS-84), rad/s.
inline constexpr double kEarthRate = 7.292115e-5;

inline constexpr double deg(double rad) { return rad / kDeg; }
inline constexpr double rad(double degrees) { return degrees * kDeg; }

}  // namespace calbench::units
