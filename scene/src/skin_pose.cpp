// Skinned poses as the glTF 2.0 specification defines them: animation samplers (§3.11: LINEAR with
// spherical interpolation of rotations, STEP, CUBICSPLINE as a cubic Hermite spline whose tangents
// are scaled by the key interval) and linear blend skinning (§3.7.3).
#include "scenelod/scene/skin_pose.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

namespace scenelod::scene {
namespace {

bool finite(const glm::vec4& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w); }

bool finite(const glm::mat4& m) { return finite(m[0]) && finite(m[1]) && finite(m[2]) && finite(m[3]); }

std::string animationName(const std::string& what, const AnimationData& a, size_t index) {
  return what + " animation " + std::to_string(index) + (a.name.empty() ? "" : " '" + a.name + "'");
}

Error validateSampler(const AnimationData::Sampler& s, const std::string& name) {
  if (s.times.empty()) return {Status::kInvalidArgument, name + " has no key times"};
  for (size_t k = 0; k < s.times.size(); ++k) {
    if (!std::isfinite(s.times[k]))
      return {Status::kInvalidArgument, name + ": key time " + std::to_string(k) + " is not finite"};
    if (k > 0 && !(s.times[k] > s.times[k - 1]))
      return {Status::kInvalidArgument, name + ": key times are not strictly increasing at key " + std::to_string(k)};
  }
  const size_t per_key = s.interpolation == AnimationData::Interpolation::kCubicSpline ? 3 : 1;
  if (s.values.size() != per_key * s.times.size())
    return {Status::kInvalidArgument, name + " has " + std::to_string(s.values.size()) + " values for " +
                                          std::to_string(s.times.size()) + " keys (needs " +
                                          std::to_string(per_key * s.times.size()) + ")"};
  for (size_t k = 0; k < s.values.size(); ++k)
    if (!finite(s.values[k])) return {Status::kInvalidArgument, name + ": value " + std::to_string(k) + " is not finite"};
  return {};
}

Error validateAnimation(const SceneData& scene, const AnimationData& a, const std::string& name) {
  for (size_t i = 0; i < a.samplers.size(); ++i)
    if (Error e = validateSampler(a.samplers[i], name + " sampler " + std::to_string(i)); !e.ok()) return e;
  for (size_t i = 0; i < a.channels.size(); ++i) {
    const AnimationData::Channel& c = a.channels[i];
    const std::string ch = name + " channel " + std::to_string(i);
    if (c.node < 0 || c.node >= static_cast<int32_t>(scene.nodes.size()))
      return {Status::kInvalidArgument, ch + " targets node " + std::to_string(c.node) + " of " +
                                            std::to_string(scene.nodes.size())};
    if (c.sampler < 0 || c.sampler >= static_cast<int32_t>(a.samplers.size()))
      return {Status::kInvalidArgument, ch + " uses sampler " + std::to_string(c.sampler) + " of " +
                                            std::to_string(a.samplers.size())};
    if (c.path != AnimationData::Path::kRotation) continue;
    // a zero quaternion has no rotation to normalise to
    const AnimationData::Sampler& s = a.samplers[c.sampler];
    const bool cubic = s.interpolation == AnimationData::Interpolation::kCubicSpline;
    for (size_t k = 0; k < s.times.size(); ++k)
      if (glm::dot(s.values[cubic ? 3 * k + 1 : k], s.values[cubic ? 3 * k + 1 : k]) <= 0.0f)
        return {Status::kInvalidArgument, ch + ": rotation key " + std::to_string(k) + " is a zero quaternion"};
  }
  return {};
}

Error validateSkin(const SceneData& scene, const SkinData& skin, const std::string& name) {
  if (skin.inverse_bind.size() != skin.joints.size())
    return {Status::kInvalidArgument, name + " has " + std::to_string(skin.inverse_bind.size()) +
                                          " inverse bind matrices for " + std::to_string(skin.joints.size()) + " joints"};
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    if (skin.joints[j] < 0 || skin.joints[j] >= static_cast<int32_t>(scene.nodes.size()))
      return {Status::kInvalidArgument, name + ": joint " + std::to_string(j) + " is node " +
                                            std::to_string(skin.joints[j]) + " of " + std::to_string(scene.nodes.size())};
    if (!finite(skin.inverse_bind[j]))
      return {Status::kInvalidArgument, name + ": inverse bind matrix " + std::to_string(j) + " is not finite"};
  }
  if (skin.skeleton < -1 || skin.skeleton >= static_cast<int32_t>(scene.nodes.size()))
    return {Status::kInvalidArgument, name + ": skeleton root " + std::to_string(skin.skeleton) + " out of range"};
  return {};
}

