// The antenna blocks of the in-motion filter (issue 34, item 4), optional, each declared once:
//   lever arm ℓ (3 states, m, reference body axes): the correction of the nominal lever arm
//     (meta.json mounting.lever_arm_m) the filter estimates, constant, prior σ lever_arm_sigma;
//   time offset δt (1 state, s): GNSS time stamp minus the true time of the fix (the fix stamped t
//     describes the antenna at t − δt), constant, prior σ time_offset_sigma.
// Their observation parts extend eqs 13–14 (obs_position.cpp, obs_velocity.cpp). The lever arm
// adds to r: p̂_b = p̂_m − Ĉ_nb·(r + ℓ̂), v̂_b = v̂_m − Ĉ_nb·(ω_eb × (r + ℓ̂)); the time offset moves
// the prediction to the fix's true time: p̂_b(t − δt̂) ≈ p̂_b − v·δt̂, v̂_b(t − δt̂) ≈ v̂_b − a·δt̂.
// Errors are estimate minus truth (δℓ = ℓ̂ − ℓ, δt̂ − δt); with u_ℓ = Ĉ_nb·ℓ̂, w_ℓ = Ĉ_nb(ω × ℓ̂):
//   z_pos += −u_ℓ − v̂·δt̂;  H_ℓ = −Ĉ_nb,        H_att += −u_ℓ×,  H_mount += u_ℓ×·Ĉ_nb,  H_δt = −v̂, H_v += −δt̂·I
//   z_vel += −w_ℓ − a·δt̂;   H_ℓ = −Ĉ_nb·[ω×],   H_att += −w_ℓ×,  H_mount += w_ℓ×·Ĉ_nb,  H_δt = −a,
//                           H += Ĉ_nb·J(ℓ̂)
// (the attitude and mounting terms are those of eqs 13–14 for the lever's part ℓ̂; J: ω_eb's own
// dependence on the state, lever_rate_jacobian in observation.hpp). Where the
// filter sets the MEMS position from a fix (start, heading re-alignment) it adds Ĉ_nb·ℓ̂ + v·δt̂,
// and the position error starts as Ĉ_nb·δℓ + v·δ(δt) (BlockSpec::position_offset).
#include "calibration/inmotion/inmotion_filter.hpp"

namespace calbench::inmotion {

namespace {
const char* const kLeverCols[] = {"lever_arm_dx_m", "lever_arm_dy_m", "lever_arm_dz_m"};
const char* const kTimeCols[] = {"time_offset_s"};


BlockSpec lever_arm_block() {
  BlockSpec b{kLeverArmBlock, "lever_arm", 3, kLeverCols, "m", "m", 1.0, true, false};
  b.active = [](const InMotionConfig& cfg) { return cfg.estimate_lever_arm; };
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    for (int i = 0; i < 3; ++i) P(off + i, off + i) = in.cfg.lever_arm_sigma * in.cfg.lever_arm_sigma;
  };
  b.feedback = additive_feedback<3>;
  b.observe = [](const BlockObsInput& o, const Nominal& n, int type, int off, MatRef H, Eigen::Vector3d& z) {
    if (type != 0 && type != 1) return;
    const Mat3 C_nb = predicted_body_attitude(o.c);
    const Vec3 l = n.x.segment<3>(off);
    const Vec3 u = type == 0 ? Vec3(C_nb * l) : Vec3(C_nb * o.c.w_eb_b.cross(l));
    z -= u;
    H.block<3, 3>(0, off) = type == 0 ? Mat3(-C_nb) : Mat3(-C_nb * ins::skew(o.c.w_eb_b));
    H.block<3, 3>(0, o.c.att) -= ins::skew(u);
    if (o.c.mount >= 0) H.block<3, 3>(0, o.c.mount) += ins::skew(u) * C_nb;
    if (type == 1) H += C_nb * lever_rate_jacobian(o.c, l);
  };
  b.total = slice_total<3>;
  b.position_offset = [](const Nominal&, const Mat3Ref& C_nb, const Vec3Ref&, int, Eigen::MatrixXd& A) { A = C_nb; };
  return b;
}

BlockSpec time_offset_block() {
  BlockSpec b{kTimeOffsetBlock, "time_offset", 1, kTimeCols, "s", "s", 1.0, true, false};
  b.active = [](const InMotionConfig& cfg) { return cfg.estimate_time_offset; };
  b.init = [](const BlockInit& in, const filter::BlockLayout&, int off, MatRef P) {
    P(off, off) = in.cfg.time_offset_sigma * in.cfg.time_offset_sigma;
  };
  b.feedback = additive_feedback<1>;
  b.observe = [](const BlockObsInput& o, const Nominal& n, int type, int off, MatRef H, Eigen::Vector3d& z) {
    if (type != 0 && type != 1) return;
    const Vec3 rate = type == 0 ? o.c.mems->v : o.c.a_ned;  // of the reference body origin (the lever's part neglected)
    z -= rate * n.x(off);
    H.block<3, 1>(0, off) = -rate;
    if (type == 0) H.block<3, 3>(0, o.c.vel) -= Mat3::Identity() * n.x(off);  // v̂ = v + δv in −v̂·δt̂
  };
  b.total = slice_total<1>;
  b.position_offset = [](const Nominal&, const Mat3Ref&, const Vec3Ref& v, int, Eigen::MatrixXd& A) { A = v; };
  return b;
}

}  // namespace

const std::array<BlockSpec, 2>& antenna_blocks() {
  static const std::array<BlockSpec, 2> specs = {{lever_arm_block(), time_offset_block()}};
  return specs;
}

}  // namespace calbench::inmotion
