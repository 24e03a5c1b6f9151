// The output pass of clustering levels for meshes with attributes. Low & Tan 1997 cluster positions
// only (one output vertex per cluster); an engine drawing the level needs its texture coordinates,
// materials and tangents too, which do not average across a UV seam, a material border or a
// mirrored tangent frame. So a cluster keeps its one representative position (no cracks) but emits
// one vertex per attribute group: its members of one UV chart (a chart lies in one triangle group)
// and one tangent sign, with the area-weighted means of that group's attributes.
#include "attribute_level.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "scenelod/lodcore/mesh_attributes.h"
#include "skin_clusters.h"

namespace scenelod::detail {

bool hasAttributes(const Mesh& m) {
  if (!m.uvs.empty() || !m.tangents.empty() || !m.joints.empty()) return true;
  for (const std::vector<glm::vec2>& set : m.extra_uvs)
    if (!set.empty()) return true;
  for (uint32_t g : m.triangle_groups)
    if (g != m.triangle_groups[0]) return true;
  return false;
}

void carryUniformGroup(const Mesh& in, Mesh& out) {
  if (!in.triangle_groups.empty()) out.triangle_groups.assign(out.triangleCount(), in.triangle_groups[0]);
}

void makeAttributeMesh(const Mesh& in, AttributeMesh& out) {
  out.input = &in;
  out.welded = Mesh();
  std::vector<uint32_t> old_to_new;
  out.did_weld = weldedCopy(in, out.welded, &old_to_new) > 0;
  out.input_vertex.clear();
  out.welded_of.clear();
  if (out.did_weld) {
    out.input_vertex.assign(out.welded.vertexCount(), kNone);
    for (size_t i = old_to_new.size(); i-- > 0;) out.input_vertex[old_to_new[i]] = static_cast<uint32_t>(i);
    out.welded_of = std::move(old_to_new);
  }
  const Mesh& m = out.mesh();
  // without texture coordinates there is no seam to keep: a group's pieces share their clusters'
  // vertices, as in the plain path (BrainStem's 515 pieces would otherwise split its clusters)
  const bool any_uvs = !m.uvs.empty() || std::any_of(m.extra_uvs.begin(), m.extra_uvs.end(),
                                                      [](const std::vector<glm::vec2>& set) { return !set.empty(); });
  if (any_uvs) {
    computeUvCharts(m, out.chart);
  } else {
    out.chart.resize(m.triangleCount());
    for (size_t t = 0; t < out.chart.size(); ++t) out.chart[t] = m.triangleGroup(t);
  }
  const size_t tn = m.triangleCount();
  out.corner_weight.resize(tn);
  double total = 0.0;
  for (size_t t = 0; t < tn; ++t) {
    const glm::vec3& a = m.positions[m.triangles[3 * t]];
    const glm::vec3 n = glm::cross(m.positions[m.triangles[3 * t + 1]] - a, m.positions[m.triangles[3 * t + 2]] - a);
    out.corner_weight[t] = glm::length(n) / 6.0f;
    total += out.corner_weight[t];
  }
  const float floor = tn ? float(1e-6 * total / double(tn)) : 0.0f;
  for (float& w : out.corner_weight) w = std::max(w, floor);
}

namespace {

// Where each averaged attribute sits in a group's row of sums (-1: the mesh has none).
struct SumLayout {
  int uv = -1;
  std::vector<int> extra;  // per extra set (-1 for an empty set)
  int color = -1;
  int tangent = -1;        // the tangent's direction (xyz); its sign is part of the group's key
  int width = 0;

