#pragma once
// Vision-characteristic simplification (Zhang, Shu & Luo 2003, "Mesh Simplification Based on
// Shading Characteristic", WSCG short papers): the per-vertex measures of the paper's definitions
// 1-9, the vertex classification of §2, the edge collapse of §3 and its triangle-decimation
// extension, and LOD chains built from one recorded run. Design notes and the choices the paper
// leaves open: docs/ZHANG.md.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod {

// The five vertex classes of §2 (Fig. 3), plus isolated vertices (no triangle).
enum class ZhangVertexClass : uint8_t {
  kSimple,     // C(V) = 0, smooth neighbourhood (largest normal angle <= feature angle)
  kComplex,    // C(V) > 2 or a pinched (non-disk) neighbourhood: kept
  kEdge,       // C(V) = 2, on a boundary (or an attribute split of an unwelded mesh): kept
  kInnerEdge,  // C(V) = 0, on a crease: normalised super height <= angle_height_ratio
  kAngle,      // C(V) = 0, a corner: normalised super height > angle_height_ratio
  kIsolated,   // in no triangle
};

const char* zhangVertexClassName(ZhangVertexClass c);

// Which value orders the vertex queue (§3 step 2).
enum class ZhangInfluence : uint8_t {
  kVisionCharacteristic,  // CA(V), definition 9
  kSuperHeight,           // SH(V), definition 8
};

// Which of the two §3 algorithms runs.
enum class ZhangMode : uint8_t {
  kEdgeCollapse,        // vertex queue, best neighbour edge collapsed
  kTriangleDecimation,  // "Extension of algorithm": triangle queue, triangle contracted to a point
};

// Where the merged vertex goes.
enum class ZhangPlacement : uint8_t {
  kInterpolated,  // the paper: position and normal interpolated by the CA of the merged vertices
  kNeighbour,     // onto the chosen neighbour V_j (a half-edge collapse; measured lower error)
};

const char* zhangInfluenceName(ZhangInfluence i);
const char* zhangPlacementName(ZhangPlacement p);
const char* zhangModeName(ZhangMode m);

struct ZhangParams {
  ZhangMode mode = ZhangMode::kEdgeCollapse;
  ZhangInfluence influence = ZhangInfluence::kVisionCharacteristic;
  ZhangPlacement placement = ZhangPlacement::kInterpolated;
  // largest angle between a vertex normal and an adjacent face normal for a simple vertex
  float feature_angle_deg = 30.0f;
  // super height over the mean distance to the neighbours above which a feature vertex is an angle
  // vertex (a cube corner gives 0.58, a vertex on a straight crease 0)
  float angle_height_ratio = 0.1f;
  // fold-over check: a collapse is rejected when it turns any remaining triangle's normal by more
  // than this angle, or leaves it with (near) zero area
  float max_normal_turn_deg = 60.0f;
  // how a candidate collapse is scored (§3 step 4, "the least characteristic vision value of changed
  // vertex"): true, the largest CA term, angle x area, over the triangles whose shape changes, taken
  // against the carried normal of the merged vertex and against the normals of the triangle's two
  // other vertices (the ring vertices whose CA the collapse raises, as Fig. 6 argues for CA(V_2));
  // false, against the merged vertex's normal only (the narrower reading; higher error, bench/zhang.md)
  bool ring_vision = true;
  // the paper processes angle vertices; set to keep them fixed (cube corners stay exact)
  bool keep_angle_vertices = false;
  // treat vertices at exactly the same position as one vertex, so that attribute seams (glTF splits a
  // vertex per distinct normal / uv) stop being borders that are never simplified. The merged
  // vertex keeps the attributes of its lowest id and input normals are replaced by geometric ones,
  // so texture seams are not preserved. Only for meshes without texture coordinates, tangents,
  // skins and with one triangle group: those are always welded with their seams kept (below).
  bool weld_positions = false;
  // meshes with texture coordinates, tangents, skin or several triangle groups: a seam vertex (its
  // position has vertices with different attributes, or triangles of different groups meet there)
  // collapses only along its seam, and only where the seam bends by at most this angle there
  float max_seam_bend_deg = 30.0f;
};

// Per-vertex measures of definitions 5-9 on the input mesh (not updated by simplification).
struct ZhangVertexMeasures {
  uint32_t characteristic = 0;  // C(V): neighbours not appearing exactly twice in the triangle fan
  float super_area = 0.0f;      // SA(V): area of the triangulated ring (the hole left by deleting V)
  float super_volume = 0.0f;    // SV(V): |signed volume| of the tetrahedra V + ring triangles
  float super_height = 0.0f;    // SH(V) = 3 SV / SA, the distance of V from its super plane
  float vision = 0.0f;          // CA(V) = max over adjacent triangles of angle(n_V, n_k) [rad] * A_k
  float max_angle_rad = 0.0f;   // max angle(n_V, n_k) alone (Schroeder's criterion)
  ZhangVertexClass vertex_class = ZhangVertexClass::kIsolated;
};

// Computes the measures of every vertex of `mesh` (triangles only; edges and points ignored).
// `out` gets one entry per vertex. Errors: invalid mesh (NaN, index out of range).
// Cost: O(V + T) plus O(d^2) per vertex of degree d (ring triangulation choice); allocates.
Error computeZhangMeasures(const Mesh& mesh, const ZhangParams& params, std::vector<ZhangVertexMeasures>& out);

