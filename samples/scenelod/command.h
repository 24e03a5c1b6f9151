#pragma once
// Subcommands of the scenelod tool. Each lives in its own cmd_<name>.cpp and registers itself with a
// static CommandRegistration, so adding a subcommand never touches main.cpp.
#include <string>
#include <vector>

namespace scenelod::tool {

struct Command {
  const char* name = "";
  const char* summary = "";  // one line for `scenelod --help`
  const char* usage = "";    // full help text for `scenelod NAME --help`
  int (*run)(const std::vector<std::string>& args) = nullptr;  // args after the subcommand name
};

std::vector<Command>& commandRegistry();

struct CommandRegistration {
  explicit CommandRegistration(const Command& c) { commandRegistry().push_back(c); }
};

}  // namespace scenelod::tool