// the skinned mesh of node `i` must have a skin and joints the skin has
Error validateSkinnedNode(const SceneData& scene, size_t i, const std::string& what) {
  const NodeData& node = scene.nodes[i];
  const std::string name = what + " node " + std::to_string(i) + (node.name.empty() ? "" : " '" + node.name + "'");
  if (node.skin < 0 || node.skin >= static_cast<int32_t>(scene.skins.size()))
    return {Status::kInvalidArgument, name + " uses skin " + std::to_string(node.skin) + " of " +
                                          std::to_string(scene.skins.size())};
  if (node.mesh < 0 || node.mesh >= static_cast<int32_t>(scene.meshes.size())) return {};
  const MeshData& md = scene.meshes[node.mesh];
  const std::string mesh = what + " mesh " + std::to_string(node.mesh) + (md.name.empty() ? "" : " '" + md.name + "'");
  if (!md.mesh.skinned() || md.mesh.weights.size() != md.mesh.joints.size())
    return {Status::kInvalidMesh, mesh + " is drawn with skin " + std::to_string(node.skin) + " by " + name +
                                      " but has no joints and weights of the same count"};
  const size_t joint_count = scene.skins[node.skin].joints.size();
  for (size_t v = 0; v < md.mesh.joints.size(); ++v)
    for (int c = 0; c < 4; ++c)
      if (md.mesh.weights[v][c] != 0.0f && md.mesh.joints[v][c] >= joint_count)
        return {Status::kInvalidMesh, mesh + ": vertex " + std::to_string(v) + " uses joint " +
                                          std::to_string(md.mesh.joints[v][c]) + " but skin " +
                                          std::to_string(node.skin) + " has " + std::to_string(joint_count) + " joints"};
  return {};
}

// spherical interpolation along the shorter arc; normalised lerp where the arc is too short for
// the sine ratio to be accurate
glm::vec4 slerp(const glm::vec4& a, glm::vec4 b, float u) {
  float d = glm::dot(a, b);
  if (d < 0.0f) { b = -b; d = -d; }
  if (d > 0.9995f) return glm::normalize(a + (b - a) * u);
  const float theta = std::acos(std::min(d, 1.0f));
  const float s = std::sin(theta);
  return a * (std::sin((1.0f - u) * theta) / s) + b * (std::sin(u * theta) / s);
}

glm::quat toQuat(const glm::vec4& xyzw) { return glm::quat(xyzw.w, xyzw.x, xyzw.y, xyzw.z); }

}  // namespace

Error validateSkinning(const SceneData& scene, const std::string& what) {
  for (size_t s = 0; s < scene.skins.size(); ++s) {
    const SkinData& skin = scene.skins[s];
    const std::string name = what + " skin " + std::to_string(s) + (skin.name.empty() ? "" : " '" + skin.name + "'");
    if (Error e = validateSkin(scene, skin, name); !e.ok()) return e;
  }
  for (size_t a = 0; a < scene.animations.size(); ++a)
    if (Error e = validateAnimation(scene, scene.animations[a], animationName(what, scene.animations[a], a)); !e.ok())
      return e;
  for (size_t i = 0; i < scene.nodes.size(); ++i)
    if (scene.nodes[i].skin != -1)
      if (Error e = validateSkinnedNode(scene, i, what); !e.ok()) return e;
  return {};
}

void animationTimeRange(const AnimationData& animation, float& start, float& end) {
  bool any = false;
  start = end = 0.0f;
  for (const AnimationData::Sampler& s : animation.samplers) {
    if (s.times.empty()) continue;
    start = any ? std::min(start, s.times.front()) : s.times.front();
    end = any ? std::max(end, s.times.back()) : s.times.back();
    any = true;
  }
}

glm::vec4 sampleAnimation(const AnimationData::Sampler& s, float t, bool rotation) {
  const size_t n = s.times.size();
  const bool cubic = s.interpolation == AnimationData::Interpolation::kCubicSpline;
  auto value = [&](size_t k) { return cubic ? s.values[3 * k + 1] : s.values[k]; };
  glm::vec4 v;
  if (n == 1 || !(t > s.times.front())) {
    v = value(0);
  } else if (t >= s.times.back()) {
    v = value(n - 1);
  } else {
    // times[k] <= t < times[k + 1]
    const size_t k = static_cast<size_t>(std::upper_bound(s.times.begin(), s.times.end(), t) - s.times.begin()) - 1;
    const float td = s.times[k + 1] - s.times[k];
    const float u = (t - s.times[k]) / td;
    switch (s.interpolation) {
      case AnimationData::Interpolation::kStep:
        v = value(k);
        break;
      case AnimationData::Interpolation::kLinear:
        v = rotation ? slerp(value(k), value(k + 1), u) : value(k) + (value(k + 1) - value(k)) * u;
        break;
      case AnimationData::Interpolation::kCubicSpline: {
        const float u2 = u * u, u3 = u2 * u;
        const glm::vec4 out_tangent = s.values[3 * k + 2] * td, in_tangent = s.values[3 * (k + 1)] * td;
        v = (2.0f * u3 - 3.0f * u2 + 1.0f) * value(k) + (u3 - 2.0f * u2 + u) * out_tangent +
            (-2.0f * u3 + 3.0f * u2) * value(k + 1) + (u3 - u2) * in_tangent;
        break;
      }
    }
  }
  return rotation ? glm::normalize(v) : v;
}