  explicit SumLayout(const Mesh& m) {
    auto take = [&](bool present, int n) { return present ? (width += n) - n : -1; };
    uv = take(!m.uvs.empty(), 2);
    for (const std::vector<glm::vec2>& set : m.extra_uvs) extra.push_back(take(!set.empty(), 2));
    color = take(!m.colors.empty(), 3);
    tangent = take(!m.tangents.empty(), 3);
  }
};

template <int N>
void addScaled(float* sum, const float* value, float w) {
  for (int i = 0; i < N; ++i) sum[i] += w * value[i];
}

// One cluster's vertices of one chart and one tangent sign.
struct Group {
  uint32_t cluster;
  uint32_t chart;     // kNone for a group of vertices no triangle uses (edges, points)
  uint32_t next;      // the cluster's next group, kNone at the end
  bool negative;      // tangent sign w < 0
  float weight = 0.0f;          // sum of the members' area shares
  uint32_t source = kNone;      // the member with the largest share
  float source_share = -1.0f;
};

// The attribute groups of one level and their area-weighted sums.
class AttributeGroups {
 public:
  AttributeGroups(const Mesh& m, uint32_t cluster_count)
      : m_(m), layout_(m), head_(cluster_count, kNone) {
    // about one group per cluster, a few more along seams: reserved, so that growth rarely doubles
    const size_t expected = size_t(cluster_count) + size_t(cluster_count) / 8 + 16;
    groups_.reserve(expected);
    sums_.reserve(expected * size_t(layout_.width));
  }

  // the group of `cluster` with this key, or kNone
  uint32_t lookup(uint32_t cluster, uint32_t chart, bool negative) const {
    for (uint32_t g = head_[cluster]; g != kNone; g = groups_[g].next)
      if (groups_[g].chart == chart && groups_[g].negative == negative) return g;
    return kNone;
  }

  // the group of `cluster` with this key, made when new
  uint32_t find(uint32_t cluster, uint32_t chart, bool negative) {
    if (const uint32_t g = lookup(cluster, chart, negative); g != kNone) return g;
    groups_.push_back({cluster, chart, head_[cluster], negative});
    sums_.resize(sums_.size() + size_t(layout_.width), 0.0f);
    return head_[cluster] = static_cast<uint32_t>(groups_.size() - 1);
  }

  // adds vertex v, whose share of group g is w, to its sums; the member of the largest share (ties:
  // the lower index) is the group's source vertex
  void add(uint32_t g, uint32_t v, float w) {
    Group& x = groups_[g];
    x.weight += w;
    if (w > x.source_share || (w == x.source_share && v < x.source)) x.source = v, x.source_share = w;
    float* s = &sums_[size_t(g) * size_t(layout_.width)];
    if (layout_.uv >= 0) addScaled<2>(s + layout_.uv, &m_.uvs[v].x, w);
    for (size_t k = 0; k < layout_.extra.size(); ++k)
      if (layout_.extra[k] >= 0) addScaled<2>(s + layout_.extra[k], &m_.extra_uvs[k][v].x, w);
    if (layout_.color >= 0) addScaled<3>(s + layout_.color, &m_.colors[v].x, w);
    if (layout_.tangent >= 0) addScaled<3>(s + layout_.tangent, &m_.tangents[v].x, w);
  }

  uint32_t head(uint32_t cluster) const { return head_[cluster]; }
  const Group& operator[](uint32_t g) const { return groups_[g]; }
  size_t size() const { return groups_.size(); }

  // the cluster's group of the largest weight (ties: the first made)
  uint32_t largest(uint32_t cluster) const {
    uint32_t best = kNone;
    for (uint32_t g = head_[cluster]; g != kNone; g = groups_[g].next)
      if (best == kNone || groups_[g].weight >= groups_[best].weight) best = g;
    return best;
  }

  // writes group g's means into output vertex i of `out` (arrays sized by the caller); the
  // tangent is made orthonormal to `normal`
  void writeMeans(uint32_t g, size_t i, const glm::vec3& normal, Mesh& out) const {
    const float* s = &sums_[size_t(g) * size_t(layout_.width)];
    const float inv = 1.0f / groups_[g].weight;
    if (layout_.uv >= 0) out.uvs[i] = glm::vec2(s[layout_.uv], s[layout_.uv + 1]) * inv;
    for (size_t k = 0; k < layout_.extra.size(); ++k)
      if (layout_.extra[k] >= 0) out.extra_uvs[k][i] = glm::vec2(s[layout_.extra[k]], s[layout_.extra[k] + 1]) * inv;
    if (layout_.color >= 0) out.colors[i] = glm::vec3(s[layout_.color], s[layout_.color + 1], s[layout_.color + 2]) * inv;
    if (layout_.tangent >= 0) {
      const glm::vec3 t(s[layout_.tangent], s[layout_.tangent + 1], s[layout_.tangent + 2]);
      out.tangents[i] = glm::vec4(orthonormalTangent(t, normal), groups_[g].negative ? -1.0f : 1.0f);
    }
  }

