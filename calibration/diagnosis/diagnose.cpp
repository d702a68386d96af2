#include "calibration/diagnosis/diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "calibration/bench_fit.hpp"
#include "calibration/diagnosis/greedy_search.hpp"
#include "calibration/gauss_markov_window.hpp"

namespace calbench {

namespace {

constexpr int kAxes = 6;  // a = sensor·3 + axis
constexpr int kBase = 4;  // b, M_i0, M_i1, M_i2

// Halves for the held-out check: the first and the second half of every plan step (splitting by
// whole steps would leave one half without the ±rate pairs or magnitudes a term needs).
bool in_subset(const DiagData& d, int p, int subset) {
  if (subset == kSubsetAll) return true;
  int first = p, last = p;
  while (first > 0 && d.parents[first - 1].step == d.parents[p].step) --first;
  while (last + 1 < static_cast<int>(d.parents.size()) && d.parents[last + 1].step == d.parents[p].step) ++last;
  const bool early = 2 * (p - first) < (last - first + 1);
  return early == (subset == kSubsetEven);
}

// Everything precomputed once: raw observations and regressor columns per sub-block.
struct Design {
  std::vector<Term> terms;
  std::vector<int> term_param_offset;  // into the global parameter vector after the 24 base params
  int n_term_params = 0;
  // per axis: columns (base 4, then every term param that touches the axis)
  std::vector<int> col_of[kAxes];  // col_of[a][t] = first local column of term t on axis a, −1 if none
  int ncols[kAxes] = {};
  std::vector<Eigen::VectorXd> z;  // per axis: raw z per sub-block (measured − ref − carried)
  std::vector<Eigen::MatrixXd> X;  // per axis: Nsub × ncols raw columns
  double white_var[kAxes] = {};
};

struct Dataset {
  int axis = 0, subset = kSubsetAll;
  std::vector<int> parents;  // parent indices
  Eigen::MatrixXd L;         // Cholesky factor of the parent covariance
  Eigen::VectorXd zl;        // whitened parent-level z
  Eigen::MatrixXd Xl;        // whitened parent-level columns
  Eigen::MatrixXd G;         // Gram (low + high)
  Eigen::VectorXd g;
  double zz = 0;
  Eigen::MatrixXd Gl;
  Eigen::VectorXd gl;
  double zzl = 0;
  int n_low = 0, n_high = 0;
  double logdet = 0;
  double drift_sigma = 0, drift_tau = 1;
};

using Model = std::vector<int>;  // indices into Design::terms

struct FitOut {
  Eigen::VectorXd theta;  // [24 base | term params (only those in the model, in model order)]
  Eigen::MatrixXd cov;
  double chi2 = 0;
  double chi2_axis[kAxes] = {};
  std::vector<int> offset;  // per model term, start in theta
  double logdet_info = 0;   // ln det(Xᵀ R⁻¹ X): the restricted-likelihood (REML) term
};

double sensor_ref(const SubBlock& s, int a, int c) {
  const Vec3& ref = a < 3 ? s.w : s.f;
  return ref(c);
}

Design build_design(const DiagData& d, const EffectTerms& carried) {
  Design D;
  // The bench refits M: a scale_factor term would be M_ii again.
  for (const Term& t : candidate_terms())
    if (effect_spec(t.effect).bench_candidate) D.terms.push_back(t);
  for (int a = 0; a < kAxes; ++a) {
    D.col_of[a].assign(D.terms.size(), -1);
    int c = kBase;
    for (std::size_t t = 0; t < D.terms.size(); ++t)
      if (D.terms[t].touches(a / 3, a % 3)) {
        D.col_of[a][t] = c;
        c += D.terms[t].nparams();
      }
    D.ncols[a] = c;
  }
  for (const auto& t : D.terms) {
    D.term_param_offset.push_back(D.n_term_params);
    D.n_term_params += t.nparams();
  }
  const int N = static_cast<int>(d.subs.size());
  D.z.assign(kAxes, Eigen::VectorXd(N));
  D.X.resize(kAxes);
  for (int a = 0; a < kAxes; ++a) D.X[a] = Eigen::MatrixXd::Zero(N, D.ncols[a]);
  const bool carry = carried.any();
  for (int j = 0; j < N; ++j) {
    const SubBlock& s = d.subs[j];
    Vec3 cg = Vec3::Zero(), ca = Vec3::Zero();
    if (carry) predict_extra(carried, s, cg, ca);
    for (int a = 0; a < kAxes; ++a) {
      const int i = a % 3;
      D.z[a](j) = a < 3 ? s.gyro(i) - s.w(i) - cg(i) : s.accel(i) - s.f(i) - ca(i);
      D.X[a](j, 0) = 1.0;
      for (int c = 0; c < 3; ++c) D.X[a](j, 1 + c) = sensor_ref(s, a, c);
    }
    for (std::size_t t = 0; t < D.terms.size(); ++t) {
      const Term& term = D.terms[t];
      for (int p = 0; p < term.nparams(); ++p) {
        EffectTerms unit;
        unit.t0_c = carried.t0_c;
        term.add_param(unit, p, 1.0);
        Vec3 dg, da;
        predict_extra(unit, s, dg, da);
        for (int a = 0; a < kAxes; ++a)
          if (D.col_of[a][t] >= 0) D.X[a](j, D.col_of[a][t] + p) = a < 3 ? dg(a) : da(a - 3);
      }
    }
  }
  // White noise per sample: pooled scatter inside static sub-blocks (all if none is static).
  for (int a = 0; a < kAxes; ++a) {
    double ss = 0, dof = 0, ss_all = 0, dof_all = 0;
    for (const auto& s : d.subs) {
      const double v = a < 3 ? s.gyro_ss(a) : s.accel_ss(a - 3);
      ss_all += v;
      dof_all += s.n - 1;
      if (!s.rotating()) {
        ss += v;
        dof += s.n - 1;
      }
    }
    D.white_var[a] = std::max(dof > 100 ? ss / dof : ss_all / std::max(dof_all, 1.0), 1e-30);
  }
  return D;
}

double bench_sigma(const ParentBlock& p, int a, const TableSpec& table) {
  BenchBlock b;
  b.w = p.w;
  b.f = p.f;
  return bench_fit_detail::bench_error_sigma(b, a < 3 ? TriadId::gyro : TriadId::accel, a % 3, table);
}

// Parent-level raw means of z and columns.
void parent_means(const DiagData& d, const Design& D, int a, int p, double& z, Eigen::RowVectorXd& x) {
  const ParentBlock& pb = d.parents[p];
  z = 0;
  x = Eigen::RowVectorXd::Zero(D.ncols[a]);
  for (int j = pb.first; j < pb.first + pb.count; ++j) {
    const double w = static_cast<double>(d.subs[j].n) / pb.n;
    z += w * D.z[a](j);
    x += w * D.X[a].row(j);
  }
}

Eigen::MatrixXd parent_cov(const DiagData& d, const std::vector<int>& P, int a, double white_var, double ds, double tau,
                           const TableSpec& table) {
  const int N = static_cast<int>(P.size());
  Eigen::MatrixXd R(N, N);
  std::vector<double> sb(N);
  for (int k = 0; k < N; ++k) sb[k] = bench_sigma(d.parents[P[k]], a, table);
  for (int k = 0; k < N; ++k)
    for (int l = 0; l <= k; ++l) {
      const ParentBlock &pk = d.parents[P[k]], &pl = d.parents[P[l]];
      double v = ds * ds * gm_window_correlation(pk.t_mid, pk.duration, pl.t_mid, pl.duration, tau);
      if (pk.step == pl.step) v += sb[k] * sb[l];
      if (k == l) v += white_var / pk.n;
      R(k, l) = R(l, k) = v;
    }
  return R;
}

Dataset build_dataset(const DiagData& d, const Design& D, int a, int subset, double ds, double tau,
                      const DiagnoseOptions& opt) {
  Dataset S;
  S.axis = a;
  S.subset = subset;
  S.drift_sigma = ds;
  S.drift_tau = tau;
  for (int p = 0; p < static_cast<int>(d.parents.size()); ++p)
    if (in_subset(d, p, subset)) S.parents.push_back(p);
  const int N = static_cast<int>(S.parents.size());
  const int C = D.ncols[a];
  Eigen::VectorXd zP(N);
  Eigen::MatrixXd XP(N, C);
  for (int k = 0; k < N; ++k) {
    double z;
    Eigen::RowVectorXd x;
    parent_means(d, D, a, S.parents[k], z, x);
    zP(k) = z;
    XP.row(k) = x;
  }
  const Eigen::MatrixXd R = parent_cov(d, S.parents, a, D.white_var[a], ds, tau, opt.table);
  Eigen::LLT<Eigen::MatrixXd> llt(R);
  S.L = llt.matrixL();
  S.zl = S.L.triangularView<Eigen::Lower>().solve(zP);
  S.Xl = S.L.triangularView<Eigen::Lower>().solve(XP);
  S.logdet = 2 * S.L.diagonal().array().log().sum();
  S.Gl = S.Xl.transpose() * S.Xl;
  S.gl = S.Xl.transpose() * S.zl;
  S.zzl = S.zl.squaredNorm();
  S.n_low = N;
  S.G = S.Gl;
  S.g = S.gl;
  S.zz = S.zzl;
  // High level: sub-block deviations from their parent's mean, white noise only.
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    if (pb.count < 2) continue;
    double zp;
    Eigen::RowVectorXd xp;
    parent_means(d, D, a, S.parents[k], zp, xp);
    for (int j = pb.first; j < pb.first + pb.count; ++j) {
      const double nj = d.subs[j].n;
      const double var = D.white_var[a] / nj * (1.0 - nj / pb.n);
      if (var <= 0) continue;
      const double w = 1.0 / std::sqrt(var);
      const double zh = (D.z[a](j) - zp) * w;
      const Eigen::RowVectorXd xh = (D.X[a].row(j) - xp) * w;
      S.G.noalias() += xh.transpose() * xh;
      S.g += xh.transpose() * zh;
      S.zz += zh * zh;
      ++S.n_high;
    }
  }
  return S;
}

// Local (column, global parameter) pairs of a model on axis a.
std::vector<std::pair<int, int>> column_map(const Design& D, const Model& m, int a, std::vector<int>& offset) {
  std::vector<std::pair<int, int>> cm;
  for (int c = 0; c < kBase; ++c) cm.push_back({c, a * kBase + c});
  offset.clear();
  int off = kAxes * kBase;
  for (int t : m) {
    offset.push_back(off);
    if (D.col_of[a][t] >= 0)
      for (int p = 0; p < D.terms[t].nparams(); ++p) cm.push_back({D.col_of[a][t] + p, off + p});
    off += D.terms[t].nparams();
  }
  return cm;
}

int model_params(const Design& D, const Model& m) {
  int n = kAxes * kBase;
  for (int t : m) n += D.terms[t].nparams();
  return n;
}

double axis_chi2(const Dataset& S, const std::vector<std::pair<int, int>>& cm, const Eigen::VectorXd& theta, bool low_only) {
  const Eigen::MatrixXd& G = low_only ? S.Gl : S.G;
  const Eigen::VectorXd& g = low_only ? S.gl : S.g;
  double chi2 = low_only ? S.zzl : S.zz;
  for (const auto& [c, p] : cm) {
    chi2 -= 2 * theta(p) * g(c);
    for (const auto& [c2, p2] : cm) chi2 += theta(p) * G(c, c2) * theta(p2);
  }
  return chi2;
}

FitOut fit_model(const Design& D, const Model& m, const std::vector<const Dataset*>& sets) {
  const int P = model_params(D, m);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(P, P);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(P);
  FitOut out;
  for (const Dataset* S : sets) {
    const auto cm = column_map(D, m, S->axis, out.offset);
    for (const auto& [c, p] : cm) {
      b(p) += S->g(c);
      for (const auto& [c2, p2] : cm) A(p, p2) += S->G(c, c2);
    }
  }
  // Jacobi scaling, tiny ridge for parameters the subset cannot see.
  Eigen::VectorXd s(P);
  for (int i = 0; i < P; ++i) s(i) = A(i, i) > 0 ? 1.0 / std::sqrt(A(i, i)) : 1.0;
  Eigen::MatrixXd As = s.asDiagonal() * A * s.asDiagonal();
  As.diagonal().array() += 1e-10;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(As);
  out.theta = s.asDiagonal() * ldlt.solve(s.asDiagonal() * b);
  out.cov = s.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(P, P)) * s.asDiagonal();
  out.logdet_info = ldlt.vectorD().array().log().sum() - 2 * s.array().log().sum();
  for (const Dataset* S : sets) {
    std::vector<int> off;
    const auto cm = column_map(D, m, S->axis, off);
    const double c2 = axis_chi2(*S, cm, out.theta, false);
    out.chi2_axis[S->axis] += c2;
    out.chi2 += c2;
  }
  return out;
}

