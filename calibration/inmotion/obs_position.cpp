// Eq 13: position difference, INS-MEMS (moved to the reference body origin through the lever
// arm) minus the reference, expressed in metres north, east, down (equivalent to the paper's
// latitude/longitude/height differences scaled by the radii of curvature).
//   p̂_b = p̂_m − Ĉ_nb·r,  Ĉ_nb = (I − φ_b×)C_nb,  φ_b = φ − C_nb·δμ
//   ⇒ z = δr − (C_nb r)×φ + (C_nb r)×C_nb·δμ.
#include "calibration/inmotion/observation.hpp"

namespace calbench::inmotion {

Observation position_observation(const ObsContext& c, const RefObs& r) {
  Observation o;
  o.H.setZero(3, c.n_states);
  const Mat3 C_nb = predicted_body_attitude(c);
  const Vec3 Cr = C_nb * c.lever;
  double lat = c.mems->lat, lon = c.mems->lon, h = c.mems->h;
  ins::geodetic_add_ned(lat, lon, h, -Cr);
  o.z = ins::geodetic_diff_ned(lat, lon, h, r.lat, r.lon, r.h);
  o.H.block<3, 3>(0, c.pos) = Mat3::Identity();
  o.H.block<3, 3>(0, c.att) = -ins::skew(Cr);
  if (c.mount >= 0) o.H.block<3, 3>(0, c.mount) = ins::skew(Cr) * C_nb;
  o.R = Mat3::Identity() * (r.sigma_pos * r.sigma_pos);
  if (r.sigma_pos_v > 0) o.R(2, 2) = r.sigma_pos_v * r.sigma_pos_v;  // GNSS: vertical σ of its own
  return o;
}

}  // namespace calbench::inmotion
