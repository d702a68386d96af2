// Eq 15: attitude difference, INS-MEMS (through the mounting) minus the reference. The paper
// differences heading, pitch and roll; we use the equivalent small rotation in NED, which is free
// of the Euler-angle singularities: Ĉ_nb·C_nb,refᵀ = I − z×, and with Ĉ_nm = (I − φ×)C_nm,
// Ĉ_mb = (I − δμ×)C_mb:  z = φ − C_nb·δμ.
#include "calibration/inmotion/observation.hpp"

namespace calbench::inmotion {

Observation attitude_observation(const ObsContext& c, const RefObs& r) {
  Observation o;
  o.H.setZero(3, c.n_states);
  const Mat3 C_nb = predicted_body_attitude(c);
  const Mat3 C_ref = ins::dcm_from_rpy(r.rpy);
  o.z = -ins::rotvec_from_dcm(C_nb * C_ref.transpose());
  o.H.block<3, 3>(0, c.att) = Mat3::Identity();
  if (c.mount >= 0) o.H.block<3, 3>(0, c.mount) = -C_nb;
  o.R = Mat3::Identity() * (r.sigma_att * r.sigma_att);
  return o;
}

}  // namespace calbench::inmotion
