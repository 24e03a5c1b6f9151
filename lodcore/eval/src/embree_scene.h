#pragma once
// Private: one mesh as an Embree scene, for closest-point queries (metrics) and ray casts (renders).
// Triangles are an Embree triangle geometry; edges and points are one user geometry of "round"
// primitives: an edge of thickness t is a capsule of radius t/2 around the segment, a point is a
// sphere of radius 0 (the point itself). A radius floor can be set so hairlines show in pictures.
#include <cstdint>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/vec3.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::eval::detail {

// a capsule from a to b (a == b for a sphere) with radius r; colour = mean of its vertices' colours
struct RoundPrim {
  glm::vec3 a{0.0f}, b{0.0f};
  float radius = 0.0f;
  glm::vec3 color{0.0f};
  bool is_point = false;
};

struct RayHit {
  bool hit = false;
  float t = 0.0f;
  glm::vec3 normal{0.0f};  // unit, facing the ray origin (two-sided): face normal of a triangle
  glm::vec3 shading{0.0f}; // unit, facing the ray origin: interpolated vertex normal when present
  glm::vec3 color{0.0f};   // linear RGB from vertex colours, or the kind's default
  int kind = 0;            // 0 triangle, 1 edge, 2 point
  uint32_t prim = 0;       // triangle index (kind 0), else the edge/point's index in rounds_
  float u = 0.0f, v = 0.0f;  // barycentrics of a triangle hit: weights of its corners 1 and 2
};

class EmbreeScene {
 public:
  EmbreeScene() = default;
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // Builds the scene; min_radius raises every capsule/sphere radius to at least this value.
  Error build(const Mesh& mesh, float min_radius = 0.0f);

  // Distance from p to the nearest geometry (triangle surface, or capsule/sphere solid: 0 inside).
  // `hint` > 0 first searches only that radius (much faster when the answer is inside it) and falls
  // back to an unbounded search; the result is exact either way. Thread-safe after build. Returns
  // +inf for an empty scene.
  float closestDistance(const glm::vec3& p, float hint = 0.0f) const;

  // First hit along origin + t * dir (dir unit) for t in [0, t_max]. Thread-safe after build.
  RayHit intersect(const glm::vec3& origin, const glm::vec3& dir, float t_max) const;

  bool empty() const { return tri_count_ == 0 && rounds_.empty(); }

  // exposed for the callbacks
  const Mesh* mesh_ = nullptr;
  std::vector<RoundPrim> rounds_;
  unsigned tri_geom_ = RTC_INVALID_GEOMETRY_ID;
  unsigned round_geom_ = RTC_INVALID_GEOMETRY_ID;

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  size_t tri_count_ = 0;
};

// exact closest point on triangle abc to p
glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);
// distance from p to segment ab (a == b allowed)
float distanceToSegment(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b);
// nearest t >= t_min where the ray enters the capsule (a, b, r); returns false when it misses
bool intersectCapsule(const glm::vec3& o, const glm::vec3& d, const glm::vec3& a, const glm::vec3& b, float r,
                      float t_min, float t_max, float& t_hit, glm::vec3& axis_point);

}  // namespace scenelod::eval::detail