Trs decomposeTrs(const glm::mat4& m) {
  Trs trs;
  trs.translation = glm::vec3(m[3]);
  glm::vec3 axis[3];
  for (int c = 0; c < 3; ++c) {
    axis[c] = glm::vec3(m[c]);
    trs.scale[c] = glm::length(axis[c]);
  }
  // a mirror goes into the x scale so that the rotation stays proper
  if (glm::dot(glm::cross(axis[0], axis[1]), axis[2]) < 0.0f) trs.scale.x = -trs.scale.x;
  glm::mat3 r(1.0f);
  for (int c = 0; c < 3; ++c)
    if (trs.scale[c] != 0.0f) r[c] = axis[c] / trs.scale[c];
  trs.rotation = glm::normalize(glm::quat_cast(r));
  return trs;
}

void animatedLocals(const SceneData& scene, int32_t animation, float t, std::vector<glm::mat4>& out) {
  out.resize(scene.nodes.size());
  for (size_t i = 0; i < scene.nodes.size(); ++i) out[i] = scene.nodes[i].local;
  if (animation == kRestPose) return;
  const AnimationData& a = scene.animations[animation];
  // the rest decomposition of each driven node, its driven parts overwritten channel by channel
  std::vector<Trs> trs(scene.nodes.size());
  std::vector<uint8_t> driven(scene.nodes.size(), 0);
  for (const AnimationData::Channel& c : a.channels) {
    if (c.path == AnimationData::Path::kWeights) continue;
    if (!driven[c.node]) trs[c.node] = decomposeTrs(scene.nodes[c.node].local);
    driven[c.node] = 1;
    const glm::vec4 v = sampleAnimation(a.samplers[c.sampler], t, c.path == AnimationData::Path::kRotation);
    if (c.path == AnimationData::Path::kTranslation) trs[c.node].translation = glm::vec3(v);
    if (c.path == AnimationData::Path::kRotation) trs[c.node].rotation = toQuat(v);
    if (c.path == AnimationData::Path::kScale) trs[c.node].scale = glm::vec3(v);
  }
  for (size_t i = 0; i < scene.nodes.size(); ++i)
    if (driven[i]) out[i] = composeTrs(trs[i]);
}

glm::mat4 nodeFrame(const SceneData& scene, Span<const glm::mat4> locals, int32_t node) {
  glm::mat4 m(1.0f);
  // validateSceneData rules out parent cycles; the count bounds the walk all the same
  for (size_t depth = 0; node >= 0 && depth < scene.nodes.size(); ++depth) {
    m = locals[node] * m;
    node = scene.nodes[node].parent;
  }
  return m;
}

void skinMatrices(const SceneData& scene, int32_t skin, Span<const glm::mat4> world, std::vector<glm::mat4>& out) {
  const SkinData& s = scene.skins[skin];
  out.resize(s.joints.size());
  for (size_t j = 0; j < s.joints.size(); ++j) out[j] = world[s.joints[j]] * s.inverse_bind[j];
}

Error poseMesh(const Mesh& mesh, Span<const glm::mat4> skin_matrices, Mesh& out, const std::string& what) {
  const size_t n = mesh.vertexCount();
  if (mesh.joints.size() != n || mesh.weights.size() != n)
    return {Status::kInvalidMesh, what + ": cannot pose a mesh without skin joints and weights for every vertex"};
  out = mesh;
  for (size_t v = 0; v < n; ++v) {
    glm::mat4 m(0.0f);
    float sum = 0.0f;
    for (int c = 0; c < 4; ++c) {
      const float w = mesh.weights[v][c];
      if (w == 0.0f) continue;
      if (mesh.joints[v][c] >= skin_matrices.size())
        return {Status::kInvalidMesh, what + ": vertex " + std::to_string(v) + " uses joint " +
                                          std::to_string(mesh.joints[v][c]) + " but the skin has " +
                                          std::to_string(skin_matrices.size()) + " joints"};
      m += skin_matrices[mesh.joints[v][c]] * w;
      sum += w;
    }
    if (!(sum > 0.0f))
      return {Status::kInvalidMesh, what + ": vertex " + std::to_string(v) + " has skin weights summing to 0"};
    m *= 1.0f / sum;
    out.positions[v] = glm::vec3(m * glm::vec4(mesh.positions[v], 1.0f));
    const glm::vec3 a(m[0]), b(m[1]), c(m[2]);
    if (!mesh.normals.empty()) {
      // the cofactor matrix is the inverse transpose times the determinant: the same directions
      const glm::mat3 cof(glm::cross(b, c), glm::cross(c, a), glm::cross(a, b));
      // (a mirror's negative determinant would turn normals inside out)
      const float sign = glm::dot(a, cof[0]) < 0.0f ? -1.0f : 1.0f;
      const glm::vec3 nn = sign * (cof * mesh.normals[v]);
      if (glm::dot(nn, nn) > 0.0f) out.normals[v] = glm::normalize(nn);
    }
    if (!mesh.tangents.empty()) {
      const glm::vec3 t = glm::mat3(a, b, c) * glm::vec3(mesh.tangents[v]);
      if (glm::dot(t, t) > 0.0f) out.tangents[v] = glm::vec4(glm::normalize(t), mesh.tangents[v].w);
    }
  }
  return {};
}

}  // namespace scenelod::scene
