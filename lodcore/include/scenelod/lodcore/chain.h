#pragma once
// Building LOD chains from an original mesh with any of the generators. Every level is derived from
// the original (Low & Tan §3.2.2), levels are built in parallel with TBB and the result does not
// depend on the thread count.
#include <cstddef>
#include <vector>

#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/progress.h"
#include "scenelod/lodcore/status.h"

namespace scenelod {

struct ChainParams {
  ClusterParams cluster;          // method and options; cluster.cell_width is ignored here
  size_t level_count = 8;         // simplified levels after the original
  float first_cell_width = 0.0f;  // w_1; 0 = chosen so level 1 has about half the triangles
  float growth = 2.0f;            // w_k = w_1 * growth^(k-1)
  // clustering methods: level k + 1 clusters level k's vertices (carrying their weights and their
  // original vertices' face sums) instead of the original's, so that every level's geomorph ends
  // exactly on the next level (docs/CLUSTERING.md, "Nested or independent levels")
  bool nested = false;
  // fill LodLevel::morph for every level but the last (clustering and Zhang chains)
  bool morphs = true;
  ProgressCallback progress;
};

// Builds level 0 (a copy of `original`) and `level_count` simplified levels with cell widths
// w_k = w_1 * growth^(k-1), dispatching on params.cluster.method (kUniform, kFloatingHeaviest,
// kFloatingNearest; kZhang goes to buildZhangChain, kScrooge to buildScroogeChain with default
// ScroogeParams; kOriginal generates nothing and is an error; ChainStats are only filled for the
// clustering methods, and total_seconds for kScrooge). Each level records
// its cell width, its measured maximum vertex displacement and a bounding sphere (centre of the
// level's vertex box, radius to the farthest vertex). Levels that come out identical in counts to
// the previous one are kept, so level indices always match cell widths. No level has more triangles,
// or more primitives (triangles, edges and points), than the level before: a clustering level that
// would is rebuilt from the level before at its own width (a nested step), a level of another
// generator is dropped. With params.morphs each level but the last gets its geomorph targets
// (LodLevel::morph), made while the levels are built; the levels' vertex -> cluster maps this needs
// (4 bytes per original vertex and level, plus 4 per level vertex) are each freed as soon as the
// targets that read them are made (docs/CLUSTERING.md, "Geomorphs"). With params.nested (clustering
// methods) the levels are built one after the other, each from the one before.
// A mesh with attributes (texture coordinates, tangents, a skin or more than one triangle group)
// is welded, split into UV charts and prepared once, and each clustering level carries its texture
// coordinates, tangents, joint weights and triangle groups and records LodLevel::source_vertex in
// the original's indices (docs/CLUSTERING.md, "Attributes"); its levels are built in parallel,
// level 1's output pass last, after the preparation is freed (no speculation as described below).
// Errors: invalid mesh (as validateMesh), first_cell_width negative or not finite, growth not finite
// or <= 1, a method that is not a generator. An empty mesh, or level_count 0, gives a chain with only
// level 0. Cost: one O(V log V) grading sort, then O(V + T) per level; allocates; uses TBB. With
// w_1 searched on a small mesh (see findCellWidthForTarget) and two threads or more, levels n .. 3
// are built at the search's first width while it is probed, and kept when that width becomes w_1
// (otherwise dropped and built again: the chain is the same either way).
Error buildChain(const Mesh& original, const ChainParams& params, LodChain& out, struct ChainStats* stats = nullptr);

// The same chain from a mesh the caller hands over: level 0 takes `original` by move instead of
// copying it (for the clustering methods only after the levels are built, so the copy's V x 24 +
// T x 12 bytes never add to the peak). On success `original` is left moved-from (empty); on error
// it is unchanged and `out` is empty. Use it when the engine no longer needs its own copy.
Error buildChain(Mesh&& original, const ChainParams& params, LodChain& out, struct ChainStats* stats = nullptr);

// Where a chain's build time went (filled by buildChain when asked).
struct ChainStats {
  double prepare_seconds = 0.0;       // validation, grading and the sort by weight
  double first_width_seconds = 0.0;   // the search for w_1 (0 when given)
  size_t first_width_probes = 0;      // clusterings the search counted (0 when w_1 is given)
  std::vector<double> level_seconds;  // per simplified level (levels run in parallel: these overlap)
  double total_seconds = 0.0;         // wall time of the whole call
};

// Finds by a safeguarded secant search (a first width from the vertices' incident areas, then
// count ~ w^-alpha with alpha from the last two probes, falling back to bisection on log width; on
// meshes under 43,690 referenced vertices the first probe is 0.7 x tolerance narrower than the
// area model's width and, when it misses, the next round probes two widths at once, on two TBB
// threads where there are two, with the same result on any number) a cell width whose clustering
// gives a triangle count within `tolerance` (relative) of `target_triangles`, or the closest found.
// A chain's automatic w_1 is this search's width for half the triangles at a tolerance of 0.05. Errors: target 0, empty mesh
// (no triangles), invalid mesh, a method that is not a clustering method. Cost: O(V log V) once,
// then typically 3-10 O(V + T) counting passes (up to 48, plus 33 when the count jumps).
Error findCellWidthForTarget(const Mesh& original, const ClusterParams& params, size_t target_triangles,
                             float& cell_width, double tolerance = 0.02);

// The same search on an already prepared mesh (no re-grading).
Error findCellWidthForTarget(const PreparedMesh& prepared, const ClusterParams& params, size_t target_triangles,
                             float& cell_width, double tolerance = 0.02);

// Bounding sphere of a mesh's vertices: centre of their box, radius to the farthest one. Cost O(V).
Sphere computeBoundingSphere(const Mesh& mesh);

}  // namespace scenelod
