#pragma once
// Shared by zhang_definitions.cpp and zhang_edge_collapse.cpp: the measures of Zhang, Shu & Luo 2003
// (definitions 5-9) computed on one vertex's triangle fan ("star"), given as (u, w) pairs of its
// triangles (v, u, w) in counter-clockwise order.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/zhang.h"

namespace scenelod::zhang_detail {

constexpr uint32_t kNone = 0xffffffffu;

struct StarPair {
  uint32_t u;
  uint32_t w;
};

// per-vertex scratch sized to the vertex count once; reset through the touched list, so one
// measurement costs O(star size), not O(vertex count)
struct StarScratch {
  std::vector<uint32_t> count;  // appearances of a ring vertex (first as low 16 bits, second as high)
  std::vector<uint32_t> next;   // ring successor: next[u] = w for the pair (u, w)
  std::vector<uint32_t> touched;
  std::vector<uint32_t> ring;   // ordered ring of a disk vertex

  void resize(size_t vertex_count) {
    count.assign(vertex_count, 0);
    next.assign(vertex_count, kNone);
  }
  void reset() {
    for (uint32_t v : touched) {
      count[v] = 0;
      next[v] = kNone;
    }
    touched.clear();
  }
};

struct StarMeasure {
  uint32_t characteristic = 0;  // C(V)
  uint32_t neighbour_count = 0;
  bool disk = false;            // C(V) = 0 and the ring is one cycle
  float super_area = 0.0f, super_volume = 0.0f, super_height = 0.0f;
  float mean_neighbour_distance = 0.0f;
  ZhangVertexClass vertex_class = ZhangVertexClass::kIsolated;
};

// Topology and super height of a star (C(V), disk test, SA, SV, SH) and the class of §2 given the
// largest normal angle of the star. `positions` indexed by vertex id. With `always_height` false, SA,
// SV and SH are only computed where the class needs them (a disk vertex above the feature angle).
void measureStar(const glm::vec3& pv, const StarPair* pairs, size_t pair_count, const glm::vec3* positions,
                 float max_angle_rad, const ZhangParams& params, StarScratch& scratch, StarMeasure& out,
                 bool always_height = true);

// Super height only (SH of a disk star; 0 when the ring is not one cycle).
float superHeightOfStar(const glm::vec3& pv, const StarPair* pairs, size_t pair_count, const glm::vec3* positions,
                        StarScratch& scratch);

// angle in radians between two unit vectors (0 when either is zero)
float angleBetweenUnit(const glm::vec3& a, const glm::vec3& b);

}  // namespace scenelod::zhang_detail