// The bench as a problem of the catalogue search (greedy_search.hpp): parameters [24 base | model
// terms in model order]; a term's penalty counts the parent and sub-block rows of the axes it
// touches, correlated_drift's the parent rows.
struct BenchProblem {
  using Dataset = calbench::Dataset;
  using Fit = FitOut;
  const DiagData& d;
  const Design& D;
  const DiagnoseOptions& opt;
  int n_terms() const { return static_cast<int>(D.terms.size()); }
  const Term& term(int t) const { return D.terms[t]; }
  Dataset build(int a, int subset, double ds, double tau) const { return build_dataset(d, D, a, subset, ds, tau, opt); }
  Fit fit(const Model& m, const std::vector<const Dataset*>& sets) const { return fit_model(D, m, sets); }
  double chi2(const Dataset& S, const Model& m, const Fit& f) const {
    std::vector<int> off;
    return axis_chi2(S, column_map(D, m, S.axis, off), f.theta, false);
  }
  bool touches(int t, int a) const { return D.col_of[a][t] >= 0; }
  int rows(const Dataset& S) const { return S.n_low + S.n_high; }
  int drift_rows(const Dataset& S) const { return S.n_low; }
  int param_index(const Fit& f, std::size_t k, int /*t*/) const { return f.offset[k]; }
};

