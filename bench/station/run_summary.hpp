// What a station run (bench/station/station.hpp) says when it ends: the message and exit code of a
// completed plan, and the summary every run returns (`station run --json`): ok, message, run id, the
// recording(s), one line per unit of a fixture, totals of samples, losses and repeats, times.
#pragma once
#include <cstddef>
#include <filesystem>
#include <string>

#include "bench/station/fixture.hpp"
#include "bench/station/station.hpp"
#include "bench/station/unit.hpp"

namespace calbench::station {

struct RunFacts {
  const Fixture& fixture;
  bool fixture_mode = false;     // a fixture (file or --units): one folder per slot
  const Units& units;
  std::filesystem::path out_dir;
  std::size_t plan_steps = 0;
  std::string run_id;
  double emulated_s = 0, wall_s = 0;
};

// The plan ran to its end and `calibrated` units were fitted and stored: the message; a fixture with a
// failed unit exits 1 and names each failed slot with its reason.
void complete_run(Result& res, const RunFacts& f, std::size_t calibrated);

// Every run, completed or not: fills res.summary (ok and message from res).
void summarise_run(Result& res, const RunFacts& f);

}  // namespace calbench::station
