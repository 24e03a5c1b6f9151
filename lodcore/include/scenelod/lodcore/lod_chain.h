#pragma once
// A level-of-detail chain: level 0 is the original mesh, levels 1.. are simplified from the original
// (never from another level), each with the object-space cell width it was built for and its
// measured error. Produced by the generators (clustering, Zhang edge collapse, SCROOGE) and consumed
// by scene and selection.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

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
};

struct LodChain {
  std::vector<LodLevel> levels;  // levels[0] is the original; cell widths strictly increase

  size_t levelCount() const { return levels.size(); }
  bool empty() const { return levels.empty(); }
};

}  // namespace scenelod