// Residual per sub-block of axis a for parameters theta of model m.
Eigen::VectorXd residual(const Design& D, const Model& m, int a, const Eigen::VectorXd& theta) {
  std::vector<int> off;
  const auto cm = column_map(D, m, a, off);
  Eigen::VectorXd r = D.z[a];
  for (const auto& [c, p] : cm) r -= theta(p) * D.X[a].col(c);
  return r;
}

// Residual of the given coefficients (b, M) on axis a.
Eigen::VectorXd residual_coeffs(const Design& D, const SensorErrors& e, int a) {
  const TriadErrors& te = a < 3 ? e.gyro : e.accel;
  const int i = a % 3;
  Eigen::VectorXd r = D.z[a];
  r.array() -= te.bias(i);
  for (int c = 0; c < 3; ++c) r -= te.M(i, c) * D.X[a].col(1 + c);
  return r;
}

// Parent-block means of a sub-block residual series on one axis.
Eigen::VectorXd parent_means(const DiagData& d, const Dataset& S, const Eigen::VectorXd& r) {
  const int N = static_cast<int>(S.parents.size());
  Eigen::VectorXd rP(N);
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    double z = 0;
    for (int j = pb.first; j < pb.first + pb.count; ++j) z += d.subs[j].n * r(j);
    rP(k) = z / pb.n;
  }
  return rP;
}

