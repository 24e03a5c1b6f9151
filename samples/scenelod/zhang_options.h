#pragma once
// Options of the Zhang, Shu & Luo 2003 edge collapse for `scenelod simplify --method zhang` and
// `scenelod lods --method zhang` (docs/ZHANG.md).
#include <string>
#include <vector>

#include "args.h"
#include "scenelod/lodcore/zhang.h"

namespace scenelod::tool {

// help text for --zhang-placement, --zhang-mode, --zhang-influence, --keep-corners, --zhang-ring, --weld
extern const char kZhangOptionsHelp[];

// the options parseZhangOptions reads (all take a value)
inline std::vector<std::string> zhangOptionNames() {
  return {"--zhang-placement", "--zhang-mode", "--zhang-influence", "--keep-corners", "--zhang-ring", "--weld"};
}

// Fills `p` from the options (defaults: ZhangParams()). Returns false with `error` set on an unknown
// value.
bool parseZhangOptions(const Args& args, ZhangParams& p, std::string& error);

}  // namespace scenelod::tool
