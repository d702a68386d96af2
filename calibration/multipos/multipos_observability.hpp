// What a multi-position recording must hold for the fit to determine the coefficients, and the
// refusals that name what is missing, with counts (issue 55 item 4). A refusal never advises
// re-recording what the recording holds: the counts are of what the detector found, and the
// messages say which noise the detector used. Internal to calibration/multipos; no I/O.
#pragma once
#include <cstddef>
#include <vector>

#include "calibration/multipos/multipos_fit.hpp"

namespace calbench::multipos {

// Directions within this angle count once (greedy, in time order).
constexpr double kDistinctDirectionDeg = 10.0;

// No static pose at all: the refusal says the noise the test used and where it came from.
void refuse_no_poses(const MultiposFit& fit, const MultiposOptions& opt);
// A median |f̄| far from g over the poses is a wrong conversion, not a calibration.
void check_gravity_units(const std::vector<StaticInterval>& statics, double gravity);
// The number of distinct gravity directions among the used poses.
std::size_t count_distinct_directions(const std::vector<StaticInterval>& statics, const std::vector<int>& used);
// Enough poses, every axis's share of gravity spread, enough distinct directions.
void check_accel_observability(const MultiposFit& fit, const std::vector<int>& used, const MultiposOptions& opt);
// Rates in the wrong unit: the path length of the turns against the angle gravity turned through.
void check_gyro_units(const MultiposInput& in, const MultiposFit& fit, const std::vector<Vec3>& up, const Vec3& b0,
                      const std::vector<int>& rused);
// Enough rotations, and a rotation of 45° or more about each axis.
void check_rotation_observability(const MultiposFit& fit, const std::vector<int>& rused, const MultiposOptions& opt);

}  // namespace calbench::multipos
