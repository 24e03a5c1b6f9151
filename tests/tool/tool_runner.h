#pragma once
// Running the built scenelod tool (SCENELOD_TOOL_PATH) from a test, as a user would.
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "test_support.h"

namespace scenelod::test {

// Exit code and everything the tool printed (stdout and stderr together).
struct ToolRun {
  int code = -1;
  std::string output;
};

// Runs `scenelod ARGS` through the shell (ARGS as written: quote paths yourself).
inline ToolRun runTool(const std::string& args) {
  ToolRun r;
  const std::string cmd = std::string(SCENELOD_TOOL_PATH) + " " + args + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline std::string readText(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

inline std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Exit code, stdout and stderr kept apart.
struct ToolOutput {
  int exit_code = -1;
  std::string out, err;
};

// Runs the tool with each argument quoted; stdout and stderr go through files in the scratch folder
// named after `tag`.
inline ToolOutput runToolSeparate(const std::vector<std::string>& args, const std::string& tag = "tool") {
  const std::string dir = scratchDir();
  std::string cmd = shellQuote(SCENELOD_TOOL_PATH);
  for (const std::string& a : args) cmd += " " + shellQuote(a);
  cmd += " >" + dir + "/" + tag + "_out.txt 2>" + dir + "/" + tag + "_err.txt";
  const int status = std::system(cmd.c_str());
  ToolOutput r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readText(dir + "/" + tag + "_out.txt");
  r.err = readText(dir + "/" + tag + "_err.txt");
  return r;
}

}  // namespace scenelod::test