// The drift as the noise model sees it in a residual series: the smoothed (conditional mean)
// first-order Gauss–Markov part of the parent means, E[drift | r] = K_drift · Σ⁻¹ · r.
Eigen::VectorXd smoothed_drift(const DiagData& d, const Dataset& S, const Eigen::VectorXd& r) {
  const int N = static_cast<int>(S.parents.size());
  const Eigen::VectorXd rw = S.L.triangularView<Eigen::Lower>().solve(parent_means(d, S, r));
  const Eigen::VectorXd v = S.L.transpose().triangularView<Eigen::Upper>().solve(rw);
  std::vector<double> centre(N), duration(N);
  for (int k = 0; k < N; ++k) {
    centre[k] = d.parents[S.parents[k]].t_mid;
    duration[k] = d.parents[S.parents[k]].duration;
  }
  return gm_window_smoothed(centre, duration, S.drift_sigma, S.drift_tau, v);
}

// Statistics of a residual series on one axis (dataset gives the noise model). The systematic
// figure removes `drift` (parent level) when given, else the drift smoothed from r itself. The
// before figure is given the drift smoothed from the final residual: smoothed from the base
// model's own residual the drift would absorb a slow effect (a temperature ramp, 1–2 mg over a
// chamber cycle) and hide it from the before figure; one drift estimate keeps before and after
// comparable.
AxisStats axis_stats(const DiagData& d, const Design& D, const Dataset& S, const Eigen::VectorXd& r, int nparams,
                     const Eigen::VectorXd* drift_given = nullptr) {
  AxisStats st;
  const int a = S.axis;
  const int N = static_cast<int>(S.parents.size());
  const Eigen::VectorXd rP = parent_means(d, S, r);
  const Eigen::VectorXd rw = S.L.triangularView<Eigen::Lower>().solve(rP);
  st.chi2_dof = rw.squaredNorm() / std::max(1, N - nparams / kAxes);
  std::vector<double> rv(rw.data(), rw.data() + rw.size());
  ljung_box(rv, std::min(10, std::max(1, N / 5)), st.ljung_box_q, st.ljung_box_p);
  // Drift as the noise model sees it (smoothed), to be removed from the systematic figure.
  const Eigen::VectorXd drift = drift_given ? *drift_given : smoothed_drift(d, S, r);
  // Per-step means (drift removed, white noise expectation subtracted).
  std::map<int, std::array<double, 3>> steps;  // step → Σn·r, Σn, duration
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    auto& acc = steps[pb.step];
    acc[0] += pb.n * (rP(k) - drift(k));
    acc[1] += pb.n;
    acc[2] += pb.duration;
  }
  double ms = 0, wt = 0;
  for (const auto& [step, acc] : steps) {
    const double m = acc[0] / acc[1];
    ms += acc[2] * (m * m - D.white_var[a] / acc[1]);
    wt += acc[2];
  }
  st.step_rms = std::sqrt(std::max(0.0, ms / std::max(wt, 1e-9)));
  // Within steps: deviations from the parent mean, binned by table angle (12 bins per step) for
  // rotating steps; sub-block χ² for the rest.
  double hi_chi2 = 0;
  int hi_n = 0;
  std::map<int, std::array<std::array<double, 3>, 12>> bins;  // step → bin → Σn·dev, Σn, Σ expected var·n²
  for (int k = 0; k < N; ++k) {
    const ParentBlock& pb = d.parents[S.parents[k]];
    if (pb.count < 2) continue;
    for (int j = pb.first; j < pb.first + pb.count; ++j) {
      const SubBlock& s = d.subs[j];
      const double dev = r(j) - rP(k);
      const double var = D.white_var[a] / s.n * (1.0 - static_cast<double>(s.n) / pb.n);
      if (var <= 0) continue;
      hi_chi2 += dev * dev / var;
      ++hi_n;
      if (s.rotating() && std::isfinite(s.angle)) {
        double u = std::fmod(s.angle, 2 * M_PI);
        if (u < 0) u += 2 * M_PI;
        const int b = std::min(11, static_cast<int>(u / (2 * M_PI) * 12));
        auto& bb = bins[pb.step][b];
        bb[0] += s.n * dev;
        bb[1] += s.n;
        bb[2] += var * s.n * s.n;
      }
    }
  }
  st.high_chi2_dof = hi_n > 0 ? hi_chi2 / hi_n : 0;
  double wms = 0, wwt = 0;
  for (const auto& [step, bs] : bins) {
    double sms = 0, sn = 0;
    for (const auto& bb : bs) {
      if (bb[1] <= 0) continue;
      const double m = bb[0] / bb[1];
      sms += bb[1] * (m * m - bb[2] / (bb[1] * bb[1]));
      sn += bb[1];
    }
    if (sn > 0) {
      wms += sms;
      wwt += sn;
    }
  }
  st.within_rms = std::sqrt(std::max(0.0, wwt > 0 ? wms / wwt : 0.0));
  st.systematic_rms = std::hypot(st.step_rms, st.within_rms);
  st.bic = rw.squaredNorm() + S.logdet + nparams / static_cast<double>(kAxes) * std::log(std::max(N, 2));
  return st;
}

