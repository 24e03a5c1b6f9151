#pragma once
// SCROOGE: perceptually driven polygon reduction restricted to sub-volumes (Reddy 1996, §4-§7).
//
// The model is normalised (welded vertices, no duplicate or degenerate polygons, no coplanar
// sub-polygons), cut into a grid of sub-volumes (with the half-offset overlapping passes of §5), and
// inside every sub-volume the polygons wholly inside it are degraded (§6: a vertex v2 between edges
// v1->v2->v3 moves onto the segment v1->v3 when |v1v3| < l(theta)) and rebuilt (§7: coplanar
// neighbours merge, co-linear vertices go, concave polygons split, colours blend by area). Vertices
// used by any polygon outside the current sub-volume never move, so no change is larger than a
// sub-volume. Works on polygons: Mesh::face_offsets/face_corners when present, else the triangles.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod {

struct ScroogeParams {
  glm::vec3 subvolume_size{0.0f};  // object-space edge lengths (w, h, d) of one sub-volume, each finite > 0
  float theta_min_deg = 5.0f;      // edge pairs bending less than this always degrade (Ware & Knight, §6.2)
  float theta_max_deg = 45.0f;     // edge pairs bending more than this never degrade; in (theta_min, 180)
  float coplanar_deg = 5.0f;       // a polygon joins a merge group within this angle of the group's first polygon
  float weld_epsilon_rel = 1e-6f;  // vertices closer than this x bbox diagonal are one vertex; 0 = exact equality
  bool prevent_foldover = true;    // refuse a move that turns a polygon around the moved vertex over
                                   // (not in the paper: without it large sub-volumes fold the surface)
  bool overlap_passes = true;      // the 8 passes offset by half a sub-volume per axis (§5); false = one grid
  bool remove_colinear = true;     // §7.1.1: drop vertices lying on the segment between their neighbours
  bool fill_holes = true;          // §7.2: a merged group with holes keeps only its outer outline (the paper);
                                   // false = such a group stays unmerged
  bool convex_polygons = true;     // §7.1.2: split rebuilt concave polygons into convex ones
  bool triangulate_faces = false;  // §7.1.3: output faces are triangles (Mesh::triangles always are)
  bool remove_sub_polygons = true; // §7.2: drop coplanar polygons lying inside another (normalisation)
};

struct ScroogeStats {
  size_t input_polygons = 0;       // faces (or triangles) read
  size_t input_vertices = 0;
  size_t welded_vertices = 0;      // vertices merged into another by normalisation
  size_t duplicate_polygons = 0;   // removed by normalisation (same corners, same orientation)
  size_t degenerate_polygons = 0;  // fewer than 3 distinct corners or no area, removed by normalisation
  size_t sub_polygons = 0;         // coplanar polygons inside another, removed by normalisation
  size_t normalised_polygons = 0;
  size_t moved_vertices = 0;       // degradation moves accepted, summed over passes
  size_t merged_groups = 0;        // coplanar groups of >= 2 polygons replaced by one
  size_t output_polygons = 0;
  size_t output_triangles = 0;
  float max_displacement = 0.0f;   // largest distance an output vertex lies from where it started
  // one per output vertex: the input vertex whose (welded) position this vertex started from
  std::vector<uint32_t> vertex_origin;
  // one per output vertex: the input vertex whose attributes it carries (its corner's vertex)
  std::vector<uint32_t> source_vertex;
};

// Reduces `in` with SCROOGE at one sub-volume size into `out`. `out` gets the rebuilt polygons in
// face_offsets/face_corners, their triangulation in triangles, the input's edges and points (whose
// vertices never move), colours (merged polygons take the area-weighted mean colour of their parts,
// §7.3), uvs (set 0) copied from a source corner, and normals recomputed from the faces when the input
// had normals; triangle groups are carried. With uvs, coplanar polygons merge only inside one uv chart
// and one group (computeUvCharts), points on a chart border or uv seam never move, and a point that
// moves inside its chart takes the uv interpolated along the segment it moved onto, so a planar
// linear uv map stays exact. Unused vertices are dropped (§4 step 4).
// Guarantee: no output vertex lies farther than |subvolume_size| (the sub-volume diagonal, l_max)
// from its starting position, and a polygon never wholly inside one sub-volume of any pass keeps
// its corners.
// Errors: sub-volume size not finite or <= 0, theta limits out of range, coplanar or weld tolerance
// negative or not finite, invalid mesh (validateMesh); `what` names the mesh in messages. An empty
// mesh gives an empty result.
// Cost: O(N) expected per pass with hash grids (8 passes with overlap_passes), O(k^2) per rebuilt
// polygon of k corners; allocates; sub-volumes of one pass run in parallel with TBB and the result
// does not depend on the thread count.
Error scroogeMesh(const Mesh& in, const ScroogeParams& params, Mesh& out, ScroogeStats* stats = nullptr,
                  const char* what = "mesh");

// Normalisation alone (§4 step 1, §7.2): welds vertices within weld_epsilon_rel x bbox diagonal
// (vertices with equal position and equal attributes become one), removes degenerate and duplicate
// polygons, duplicate edges and points, and (when remove_sub_polygons) coplanar sub-polygons; then
// drops unused vertices. Only weld_epsilon_rel and remove_sub_polygons of `params` are read.
// Errors: as scroogeMesh. Cost: O(N) expected; allocates.
Error scroogeNormalise(const Mesh& in, const ScroogeParams& params, Mesh& out, ScroogeStats* stats = nullptr,
                       const char* what = "mesh");

// Sub-volume size whose diagonal is `cell_rel` x the diagonal of `bounds` (a cube; --cell-rel).
// Returns a zero vector when bounds are empty or cell_rel <= 0.
glm::vec3 scroogeSubvolumeForCellRel(const Aabb& bounds, float cell_rel);

// Sub-volume size for the paper's fractions of the bounding volume (§8, Table 1): `divisions` per
// axis, so 4 gives 1/64, 2 gives 1/8, 1 gives the whole box. Axes where the box is flat get the
// largest of the other edges (a flat model still has sub-volumes with a size).
glm::vec3 scroogeSubvolumeForDivisions(const Aabb& bounds, int divisions);

// Builds level 0 (a copy of `original`) and params.level_count SCROOGE levels with cubic sub-volumes
// of edge length w_k = w_1 * growth^(k-1); w_1 = params.first_cell_width, or when 0 the longest bbox
// edge / growth^(level_count-1) so that the last level's sub-volume holds the whole model. Each level
// records cell_width = w_k (the sub-volume edge length), max_error = its measured largest vertex
// displacement (<= w_k * sqrt(3)) and source_vertex (ScroogeStats::source_vertex). params.cluster is
// ignored; `scrooge` gives the other options (its subvolume_size is ignored). Errors: as scroogeMesh, growth <= 1 with more than one level, negative
// first width. An empty mesh gives only level 0. Allocates; levels are built in parallel (TBB).
Error buildScroogeChain(const Mesh& original, const ChainParams& params, const ScroogeParams& scrooge,
                        LodChain& out);
Error buildScroogeChain(const Mesh& original, const ChainParams& params, LodChain& out);

}  // namespace scenelod
