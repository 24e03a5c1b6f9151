#pragma once
// The camera selection looks through, the pixel size R of Low & Tan 1997 §4, and frustum culling of
// bounding spheres.
#include <cstdint>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace scenelod::selection {

enum class Projection : uint8_t { kPerspective, kOrthographic };

struct Camera {
  glm::vec3 eye{0.0f, 0.0f, 5.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fov_y_rad = 1.0471976f;      // vertical field of view (perspective), 60 degrees
  float ortho_height = 2.0f;         // world-space height of the view (orthographic)
  float near_plane = 0.01f;
  float far_plane = 1.0e6f;
  uint32_t viewport_width_px = 1280;
  uint32_t viewport_height_px = 720;
  Projection projection = Projection::kPerspective;
};

// Object-space width of one pixel at distance `distance` from the eye:
// R = 2 * D * tan(FOV/2) / viewport height (Low & Tan 1997 §4); for an orthographic camera the
// distance does not matter: R = ortho_height / viewport height. Distances below the near plane are
// clamped to it. Cost: a few flops, no allocation, thread-safe.
float pixelSize(const Camera& camera, float distance);

// The factor 2 * tan(FOV/2) / viewport height of a perspective camera (pixelSize is
// max(distance, near) times it), or 0 for an orthographic one. Selection hoists it out of its loop.
float pixelSizeFactor(const Camera& camera);

// True when the camera can be used: finite eye/target/up, eye != target, up not parallel to the view
// direction, 0 < fov < pi, 0 < near < far, viewport at least 1x1, ortho_height > 0.
bool cameraValid(const Camera& camera);

// The six planes of the view volume, normals pointing inside: a point p is inside plane i when
// dot(planes[i].xyz, p) + planes[i].w >= 0. Order: near, far, left, right, bottom, top.
struct Frustum {
  glm::vec4 planes[6];
  glm::vec3 eye{0.0f};
  glm::vec3 forward{0.0f, 0.0f, -1.0f};  // unit view direction
};

// Builds the frustum of a valid camera (cameraValid). Cost: a few dozen flops, thread-safe.
Frustum computeFrustum(const Camera& camera);

// False when the sphere lies entirely outside one plane (conservative: a sphere near a corner may be
// reported inside). A sphere entirely behind the eye is always outside (the near plane).
// Inline: selection calls it once per object per frame.
inline bool sphereInFrustum(const Frustum& frustum, const glm::vec3& center, float radius) {
  for (const glm::vec4& p : frustum.planes)
    if (p.x * center.x + p.y * center.y + p.z * center.z + p.w < -radius) return false;
  return true;
}

}  // namespace scenelod::selection
