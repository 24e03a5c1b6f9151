// Skinned meshes in clustering levels. A level vertex stands for a whole cluster, so its joint
// weights are the cluster's: every group of a cluster moves as one in any pose. A cluster that held
// vertices of two unrelated bones (two limbs touching in the bind pose) would stretch between them
// once posed, so such clusters are split by dominant joint before synthesis.
#include "skin_clusters.h"

#include <algorithm>

namespace scenelod::detail {

namespace {

// the joint of the vertex's largest weight (ties: the first slot)
uint16_t dominantJoint(const Mesh& m, size_t v) {
  const glm::vec4& w = m.weights[v];
  int best = 0;
  for (int k = 1; k < 4; ++k)
    if (w[k] > w[best]) best = k;
  return m.joints[v][best];
}

}  // namespace

void clusterMembers(const Assignment& a, std::vector<uint32_t>& offset, std::vector<uint32_t>& members) {
  offset.assign(size_t(a.cluster_count) + 1, 0);
  for (uint32_t c : a.cluster_of)
    if (c != kNone) ++offset[c + 1];
  for (size_t c = 0; c < a.cluster_count; ++c) offset[c + 1] += offset[c];
  members.resize(offset.back());
  std::vector<uint32_t> fill(offset.begin(), offset.end() - 1);
  for (size_t v = 0; v < a.cluster_of.size(); ++v)
    if (a.cluster_of[v] != kNone) members[fill[a.cluster_of[v]]++] = static_cast<uint32_t>(v);
}

void splitSkinClusters(const PreparedMesh& p, Assignment& a) {
  const Mesh& m = *p.mesh;
  if (m.joints.empty()) return;
  std::vector<uint32_t> offset, members;
  clusterMembers(a, offset, members);
  std::vector<uint16_t> dominant(m.vertexCount());
  for (size_t v = 0; v < m.vertexCount(); ++v) dominant[v] = dominantJoint(m, v);
  // heavier: greater weight, ties the lower index (the order of PreparedMesh::order)
  auto heavier = [&](uint32_t u, uint32_t v) { return p.weights[u] != p.weights[v] ? p.weights[u] > p.weights[v] : u < v; };
  const uint32_t old_count = a.cluster_count;
  std::vector<std::pair<uint16_t, uint32_t>> rest;  // (dominant joint, vertex) of the members that leave
  for (uint32_t c = 0; c < old_count; ++c) {
    const uint32_t* begin = members.data() + offset[c];
    const uint32_t* end = members.data() + offset[c + 1];
    const uint16_t centre = dominant[a.heaviest[c]];
    if (std::all_of(begin, end, [&](uint32_t v) { return dominant[v] == centre; })) continue;
    rest.clear();
    for (const uint32_t* v = begin; v != end; ++v)
      if (dominant[*v] != centre) rest.push_back({dominant[*v], *v});
    // the others: one new cluster per dominant joint, its heaviest vertex as its centre
    std::sort(rest.begin(), rest.end());
    for (size_t i = 0; i < rest.size(); ++i) {
      if (i == 0 || rest[i].first != rest[i - 1].first) {
        a.heaviest.push_back(rest[i].second);
        ++a.cluster_count;
      }
      uint32_t& h = a.heaviest.back();
      if (heavier(rest[i].second, h)) h = rest[i].second;
      a.cluster_of[rest[i].second] = a.cluster_count - 1;
    }
  }
}

void clusterSkinWeights(const Mesh& m, const Assignment& a, std::vector<glm::u16vec4>& joints,
                        std::vector<glm::vec4>& weights) {
  joints.assign(a.cluster_count, glm::u16vec4(0));
  weights.assign(a.cluster_count, glm::vec4(0.0f));
  if (m.joints.empty()) return;
  std::vector<uint32_t> offset, members;
  clusterMembers(a, offset, members);
  std::vector<std::pair<uint16_t, float>> sums;  // (joint, summed weight) of one cluster
  for (uint32_t c = 0; c < a.cluster_count; ++c) {
    sums.clear();
    for (uint32_t i = offset[c]; i < offset[c + 1]; ++i) {
      const uint32_t v = members[i];
      for (int k = 0; k < 4; ++k) {
        if (!(m.weights[v][k] > 0.0f)) continue;
        const uint16_t j = m.joints[v][k];
        auto it = std::find_if(sums.begin(), sums.end(), [&](const auto& s) { return s.first == j; });
        if (it == sums.end()) sums.push_back({j, m.weights[v][k]});
        else it->second += m.weights[v][k];
      }
    }
    // the four largest (ties: the lower joint), renormalised to sum 1
    std::sort(sums.begin(), sums.end(), [](const auto& x, const auto& y) {
      return x.second != y.second ? x.second > y.second : x.first < y.first;
    });
    const size_t kept = std::min<size_t>(sums.size(), 4);
    float total = 0.0f;
    for (size_t k = 0; k < kept; ++k) total += sums[k].second;
    for (size_t k = 0; k < kept; ++k) joints[c][int(k)] = sums[k].first, weights[c][int(k)] = sums[k].second / total;
  }
}

}  // namespace scenelod::detail