std::vector<ConditionCorrelation> correlations(const DiagData& d, const Eigen::VectorXd& r) {
  std::vector<ConditionCorrelation> out;
  // Parent-level for slow conditions; sub-block deviations for the angle.
  std::vector<double> rp(d.parents.size());
  for (std::size_t p = 0; p < d.parents.size(); ++p) {
    const ParentBlock& pb = d.parents[p];
    double z = 0;
    for (int j = pb.first; j < pb.first + pb.count; ++j) z += d.subs[j].n * r(j);
    rp[p] = z / pb.n;
  }
  auto corr = [](const std::vector<double>& x, const std::vector<double>& y) {
    const double n = static_cast<double>(x.size());
    if (n < 3) return 0.0;
    const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n, my = std::accumulate(y.begin(), y.end(), 0.0) / n;
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
      sxy += (x[k] - mx) * (y[k] - my);
      sxx += (x[k] - mx) * (x[k] - mx);
      syy += (y[k] - my) * (y[k] - my);
    }
    return (sxx > 0 && syy > 0) ? sxy / std::sqrt(sxx * syy) : 0.0;
  };
  for (const auto& name : condition_names()) {
    if (name == "angle") continue;
    std::vector<double> x(d.parents.size());
    for (std::size_t p = 0; p < d.parents.size(); ++p) {
      const ParentBlock& pb = d.parents[p];
      x[p] = condition_value(d, d.subs[pb.first + pb.count / 2], name);
      if (name == "dT/dt") x[p] = pb.dtemp;
    }
    out.push_back({name, corr(x, rp)});
  }
  // Angle: amplitude-correlation of within-parent deviations with cos/sin of the angle (rotating).
  std::vector<double> dev, c, s;
  for (const auto& sb : d.subs)
    if (sb.rotating() && std::isfinite(sb.angle)) {
      dev.push_back(r(&sb - &d.subs[0]) - rp[sb.parent]);
      c.push_back(std::cos(sb.angle));
      s.push_back(std::sin(sb.angle));
    }
  if (dev.size() > 10) out.push_back({"angle", std::hypot(corr(c, dev), corr(s, dev))});
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return std::abs(x.r) > std::abs(y.r); });
  return out;
}

// Amplitude of harmonics 1..4 of the table angle in the within-parent residual (rotating sub-blocks).
void angle_spectrum(const DiagData& d, const Eigen::VectorXd& r, int& best_k, double& best_amp) {
  best_k = 0;
  best_amp = 0;
  std::vector<double> rp(d.parents.size());
  for (std::size_t p = 0; p < d.parents.size(); ++p) {
    const ParentBlock& pb = d.parents[p];
    double z = 0;
    for (int j = pb.first; j < pb.first + pb.count; ++j) z += d.subs[j].n * r(j);
    rp[p] = z / pb.n;
  }
  for (int k = 1; k <= 4; ++k) {
    double sc = 0, ss = 0, n = 0;
    for (const auto& sb : d.subs)
      if (sb.rotating() && std::isfinite(sb.angle)) {
        const double dev = r(&sb - &d.subs[0]) - rp[sb.parent];
        sc += dev * std::cos(k * sb.angle);
        ss += dev * std::sin(k * sb.angle);
        ++n;
      }
    if (n < 10) return;
    const double amp = 2 * std::hypot(sc, ss) / n;
    if (amp > best_amp) {
      best_amp = amp;
      best_k = k;
    }
  }
}

