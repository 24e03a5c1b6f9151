// Scripted camera paths (orbit, fly-through, approach) for recorded replays.
#include "scenelod/selection/camera_path.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace scenelod::selection {

bool parseCameraPathKind(const std::string& name, CameraPathKind& out) {
  if (name == "orbit") out = CameraPathKind::kOrbit;
  else if (name == "flythrough") out = CameraPathKind::kFlythrough;
  else if (name == "approach") out = CameraPathKind::kApproach;
  else return false;
  return true;
}

Sphere sceneBounds(const ReplayScene& scene) {
  std::vector<glm::vec3> c;
  std::vector<float> r, s;
  computeWorldSpheres(scene, c, r, s);
  Sphere b;
  if (c.empty()) {
    b.radius = 1.0f;
    return b;
  }
  glm::vec3 lo(c[0] - r[0]), hi(c[0] + r[0]);
  for (size_t i = 0; i < c.size(); ++i) {
    lo = glm::min(lo, c[i] - glm::vec3(r[i]));
    hi = glm::max(hi, c[i] + glm::vec3(r[i]));
  }
  b.center = (lo + hi) * 0.5f;
  for (size_t i = 0; i < c.size(); ++i) b.radius = std::max(b.radius, glm::length(c[i] - b.center) + r[i]);
  if (!(b.radius > 0.0f)) b.radius = 1.0f;
  return b;
}

void makeCameraPath(const Sphere& bounds, CameraPathKind kind, size_t frames, double fps, Replay& replay,
                    double approach_from) {
  replay.frames.clear();
  const glm::vec3 c = bounds.center;
  const float r = bounds.radius;
  for (size_t i = 0; i < frames; ++i) {
    const float t = frames > 1 ? static_cast<float>(i) / static_cast<float>(frames - 1) : 0.0f;
    ReplayFrame f;
    f.frame = i;
    f.time_s = static_cast<double>(i) / fps;
    switch (kind) {
      case CameraPathKind::kOrbit: {
        const float a = 6.2831853f * t;
        f.eye = c + glm::vec3(1.6f * r * std::cos(a), 0.35f * r, 1.6f * r * std::sin(a));
        f.target = c;
        break;
      }
      case CameraPathKind::kFlythrough: {
        auto at = [&](float s) {
          return c + glm::vec3(-0.9f * r + 1.8f * r * s, 0.1f * r, 0.3f * r * std::sin(6.2831853f * s));
        };
        f.eye = at(t);
        glm::vec3 ahead = at(std::min(t + 0.02f, 1.02f)) - f.eye;
        if (glm::length(ahead) < 1e-6f * r) ahead = glm::vec3(1.0f, 0.0f, 0.0f);
        f.target = f.eye + glm::normalize(ahead) * r * 0.2f - glm::vec3(0.0f, 0.03f * r, 0.0f);
        break;
      }
      case CameraPathKind::kApproach: {
        const glm::vec3 dir = glm::normalize(glm::vec3(0.3f, 0.25f, 1.0f));
        const float from = static_cast<float>(approach_from) * r;
        const float d = from + (0.15f * r - from) * t;
        f.eye = c + dir * d;
        f.target = c;
        break;
      }
    }
    replay.frames.push_back(f);
  }
}

}  // namespace scenelod::selection
