#pragma once
// Options shared by the clustering subcommands (simplify, lods): method, grading, synthesis, cell
// shape; reading any scene as one world-space mesh; writing a mesh as OBJ or GLB; the level table.
#include <string>

#include "args.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"

namespace scenelod::tool {

// help text for --method, --grading, --synthesis, --cell-shape
extern const char kClusterOptionsHelp[];

// the option names parseClusterOptions reads
inline std::vector<std::string> clusterOptionNames() {
  return {"--method", "--grading", "--synthesis", "--cell-shape"};
}

// Fills `p` from the options; `--method floating` (the default) keeps ClusterParams' defaults, the
// best measured ones (docs/CLUSTERING.md). Returns false with `error` set on an unknown value.
bool parseClusterOptions(const Args& args, ClusterParams& p, std::string& error);

// --nested / --independent (flags): ChainParams::nested; only with a clustering method. Returns false
// with `error` set when both are given or the method is not a clustering one.
bool parseNesting(const Args& args, ChainParams& cp, std::string& error);

// Reads an OBJ, glTF or GLB file as one mesh in world space (every node instance, transforms applied).
Error loadWorldMesh(const std::string& path, Mesh& out);

// Writes `mesh` as OBJ (.obj: f, l, p, #t thickness) or GLB (.glb: one node); other extensions are
// refused. `name` names the mesh and node in a GLB.
Error writeMeshFile(const std::string& path, const Mesh& mesh, const std::string& name);

// Prints the table of a chain's levels: cell width, vertices, triangles, edges, points, max error,
// and the build time of each level when `stats` is given.
void printLevelTable(const LodChain& chain, const ChainStats* stats);

}  // namespace scenelod::tool
