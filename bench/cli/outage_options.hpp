// The outage-QC options of `fit drive` and `qc` (docs/in-motion.md, "Outage QC"), declared once.
#pragma once
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "bench/cli/number_options.hpp"
#include "bench/drive/outage_qc.hpp"

namespace calbench::cli {

struct OutageArgs {
  std::string lengths = "15,30,60";
  CLI::Option* lengths_opt = nullptr;
  bool given() const { return lengths_opt && lengths_opt->count() > 0; }
};

// Adds --outages, --outage-count, --outage-gap and --outage-nhc; the lengths are parsed by
// outage_options() when the command runs (bad input: exit 2 naming --outages).
inline void add_outage_options(CLI::App* app, OutageArgs& a, OutageOptions& o) {
  const char* group = "Outage QC (GNSS-only drives)";
  a.lengths_opt = app->add_option("--outages", a.lengths,
                                  "simulated GNSS outages of a GNSS-aided drive, lengths in s (default 15,30,60), or none: "
                                  "each navigated inertial-only from the aided filter's state at its start, error "
                                  "against the fixes (docs/in-motion.md, Outage QC)")
                      ->group(group);
  app->add_option("--outage-count", o.request.count, "outages per length (default 3; fewer when the drive is short)")
      ->check(whole_number(1, 1000))
      ->group(group);
  app->add_option("--outage-gap", o.request.gap_s, "least time between one outage's end and the next start, s (default 30)")
      ->check(finite_non_negative())
      ->group(group);
  app->add_flag("--outage-nhc", o.nhc,
                "non-holonomic constraint during the outages (needs the NHC observation, issue 34 item 4: refused in "
                "this build)")
      ->group(group);
}
inline void outage_options(const OutageArgs& a, OutageOptions& o) {
  parse_outage_lengths(a.lengths, o);
  o.lengths_given = a.given();
  check_outage_options(o);
}

}  // namespace calbench::cli
