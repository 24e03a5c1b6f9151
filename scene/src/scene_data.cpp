#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

namespace {

std::string meshName(const SceneData& s, size_t m, const std::string& what) {
  return what + " mesh " + std::to_string(m) + (s.meshes[m].name.empty() ? "" : " '" + s.meshes[m].name + "'");
}

bool inRange(int32_t i, size_t n) { return i >= -1 && i < static_cast<int32_t>(n); }

Error validateMaterials(const SceneData& s, const std::string& what) {
  for (size_t i = 0; i < s.materials.size(); ++i)
    if (!inRange(s.materials[i].base_color_texture, s.textures.size()))
      return {Status::kInvalidArgument, what + ": material " + std::to_string(i) + ": texture " +
                                            std::to_string(s.materials[i].base_color_texture) + " out of range"};
  for (size_t i = 0; i < s.textures.size(); ++i)
    if (!inRange(s.textures[i].image, s.images.size()))
      return {Status::kInvalidArgument, what + ": texture " + std::to_string(i) + ": image " +
                                            std::to_string(s.textures[i].image) + " out of range"};
  return {};
}

// skins name nodes; a skinned node's mesh indexes its skin's joints
Error validateSkins(const SceneData& s, const std::string& what) {
  for (size_t k = 0; k < s.skins.size(); ++k) {
    const SkinData& skin = s.skins[k];
    for (int32_t j : skin.joints)
      if (j < 0 || j >= static_cast<int32_t>(s.nodes.size()))
        return {Status::kInvalidArgument, what + ": skin " + std::to_string(k) + ": joint node " + std::to_string(j) +
                                              " out of range (" + std::to_string(s.nodes.size()) + " nodes)"};
    if (skin.inverse_bind.size() != skin.joints.size())
      return {Status::kInvalidArgument, what + ": skin " + std::to_string(k) + " has " + std::to_string(skin.inverse_bind.size()) +
                                            " inverse bind matrices for " + std::to_string(skin.joints.size()) + " joints"};
  }
  for (size_t i = 0; i < s.nodes.size(); ++i) {
    const NodeData& node = s.nodes[i];
    if (!inRange(node.skin, s.skins.size()))
      return {Status::kInvalidArgument, what + ": node " + std::to_string(i) + " refers to skin " + std::to_string(node.skin) +
                                            " of " + std::to_string(s.skins.size())};
    if (node.skin < 0 || node.mesh < 0) continue;
    const Mesh& m = s.meshes[static_cast<size_t>(node.mesh)].mesh;
    const size_t count = s.skins[static_cast<size_t>(node.skin)].joints.size();
    for (size_t v = 0; v < m.joints.size(); ++v)
      for (int c = 0; c < 4; ++c)
        if (m.joints[v][c] >= count)
          return {Status::kInvalidArgument, meshName(s, static_cast<size_t>(node.mesh), what) + " JOINTS_0: vertex " +
                                                std::to_string(v) + " uses joint " + std::to_string(m.joints[v][c]) +
                                                " but skin " + std::to_string(node.skin) + " (node " + std::to_string(i) +
                                                ") has " + std::to_string(count) + " joints"};
  }
  return {};
}

Error validateAnimations(const SceneData& s, const std::string& what) {
  for (size_t a = 0; a < s.animations.size(); ++a)
    for (size_t c = 0; c < s.animations[a].channels.size(); ++c) {
      const AnimationData::Channel& ch = s.animations[a].channels[c];
      const std::string where = what + ": animation " + std::to_string(a) + " channel " + std::to_string(c);
      if (ch.node < 0 || ch.node >= static_cast<int32_t>(s.nodes.size()))
        return {Status::kInvalidArgument, where + " targets node " + std::to_string(ch.node) + " of " + std::to_string(s.nodes.size())};
      if (ch.sampler < 0 || ch.sampler >= static_cast<int32_t>(s.animations[a].samplers.size()))
        return {Status::kInvalidArgument, where + " uses sampler " + std::to_string(ch.sampler) + " out of range"};
    }
  return {};
}

}  // namespace

Error validateSceneData(const SceneData& s, const std::string& what) {
  const int32_t n = static_cast<int32_t>(s.nodes.size());
  for (int32_t i = 0; i < n; ++i) {
    const NodeData& node = s.nodes[i];
    if (node.mesh < -1 || node.mesh >= static_cast<int32_t>(s.meshes.size()))
      return {Status::kInvalidArgument, what + ": node " + std::to_string(i) + " refers to mesh " +
                                            std::to_string(node.mesh) + " of " + std::to_string(s.meshes.size())};
    if (node.parent < -1 || node.parent >= n)
      return {Status::kInvalidArgument, what + ": node " + std::to_string(i) + " has parent " + std::to_string(node.parent) +
                                            " out of range"};
    for (int32_t c : node.children) {
      if (c < 0 || c >= n)
        return {Status::kInvalidArgument, what + ": node " + std::to_string(i) + " has child " + std::to_string(c) + " out of range"};
      if (s.nodes[c].parent != i)
        return {Status::kInvalidArgument, what + ": node " + std::to_string(c) + " is a child of node " + std::to_string(i) +
                                              " but names parent " + std::to_string(s.nodes[c].parent)};
    }
  }
  // walking up from any node must end at a root (linear in the nodes, however deep the tree)
  std::vector<int32_t> parents(s.nodes.size());
  for (size_t i = 0; i < s.nodes.size(); ++i) parents[i] = s.nodes[i].parent;
  const size_t cycle = firstParentCycle(Span<const int32_t>(parents.data(), parents.size()));
  if (cycle < parents.size())
    return {Status::kInvalidArgument, what + ": node " + std::to_string(cycle) + " is part of a parent cycle"};
  std::vector<char> seen(s.nodes.size(), 0);
  for (int32_t r : s.roots) {
    if (r < 0 || r >= n) return {Status::kInvalidArgument, what + ": root " + std::to_string(r) + " out of range"};
    if (s.nodes[r].parent != -1)
      return {Status::kInvalidArgument, what + ": root node " + std::to_string(r) + " has a parent"};
    if (seen[r]) return {Status::kInvalidArgument, what + ": root node " + std::to_string(r) + " listed twice"};
    seen[r] = 1;
  }
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const std::string name = meshName(s, m, what);
    if (Error e = validateMesh(s.meshes[m].mesh, name); !e.ok()) return e;
    for (int32_t mat : s.meshes[m].primitive_materials)
      if (mat < -1 || mat >= static_cast<int32_t>(s.materials.size()))
        return {Status::kInvalidArgument, name + ": material " + std::to_string(mat) + " out of range"};
  }
  if (Error e = validateMaterials(s, what); !e.ok()) return e;
  if (Error e = validateSkins(s, what); !e.ok()) return e;
  return validateAnimations(s, what);
}

