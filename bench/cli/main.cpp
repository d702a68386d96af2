// calbench: the MEMS IMU calibration station. One executable, subcommands in workflow order.
#include <iostream>
#include <map>

#include "bench/cli/registry.hpp"
#include "bench/io/input_error.hpp"

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

}  // namespace calbench::cli

int main(int argc, char** argv) {
  CLI::App app{"calbench: calibration station for MEMS IMUs (ADIS16488A).\n"
               "Workflow: simulate | station | fit | identify | qc | diagnose | db | provision | report"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "calbench 0.1.0");
  for (auto& [order, setup] : calbench::cli::registry()) setup(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
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