enum class ZhangStopReason : uint8_t {
  kTargetReached,
  kNoValidCollapse,  // every remaining candidate is kept or its collapse fails a check
};

const char* zhangStopReasonName(ZhangStopReason r);

struct ZhangStats {
  size_t input_triangles = 0;   // after dropping index-degenerate and duplicate triangles
  size_t output_triangles = 0;
  size_t collapses = 0;         // edge collapses or triangle contractions done
  size_t rejected_topology = 0; // candidates refused by the link / manifold checks
  size_t rejected_fold = 0;     // candidates refused by the fold-over check
  size_t blocked = 0;           // vertices (triangles) popped with no valid collapse, re-queued later
  size_t dropped_degenerate = 0;  // input triangles with a repeated index
  size_t dropped_duplicate = 0;   // input triangles with the vertex set of an earlier one
  // vertices that never move, by their class on the (welded) input: edge (borders, and the
  // attribute splits of an unwelded mesh without uvs), complex (non-manifold), angle (only with
  // keep_angle_vertices)
  size_t kept_edge_vertices = 0;
  size_t kept_complex_vertices = 0;
  size_t kept_angle_vertices = 0;
  size_t free_vertices_left = 0;  // vertices of the result that are not kept (could still collapse)
  float max_displacement = 0.0f;  // largest distance an input vertex moved to its representative
  // upper bound of the largest distance from an input vertex to the result's surface: each input
  // vertex measured against the triangles around its representative
  float max_surface_distance = 0.0f;
  ZhangStopReason stop_reason = ZhangStopReason::kTargetReached;
  // (welded) input vertices on a seam: texture / attribute seams and triangle group borders; 0 for a
  // mesh without texture coordinates, tangents, skin and with one group
  size_t seam_vertices = 0;
  // one per output vertex: the input vertex whose attributes it carries (the collapse survivor)
  std::vector<uint32_t> source_vertex;
  // where the input went, for geomorphs (buildZhangChain): per input vertex, the input vertex whose
  // position it collapsed into (UINT32_MAX where that vertex is in no primitive of the result); per
  // output vertex, the input vertex whose position it has
  std::vector<uint32_t> collapsed_into;
  std::vector<uint32_t> output_vertex_of;
};

// Simplifies the triangles of `in` to at most `target_triangles` (or as close as the checks allow)
// into `out`: positions and normals (carried by the paper's CA interpolation), colours and uvs
// (area-weighted) of the surviving vertices; the input's edges and points are carried through the
// collapse map. Boundary and complex vertices never move. Unreferenced vertices are dropped.
// A mesh with texture coordinates (any set), tangents, a skin or several triangle groups is welded by
// position for the collapse, and keeps its seams: a seam vertex collapses only along its seam onto
// the next seam vertex (a half-edge collapse keeping that vertex's attributes), each triangle keeps
// its own chart's attributes and its group (carried to out.triangle_groups), merged vertices off the
// seams interpolate every attribute with the position's weights, tangents are re-orthonormalised
// against the output normal with their sign kept, and joints / weights are the survivor's. Without
// such attributes the output is that of the plain algorithm (unwelded unless weld_positions).
// Errors: invalid mesh. A target at or above the triangle count gives a cleaned copy.
// Cost: O(T log T) time, O(V + T) memory, no allocation per collapse after warm-up.
Error simplifyZhang(const Mesh& in, size_t target_triangles, const ZhangParams& params, Mesh& out,
                    ZhangStats* stats = nullptr);

// Like simplifyZhang, one run for several targets: out[i] is exactly the mesh simplifyZhang gives
// for targets[i] (the greedy order does not depend on the target, so the run is recorded once and
// cut at each count). `targets` must be strictly decreasing. `stats` (optional) gets one entry per
// target. Cost: one run to the smallest target plus one compaction per target.
Error simplifyZhangMulti(const Mesh& in, const std::vector<size_t>& targets, const ZhangParams& params,
                         std::vector<Mesh>& out, std::vector<ZhangStats>* stats = nullptr,
                         const ProgressCallback& progress = {});

// The "equivalent cell width" of a level whose error is at most `max_distance`: the width of a cube
// cell whose centre is within that distance of every point of the cell, 2 d / sqrt(3).
float zhangEquivalentCellWidth(float max_distance);

// Builds level 0 (a copy of `original`) and up to params.level_count levels at triangle targets
// halving each level (T / 2, T / 4, ...), from one recorded run of simplifyZhang. Each level gets
// method kZhang, its source_vertex (ZhangStats::source_vertex), its geomorph toward the next level
// (LodLevel::morph, with params.morphs; the levels nest, so a vertex's target is the position its
// vertex collapsed into), its measured max_error (max vertex
// displacement), bounds, and cell_width =
// zhangEquivalentCellWidth(ZhangStats::max_surface_distance) (the bound of the input vertices'
// distance to the level, much tighter than the displacement for edge collapse; docs/ZHANG.md),
// raised where needed so widths strictly increase. Stops early
// when a level would have fewer than 4 triangles or no collapse is possible any more.
// params.cluster is ignored but for its method; params.first_cell_width and growth are ignored.
// Errors: invalid mesh. Cost: one simplification run; allocates.
Error buildZhangChain(const Mesh& original, const ChainParams& params, LodChain& out);
Error buildZhangChain(const Mesh& original, const ChainParams& params, const ZhangParams& zhang, LodChain& out);

}  // namespace scenelod