 private:
  // t made orthogonal to the unit normal n and unit length (Gram-Schmidt); where the mean tangent
  // vanishes or is parallel to n, any unit vector orthogonal to n
  static glm::vec3 orthonormalTangent(const glm::vec3& t, const glm::vec3& n) {
    glm::vec3 u = t - n * glm::dot(n, t);
    float l = glm::length(u);
    if (!(l > 1e-6f * std::max(glm::length(t), 1e-30f))) {
      const glm::vec3 axis = std::fabs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
      u = glm::cross(n, axis);
      l = glm::length(u);
    }
    return l > 0.0f ? u / l : glm::vec3(1, 0, 0);
  }

  const Mesh& m_;
  SumLayout layout_;
  std::vector<uint32_t> head_;  // per cluster: its first group
  std::vector<Group> groups_;
  std::vector<float> sums_;     // layout_.width per group
};

// whether vertex v's tangent sign is negative
inline bool negativeSign(const Mesh& m, uint32_t v) { return !m.tangents.empty() && m.tangents[v].w < 0.0f; }

// Every source triangle's corners add a third of its area (AttributeMesh::corner_weight) to the
// group of their own vertex; vertices no triangle uses (edges, points) make a group of their own in a
// cluster that has none. The corners' weights are summed per vertex first and each vertex's
// attributes added once per group it is in (nearly always one), not once per corner.
void gatherGroups(const Mesh& m, const AttributeMesh& am, const uint32_t* cluster_of, AttributeGroups& groups) {
  const size_t tn = m.triangleCount(), vn = m.vertexCount();
  // each vertex's share of its first group; shares of any other group (a vertex where charts or
  // triangle groups meet at a corner only) are listed apart
  std::vector<uint32_t> first_group(vn, kNone), first_chart(vn, kNone);
  std::vector<float> share(vn, 0.0f);
  struct OtherShare {
    uint32_t group, vertex;
    float share;
    bool operator<(const OtherShare& o) const { return group != o.group ? group < o.group : vertex < o.vertex; }
  };
  std::vector<OtherShare> others;
  for (size_t t = 0; t < tn; ++t) {
    const float w = am.corner_weight[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.triangles[3 * t + k], chart = am.chart[t];
      // (the cluster and the sign are the vertex's: the chart alone tells its groups apart)
      if (first_chart[v] == chart) {
        share[v] += w;
        continue;
      }
      const uint32_t g = groups.find(cluster_of[v], chart, negativeSign(m, v));
      if (first_group[v] == kNone) first_group[v] = g, first_chart[v] = chart, share[v] = w;
      else others.push_back({g, v, w});
    }
  }
  for (uint32_t v = 0; v < vn; ++v) {
    const uint32_t c = cluster_of[v];
    if (c == kNone || first_group[v] != kNone) continue;
    // (a cluster's triangle groups were all made above: any group it has by now is of this pass)
    const uint32_t h = groups.head(c);
    if (h != kNone && groups[h].chart != kNone) continue;
    first_group[v] = groups.find(c, kNone, negativeSign(m, v)), share[v] = 1.0f;
  }
  for (uint32_t v = 0; v < vn; ++v)
    if (first_group[v] != kNone) groups.add(first_group[v], v, share[v]);
  std::sort(others.begin(), others.end());
  for (size_t i = 0; i < others.size();) {
    size_t j = i;
    float s = 0.0f;
    for (; j < others.size() && others[j].group == others[i].group && others[j].vertex == others[i].vertex; ++j)
      s += others[j].share;
    groups.add(others[i].group, others[i].vertex, s);
    i = j;
  }
}

// The source triangles that survive: three distinct clusters, and the first in triangle order of
// each (cluster triple, triangle group); the triple is compared rotated to its smallest cluster
// first, so a triangle of the same clusters in the other orientation (the other side of a sheet)
// stays, as in elimination.cpp.
std::vector<uint32_t> survivingTriangles(const Mesh& m, const uint32_t* cluster_of, uint32_t cluster_count) {
  struct Kept {
    uint32_t b, c, group, next;
  };
  std::vector<uint32_t> head(cluster_count, kNone), out;
  std::vector<Kept> kept;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    uint32_t k[3] = {cluster_of[m.triangles[3 * t]], cluster_of[m.triangles[3 * t + 1]],
                     cluster_of[m.triangles[3 * t + 2]]};
    if (k[0] == k[1] || k[1] == k[2] || k[0] == k[2]) continue;
    std::rotate(k, std::min_element(k, k + 3), k + 3);
    const uint32_t group = m.triangleGroup(t);
    bool seen = false;
    for (uint32_t i = head[k[0]]; i != kNone && !seen; i = kept[i].next)
      seen = kept[i].b == k[1] && kept[i].c == k[2] && kept[i].group == group;
    if (seen) continue;
    kept.push_back({k[1], k[2], group, head[k[0]]});
    head[k[0]] = static_cast<uint32_t>(kept.size() - 1);
    out.push_back(static_cast<uint32_t>(t));
  }
  return out;
}

// The output vertices of one level: per cluster, one per (group, crease-split normal) used by a
// surviving triangle's corner, then the vertices edges and points need.
class OutputVertices {
 public:
  OutputVertices(const Mesh& m, const Representatives& r, const uint32_t* cluster_of, const AttributeGroups& groups)
      : m_(m), r_(r), cluster_of_(cluster_of), groups_(groups), edge_vertex_(r.positions.size(), kNone) {
    // about a vertex per group, a few more at creases
    group_.reserve(groups.size() + groups.size() / 8 + 16);
    normal_.reserve(group_.capacity());
  }

