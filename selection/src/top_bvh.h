#pragma once
// The top level of the ray scene: a BVH over the objects' world boxes, refitted when objects move and
// rebuilt only when objects were added or removed in numbers, or refits made it loose. Leaves name
// objects; each object is ray-traced in its own space against a per-mesh Embree scene. Private to the
// selection module (see docs/VISIBILITY.md for why this replaces Embree's own instance level).
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace scenelod::selection {

struct TopBvh {
  struct Node {
    glm::vec3 lo{0.0f};
    uint32_t first = 0;   // leaf: first entry in items; inner: index of the left child (right = +1)
    glm::vec3 hi{0.0f};
    uint32_t count = 0;   // leaf: number of items (> 0); inner: 0
  };
  static constexpr uint32_t kLeafSize = 4;
  static constexpr int kStackSize = 64;

  std::vector<Node> nodes;          // nodes[0] is the root when not empty
  std::vector<uint32_t> items;      // object ids, grouped by leaf
  std::vector<uint32_t> pending;    // live objects added since the last build, tested one by one
  float built_area = 0.0f;          // summed inner-node surface area right after the build
  float area = 0.0f;                // the same after the latest refit

  // Builds over `ids` (object boxes in lo/hi, indexed by id) by median splits on the longest axis of
  // the centroid bounds. O(n log n), allocates.
  void build(const std::vector<uint32_t>& ids, const std::vector<glm::vec3>& lo, const std::vector<glm::vec3>& hi);
  // Recomputes every node box bottom-up from the object boxes (dead objects have empty boxes). O(n).
  void refit(const std::vector<glm::vec3>& lo, const std::vector<glm::vec3>& hi);
};

// Slab test of a ray against a box: true when [t0, t1] overlaps [t_near, t_far]; writes the overlap.
inline bool rayBox(const glm::vec3& org, const glm::vec3& inv_dir, const glm::vec3& lo, const glm::vec3& hi,
                   float t_near, float t_far, float& t_enter, float& t_exit) {
  float t0 = t_near, t1 = t_far;
  for (int a = 0; a < 3; ++a) {
    float ta = (lo[a] - org[a]) * inv_dir[a];
    float tb = (hi[a] - org[a]) * inv_dir[a];
    if (ta > tb) {
      const float s = ta;
      ta = tb;
      tb = s;
    }
    // NaN (0 * inf when the ray lies in a slab plane) leaves the bounds unchanged
    t0 = ta > t0 ? ta : t0;
    t1 = tb < t1 ? tb : t1;
  }
  t_enter = t0;
  t_exit = t1;
  return t0 <= t1;
}

// Visits the objects whose boxes the ray crosses within [t_near, t_far]. `visit(id, t_enter, t_exit,
// t_far)` may lower t_far (closest-hit search) and returns true to stop the traversal (any-hit).
// Children are visited nearer first. Pending objects are visited after the tree.
template <class Visit>
void traverse(const TopBvh& bvh, const std::vector<glm::vec3>& lo, const std::vector<glm::vec3>& hi,
              const glm::vec3& org, const glm::vec3& dir, float t_near, float& t_far, Visit&& visit) {
  const glm::vec3 inv(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
  float te, tx;
  if (!bvh.nodes.empty() && rayBox(org, inv, bvh.nodes[0].lo, bvh.nodes[0].hi, t_near, t_far, te, tx)) {
    // entries carry the node's entry distance, so a popped node is only re-checked against t_far
    struct Entry {
      uint32_t node;
      float t_enter;
    };
    Entry stack[TopBvh::kStackSize];
    int top = 0;
    stack[top++] = {0, te};
    while (top > 0) {
      const Entry e = stack[--top];
      if (e.t_enter > t_far) continue;
      const TopBvh::Node& n = bvh.nodes[e.node];
      if (n.count > 0) {
        for (uint32_t k = n.first; k < n.first + n.count; ++k) {
          const uint32_t id = bvh.items[k];
          if (!rayBox(org, inv, lo[id], hi[id], t_near, t_far, te, tx)) continue;
          if (visit(id, te, tx, t_far)) return;
        }
        continue;
      }
      // push the farther child first so the nearer one is popped next
      const TopBvh::Node& l = bvh.nodes[n.first];
      const TopBvh::Node& r = bvh.nodes[n.first + 1];
      float le, lx, re, rx;
      const bool hit_l = rayBox(org, inv, l.lo, l.hi, t_near, t_far, le, lx);
      const bool hit_r = rayBox(org, inv, r.lo, r.hi, t_near, t_far, re, rx);
      if (hit_l && hit_r) {
        if (top + 2 > TopBvh::kStackSize) continue;  // cannot happen: the median split keeps depth ~log2(n)
        if (le <= re) {
          stack[top++] = {n.first + 1, re};
          stack[top++] = {n.first, le};
        } else {
          stack[top++] = {n.first, le};
          stack[top++] = {n.first + 1, re};
        }
      } else if (hit_l) {
        stack[top++] = {n.first, le};
      } else if (hit_r) {
        stack[top++] = {n.first + 1, re};
      }
    }
  }
  for (uint32_t id : bvh.pending) {
    if (!rayBox(org, inv, lo[id], hi[id], t_near, t_far, te, tx)) continue;
    if (visit(id, te, tx, t_far)) return;
  }
}

}  // namespace scenelod::selection
