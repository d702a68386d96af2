#include "calibration/bench_sim.hpp"

#include <cmath>

#include "calibration/effects/effect_registry.hpp"
#include "common/units.hpp"

namespace calbench {

BenchTimeline::BenchTimeline(const BenchPlan& plan) {
  const TableSpec& tb = plan.table;
  int mount = plan.steps.empty() ? 2 : plan.steps.front().mount;
  auto sync = [&] {
    const double t = std::max(outer_.end_time(), inner_.end_time());
    outer_.hold_until(t);
    inner_.hold_until(t);
    return t;
  };
  for (std::size_t k = 0; k < plan.steps.size(); ++k) {
    const PlanStep& s = plan.steps[k];
    if (s.mount != mount) {
      inner_.ramp_to(0.0, tb.max_accel);
      phase(sync(), -1, mount, true);
      outer_.hold(tb.remount_s);
      inner_.hold(tb.remount_s);
      phase(sync(), -1, mount, false);
      mount = s.mount;
    }
    inner_.ramp_to(0.0, tb.max_accel);
    sync();
    outer_.slew(std::remainder(s.outer - outer_.end_state().angle, 2 * M_PI), tb.slew_rate, tb.max_accel);
    inner_.slew(std::remainder(s.inner - inner_.end_state().angle, 2 * M_PI), tb.slew_rate, tb.max_accel);
    sync();
    if (s.kind == StepKind::rate) inner_.ramp_to(s.rate, tb.max_accel);
    outer_.hold(tb.settle_s);
    inner_.hold(tb.settle_s);
    phase(sync(), -1, mount, true);
    outer_.hold(s.dwell_s);
    inner_.hold(s.dwell_s);
    phase(sync(), static_cast<int>(k), mount, true);
  }
  inner_.ramp_to(0.0, tb.max_accel);
  phase(sync(), -1, mount, true);
}

void BenchTimeline::phase(double t1, int step, int mount, bool recording) {
  const double t0 = phases_.empty() ? 0.0 : phases_.back().t1;
  if (t1 <= t0) return;
  phases_.push_back({t0, t1, step, mount, recording});
}

double simulated_temperature(double t) {
  const double v = 25.0 + 6.0 * (1.0 - std::exp(-t / 900.0));
  return std::round(v / 0.00565) * 0.00565;
}

double TemperatureProfile::chamber_at(double t) const {
  if (chamber.empty()) return 25.0;
  if (t <= chamber.front().first) return chamber.front().second;
  for (std::size_t k = 1; k < chamber.size(); ++k)
    if (t <= chamber[k].first) {
      const auto& [t0, c0] = chamber[k - 1];
      const auto& [t1, c1] = chamber[k];
      return t1 > t0 ? c0 + (c1 - c0) * (t - t0) / (t1 - t0) : c1;
    }
  return chamber.back().second;
}

double simulated_temperature_rate(double t) { return 6.0 / 900.0 * std::exp(-t / 900.0); }

ProfileTemperature::ProfileTemperature(const TemperatureProfile& p) : p_(p), dev_(p.chamber_at(0.0)) {}

double ProfileTemperature::at(double t) {
  // First-order lag of the device behind the chamber, integrated forward in steps of ≤ 0.5 s
  // (exact for a setpoint that is constant over the step).
  while (t_ < t) {
    const double h = std::min(0.5, t - t_);
    const double c = p_.chamber_at(t_ + 0.5 * h);
    dev_ = p_.lag_s > 0 ? c + (dev_ - c) * std::exp(-h / p_.lag_s) : c;
    t_ += h;
  }
  const double v = dev_ + p_.self_heating_k * (1.0 - std::exp(-t / std::max(p_.self_heating_tau_s, 1e-9)));
  return std::round(v / 0.00565) * 0.00565;
}

double ProfileTemperature::rate() const {
  const double tau = std::max(p_.self_heating_tau_s, 1e-9);
  const double self = p_.self_heating_k / tau * std::exp(-t_ / tau);
  if (p_.lag_s > 0) return (p_.chamber_at(t_) - dev_) / p_.lag_s + self;
  constexpr double h = 0.25;
  return (p_.chamber_at(t_ + h) - p_.chamber_at(std::max(0.0, t_ - h))) / (t_ + h - std::max(0.0, t_ - h)) + self;
}

void simulate_bench(const BenchPlan& plan, const Site& site, const SensorErrors& truth, const BenchSimOptions& opt,
                    const std::function<void(const BenchSample&)>& sink) {
  const BenchTimeline tl(plan);
  const SiteEarth earth(site);
  const EffectTerms& fx = opt.effects;
  NoiseSpec noise = opt.noise;
  noise = noise_with_effects(noise, fx);  // a correlated_drift term replaces the drift prior
  const bool effects = fx.any();
  const Mat3 gyro_inv = (Mat3::Identity() + truth.gyro.M).inverse();
  const Mat3 accel_inv = (Mat3::Identity() + truth.accel.M).inverse();
  // What the IMU really experiences at time t (effects on), in IMU axes.
  auto true_kinematics = [&](double t, int mount, Vec3& w, Vec3& f, Mat3& C) {
    // The effects' truth-side hooks (effect_specs.cpp: time offset, wobble, tilted base), exact.
    const double te = truth_time(fx, t);
    const AxisState o = tl.outer(te);
    AxisState i = tl.inner(te);
    truth_table_angle(fx, i.angle, i.rate);
    const BenchKinematics k = bench_kinematics(earth, o, i, mount);
    w = k.w_ib_b;
    f = k.f_b;
    C = k.C_b_l;
    truth_level_frame(fx, k.C_b_l, k.f_b, k.C_b_l.transpose() * earth.w_ie_ned, f, w);
  };
  const bool need_dw = needs_rate_derivative(fx);
  ImuErrorSimulator imu(truth, noise, opt.seed);
  ProfileTemperature profile(plan.temperature);
  auto temperature = [&](double t) { return plan.temperature.set ? profile.at(t) : simulated_temperature(t); };
  const double dt = 1.0 / opt.noise.output_rate_hz;
  BenchSample s;
  std::size_t ph = 0;
  const auto& phases = tl.phases();
  for (std::uint64_t n = 0;; ++n) {
    const double t = static_cast<double>(n) * dt;
    while (ph < phases.size() && t >= phases[ph].t1) ++ph;
    if (ph >= phases.size()) break;
    const BenchPhase& p = phases[ph];
    if (!p.recording) continue;
    const AxisState o = tl.outer(t), i = tl.inner(t);
    const BenchKinematics k = bench_kinematics(earth, o, i, p.mount);
    Vec3 w_in = k.w_ib_b, f_in = k.f_b;
    const double temp = temperature(t);
    if (effects) {
      Mat3 C;
      true_kinematics(t, p.mount, w_in, f_in, C);
      EffectContext c;
      c.w = w_in;
      c.f = f_in;
      c.temp_c = temp;
      c.dtemp_k_s = plan.temperature.set ? profile.rate() : simulated_temperature_rate(t);
      if (need_dw) {
        constexpr double h = 2e-4;
        Vec3 wa, wb, fa, fb;
        Mat3 Ca, Cb;
        true_kinematics(t - h, p.mount, wa, fa, Ca);
        true_kinematics(t + h, p.mount, wb, fb, Cb);
        c.dw = (wb - wa) / (2 * h);
      }
      Vec3 dg, da;
      sensor_side_terms(fx, c, dg, da);
      // (I+M)(x + (I+M)⁻¹d) + b = (I+M)x + b + d: the extra output enters before noise and quantisation.
      w_in += gyro_inv * dg;
      f_in += accel_inv * da;
    }
    const auto out = imu.sample(t, w_in, f_in);
    s.t = t;
    s.gyro = out.gyro;
    s.accel = out.accel;
    s.saturated = out.saturated;
    s.temp_c = temp;
    s.w_ref = k.w_ib_b;
    s.f_ref = k.f_b;
    s.step = p.step;
    double a = std::fmod(units::deg(i.angle), 360.0);
    s.angle_deg = a < 0 ? a + 360.0 : a;
    sink(s);
  }
}

}  // namespace calbench
