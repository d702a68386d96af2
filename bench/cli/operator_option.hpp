// --operator NAME: who runs a command that writes to the store (db/store.hpp, Actor). One option,
// one check, for every command that takes it: a bad name is a usage error (exit 2) naming the option.
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "db/store.hpp"

namespace calbench::cli {

inline CLI::Option* add_operator_option(CLI::App* sub, std::string& target, const std::string& help) {
  return sub->add_option("--operator", target, help)
      ->check(CLI::Validator([](std::string& v) { return db::operator_name_problem(v); }, "NAME"));
}

}  // namespace calbench::cli
