// The in-motion filter's unobservable rotation and its covariance (gauge.hpp).
#include "calibration/inmotion/gauge.hpp"

#include <cmath>
#include <vector>

#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/ins/nav_math.hpp"

namespace calbench::inmotion {

Eigen::MatrixXd unobservable_rotation(const StateLayout& s, const Nominal& n) {
  const int att = s.offset(Block::att), mg = s.offset(Block::Mg), ma = s.offset(Block::Ma), mu = s.offset(Block::mount);
  if (att < 0 || mg < 0 || ma < 0 || mu < 0 || n.nav == nullptr) return {};
  const Eigen::Matrix3d C_nm = n.nav->C_nb();
  const Eigen::Matrix3d Ig = Eigen::Matrix3d::Identity() + n.mat3(mg), Ia = Eigen::Matrix3d::Identity() + n.mat3(ma);
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(s.size(), 3);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
    const Eigen::Matrix3d ex = ins::skew(e);
    const Eigen::Matrix3d dMg = Ig * ex, dMa = Ia * ex;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {  // M row by row
        N(mg + 3 * i + j, k) = dMg(i, j);
        N(ma + 3 * i + j, k) = dMa(i, j);
      }
    N.block<3, 1>(att, k) = -C_nm * e;
    N.block<3, 1>(mu, k) = -n.C_mb * e;
  }
  return N;
}

bool unobservable_rotation_covariance(const Eigen::MatrixXd& P, const Eigen::MatrixXd& N, Eigen::Matrix3d& S_out) {
  if (N.size() == 0) return false;
  // States whose variance is exactly zero (unused exp-cosine aux axes, a drift of σ 0) have zero
  // rows and columns in P: factorise over the others; N must not reach into them.
  std::vector<int> keep;
  for (int i = 0; i < P.rows(); ++i)
    if (P(i, i) > 0)
      keep.push_back(i);
    else if (N.row(i).any())
      return false;
  const Eigen::MatrixXd Pk = P(keep, keep);
  const Eigen::MatrixXd Nk = N(keep, Eigen::all);
  const Eigen::LLT<Eigen::MatrixXd> Pl(Pk);
  if (Pl.info() != Eigen::Success) return false;
  const Eigen::Matrix3d I = Nk.transpose() * Pl.solve(Nk);
  const Eigen::LLT<Eigen::Matrix3d> Il(I);
  if (Il.info() != Eigen::Success || !I.allFinite()) return false;
  const Eigen::Matrix3d S = Il.solve(Eigen::Matrix3d::Identity());
  if (!S.allFinite()) return false;
  S_out = S;
  return true;
}

void restore_unobservable_rotation(Eigen::MatrixXd& P, const Eigen::MatrixXd& N, const Eigen::Matrix3d& S) {
  Eigen::Matrix3d S_now;
  if (!unobservable_rotation_covariance(P, N, S_now)) return;
  P.noalias() += N * (S - S_now) * N.transpose();
  P = 0.5 * (P + P.transpose()).eval();
}

Eigen::Vector3d carry_unobservable_rotation(Eigen::MatrixXd& P, const Eigen::MatrixXd& N_before, const Eigen::MatrixXd& N_after) {
  Eigen::Matrix3d S;
  if (N_after.size() == 0 || !unobservable_rotation_covariance(P, N_before, S)) return Eigen::Vector3d::Zero();
  P.noalias() += N_after * S * N_after.transpose();
  P.noalias() -= N_before * S * N_before.transpose();
  P = 0.5 * (P + P.transpose()).eval();
  return S.diagonal().cwiseSqrt();
}

Eigen::Vector3d unobservable_rotation_sigma(const Eigen::MatrixXd& P, const Eigen::MatrixXd& N) {
  Eigen::Matrix3d S;
  if (!unobservable_rotation_covariance(P, N, S)) return Eigen::Vector3d::Zero();
  return S.diagonal().cwiseSqrt();
}

}  // namespace calbench::inmotion
