#include "args.h"

#include <algorithm>
#include <cstdio>
#include <cctype>
#include <cstdlib>

namespace scenelod::tool {

namespace {
bool listed(const std::vector<std::string>& v, const std::string& s) { return std::find(v.begin(), v.end(), s) != v.end(); }
}  // namespace

Args::Args(const std::vector<std::string>& argv, std::vector<std::string> flags, std::vector<std::string> options) {
  for (size_t i = 0; i < argv.size(); ++i) {
    std::string a = argv[i];
    if (a == "-h" || a == "--help") { help_ = true; continue; }
    if (a == "-o") a = "--out";
    if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && (std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.'))) {
      std::string value;
      bool inline_value = false;
      const size_t eq = a.find('=');
      if (eq != std::string::npos && a.rfind("--", 0) == 0) {
        value = a.substr(eq + 1);
        a = a.substr(0, eq);
        inline_value = true;
      }
      if (listed(flags, a)) {
        if (inline_value) { fail("option " + a + " takes no value"); continue; }
        values_.emplace_back(a, "");
      } else if (listed(options, a)) {
        if (!inline_value) {
          if (i + 1 >= argv.size()) { fail("option " + a + " needs a value"); continue; }
          value = argv[++i];
        }
        values_.emplace_back(a, value);
      } else {
        fail("unknown option " + a);
      }
      continue;
    }
    positional_.push_back(a);
  }
}

bool Args::has(const std::string& name) const {
  return std::any_of(values_.begin(), values_.end(), [&](const auto& p) { return p.first == name; });
}

std::string Args::get(const std::string& name, const std::string& fallback) const {
  for (auto it = values_.rbegin(); it != values_.rend(); ++it)
    if (it->first == name) return it->second;
  return fallback;
}

std::vector<std::string> Args::getAll(const std::string& name) const {
  std::vector<std::string> out;
  for (const auto& p : values_)
    if (p.first == name) out.push_back(p.second);
  return out;
}

bool Args::getDouble(const std::string& name, double& out) {
  if (!has(name)) return true;
  const std::string s = get(name);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0') { fail("option " + name + " needs a number, got '" + s + "'"); return false; }
  out = v;
  return true;
}

bool Args::getInt(const std::string& name, long& out) {
  if (!has(name)) return true;
  const std::string s = get(name);
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0') { fail("option " + name + " needs a whole number, got '" + s + "'"); return false; }
  out = v;
  return true;
}

int usageError(const char* command, const std::string& message) {
  std::fprintf(stderr, "scenelod %s: %s\n(see 'scenelod %s --help')\n", command, message.c_str(), command);
  return 2;
}

int runError(const char* command, const std::string& message) {
  std::fprintf(stderr, "scenelod %s: %s\n", command, message.c_str());
  return 1;
}

}  // namespace scenelod::tool
