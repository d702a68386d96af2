#include "calibration/bench_sim.hpp"

#include <cmath>

#include "calibration/units.hpp"

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

void simulate_bench(const BenchPlan& plan, const Site& site, const SensorErrors& truth, const BenchSimOptions& opt,
                    const std::function<void(const BenchSample&)>& sink) {
  const BenchTimeline tl(plan);
  const SiteEarth earth(site);
  ImuErrorSimulator imu(truth, opt.noise, opt.seed);
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
    const auto out = imu.sample(t, k.w_ib_b, k.f_b);
    s.t = t;
    s.gyro = out.gyro;
    s.accel = out.accel;
    s.saturated = out.saturated;
    s.temp_c = simulated_temperature(t);
    s.w_ref = k.w_ib_b;
    s.f_ref = k.f_b;
    s.step = p.step;
    double a = std::fmod(units::deg(i.angle), 360.0);
    s.angle_deg = a < 0 ? a + 360.0 : a;
    sink(s);
  }
}

}  // namespace calbench
