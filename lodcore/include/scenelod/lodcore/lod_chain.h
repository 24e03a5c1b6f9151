#pragma once
// A level-of-detail chain: level 0 is the original mesh, levels 1.. are simplified from the original
// (independent levels) or each from the one before (nested levels), each with the object-space cell width it was built for and its
// measured error. Produced by the generators (clustering, Zhang edge collapse, SCROOGE) and consumed
// by scene and selection.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "scenelod/lodcore/mesh.h"

namespace scenelod {

// How a level was produced.
enum class LodMethod : uint8_t {
  kOriginal = 0,
  kUniform,           // Rossignac & Borrel uniform-subdivision clustering
  kFloatingHeaviest,  // Low & Tan floating cells, vertex joins the heaviest containing cell
  kFloatingNearest,   // Low & Tan §3.2.3, vertex joins the nearest containing centre
  kZhang,             // Zhang, Shu & Luo 2003 vision-characteristic edge collapse
  kScrooge,           // Reddy, SCROOGE perceptually driven reduction
};

const char* lodMethodName(LodMethod method);

struct Sphere {
  glm::vec3 center{0.0f};
  float radius = 0.0f;
};

// Geomorph targets of a level (Hoppe 1996): for every vertex of the level, where it goes in the next
// coarser level of its chain. A renderer draws the level with each attribute mixed as
// (1 - f) x own + f x target for a morph factor f in [0, 1]; at f = 1 the vertex sits on its
// target, so the switch to the next level moves nothing (exactly, for nested chains:
// docs/CLUSTERING.md, "Geomorphs"). The target of a vertex is a vertex of the next level whose
// cluster holds the largest area share of the vertex's cluster's original vertices: the one the
// vertex's triangles are drawn with in the next level (position, normal and attributes all of that
// vertex), else the one in the same triangle group, with the nearest texture coordinates, then the
// nearest normal. Every array is empty or one per vertex of the level's mesh, present where both
// levels' meshes have that attribute, normals also where only the next level has them (a level
// drawn with computed normals: computeVertexNormals); all empty (empty()) on the last level and
// where the generator records none (SCROOGE). Skin joints and weights have no target (a vertex
// keeps its own).
struct LevelMorph {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec3> colors;
  std::vector<glm::vec2> uvs;
  std::vector<std::vector<glm::vec2>> extra_uvs;  // per set, as Mesh::extra_uvs
  std::vector<glm::vec4> tangents;

  bool empty() const { return positions.empty(); }
  // bytes the targets take: 12 per vertex for positions, 12 for normals and colours, 8 per texture
  // coordinate set, 16 for tangents
  size_t byteSize() const;
};

struct LodLevel {
  Mesh mesh;
  float cell_width = 0.0f;   // object space; 0 for the original. The level is accurate enough
                             // while cell_width <= X * R (X pixels per cell, R the pixel size)
  float max_error = 0.0f;    // measured maximum vertex displacement, object space
  LodMethod method = LodMethod::kOriginal;
  Sphere bounds;             // contains every vertex of this level
  // for every vertex of `mesh`, one vertex of the original (levels[0].mesh) it stands for: its
  // attributes' main source, for engines that rebuild their own vertex format. Empty for level 0
  // (the identity) and where a generator does not record it.
  std::vector<uint32_t> source_vertex;
  LevelMorph morph;  // this level's vertices' targets in the next level (empty when absent)
};

// Per triangle corner of `level` (3 per triangle, in its triangle order): the vertex of `next`
// (the chain's next level) that draws that corner when `level` is drawn at morph factor 1: the
// corner of the triangle of `next` whose corners sit exactly on the targets (level.morph.positions)
// of the triangle's corners, in the same triangle group and orientation first, then with the
// nearest texture coordinates; UINT32_MAX where two corners share a target (the triangle
// collapses), where no triangle of `next` lies there (levels that are not nested) and for a level
// without morph targets. A vertex has one target, yet its triangles may be drawn with several
// vertices of the next level (a crease of the next level through it): a renderer that wants level
// k at factor 1 to be shaded exactly as level k + 1 draws such a corner with a copy of the vertex
// whose target attributes are this vertex's (the GL adapter does). Cost: O(T log T) time, 16 bytes
// per triangle of `next`. Thread-safe. With `next_triangle`: per triangle of `level`, the triangle
// of `next` it was matched to (UINT32_MAX where none): a renderer draws level k's triangles in the
// order of their matches, so that surfaces that coincide at factor 1 overlap in the order level
// k + 1 draws them (a depth tie keeps the first).
std::vector<uint32_t> morphCornerVertices(const LodLevel& level, const Mesh& next,
                                          std::vector<uint32_t>* next_triangle = nullptr);

struct LodChain {
  std::vector<LodLevel> levels;  // levels[0] is the original; cell widths strictly increase and no
                                 // level has more triangles or primitives than the one before

  size_t levelCount() const { return levels.size(); }
  bool empty() const { return levels.empty(); }
};

}  // namespace scenelod