const char* revealing_condition(EffectId e) { return effect_spec(e).condition; }

}  // namespace

DiagFinding correlated_drift_finding(int triad, double sigma, double tau_s, const DriftInterval& interval,
                                     double delta_chi2, double delta_bic, const AxisStats (&before)[6],
                                     const AxisStats (&after)[6]) {
  DiagFinding f;
  f.term = Term{EffectId::correlated_drift, triad, -1};
  f.value = {sigma};
  f.sigma = {0.5 * (interval.sigma_hi - interval.sigma_lo)};
  f.noise_tau_s = tau_s;
  f.noise_interval = interval;
  f.unit = term_unit(f.term);
  f.report_sensor = triad;
  f.report_axis = -1;
  f.delta_chi2 = delta_chi2;
  f.delta_bic = delta_bic;
  f.condition = "time";
  double rb = 0, ra = 0;
  for (int a = triad * 3; a < triad * 3 + 3; ++a) {
    rb += std::pow(before[a].systematic_rms, 2);
    ra += std::pow(after[a].systematic_rms, 2);
  }
  f.rms_before = std::sqrt(rb / 3);
  f.rms_after = std::sqrt(ra / 3);
  return f;
}

std::vector<std::string> condition_names() {
  return {"rate", "w_x", "w_y", "w_z", "f_x", "f_y", "f_z", "temperature", "dT/dt", "time", "angle"};
}

double condition_value(const DiagData& d, const SubBlock& s, const std::string& name) {
  if (name == "rate") return s.w.norm();
  if (name == "w_x") return s.w(0);
  if (name == "w_y") return s.w(1);
  if (name == "w_z") return s.w(2);
  if (name == "f_x") return s.f(0);
  if (name == "f_y") return s.f(1);
  if (name == "f_z") return s.f(2);
  if (name == "temperature") return std::isfinite(s.temp_c) ? s.temp_c : 0.0;
  if (name == "dT/dt") return s.parent >= 0 ? d.parents[s.parent].dtemp : 0.0;
  if (name == "time") return s.t_mid;
  if (name == "angle") {
    if (!std::isfinite(s.angle)) return 0.0;
    double u = std::fmod(s.angle * 180.0 / M_PI, 360.0);
    return u < 0 ? u + 360.0 : u;
  }
  return 0.0;
}

std::string condition_axis_label(const std::string& name) {
  static const std::vector<std::pair<std::string, std::string>> units = {
      {"rate", "rad/s"},      {"|w|", "rad/s"},       {"w_x", "rad/s"},        {"w_y", "rad/s"},
      {"w_z", "rad/s"},       {"turn_rate", "rad/s"}, {"f_x", "m/s²"},         {"f_y", "m/s²"},
      {"f_z", "m/s²"},        {"f", "m/s²"},          {"|f|", "m/s²"},         {"along_accel", "m/s²"},
      {"ang_accel", "rad/s²"}, {"speed", "m/s"},      {"temperature", "°C"},   {"dT/dt", "°C/s"},
      {"time", "s"},          {"angle", "°"}};
  for (const auto& [n, u] : units)
    if (n == name) return name + " (" + u + ")";
  return name;
}

void ljung_box(const std::vector<double>& x, int lags, double& q, double& p) {
  const std::size_t n = x.size();
  q = 0;
  p = 1;
  if (n < 4 || lags < 1) return;
  const double m = std::accumulate(x.begin(), x.end(), 0.0) / n;
  double c0 = 0;
  for (double v : x) c0 += (v - m) * (v - m);
  if (c0 <= 0) return;
  for (int k = 1; k <= lags && k < static_cast<int>(n); ++k) {
    double ck = 0;
    for (std::size_t t = k; t < n; ++t) ck += (x[t] - m) * (x[t - k] - m);
    const double rho = ck / c0;
    q += rho * rho / (n - k);
  }
  q *= n * (n + 2.0);
  const double h = lags;
  const double z = (std::cbrt(q / h) - (1 - 2 / (9 * h))) / std::sqrt(2 / (9 * h));
  p = 0.5 * std::erfc(z / std::sqrt(2.0));
}

