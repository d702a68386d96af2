// Subcommands register themselves here (one file per subcommand, bench/cli/cmd_*.cpp):
//   static const bool registered = calbench::cli::add_command(30, [](CLI::App& app) { ... });
// `order` sets their place in `calbench --help`, which follows the workflow.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace calbench::cli {

using CommandSetup = std::function<void(CLI::App& app)>;
bool add_command(int order, CommandSetup setup);

// Print JSON to stdout (for --json).
void print_json(const std::string& text);

}  // namespace calbench::cli

namespace calbench::cli {
// Thrown by a subcommand to end with a given exit status after it has printed its result
// (e.g. a QC check that ran fine but failed its threshold).
struct Exit {
  int code;
};
}  // namespace calbench::cli
