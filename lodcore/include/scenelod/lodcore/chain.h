#pragma once
// Building LOD chains from an original mesh with any of the generators. Every level is derived from
// the original (Low & Tan §3.2.2), levels are built in parallel with TBB and the result does not
// depend on the thread count.
#include <cstddef>

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
  ProgressCallback progress;
};

// Builds level 0 (a copy of `original`) and `level_count` simplified levels with cell widths
// w_k = w_1 * growth^(k-1). Levels that come out identical in counts to the previous one are kept,
// so level indices always match cell widths. Errors: as clusterMesh, plus level_count of 0 with an
// explicit width <= 0. An empty mesh gives a chain with only level 0. Allocates; uses TBB.
Error buildChain(const Mesh& original, const ChainParams& params, LodChain& out);

// Finds by bisection a cell width whose clustering gives a triangle count within `tolerance`
// (relative) of `target_triangles`, or the closest found. Errors: target 0, empty mesh.
Error findCellWidthForTarget(const Mesh& original, const ClusterParams& params, size_t target_triangles,
                             float& cell_width, double tolerance = 0.02);

}  // namespace scenelod
