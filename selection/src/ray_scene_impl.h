#pragma once
// Private state of RayScene, shared by ray_scene.cpp, picking.cpp and occlusion.cpp.
#include <cmath>
#include <cstdint>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>

#include "scenelod/selection/visibility.h"
#include "top_bvh.h"

namespace scenelod::selection {

struct ChainPrototypes {
  std::vector<RTCScene> levels;      // one per chain level; null when the level has no triangles
  std::vector<float> max_error;      // per level, object space
  int32_t occluder_level = 0;
  glm::vec3 center{0.0f};            // object-space sphere containing every level
  float radius = 0.0f;
  glm::vec3 box_lo{0.0f}, box_hi{0.0f};  // object-space box containing every level
};

struct RayScene::Impl {
  RaySceneParams params;
  RTCDevice device = nullptr;
  std::vector<ChainPrototypes> chains;
  TopBvh bvh;
  bool built = false;                // bvh matches the live set (apart from `pending`)
  bool moved = false;                // some box changed since the last commit
  size_t dead_in_bvh = 0;            // removed objects still in the tree

  // per object, indexed by id (hot columns first)
  std::vector<glm::vec3> box_lo, box_hi;      // 24 B: world box (empty when free), the BVH's input
  std::vector<glm::vec4> world_sphere;        // 16 B: centre, radius (0 when free)
  std::vector<float> largest_scale;           // 4 B: largest axis scale of the world transform
  std::vector<glm::mat4> inverse_world;       // 64 B: for rays into the object's own prototype
  std::vector<glm::mat4> world;               // 64 B
  std::vector<uint32_t> chain;                // 4 B
  std::vector<int32_t> drawn_level;           // 4 B: -1 = not drawn
  std::vector<uint32_t> generation;           // 4 B: bumped when the id is (re)used
  std::vector<uint8_t> live;                  // 1 B
  std::vector<uint32_t> free_ids;
  std::vector<uint64_t> scene_handle;         // syncFromScene: (slot << 32 | generation) per id

  void release();
};

}  // namespace scenelod::selection

namespace scenelod::selection {

inline void fillEmbreeRay(RTCRay& r, const glm::vec3& o, const glm::vec3& d, float t_near, float t_far) {
  r.org_x = o.x;
  r.org_y = o.y;
  r.org_z = o.z;
  r.dir_x = d.x;
  r.dir_y = d.y;
  r.dir_z = d.z;
  r.tnear = t_near;
  r.tfar = t_far;
  r.time = 0.0f;
  r.mask = 0xFFFFFFFFu;
  r.id = 0;
  r.flags = 0;
}

// Closest hit of the world ray (o, d) with object `id` drawn as prototype `proto`, within
// [t_near, t_far]; lowers t_far to the hit and returns true on a hit. The ray goes into object space
// through the inverse world transform, which keeps the ray parameter t.
inline bool intersectObject(const RayScene::Impl& m, uint32_t id, RTCScene proto, const glm::vec3& o,
                            const glm::vec3& d, float t_near, float& t_far) {
  const glm::mat4& inv = m.inverse_world[id];
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  fillEmbreeRay(rh.ray, glm::vec3(inv * glm::vec4(o, 1.0f)), glm::vec3(inv * glm::vec4(d, 0.0f)), t_near, t_far);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(proto, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  t_far = rh.ray.tfar;
  return true;
}

// Any hit of the object-space ray (o, d) with prototype `proto` within [t_near, t_far].
inline bool occludedInObjectSpace(RTCScene proto, const glm::vec3& o, const glm::vec3& d, float t_near, float t_far) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  fillEmbreeRay(r, o, d, t_near, t_far);
  rtcOccluded1(proto, &ctx, &r);
  return r.tfar < 0.0f && std::isinf(r.tfar);
}

}  // namespace scenelod::selection
