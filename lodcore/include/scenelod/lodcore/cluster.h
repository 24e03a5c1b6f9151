#pragma once
// Vertex-clustering simplification of one mesh at one cell width: Rossignac & Borrel 1993 uniform
// subdivision (the baseline) and Low & Tan 1997 floating cells (§3.2, §4), with the nearest-centre
// variant (§3.2.3), cube or sphere cells, thick edges (§3.3.1).
//
// Pipeline (docs/CLUSTERING.md): grade every vertex, sort by weight (once per mesh: PreparedMesh),
// assign vertices to cells, synthesise one representative per cluster, eliminate degenerate and
// duplicate primitives into triangles / thick edges / points, recompute normals and colours.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

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
  bool boost_features = true;      // grading: boundary and crease vertices get a higher angular factor
  float crease_angle_deg = 60.0f;  // output normals: faces meeting at a larger angle do not share normals
};

// Sums over the triangles incident on one vertex (each triangle counted once per corner, as in
// Lindstrom's per-cluster accumulation), made once per mesh so that a level's synthesis is a pass
// over vertices. Stored in 24 bytes as the summed area and 16-bit fractions of it: the quadric's
// entries are at most the area (its trace) in size and the normal sum at most the area in length,
// so each keeps about 3e-5 of the area (decode with decode()).
struct VertexFaceSums {
  float area = 0.0f;  // sum of the incident faces' areas (the trace of the quadric)
  // snorm16 fractions of area: sum of area * n n^T (xx, xy, xz, yy, yz, zz, n the unit face normal),
  // then sum of area * n (x, y, z)
  int16_t q[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  // every incident plane passes through the vertex, so the quadric's linear part relative to the
  // vertex is 0 and needs no storage: relative to a point c it is -A (v - c)

  // fills the fields from the sums: quadric xx, xy, xz, yy, yz, zz, then the normal sum x, y, z
  void encode(float face_area, const float sums[9]);
  // out[0..5]: the quadric's entries xx, xy, xz, yy, yz, zz; out[6..8]: the normal sum
  void decode(float out[9]) const;
};

// A mesh graded and sorted by weight once, so that every level of a chain reuses the sort (§4).
// Holds a pointer to the mesh it was made from: that mesh must outlive it and stay unchanged.
struct PreparedMesh {
  const Mesh* mesh = nullptr;
  Grading grading = Grading::kLowTan;
  bool boost_features = true;
  std::vector<float> weights;    // one per vertex: angular factor x (longest incident edge / longest edge)
  std::vector<uint32_t> order;   // referenced vertices only, heaviest first, ties by vertex index
  std::vector<glm::vec3> sorted_positions;  // positions[order[i]], so that levels stream through them
  Aabb bounds;                   // of the referenced vertices
  float longest_edge = 0.0f;     // longest edge of the mesh (the length normaliser)
  float mean_edge_length = 0.0f;
  double surface_area = 0.0;     // of all triangles (sizes the per-level grid hash)
  // filled by prepareMesh; a hand-made PreparedMesh without them clusters with the weighted mean in
  // place of the quadric minimiser and +z as the normal of edge and point vertices
  std::vector<VertexFaceSums> face_sums;  // one per vertex (24 bytes): incident-face quadric and normal
  std::vector<glm::vec4> face_colors;     // one per vertex when the mesh has colours: sum of area x face
                                          // colour (xyz) and of area (w); empty otherwise