std::vector<int32_t> objectNodes(const SceneData& s) {
  std::vector<int32_t> out, stack;
  for (auto r = s.roots.rbegin(); r != s.roots.rend(); ++r) stack.push_back(*r);
  std::vector<char> visited(s.nodes.size(), 0);
  while (!stack.empty()) {
    const int32_t i = stack.back();
    stack.pop_back();
    if (i < 0 || i >= static_cast<int32_t>(s.nodes.size()) || visited[i]) continue;
    visited[i] = 1;
    if (s.nodes[i].mesh >= 0) out.push_back(i);
    const auto& ch = s.nodes[i].children;
    for (auto c = ch.rbegin(); c != ch.rend(); ++c) stack.push_back(*c);
  }
  return out;
}

std::vector<glm::mat4> worldTransforms(const SceneData& s) {
  std::vector<glm::mat4> locals(s.nodes.size());
  for (size_t i = 0; i < s.nodes.size(); ++i) locals[i] = s.nodes[i].local;
  return worldTransforms(s, Span<const glm::mat4>(locals.data(), locals.size()));
}

std::vector<glm::mat4> worldTransforms(const SceneData& s, Span<const glm::mat4> locals) {
  const size_t n = s.nodes.size();
  std::vector<glm::mat4> world(n, glm::mat4(1.0f));
  std::vector<char> done(n, 0);
  std::vector<int32_t> chain;
  for (size_t i = 0; i < n; ++i) {
    // climb to the first computed ancestor, then come back down
    chain.clear();
    int32_t p = static_cast<int32_t>(i);
    while (p >= 0 && !done[p] && chain.size() <= n) { chain.push_back(p); p = s.nodes[p].parent; }
    glm::mat4 m = p >= 0 && done[p] ? world[p] : glm::mat4(1.0f);
    for (auto c = chain.rbegin(); c != chain.rend(); ++c) {
      m = m * locals[*c];
      world[*c] = m;
      done[*c] = 1;
    }
  }
  // after the walk, so that the children of a skinned mesh node keep its transform
  for (size_t i = 0; i < n; ++i)
    if (s.nodes[i].skin >= 0 && s.nodes[i].mesh >= 0) world[i] = glm::mat4(1.0f);
  return world;
}

std::vector<glm::vec3> bakedMaterialColors(const SceneData& s, const MeshData& md) {
  const Mesh& m = md.mesh;
  bool any_material = false;
  for (int32_t mat : md.primitive_materials) any_material |= mat >= 0 && mat < static_cast<int32_t>(s.materials.size());
  if (!any_material && m.colors.empty()) return {};
  std::vector<glm::vec3> factor(m.vertexCount(), glm::vec3(1.0f));
  auto materialColor = [&](uint32_t group) {
    const int32_t mat = group < md.primitive_materials.size() ? md.primitive_materials[group] : -1;
    if (mat < 0 || mat >= static_cast<int32_t>(s.materials.size())) return glm::vec3(1.0f);
    const MaterialData& x = s.materials[static_cast<size_t>(mat)];
    return glm::vec3(x.base_color) * (x.textured ? x.average_texel_color : glm::vec3(1.0f));
  };
  // edges and points in their group's material, unless a triangle uses the vertex
  for (size_t e = 0; e < m.edgeCount(); ++e) factor[m.edges[2 * e]] = factor[m.edges[2 * e + 1]] = materialColor(m.edgeGroup(e));
  for (size_t p = 0; p < m.pointCount(); ++p) factor[m.points[p]] = materialColor(m.pointGroup(p));
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const glm::vec3 c = materialColor(m.triangleGroup(t));
    for (int k = 0; k < 3; ++k) factor[m.triangles[3 * t + static_cast<size_t>(k)]] = c;
  }
  for (size_t v = 0; v < factor.size(); ++v)
    if (!m.colors.empty()) factor[v] *= m.colors[v];
  return factor;
}

void bakeMaterialColors(SceneData& s) {
  for (MeshData& md : s.meshes) md.mesh.colors = bakedMaterialColors(s, md);
}

}  // namespace scenelod::scene