  // the triangles `kept` (source triangles) with each corner at the vertex of its group and its
  // crease-aware normal (normals.cpp's rule: the faces of the cluster within the crease angle of
  // the corner's face), written to out.triangles and out.triangle_groups
  void addTriangles(const std::vector<uint32_t>& kept, const std::vector<uint32_t>& chart, float crease_angle_deg,
                    Mesh& out);

  // the vertex edges and points of `cluster` use: one of its largest group, made if there is none
  uint32_t edgeVertex(uint32_t cluster) {
    uint32_t& e = edge_vertex_[cluster];
    if (e != kNone) return e;
    const uint32_t g = groups_.largest(cluster);
    for (uint32_t i = first_[cluster]; i < end_[cluster] && e == kNone; ++i)
      if (group_[i] == g) e = i;
    if (e == kNone) e = addVertex(g, r_.normals[cluster]);
    return e;
  }

  // the vertex arrays: positions, normals, means of every averaged attribute
  void write(Mesh& out) const;

  const std::vector<uint32_t>& groupOfVertex() const { return group_; }

 private:
  uint32_t addVertex(uint32_t g, const glm::vec3& n) {
    group_.push_back(g);
    normal_.push_back(n);
    return static_cast<uint32_t>(group_.size() - 1);
  }

  const Mesh& m_;
  const Representatives& r_;
  const uint32_t* cluster_of_;
  const AttributeGroups& groups_;
  std::vector<uint32_t> group_;      // per output vertex
  std::vector<glm::vec3> normal_;    // per output vertex
  std::vector<uint32_t> first_, end_;  // per cluster: its triangle vertices first_ .. end_ - 1
  std::vector<uint32_t> edge_vertex_;
};

void OutputVertices::addTriangles(const std::vector<uint32_t>& kept, const std::vector<uint32_t>& chart,
                                  float crease_angle_deg, Mesh& out) {
  const size_t nc = r_.positions.size(), kn = kept.size();
  const float cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0f, 180.0f) * 3.14159265358979f / 180.0f);
  // face normals (unit, and twice the area) of the output triangles
  std::vector<glm::vec4> face(kn);
  out.triangles.resize(3 * kn);
  for (size_t i = 0; i < kn; ++i) {
    const uint32_t* s = &m_.triangles[3 * size_t(kept[i])];
    const glm::vec3& a = r_.positions[cluster_of_[s[0]]];
    const glm::vec3 n = glm::cross(r_.positions[cluster_of_[s[1]]] - a, r_.positions[cluster_of_[s[2]]] - a);
    const float l = glm::length(n);
    face[i] = l > 0.0f ? glm::vec4(n / l, l) : glm::vec4(0.0f);
  }
  // each cluster's output corners, in order (a counting sort)
  // (each corner's cluster held in out.triangles until the corner's vertex takes its place)
  std::vector<uint32_t> offset(nc + 1, 0), corners(3 * kn);
  uint32_t* corner_cluster = out.triangles.data();
  for (size_t i = 0; i < kn; ++i)
    for (int k = 0; k < 3; ++k) corner_cluster[3 * i + k] = cluster_of_[m_.triangles[3 * size_t(kept[i]) + k]];
  for (size_t i = 0; i < 3 * kn; ++i) ++offset[corner_cluster[i] + 1];
  for (size_t c = 0; c < nc; ++c) offset[c + 1] += offset[c];
  std::vector<uint32_t> fill(offset.begin(), offset.end() - 1);
  for (size_t i = 0; i < 3 * kn; ++i) corners[fill[corner_cluster[i]]++] = static_cast<uint32_t>(i);
  // normals.cpp's sufficient test for a cluster whose faces all lie within the crease angle of each
  // other: each face within alpha of their normalised sum, 2 alpha the crease angle less a margin
  // for rounding; every corner's sum is then the sum of all its faces, in order (the same bits)
  const double cos_2alpha = double(cos_crease) + 1e-4;
  const float cos_ref = cos_2alpha < 1.0 ? float(std::cos(0.5 * std::acos(std::max(-1.0, cos_2alpha))) + 1e-5) : 2.0f;
  first_.assign(nc, 0), end_.assign(nc, 0);
  for (uint32_t c = 0; c < nc; ++c) {
    first_[c] = static_cast<uint32_t>(group_.size());
    glm::vec3 all(0.0f);
    for (uint32_t j = offset[c]; j < offset[c + 1]; ++j) all += glm::vec3(face[corners[j] / 3]) * face[corners[j] / 3].w;
    const float all_length = glm::length(all);
    bool smooth = all_length >= 1e-18f;
    for (uint32_t j = offset[c]; j < offset[c + 1] && smooth; ++j) {
      const glm::vec4& fj = face[corners[j] / 3];
      smooth = fj.w >= 1e-18f && glm::dot(glm::vec3(fj), all / all_length) >= cos_ref;
    }
    for (uint32_t i = offset[c]; i < offset[c + 1]; ++i) {
      const glm::vec3 ui(face[corners[i] / 3]);
      glm::vec3 sum = all;
      if (!smooth) {
        sum = glm::vec3(0.0f);
        for (uint32_t j = offset[c]; j < offset[c + 1]; ++j) {
          const glm::vec4& fj = face[corners[j] / 3];
          if (j == i || glm::dot(ui, glm::vec3(fj)) >= cos_crease) sum += glm::vec3(fj) * fj.w;
        }
      }
      const float l = glm::length(sum);
      const glm::vec3 n = l > 0.0f ? sum / l : r_.normals[c];
      const uint32_t corner = corners[i];
      const uint32_t t = kept[corner / 3], source = m_.triangles[3 * size_t(t) + corner % 3];
      const uint32_t g = groups_.lookup(c, chart[t], negativeSign(m_, source));
      uint32_t v = first_[c];
      while (v < group_.size() && !(group_[v] == g && normal_[v] == n)) ++v;
      out.triangles[corner] = v < group_.size() ? v : addVertex(g, n);
    }
    end_[c] = static_cast<uint32_t>(group_.size());
  }
  if (!m_.triangle_groups.empty()) {
    out.triangle_groups.resize(kn);
    for (size_t i = 0; i < kn; ++i) out.triangle_groups[i] = m_.triangle_groups[kept[i]];
  }
}