  size_t referencedVertexCount() const { return order.size(); }
};

// Per-vertex grading only. `angular` (optional, may be null) receives the angular factor alone:
// cos(theta/2) for kLowTan (0 for a flat interior vertex, where theta = pi), pi/theta for kRossignac;
// with boost_features, max(that, 0.5 on a boundary, (1 - cos(dihedral))/2 at a crease) for kLowTan.
// `weights` gets angular x (longest incident edge / longest edge of the mesh); `raw` (optional) the
// unnormalised angular x longest incident edge, which orders vertices the same way. A vertex with no
// incident edge of non-zero length weighs 0. Precondition: `mesh` is valid (validateMesh).
// Cost: O(sum of vertex degrees^2) time (more than 64 distinct neighbours: an O(degree) estimate of theta),
// O(V + T) temporary memory; parallel over vertices with TBB.
void gradeVertices(const Mesh& mesh, Grading grading, bool boost_features, std::vector<float>& weights,
                   std::vector<float>* angular = nullptr, float* longest_edge = nullptr,
                   std::vector<float>* raw = nullptr);

// Validates `in`, grades its vertices and sorts the referenced ones by weight. `what` names the mesh
// in error messages. Errors: invalid mesh (NaN, index out of range, size mismatch).
// Cost: O(V + T) (grading over a vertex -> incidence table built by counting sort, radix sort by
// weight); keeps weights, order and sorted positions (20 bytes per vertex) and the per-vertex face
// sums (24 bytes per vertex, 16 more with colours); parallel over vertices with TBB.
Error prepareMesh(const Mesh& in, const ClusterParams& params, PreparedMesh& out,
                  const std::string& what = "mesh");

// Which cluster every vertex joined at one cell width (for tests, diagnostics and other generators).
struct ClusterAssignment {
  std::vector<uint32_t> cluster_of;  // per vertex; UINT32_MAX for vertices no primitive references
  std::vector<uint32_t> heaviest;    // per cluster: its heaviest vertex (a floating cell's centre)
};

// Runs only the clustering step of clusterPrepared. Same errors. Cost: O(V) time and memory.
// Clusters are numbered in creation order, so heaviest centre first (clusterPrepared renumbers them
// by first vertex index before building the level, which orders its output vertices that way).
Error assignClusters(const PreparedMesh& prepared, const ClusterParams& params, ClusterAssignment& out);

// Numbers measured while clustering one level.
struct ClusterStats {
  size_t cluster_count = 0;       // clusters (cells holding at least one referenced vertex)
  float max_error = 0.0f;         // largest distance an input vertex moved to its representative
  size_t collapsed_triangles = 0; // input triangles that became edges or points
};

// What clusterPrepared and clusterMesh return besides the level.
struct ClusterOutputs {
  ClusterStats stats;
  // per output vertex, one vertex of the input mesh it stands for (the main source of its
  // attributes, for engines that rebuild their own vertex format): with attributes, the member of
  // its attribute group with the largest area share; without, its cluster's heaviest vertex. Either
  // lies within stats.max_error of the output vertex.
  std::vector<uint32_t> source_vertex;
};

// Simplifies a prepared mesh at params.cell_width (params.grading and boost_features are those of
// the preparation). Writes positions, normals (crease-aware: a vertex is split where faces meet at
// more than crease_angle_deg), colours (area-weighted, when the input has colours), triangles, thick
// edges and points into `out`.
// A mesh with attributes (texture coordinates, tangents, a skin or more than one triangle group) is
// welded and each cluster emits one vertex per attribute group, with its texture coordinates,
// tangents, joint weights and the triangles' groups (docs/CLUSTERING.md, "Attributes"); where the
// weld removes vertices, the welded mesh is prepared again here (a chain does it once).
// Errors: cell width not finite or <= 0, or too small for the mesh extent (more than 2^30 cells
// along an axis), method not a clustering method.
// Thread-safe for distinct `out`. Cost: O(V + T) time and memory per call.
Error clusterPrepared(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out,
                      ClusterStats* stats = nullptr);
// The same, with the source vertices.
Error clusterPrepared(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out, ClusterOutputs& outputs);

// Counts the triangles clusterPrepared would output at `cell_width`, without synthesis or normals
// (used by width searches). Same errors. Cost: O(V + T).
Error countClusteredTriangles(const PreparedMesh& prepared, const ClusterParams& params, size_t& triangle_count);

// Simplifies `in` (triangles, and its edges and points) at one cell width into `out`.
// `out` gets positions, normals (crease-aware), colours (area-weighted) of the representatives and
// the surviving triangles, thick edges and points, and for a mesh with attributes those of
// clusterPrepared. `max_error`, when not null, receives the largest distance any input vertex moved
// to its representative.
// Errors: cell width not finite or <= 0, invalid mesh (NaN, index out of range, attribute arrays
// of the wrong size, bad skin), named "mesh". An empty mesh gives an empty result.
// Cost: O(N log N) for the weight sort, O(N) per call otherwise; allocates.
Error clusterMesh(const Mesh& in, const ClusterParams& params, Mesh& out, float* max_error = nullptr);
// The same, with the source vertices.
Error clusterMesh(const Mesh& in, const ClusterParams& params, Mesh& out, ClusterOutputs& outputs);

}  // namespace scenelod
