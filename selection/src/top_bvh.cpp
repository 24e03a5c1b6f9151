// Top-level BVH over object boxes: median-split build and bottom-up refit (the refit-or-rebuild policy
// of dynamic BVHs, e.g. Wald, Boulos & Shirley 2007 "Ray tracing deformable scenes using dynamic
// bounding volume hierarchies").
#include "top_bvh.h"

#include <algorithm>

#include <glm/common.hpp>

namespace scenelod::selection {
namespace {

float halfArea(const glm::vec3& lo, const glm::vec3& hi) {
  const glm::vec3 e = glm::max(hi - lo, glm::vec3(0.0f));
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

struct Builder {
  TopBvh& bvh;
  const std::vector<glm::vec3>& lo;
  const std::vector<glm::vec3>& hi;

  // builds node `index` over items[first, first + count); children are appended in pairs
  void build(uint32_t index, uint32_t first, uint32_t count) {
    glm::vec3 blo(3.0e38f), bhi(-3.0e38f), clo(3.0e38f), chi(-3.0e38f);
    for (uint32_t k = first; k < first + count; ++k) {
      const uint32_t id = bvh.items[k];
      blo = glm::min(blo, lo[id]);
      bhi = glm::max(bhi, hi[id]);
      const glm::vec3 c = 0.5f * (lo[id] + hi[id]);
      clo = glm::min(clo, c);
      chi = glm::max(chi, c);
    }
    bvh.nodes[index].lo = blo;
    bvh.nodes[index].hi = bhi;
    if (count <= TopBvh::kLeafSize) {
      bvh.nodes[index].first = first;
      bvh.nodes[index].count = count;
      return;
    }
    const glm::vec3 ext = chi - clo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    const uint32_t half = count / 2;
    auto* b = bvh.items.data() + first;
    const auto& l = lo;
    const auto& h = hi;
    // ties broken by id: the same input always gives the same tree
    std::nth_element(b, b + half, b + count, [&](uint32_t p, uint32_t q) {
      const float cp = l[p][axis] + h[p][axis], cq = l[q][axis] + h[q][axis];
      return cp < cq || (cp == cq && p < q);
    });
    const uint32_t left = static_cast<uint32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    bvh.nodes.emplace_back();
    bvh.nodes[index].first = left;
    bvh.nodes[index].count = 0;
    build(left, first, half);
    build(left + 1, first + half, count - half);
  }
};

}  // namespace

void TopBvh::build(const std::vector<uint32_t>& ids, const std::vector<glm::vec3>& lo, const std::vector<glm::vec3>& hi) {
  nodes.clear();
  items = ids;
  pending.clear();
  area = built_area = 0.0f;
  if (ids.empty()) return;
  nodes.reserve(2 * (ids.size() / kLeafSize + 1));
  nodes.emplace_back();
  Builder{*this, lo, hi}.build(0, 0, static_cast<uint32_t>(ids.size()));
  for (const Node& n : nodes)
    if (n.count == 0) built_area += halfArea(n.lo, n.hi);
  area = built_area;
}

void TopBvh::refit(const std::vector<glm::vec3>& lo, const std::vector<glm::vec3>& hi) {
  // children always follow their parent, so a reverse pass sees children first
  area = 0.0f;
  for (size_t i = nodes.size(); i-- > 0;) {
    Node& n = nodes[i];
    glm::vec3 blo(3.0e38f), bhi(-3.0e38f);
    if (n.count > 0) {
      for (uint32_t k = n.first; k < n.first + n.count; ++k) {
        blo = glm::min(blo, lo[items[k]]);
        bhi = glm::max(bhi, hi[items[k]]);
      }
    } else {
      blo = glm::min(nodes[n.first].lo, nodes[n.first + 1].lo);
      bhi = glm::max(nodes[n.first].hi, nodes[n.first + 1].hi);
      area += halfArea(blo, bhi);
    }
    n.lo = blo;
    n.hi = bhi;
  }
}

}  // namespace scenelod::selection