void OutputVertices::write(Mesh& out) const {
  const size_t n = group_.size();
  out.positions.resize(n);
  out.normals = normal_;
  if (!m_.uvs.empty()) out.uvs.resize(n);
  out.extra_uvs.resize(m_.extra_uvs.size());
  for (size_t k = 0; k < m_.extra_uvs.size(); ++k)
    if (!m_.extra_uvs[k].empty()) out.extra_uvs[k].resize(n);
  if (!m_.colors.empty()) out.colors.resize(n);
  if (!m_.tangents.empty()) out.tangents.resize(n);
  for (size_t i = 0; i < n; ++i) {
    out.positions[i] = r_.positions[groups_[group_[i]].cluster];
    groups_.writeMeans(group_[i], i, normal_[i], out);
  }
}

// every output vertex takes its cluster's joint weights; the skeleton is kept
void writeSkin(const Mesh& m, const Assignment& a, const std::vector<uint32_t>& group_of_vertex,
               const AttributeGroups& groups, Mesh& out) {
  std::vector<glm::u16vec4> joints;
  std::vector<glm::vec4> weights;
  clusterSkinWeights(m, a, joints, weights);
  out.joints.resize(group_of_vertex.size());
  out.weights.resize(group_of_vertex.size());
  for (size_t i = 0; i < group_of_vertex.size(); ++i) {
    const uint32_t c = groups[group_of_vertex[i]].cluster;
    out.joints[i] = joints[c];
    out.weights[i] = weights[c];
  }
  out.joint_parents = m.joint_parents;
}

}  // namespace

