// scenelod demo: the main job on the built-in default model (the Stanford bunny): an 8-level
// floating-cell LOD chain, with the table of its levels.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "cluster_options.h"
#include "command.h"

namespace scenelod::tool {

namespace {

const char kUsage[] =
    "usage: scenelod demo [IN] [--levels N]\n"
    "\n"
    "Builds an LOD chain of IN (default: " SCENELOD_DEFAULT_MODEL ") with floating-cell clustering\n"
    "(Low & Tan 1997) and prints its levels: cell width, vertices, triangles, thick edges, points,\n"
    "measured maximum vertex displacement and build time. Writes nothing.";

int runDemo(const std::vector<std::string>& argv) {
  Args args(argv, {}, {"--levels"});
  if (!args.ok()) return usageError("demo", args.error());
  if (args.positional().size() > 1) return usageError("demo", "expected at most one input file");
  const std::string in = args.positional().empty() ? SCENELOD_DEFAULT_MODEL : args.positional()[0];
  long levels = 8;
  if (args.has("--levels") && (!args.getInt("--levels", levels) || levels < 0 || levels > 64))
    return usageError("demo", args.ok() ? "--levels must be an integer from 0 to 64" : args.error());
  Mesh mesh;
  if (Error e = loadWorldMesh(in, mesh)) return runError("demo", e.message);
  ChainParams cp;
  cp.level_count = size_t(levels);
  LodChain chain;
  ChainStats stats;
  if (Error e = buildChain(mesh, cp, chain, &stats)) return runError("demo", in + ": " + e.message);
  std::printf("%s: LOD chain by floating-cell clustering (%s, %s grading, %s synthesis, %s cells)\n", in.c_str(),
              lodMethodName(cp.cluster.method), gradingName(cp.cluster.grading), synthesisName(cp.cluster.synthesis),
              cellShapeName(cp.cluster.cell_shape));
  printLevelTable(chain, &stats);
  std::printf("time: grading and sort %.1f ms, w1 search %.1f ms, whole chain %.1f ms (levels in parallel)\n",
              stats.prepare_seconds * 1e3, stats.first_width_seconds * 1e3, stats.total_seconds * 1e3);
  return 0;
}

const CommandRegistration kRegister({"demo", "build and print an LOD chain of the default model", kUsage, &runDemo});

}  // namespace

}  // namespace scenelod::tool
