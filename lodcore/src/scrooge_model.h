#pragma once
// Private working model of the SCROOGE files (Reddy 1996): welded points that degradation moves,
// polygons as point rings with the input vertex each corner takes its attributes from.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/scrooge.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::scrooge {

struct Face {
  std::vector<uint32_t> pts;    // ring of point indices, counter-clockwise seen from the front
  std::vector<uint32_t> verts;  // per corner: the (deduplicated) input vertex giving its attributes
  glm::vec3 color{1.0f};        // area-weighted mean colour (of the corners, or of the merged parts)
  bool blended = false;         // formed by merging: corners take `color`, not their vertex colour
  bool rebuilt = false;         // changed by reconstruction (gets the §7.1 polygon constraints)
  bool inside = false;          // was wholly inside a sub-volume in some pass (may lose co-linear corners)
  bool alive = true;
  uint32_t chart = 0;           // uv chart of the input polygon (computeUvCharts; its group without uvs);
                                // merging stays inside one
  uint32_t group = 0;           // triangle group (material) of the input polygon
};

struct Model {
  std::vector<glm::vec3> points;       // current positions
  std::vector<glm::vec3> origin;       // positions after welding, for the displacement bound
  std::vector<uint32_t> point_source;  // an input vertex that sits at the point's origin
  std::vector<uint32_t> vertex_point;  // input vertex -> point (kNoPoint when unused)
  std::vector<Face> faces;
  std::vector<uint32_t> edge_verts;    // line primitives, 2 input vertices each (never move)
  std::vector<float> edge_thickness;
  std::vector<uint32_t> point_verts;   // point primitives (never move)
  float diagonal = 0.0f;               // bbox diagonal of the input
  // texture coordinates (set 0) of the input vertices, empty without; a point inside one chart that
  // degradation moved gets its uv interpolated along the same segment (point_uv, where point_uv_moved)
  std::vector<glm::vec2> vertex_uv;
  std::vector<glm::vec2> point_uv;
  std::vector<uint8_t> point_uv_moved;
};

constexpr uint32_t kNoPoint = 0xffffffffu;

// splitmix64 finaliser, for hashing grid cell keys (small correlated integers)
inline uint64_t mix(uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// §4 step 1: fills `model` from `in` (validated by the caller). Counts go to `stats`.
void normaliseModel(const Mesh& in, const ScroogeParams& params, Model& model, ScroogeStats& stats);

// §7.2: removes polygons coplanar with and lying inside another polygon of the same facing.
size_t removeSubPolygons(Model& model);

// §5, §6: the sub-volume passes with edge degradation and, per sub-volume, reconstruction.
void degradeInSubvolumes(Model& model, const ScroogeParams& params, ScroogeStats& stats);

// §6.3 for one sub-volume: degrades the points of `faces` whose owner is `cell` (a point used by any
// polygon outside the sub-volume has another owner and stays, §6.1). Returns the moves made.
size_t degradeFaces(Model& model, const std::vector<uint32_t>& faces, const std::vector<uint32_t>& owner,
                    uint32_t cell, double l_max, double theta_min_rad, double theta_max_rad, bool prevent_foldover);

// §7 for one sub-volume: merges coplanar neighbours (new faces go to `added`, merged ones die).
// Returns the number of groups merged.
size_t reconstructFaces(Model& model, const std::vector<uint32_t>& faces, const ScroogeParams& params,
                        std::vector<Face>& added);

// after all passes: drops polygons flattened by degradation and (§7.1.1) removes co-linear corners
// of polygons that were inside a sub-volume. Done last because nothing moves afterwards, so the
// T-junctions both leave behind cannot open.
void finishFaces(Model& model, const ScroogeParams& params, double l_max);

// §7.1.2: splits a concave face into convex pieces (Hertel-Mehlhorn over an ear-clipping).
void splitConcave(const Model& model, const Face& face, std::vector<Face>& pieces);

// §4 step 4 and output: rebuilds a Mesh from the live faces, dropping unused vertices.
void assembleMesh(const Mesh& in, const Model& model, const ScroogeParams& params, Mesh& out, ScroogeStats& stats);

// geometry shared by the files
glm::dvec3 newellNormal(const Model& model, const std::vector<uint32_t>& pts);
double faceArea(const Model& model, const std::vector<uint32_t>& pts);
bool isDegenerate(const Model& model, const std::vector<uint32_t>& pts);
glm::vec3 faceMeanColor(const Mesh& in, const Model& model, const Face& f);

}  // namespace scenelod::scrooge
