// scenelod: the command-line tool. Subcommands register themselves (see command.h).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "command.h"

namespace scenelod::tool {

std::vector<Command>& commandRegistry() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace scenelod::tool

namespace {

void printHelp() {
  using scenelod::tool::commandRegistry;
  auto commands = commandRegistry();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return std::strcmp(a.name, b.name) < 0; });
  std::printf("scenelod - runtime level-of-detail manager for scene graphs\n\n"
              "usage: scenelod <command> [options]\n       scenelod <command> --help\n\ncommands:\n");
  for (const auto& c : commands) std::printf("  %-12s %s\n", c.name, c.summary);
  std::printf("\nEvery command takes -o and --out as the same option.\n");
}

}  // namespace

int main(int argc, char** argv) {
  using scenelod::tool::commandRegistry;
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    printHelp();
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::printf("scenelod 1.1.0\n");
    return 0;
  }
  for (const auto& c : commandRegistry()) {
    if (std::strcmp(c.name, argv[1]) != 0) continue;
    std::vector<std::string> args(argv + 2, argv + argc);
    for (const auto& a : args)
      if (a == "--help" || a == "-h") {
        std::printf("%s\n", c.usage);
        return 0;
      }
    // the commands return errors as exit codes; what escapes them is reported, never a core dump
    try {
      return c.run(args);
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "scenelod %s: out of memory\n", c.name);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "scenelod %s: %s\n", c.name, e.what());
    }
    return 1;
  }
  std::fprintf(stderr, "scenelod: unknown command '%s' (see 'scenelod --help')\n", argv[1]);
  return 2;
}
