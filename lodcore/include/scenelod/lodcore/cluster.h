#pragma once
// Vertex-clustering simplification of one mesh at one cell width: Rossignac & Borrel 1993 uniform
// subdivision (the baseline) and Low & Tan 1997 floating cells (§3.2, §4), with the nearest-centre
// variant (§3.2.3), cube or sphere cells, thick edges (§3.3.1).
#include <cstddef>
#include <cstdint>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod {

enum class Grading : uint8_t {
  kLowTan,     // cos(theta/2) x longest incident edge (Low & Tan §3.1)
  kRossignac,  // 1/theta x longest incident edge (Rossignac & Borrel), for comparison
};

enum class Synthesis : uint8_t {
  kMean,      // weight-averaged position of the cluster
  kHeaviest,  // the heaviest vertex (the floating cell's centre)
  kQuadric,   // minimiser of the cluster's summed face quadrics (Lindstrom 2000), clamped to the cell
};

enum class CellShape : uint8_t { kCube, kSphere };  // sphere cells have diameter = cell width

const char* gradingName(Grading g);
const char* synthesisName(Synthesis s);
const char* cellShapeName(CellShape s);

struct ClusterParams {
  LodMethod method = LodMethod::kFloatingNearest;  // kUniform, kFloatingHeaviest or kFloatingNearest
  Grading grading = Grading::kLowTan;
  Synthesis synthesis = Synthesis::kQuadric;
  CellShape cell_shape = CellShape::kCube;
  float cell_width = 0.0f;         // object space, finite and > 0
  bool keep_edges = true;          // triangles collapsed to two clusters become thick edges
  bool keep_points = true;         // triangles collapsed to one cluster become points
};

// Simplifies `in` (triangles, and its edges and points) at one cell width into `out`.
// `out` gets positions, normals (crease-aware), colours (area-weighted) of the representatives and
// the surviving triangles, thick edges and points; uvs are dropped. `max_error`, when not null,
// receives the largest distance any input vertex moved to its representative.
// Errors: cell width not finite or <= 0, invalid mesh (NaN, index out of range). An empty mesh gives
// an empty result. Cost: O(N log N) for the weight sort, O(N) per call otherwise; allocates.
Error clusterMesh(const Mesh& in, const ClusterParams& params, Mesh& out, float* max_error = nullptr);

}  // namespace scenelod
