#include "calibration/bench_fit_effects.hpp"

#include <cmath>

#include "calibration/diagnosis/catalogue.hpp"

namespace calbench {

std::vector<BenchBlock> blocks_without_effects(const DiagData& d, const EffectTerms& e) {
  std::vector<BenchBlock> out;
  out.reserve(d.parents.size());
  const bool any = e.any();
  std::vector<Vec3> rg, ra;  // corrected sub-block residual means (measured − extra − reference)
  std::vector<double> wn;
  for (const ParentBlock& p : d.parents) {
    if (p.n < 2) continue;
    BenchBlock b;
    b.step = p.step;
    b.t_mid = p.t_mid;
    b.duration = p.duration;
    b.n = p.n;
    b.w = p.w;
    b.f = p.f;
    b.temp_c = p.temp_c;
    rg.clear();
    ra.clear();
    wn.clear();
    Vec3 mg = Vec3::Zero(), ma = Vec3::Zero();
    for (int j = p.first; j < p.first + p.count; ++j) {
      const SubBlock& s = d.subs[j];
      Vec3 dg = Vec3::Zero(), da = Vec3::Zero();
      if (any) predict_extra(e, s, dg, da);
      const double w = static_cast<double>(s.n) / p.n;
      b.gyro += w * (s.gyro - dg);
      b.accel += w * (s.accel - da);
      rg.push_back(s.gyro - dg - s.w);
      ra.push_back(s.accel - da - s.f);
      wn.push_back(s.n);
      mg += w * rg.back();
      ma += w * ra.back();
      b.gyro_ss += s.gyro_ss;
      b.accel_ss += s.accel_ss;
    }
    for (std::size_t k = 0; k < rg.size(); ++k) {
      b.gyro_ss += wn[k] * (rg[k] - mg).cwiseAbs2();
      b.accel_ss += wn[k] * (ra[k] - ma).cwiseAbs2();
    }
    out.push_back(b);
  }
  return out;
}

BenchFitOptions options_with_effects(BenchFitOptions opt, const EffectTerms& e) {
  opt.noise = noise_with_effects(opt.noise, e);
  return opt;
}

BenchFitResult fit_bench_with_effects(const DiagData& d, const EffectTerms& e, const BenchFitOptions& opt,
                                      const EffectTerms* sigma) {
  const BenchFitOptions o = options_with_effects(opt, e);
  BenchFitResult r = fit_bench(blocks_without_effects(d, e), o);
  if (!sigma) return r;
  SensorErrors var_b;  // accumulated (Δ estimate)² per coefficient, in the bias/M slots
  var_b.gyro.bias.setZero();
  var_b.accel.bias.setZero();
  var_b.gyro.M.setZero();
  var_b.accel.M.setZero();
  for (const Term& t : candidate_terms())
    for (int p = 0; p < t.nparams(); ++p) {
      const double s = t.get_param(*sigma, p);
      if (!(s > 0) || !std::isfinite(s)) continue;
      EffectTerms moved = e;
      t.add_param(moved, p, s);
      const SensorErrors est = fit_bench(blocks_without_effects(d, moved), o).estimate;
      for (int triad = 0; triad < 2; ++triad) {
        const TriadErrors& a = triad ? r.estimate.accel : r.estimate.gyro;
        const TriadErrors& b = triad ? est.accel : est.gyro;
        TriadErrors& v = triad ? var_b.accel : var_b.gyro;
        v.bias += (b.bias - a.bias).cwiseAbs2();
        v.M += (b.M - a.M).cwiseAbs2();
      }
    }
  for (int triad = 0; triad < 2; ++triad) {
    TriadErrors& a = triad ? r.estimate.accel : r.estimate.gyro;
    const TriadErrors& v = triad ? var_b.accel : var_b.gyro;
    for (int i = 0; i < 3; ++i) {
      if (std::isfinite(a.sigma_bias(i))) a.sigma_bias(i) = std::sqrt(a.sigma_bias(i) * a.sigma_bias(i) + v.bias(i));
      for (int j = 0; j < 3; ++j)
        if (std::isfinite(a.sigma_M(i, j))) a.sigma_M(i, j) = std::sqrt(a.sigma_M(i, j) * a.sigma_M(i, j) + v.M(i, j));
    }
  }
  return r;
}

}  // namespace calbench