Error clusterAttributeParts(const PreparedMesh& p, const ClusterParams& params, AttributeLevelParts& parts,
                            ClusterStats* stats) {
  parts = AttributeLevelParts();
  if (stats) *stats = ClusterStats();
  Assignment& a = parts.assignment;
  if (Error e = assign(p, params, a); !e.ok()) return e;
  splitSkinClusters(p, a);
  synthesize(p, a, params.synthesis, parts.representatives);
  eliminate(p, a, params.keep_edges, params.keep_points, true, parts.eliminated);
  std::vector<uint32_t>().swap(parts.eliminated.triangles);  // (the output pass keeps triangles per group)
  if (stats) {
    stats->cluster_count = a.cluster_count;
    stats->collapsed_triangles = parts.eliminated.collapsed_triangles;
    const Mesh& m = *p.mesh;
    float max_d2 = 0.0f;
    for (size_t v = 0; v < a.cluster_of.size(); ++v)
      if (a.cluster_of[v] != kNone) {
        const glm::vec3 d = m.positions[v] - parts.representatives.positions[a.cluster_of[v]];
        max_d2 = std::max(max_d2, glm::dot(d, d));
      }
    stats->max_error = std::sqrt(max_d2);
  }
  return {};
}

// each edge and point in the triangle group (material) of its first vertex's attribute group: a thin
// part collapsed into thick edges keeps the material its triangles had. A group no triangle made
// (vertices only edges and points use) takes the mesh's first triangle group.
void writeEdgeAndPointGroups(const AttributeMesh& am, const AttributeGroups& groups,
                             const std::vector<uint32_t>& group_of_vertex, Mesh& out) {
  if (out.edges.empty() && out.points.empty()) return;
  const Mesh& m = am.mesh();
  std::vector<uint32_t> chart_group;  // (a chart lies in one triangle group)
  for (size_t t = 0; t < am.chart.size(); ++t) {
    if (am.chart[t] >= chart_group.size()) chart_group.resize(size_t(am.chart[t]) + 1, 0);
    chart_group[am.chart[t]] = m.triangleGroup(t);
  }
  auto groupOf = [&](uint32_t v) {
    const uint32_t chart = groups[group_of_vertex[v]].chart;
    return chart == kNone ? m.triangleGroup(0) : chart_group[chart];
  };
  out.edge_groups.resize(out.edgeCount());
  for (size_t e = 0; e < out.edgeCount(); ++e) out.edge_groups[e] = groupOf(out.edges[2 * e]);
  out.point_groups.resize(out.pointCount());
  for (size_t i = 0; i < out.pointCount(); ++i) out.point_groups[i] = groupOf(out.points[i]);
}

