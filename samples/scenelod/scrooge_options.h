#pragma once
// SCROOGE (Reddy 1996) in the clustering subcommands: `scenelod simplify|lods --method scrooge`.
#include <string>
#include <vector>

#include "args.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/scrooge.h"

namespace scenelod::tool {

// help text for the SCROOGE options
extern const char kScroogeOptionsHelp[];

// the option names the SCROOGE helpers read
inline std::vector<std::string> scroogeOptionNames() { return {"--subvolume", "--theta-max"}; }

// true when --method scrooge was given
bool isScroogeMethod(const Args& args);

// Reads --theta-max into `p` (other fields keep their defaults). Returns false with `error` set.
bool parseScroogeOptions(Args& args, ScroogeParams& p, std::string& error);

// The sub-volume of `simplify`: --cell W (a cube of edge W), --cell-rel F (a cube whose diagonal is
// F x the bbox diagonal) or --subvolume 1/64|1/8|1 (the paper's fractions of the bounding volume,
// the default 1/64). Returns false with `error` set on a bad or conflicting value.
bool scroogeSubvolume(Args& args, const Mesh& mesh, glm::vec3& size, std::string& error);

// The first level's cube edge for `lods`: --cell W1, --cell-rel F (diagonal F x the bbox diagonal) or
// --subvolume (the longest edge of that fraction's box, so --subvolume 1/64 --levels 3 gives the
// paper's 1/64, 1/8 and 1). 0 when none is given (buildScroogeChain's default).
bool scroogeFirstWidth(Args& args, const Mesh& mesh, float& width, std::string& error);

// `scenelod simplify IN -o OUT --method scrooge ...` after the common checks.
int runScroogeSimplify(Args& args, const std::string& in, const std::string& out);

}  // namespace scenelod::tool