DiagnoseResult diagnose_bench(const DiagData& data, const SensorErrors& current, const EffectTerms& carried,
                              const DiagnoseOptions& opt) {
  DiagnoseResult res;
  if (data.parents.size() < 8) throw std::runtime_error("diagnose: fewer than 8 data blocks in plan steps");
  const Design D = build_design(data, carried);
  res.parents = static_cast<int>(data.parents.size());
  res.subs = static_cast<int>(data.subs.size());
  for (const auto& p : data.parents) res.data_s += p.duration;
  for (int a = 0; a < kAxes; ++a) res.white_sigma[a] = std::sqrt(D.white_var[a]);
  res.base_before = current;

  const BenchProblem problem{data, D, opt};
  GreedyPolicy policy;
  policy.min_delta_chi2 = opt.min_delta_chi2;
  policy.penalty_per_param = opt.penalty_per_param;
  policy.max_findings = opt.max_findings;
  policy.drift_competes = true;  // correlated_drift competes with the best linear term every round
  const double drift_sigma[2] = {opt.noise.gyro.drift_sigma, opt.noise.accel.drift_sigma};
  const double drift_tau[2] = {opt.noise.gyro.drift_tau_s, opt.noise.accel.drift_tau_s};
  GreedySearch<BenchProblem> search(problem, policy, drift_sigma, drift_tau);
  const std::vector<Dataset>& all = search.all;
  const double* ds = search.ds;
  const double* tau = search.tau;

  // Before: the given coefficients.
  Eigen::VectorXd r_before[kAxes];
  for (int a = 0; a < kAxes; ++a) {
    r_before[a] = residual_coeffs(D, current, a);
    res.before[a] = axis_stats(data, D, all[a], r_before[a], kAxes * kBase);
    res.correlations_before[a] = correlations(data, r_before[a]);
  }

  search.run();
  // Backward check (stepwise): a term accepted in an early round can lose its evidence once later
  // terms or a larger drift (correlated_drift) are in the model — e.g. a g-sensitivity that only
  // half-fitted an effect outside the catalogue. Withdrawn terms are reported, not findings.
  for (const auto& w : search.recheck_drift()) res.withdrawn.push_back(search.withdrawn_report(w));
  for (const auto& w : search.withdraw_weak()) res.withdrawn.push_back(search.withdrawn_report(w));
  const Model& model = search.model;
  const FitOut& cur = search.cur;

  // The improved model.
  search.fitted_terms(carried, res.improved_terms, res.terms_sigma);
  for (int a = 0; a < kAxes; ++a) {
    TriadErrors& te = a < 3 ? res.improved.gyro : res.improved.accel;
    const int i = a % 3;
    te.bias(i) = cur.theta(a * kBase);
    te.sigma_bias(i) = std::sqrt(std::max(cur.cov(a * kBase, a * kBase), 0.0));
    for (int c = 0; c < 3; ++c) {
      te.M(i, c) = cur.theta(a * kBase + 1 + c);
      te.sigma_M(i, c) = std::sqrt(std::max(cur.cov(a * kBase + 1 + c, a * kBase + 1 + c), 0.0));
    }
  }
  for (int triad = 0; triad < 2; ++triad) {
    res.drift_sigma[triad] = ds[triad];
    res.drift_tau[triad] = tau[triad];
  }
  Eigen::VectorXd r_after[kAxes];
  const int np = model_params(D, model);
  for (int a = 0; a < kAxes; ++a) {
    r_after[a] = residual(D, model, a, cur.theta);
    res.after[a] = axis_stats(data, D, all[a], r_after[a], np);
    // The before figures keep their own χ², whiteness and BIC (base model, data-sheet noise); the
    // systematic part is re-measured against the drift the data-sheet noise model sees in the final
    // residual (for linear findings the same drift the after figure removes; a correlated_drift
    // finding's excess drift stays in the before figure).
    // The data-sheet noise model: `all` unless a correlated_drift finding rebuilt this triad's
    // datasets (only then is it built again, not copied up front).
    const int triad = a / 3;
    const bool drift_changed = ds[triad] != drift_sigma[triad] || tau[triad] != drift_tau[triad];
    const Dataset prior = drift_changed ? problem.build(a, kSubsetAll, drift_sigma[triad], drift_tau[triad]) : Dataset{};
    const Dataset& noise_before = drift_changed ? prior : all[a];
    const Eigen::VectorXd drift = smoothed_drift(data, noise_before, r_after[a]);
    const AxisStats sys = axis_stats(data, D, noise_before, r_before[a], kAxes * kBase, &drift);
    res.before[a].step_rms = sys.step_rms;
    res.before[a].within_rms = sys.within_rms;
    res.before[a].systematic_rms = sys.systematic_rms;
    res.residual[a].before.assign(r_before[a].data(), r_before[a].data() + r_before[a].size());
    res.residual[a].after.assign(r_after[a].data(), r_after[a].data() + r_after[a].size());
  }

  // Findings.
  for (const auto& acc : search.steps) {
    if (acc.term < 0) {
      const int triad = -1 - acc.term;
      const DiagFinding f = correlated_drift_finding(triad, ds[triad], tau[triad], search.drift_interval[triad],
                                                     acc.dchi2, acc.dbic, res.before, res.after);
      res.findings.push_back(f);
      res.improved_terms.gyro.drift_sigma = ds[0] > opt.noise.gyro.drift_sigma ? ds[0] : 0;
      res.improved_terms.gyro.drift_tau_s = ds[0] > opt.noise.gyro.drift_sigma ? tau[0] : 0;
      res.improved_terms.accel.drift_sigma = ds[1] > opt.noise.accel.drift_sigma ? ds[1] : 0;
      res.improved_terms.accel.drift_tau_s = ds[1] > opt.noise.accel.drift_sigma ? tau[1] : 0;
      continue;
    }
    DiagFinding f = search.term_finding(acc, carried);
    const Term& t = D.terms[acc.term];
    // Could another candidate in its place explain the recording as well? It must itself explain
    // the residual (Δχ² ≥ min_delta_chi2 against the model without the finding) and fit within
    // ambiguity_chi2 of the finding.
    f.alternatives = search.alternatives(acc.term, opt.ambiguity_chi2, opt.min_delta_chi2, carried);
    // Axis on which it shows: the touched axis whose residual it explains most.
    std::vector<int> touched;
    for (int a = 0; a < kAxes; ++a)
      if (D.col_of[a][acc.term] >= 0) touched.push_back(a);
    if (effect_spec(t.effect).dominant_component) {
      int imax = 0;
      for (int i = 1; i < 3; ++i)
        if (std::abs(f.value[i]) > std::abs(f.value[imax])) imax = i;
      double others = 0;
      for (int i = 0; i < 3; ++i)
        if (i != imax) others = std::max(others, std::abs(f.value[i]));
      f.report_axis = others < 0.3 * std::abs(f.value[imax]) ? imax : -1;
    }
    double rb = 0, ra = 0;
    int n = 0;
    for (int a : touched) {
      if (t.sensor < 2 && f.report_axis >= 0 && !effect_spec(t.effect).dominant_component && a != t.sensor * 3 + t.axis) continue;
      rb += std::pow(res.before[a].systematic_rms, 2);
      ra += std::pow(res.after[a].systematic_rms, 2);
      ++n;
    }
    if (effect_spec(t.effect).dominant_component || t.sensor == 2) {
      // Report the worst-affected touched axis (largest systematic before).
      double worst = -1;
      for (int a : touched)
        if (res.before[a].systematic_rms > worst) {
          worst = res.before[a].systematic_rms;
          rb = worst * worst;
          ra = std::pow(res.after[a].systematic_rms, 2);
          n = 1;
        }
    }
    f.rms_before = n ? std::sqrt(rb / n) : 0;
    f.rms_after = n ? std::sqrt(ra / n) : 0;
    f.condition = revealing_condition(t.effect);
    if (effect_spec(t.effect).condition_by_column) {
      int jmax = 0;
      for (int j = 1; j < 3; ++j)
        if (std::abs(f.value[j]) > std::abs(f.value[jmax])) jmax = j;
      f.condition = std::string("f_") + "xyz"[jmax];
    }
    const int ra_axis = f.report_axis >= 0 && t.sensor < 2 ? t.sensor * 3 + f.report_axis : touched.front();
    for (const auto& c : res.correlations_before[ra_axis])
      if (c.condition == f.condition) f.condition_r = c.r;
    res.findings.push_back(f);
  }

  // Unexplained structure: an axis still far from its noise model.
  for (int a = 0; a < kAxes; ++a) {
    const AxisStats& s = res.after[a];
    const double n = std::max(1, all[a].n_low);
    const double z_low = (s.chi2_dof - 1) * std::sqrt(n / 2.0);
    const double z_high = (s.high_chi2_dof - 1) * std::sqrt(std::max(1, all[a].n_high) / 2.0);
    if (z_low < 6 && z_high < 6 && s.ljung_box_p > 1e-4) continue;
    DiagUnexplained u;
    u.sensor = a / 3;
    u.axis = a % 3;
    u.chi2_dof = s.chi2_dof;
    u.high_chi2_dof = s.high_chi2_dof;
    u.ljung_box_p = s.ljung_box_p;
    u.systematic_rms = s.systematic_rms;
    u.correlations = correlations(data, r_after[a]);
    if (u.correlations.size() > 4) u.correlations.resize(4);
    angle_spectrum(data, r_after[a], u.angle_harmonic, u.angle_harmonic_amp);
    // Worst steps by |mean residual| relative to its white-noise σ.
    std::map<int, std::pair<double, double>> st;
    for (const auto& sb : data.subs) {
      auto& x = st[sb.step];
      x.first += sb.n * r_after[a](&sb - &data.subs[0]);
      x.second += sb.n;
    }
    std::vector<std::pair<double, int>> score;
    for (const auto& [step, x] : st) score.push_back({std::abs(x.first / x.second) * std::sqrt(x.second), step});
    std::sort(score.rbegin(), score.rend());
    for (std::size_t k = 0; k < score.size() && k < 3; ++k) u.worst_steps.push_back(score[k].second);
    res.unexplained.push_back(u);
  }
  return res;
}

}  // namespace calbench
