#include "bench/station/run_summary.hpp"

namespace calbench::station {

void complete_run(Result& res, const RunFacts& f, std::size_t calibrated) {
  if (!f.fixture_mode) {
    const Unit& u = *f.units.front();
    res.message = "station run complete: " + std::to_string(f.plan_steps) + " steps, coefficients in " +
                  (u.out / "COEFFS.json").string();
    res.summary["coefficients"] = u.summary["coefficients"];
    res.summary["fit"] = u.summary["fit"];
    if (u.summary.contains("db")) res.summary["db"] = u.summary["db"];
  } else {
    res.message = "station run complete: " + std::to_string(f.plan_steps) + " steps, " + std::to_string(calibrated) +
                  " of " + std::to_string(f.units.size()) + " units calibrated (coefficients in " +
                  (f.out_dir / "SLOT" / "COEFFS.json").string() + ")";
    for (const auto& u : f.units)
      if (u->failed) res.message += "; " + u->label() + " failed: " + u->why;
    if (calibrated < f.units.size()) res.exit_code = 1;
  }
}

void summarise_run(Result& res, const RunFacts& f) {
  res.summary["ok"] = res.exit_code == 0;
  res.summary["message"] = res.message;
  res.summary["run_id"] = f.run_id;
  if (!f.fixture_mode) {
    const fs::path rec = f.units.empty() ? f.out_dir / "recording" : f.units.front()->rec_dir;
    res.summary["recording"] = rec.string();
    res.summary["steps"] = f.units.empty() ? nlohmann::json::array() : f.units.front()->steps;
  } else {
    res.summary["fixture"] = {{"name", f.fixture.name}, {"file", f.fixture.file}, {"units", f.units.size()},
                              {"arbitration", "one bridge per unit"}};
    nlohmann::json us = nlohmann::json::array();
    for (const auto& u : f.units) {
      nlohmann::json j = u->summary;
      j["slot"] = u->slot.name;
      j["ok"] = !u->failed && j.contains("coefficients");
      if (u->failed) j["failed"] = u->why;
      if (u->identified) j["serial"] = u->imu->identity().serial_string();
      j["recording"] = u->rec_dir.string();
      j["samples"] = u->samples;
      j["samples_lost"] = u->lost;
      j["error_samples"] = u->error_samples;
      j["repeats"] = u->repeats;
      j["steps"] = u->steps.size();
      j["rate_hz"] = u->identified ? u->imu->identity().output_rate_hz : 0.0;
      us.push_back(j);
    }
    res.summary["units"] = us;
  }
  res.summary["samples"] = total(f.units, &Unit::samples);
  res.summary["samples_lost"] = total(f.units, &Unit::lost);
  res.summary["error_samples"] = total(f.units, &Unit::error_samples);
  res.summary["repeats"] = total(f.units, &Unit::repeats);
  res.summary["emulated_s"] = f.emulated_s;
  res.summary["wall_s"] = f.wall_s;
}

}  // namespace calbench::station
