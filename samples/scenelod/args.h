#pragma once
// A small command-line parser for the tool's subcommands: positional arguments, flags and options
// with values. `-o` and `--out` are always the same option. Unknown options are errors.
#include <string>
#include <vector>

namespace scenelod::tool {

class Args {
 public:
  // flags: options without a value ("--json"); options: options with a value ("--cell").
  // "--out" (alias "-o") is accepted whenever it is listed in options.
  Args(const std::vector<std::string>& argv, std::vector<std::string> flags, std::vector<std::string> options);

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool help() const { return help_; }

  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& name) const;                    // flag or option present
  std::string get(const std::string& name, const std::string& fallback = "") const;  // last value
  std::vector<std::string> getAll(const std::string& name) const;                      // every value
  // parse helpers: set error() and return false on a malformed number
  bool getDouble(const std::string& name, double& out);
  bool getInt(const std::string& name, long& out);

  void fail(const std::string& message) { if (error_.empty()) error_ = message; }

 private:
  std::vector<std::string> positional_;
  std::vector<std::pair<std::string, std::string>> values_;
  std::string error_;
  bool help_ = false;
};

// Prints "scenelod <cmd>: <message>" and the usage hint to stderr; returns the exit code 2.
int usageError(const char* command, const std::string& message);
// Prints "scenelod <cmd>: <message>" to stderr; returns the exit code 1.
int runError(const char* command, const std::string& message);

}  // namespace scenelod::tool