void finishAttributeLevel(const AttributeMesh& am, const ClusterParams& params, AttributeLevelParts& parts, Mesh& out,
                          std::vector<uint32_t>* source_vertex, std::vector<uint32_t>* cluster_of_out,
                          std::vector<uint32_t>* vertex_cluster) {
  out = Mesh();
  if (source_vertex) source_vertex->clear();
  const Mesh& m = am.mesh();
  const Assignment& a = parts.assignment;
  Eliminated& el = parts.eliminated;
  const uint32_t* cluster_of = a.cluster_of.data();
  AttributeGroups groups(m, a.cluster_count);
  gatherGroups(m, am, cluster_of, groups);
  OutputVertices vertices(m, parts.representatives, cluster_of, groups);
  vertices.addTriangles(survivingTriangles(m, cluster_of, a.cluster_count), am.chart, params.crease_angle_deg, out);
  out.edges.resize(el.edges.size());
  for (size_t i = 0; i < el.edges.size(); ++i) out.edges[i] = vertices.edgeVertex(el.edges[i]);
  out.edge_thickness = std::move(el.edge_thickness);
  if (out.edge_thickness.size() != out.edges.size() / 2) out.edge_thickness.assign(out.edges.size() / 2, 0.0f);
  out.points.resize(el.points.size());
  for (size_t i = 0; i < el.points.size(); ++i) out.points[i] = vertices.edgeVertex(el.points[i]);
  vertices.write(out);
  if (!m.triangle_groups.empty()) writeEdgeAndPointGroups(am, groups, vertices.groupOfVertex(), out);
  if (m.skinned()) writeSkin(m, a, vertices.groupOfVertex(), groups, out);
  if (source_vertex) {
    const std::vector<uint32_t>& group_of = vertices.groupOfVertex();
    source_vertex->resize(group_of.size());
    for (size_t i = 0; i < group_of.size(); ++i) {
      const uint32_t v = groups[group_of[i]].source;
      (*source_vertex)[i] = am.did_weld ? am.input_vertex[v] : v;
    }
  }
  if (vertex_cluster) {
    const std::vector<uint32_t>& group_of = vertices.groupOfVertex();
    vertex_cluster->resize(group_of.size());
    for (size_t i = 0; i < group_of.size(); ++i) (*vertex_cluster)[i] = groups[group_of[i]].cluster;
  }
  if (cluster_of_out) *cluster_of_out = std::move(parts.assignment.cluster_of);
  parts = AttributeLevelParts();
}

Error clusterAttributeLevel(const PreparedMesh& p, const AttributeMesh& am, const ClusterParams& params, Mesh& out,
                            std::vector<uint32_t>* source_vertex, ClusterStats* stats) {
  out = Mesh();
  if (source_vertex) source_vertex->clear();
  AttributeLevelParts parts;
  if (Error e = clusterAttributeParts(p, params, parts, stats); !e.ok()) return e;
  finishAttributeLevel(am, params, parts, out, source_vertex);
  return {};
}

Error clusterAttributeMesh(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out,
                           std::vector<uint32_t>* source_vertex, ClusterStats* stats) {
  AttributeMesh am;
  makeAttributeMesh(*prepared.mesh, am);
  if (!am.did_weld) return clusterAttributeLevel(prepared, am, params, out, source_vertex, stats);
  ClusterParams grading = params;
  grading.grading = prepared.grading;
  grading.boost_features = prepared.boost_features;
  PreparedMesh welded;
  if (Error e = prepareMesh(am.mesh(), grading, welded); !e.ok()) return e;
  return clusterAttributeLevel(welded, am, params, out, source_vertex, stats);
}

}  // namespace scenelod::detail
