#pragma once
// Small helpers shared by the glTF tests: scratch folders and message checks.
#include <sys/stat.h>

#include <string>

#include "test_support.h"

namespace scenelod::test {

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// a folder `name` inside the test scratch folder (created when missing)
inline std::string makeDir(const std::string& name) {
  const std::string d = scratchDir() + "/" + name;
  ::mkdir(d.c_str(), 0755);
  return d;
}

}  // namespace scenelod::test
