#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

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
    const std::string name = what + " mesh " + std::to_string(m) + (s.meshes[m].name.empty() ? "" : " '" + s.meshes[m].name + "'");
    if (Error e = validateMesh(s.meshes[m].mesh, name); !e.ok()) return e;
    for (int32_t mat : s.meshes[m].primitive_materials)
      if (mat < -1 || mat >= static_cast<int32_t>(s.materials.size()))
        return {Status::kInvalidArgument, name + ": material " + std::to_string(mat) + " out of range"};
  }
  return {};
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
  return world;
}

}  // namespace scenelod::scene
