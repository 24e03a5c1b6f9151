#pragma once
// Private state of RayScene, shared by ray_scene.cpp, picking.cpp and occlusion.cpp.
#include <cstdint>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>

#include "scenelod/selection/visibility.h"

namespace scenelod::selection {

struct ChainPrototypes {
  std::vector<RTCScene> levels;      // one per chain level; null when the level has no triangles
  std::vector<float> max_error;      // per level, object space
  int32_t occluder_level = 0;
  glm::vec3 center{0.0f};            // object-space sphere containing every level
  float radius = 0.0f;
};

struct RayScene::Impl {
  RaySceneParams params;
  RTCDevice device = nullptr;
  RTCScene pick_scene = nullptr;     // instances at the drawn level
  RTCScene occluder_scene = nullptr; // instances at the occluder level
  std::vector<ChainPrototypes> chains;

  // per object, indexed by id (hot columns first)
  std::vector<glm::vec4> world_sphere;        // 16 B: centre, radius (0 when free)
  std::vector<float> occluder_error_world;    // 4 B: occluder level max_error * largest scale
  std::vector<glm::mat4> inverse_world;       // 64 B: for rays into the object's own prototype
  std::vector<glm::mat4> world;               // 64 B
  std::vector<uint32_t> chain;                // 4 B
  std::vector<int32_t> drawn_level;           // 4 B: -1 = not drawn
  std::vector<uint32_t> generation;           // 4 B: bumped when the id is (re)used
  std::vector<uint8_t> live;                  // 1 B
  std::vector<RTCGeometry> pick_instance;     // 8 B: geometry id == object id in pick_scene
  std::vector<RTCGeometry> occluder_instance; // 8 B: geometry id == object id in occluder_scene
  std::vector<uint32_t> free_ids;

  void release();
};

}  // namespace scenelod::selection
