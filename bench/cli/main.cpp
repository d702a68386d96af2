// calbench: the MEMS IMU calibration station. One executable, subcommands in workflow order.
#include <algorithm>
#include <iostream>
#include <map>
#include <vector>

#include "bench/cli/registry.hpp"
#include "common/input_error.hpp"

namespace calbench::cli {
namespace {
std::multimap<int, CommandSetup>& registry() {
  static std::multimap<int, CommandSetup> r;
  return r;
}
}  // namespace

bool add_command(int order, CommandSetup setup) {
  registry().emplace(order, std::move(setup));
  return true;
}

void print_json(const std::string& text) { std::cout << text << std::endl; }

namespace {
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> d(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) d[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t prev = d[0];
    d[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cur = d[j];
      d[j] = std::min({d[j] + 1, d[j - 1] + 1, prev + (a[i - 1] == b[j - 1] ? 0 : 1)});
      prev = cur;
    }
  }
  return d[b.size()];
}
}  // namespace

// Walks the command words of argv down the subcommand tree; a word where a subcommand is required
// and none has that name is an unknown command: the message names it and suggests the nearest. An
// unknown option where a command is required, or no command at all, is named the same way (CLI11
// would only say "A subcommand is required").
std::string unknown_command(const CLI::App& root, int argc, char** argv) {
  const CLI::App* app = &root;
  std::string path = "calbench";
  auto commands = [&] {
    std::string all;
    for (const CLI::App* c : const_cast<CLI::App*>(app)->get_subcommands([](CLI::App*) { return true; }))
      all += (all.empty() ? "" : ", ") + c->get_name();
    return "(commands: " + all + "; " + path + " --help)";
  };
  for (int i = 1; i < argc; ++i) {
    const std::string w = argv[i];
    if (w.empty()) return {};
    if (w[0] == '-') {
      if (app->get_require_subcommand_min() == 0) return {};
      const std::string name = w.substr(0, w.find('='));
      if (const_cast<CLI::App*>(app)->get_option_no_throw(name)) return {};  // --help, --version
      return "unknown option '" + name + "' for '" + path + "': a command comes first " + commands();
    }
    const auto subs = const_cast<CLI::App*>(app)->get_subcommands([](CLI::App*) { return true; });
    if (subs.empty()) return {};
    const CLI::App* next = nullptr;
    for (const CLI::App* c : subs)
      if (c->get_name() == w) next = c;
    if (next) {
      app = next;
      path += " " + w;
      continue;
    }
    if (app->get_require_subcommand_min() == 0) return {};  // a positional argument (e.g. report SERIAL)
    std::string best;
    std::size_t bd = 99;
    for (const CLI::App* c : subs) {
      const std::size_t d = edit_distance(w, c->get_name());
      if (d < bd) bd = d, best = c->get_name();
    }
    std::string m = "unknown command '" + w + "' for '" + path + "'";
    if (bd <= std::max<std::size_t>(2, w.size() / 3)) m += "; did you mean '" + best + "'?";
    return m + " " + commands();
  }
  if (app->get_require_subcommand_min() > 0) return "'" + path + "' needs a command " + commands();
  return {};
}

// An option the command does not have (CLI11: "The following arguments were not expected"): the
// nearest long option of that command, when one is near.
std::string nearest_option(CLI::App& root, int argc, char** argv) {
  CLI::App* app = &root;
  std::string path = "calbench";
  std::vector<std::string> unknown;
  for (int i = 1; i < argc; ++i) {
    const std::string w = argv[i];
    if (w.rfind("--", 0) == 0) {
      const std::string name = w.substr(0, w.find('='));
      if (!app->get_option_no_throw(name)) unknown.push_back(name);
      continue;
    }
    for (CLI::App* c : app->get_subcommands([](CLI::App*) { return true; }))
      if (c->get_name() == w) {
        app = c;
        path += " " + w;
        unknown.clear();  // options before a subcommand belong to its parent
        break;
      }
  }
  std::string out;
  for (const std::string& u : unknown) {
    std::string best;
    std::size_t bd = 99;
    for (const CLI::Option* o : app->get_options())
      for (const std::string& l : o->get_lnames()) {
        const std::size_t d = edit_distance(u.substr(2), l);
        if (d < bd) bd = d, best = "--" + l;
      }
    if (!best.empty() && bd <= std::max<std::size_t>(2, (u.size() - 2) / 3))
      out += "calbench: '" + u + "' is not an option of '" + path + "'; did you mean '" + best + "'? (" + path + " --help)\n";
  }
  return out;
}

}  // namespace calbench::cli

int main(int argc, char** argv) {
  CLI::App app{"calbench: calibration station for MEMS IMUs (ADIS16488A).\n"
               "Workflow: simulate | station (emulate: its devices alone) | import, convert, export (other formats) | fit | identify | qc | diagnose | db | provision | report; serve: the web console"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "calbench 0.1.0");
  for (auto& [order, setup] : calbench::cli::registry()) setup(app);
  if (const std::string m = calbench::cli::unknown_command(app, argc, argv); !m.empty()) {
    std::cerr << "calbench: error: " << m << std::endl;
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ExtrasError& e) {
    app.exit(e);
    std::cerr << calbench::cli::nearest_option(app, argc, argv);
    return 2;
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const calbench::cli::Exit& e) {
    return e.code;
  } catch (const calbench::InputError& e) {
    std::cerr << "calbench: error: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "calbench: error: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
