// Vertex welding and UV charts. Both find, for each vertex, the first vertex equal to it in a chosen
// set of attributes (a row of 32-bit words per vertex, made on demand and found again through an
// open-addressing hash table); the charts then join triangles across edges of equal vertices
// (union-find over the triangles around each vertex).
#include "scenelod/lodcore/mesh_attributes.h"

#include <algorithm>
#include <cstring>
#include <numeric>

namespace scenelod {

namespace {

// each vertex's attributes as a row of words; -0.0 written as +0.0 so that equal values compare equal
class VertexRows {
 public:
  VertexRows(const Mesh& m, bool all_attributes) : n_(m.vertexCount()) {
    addFloats(&m.positions[0].x, 3, n_);  // callers pass a mesh with vertices
    if (!m.uvs.empty()) addFloats(&m.uvs[0].x, 2, n_);
    for (const std::vector<glm::vec2>& set : m.extra_uvs)
      if (!set.empty()) addFloats(&set[0].x, 2, n_);
    if (!all_attributes) return;
    if (!m.normals.empty()) addFloats(&m.normals[0].x, 3, n_);
    if (!m.colors.empty()) addFloats(&m.colors[0].x, 3, n_);
    if (!m.tangents.empty()) addFloats(&m.tangents[0].x, 4, n_);
    if (!m.weights.empty()) addFloats(&m.weights[0].x, 4, n_);
    if (!m.joints.empty()) {
      static_assert(sizeof(glm::u16vec4) == 8, "packed joints");
      columns_.push_back({reinterpret_cast<const uint32_t*>(&m.joints[0].x), 2, false});
    }
  }

  size_t width() const {
    size_t w = 0;
    for (const Column& c : columns_) w += c.words;
    return w;
  }

  // the row of vertex i into `row` (width() words)
  void row(size_t i, uint32_t* row) const {
    for (const Column& c : columns_) {
      const uint32_t* src = c.data + i * c.words;
      for (size_t k = 0; k < c.words; ++k) row[k] = c.floats && src[k] == 0x80000000u ? 0u : src[k];
      row += c.words;
    }
  }

 private:
  struct Column {
    const uint32_t* data;
    size_t words;
    bool floats;
  };

  void addFloats(const float* data, size_t words, size_t count) {
    if (count == 0) return;
    static_assert(sizeof(float) == sizeof(uint32_t), "32-bit floats");
    columns_.push_back({reinterpret_cast<const uint32_t*>(data), words, true});
  }

  size_t n_;
  std::vector<Column> columns_;
};

uint64_t hashRow(const uint32_t* row, size_t width) {
  uint64_t h = 0x9e3779b97f4a7c15ull;
  for (size_t k = 0; k < width; ++k) {
    h ^= row[k];
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 32;
  }
  return h;
}

// for each vertex, the index of the first vertex with the same row (rows made again for each
// comparison rather than stored: 4 bytes a vertex for the table, not a row's 48)
std::vector<uint32_t> firstEqualVertex(const Mesh& m, bool all_attributes) {
  const size_t n = m.vertexCount();
  std::vector<uint32_t> first(n);
  if (n == 0) return first;
  const VertexRows rows(m, all_attributes);
  const size_t w = rows.width();
  std::vector<uint32_t> row(w), other(w);
  size_t slots = 1;
  while (slots < 2 * n) slots <<= 1;
  std::vector<uint32_t> table(slots, UINT32_MAX);
  for (size_t i = 0; i < n; ++i) {
    rows.row(i, row.data());
    size_t s = hashRow(row.data(), w) & (slots - 1);
    for (; table[s] != UINT32_MAX; s = (s + 1) & (slots - 1)) {
      rows.row(table[s], other.data());
      if (std::memcmp(other.data(), row.data(), w * sizeof(uint32_t)) == 0) break;
    }
    if (table[s] == UINT32_MAX) table[s] = static_cast<uint32_t>(i);
    first[i] = table[s];
  }
  return first;
}

std::vector<uint32_t> remapped(const std::vector<uint32_t>& idx, const std::vector<uint32_t>& to) {
  std::vector<uint32_t> out(idx.size());
  for (size_t k = 0; k < idx.size(); ++k) out[k] = to[idx[k]];
  return out;
}

// the elements of `v` at `keep` (empty stays empty)
template <class T>
std::vector<T> gathered(const std::vector<T>& v, const std::vector<uint32_t>& keep) {
  std::vector<T> out;
  if (v.empty()) return out;
  out.reserve(keep.size());
  for (uint32_t i : keep) out.push_back(v[i]);
  return out;
}

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

size_t weldedCopy(const Mesh& m, Mesh& out, std::vector<uint32_t>* old_to_new) {
  const size_t n = m.vertexCount();
  const std::vector<uint32_t> first = firstEqualVertex(m, true);
  std::vector<uint32_t> to(n), keep;
  for (size_t i = 0; i < n; ++i) {
    if (first[i] == i) {
      to[i] = static_cast<uint32_t>(keep.size());
      keep.push_back(static_cast<uint32_t>(i));
    } else {
      to[i] = to[first[i]];
    }
  }
  const size_t removed = n - keep.size();
  if (removed > 0) {
    out = Mesh();
    out.positions = gathered(m.positions, keep);
    out.normals = gathered(m.normals, keep);
    out.colors = gathered(m.colors, keep);
    out.uvs = gathered(m.uvs, keep);
    for (const std::vector<glm::vec2>& set : m.extra_uvs) out.extra_uvs.push_back(gathered(set, keep));
    out.tangents = gathered(m.tangents, keep);
    out.joints = gathered(m.joints, keep);
    out.weights = gathered(m.weights, keep);
    out.joint_parents = m.joint_parents;
    out.triangles = remapped(m.triangles, to);
    out.edges = remapped(m.edges, to);
    out.edge_thickness = m.edge_thickness;
    out.points = remapped(m.points, to);
    out.triangle_groups = m.triangle_groups;
    out.face_offsets = m.face_offsets;
    out.face_corners = remapped(m.face_corners, to);
  }
  if (old_to_new) old_to_new->swap(to);
  return removed;
}

size_t weldVertices(Mesh& m, std::vector<uint32_t>* old_to_new) {
  Mesh welded;
  const size_t removed = weldedCopy(m, welded, old_to_new);
  if (removed > 0) m = std::move(welded);
  return removed;
}

uint32_t computeUvCharts(const Mesh& m, std::vector<uint32_t>& triangle_chart) {
  const size_t tn = m.triangleCount();
  triangle_chart.assign(tn, 0);
  if (tn == 0) return 0;
  const std::vector<uint32_t> same = firstEqualVertex(m, false);
  // the triangles around each vertex (by its first equal vertex), a counting sort of the corners
  const size_t n = m.vertexCount();
  std::vector<uint32_t> offset(n + 1, 0), around(3 * tn);
  for (uint32_t v : m.triangles) ++offset[same[v] + 1];
  for (size_t v = 0; v < n; ++v) offset[v + 1] += offset[v];
  for (size_t i = 0; i < 3 * tn; ++i) around[offset[same[m.triangles[i]]]++] = static_cast<uint32_t>(i / 3);
  for (size_t v = n; v > 0; --v) offset[v] = offset[v - 1];
  offset[0] = 0;
  // an edge (a, b) joins triangle t to every earlier triangle u of its group around a that has b
  auto has = [&](uint32_t u, uint32_t v) {
    return same[m.triangles[3 * size_t(u)]] == v || same[m.triangles[3 * size_t(u) + 1]] == v ||
           same[m.triangles[3 * size_t(u) + 2]] == v;
  };
  std::vector<uint32_t> parent(tn);
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t t = 0; t < tn; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = same[m.triangles[3 * size_t(t) + k]], b = same[m.triangles[3 * size_t(t) + (k + 1) % 3]];
      if (a == b) continue;
      for (uint32_t i = offset[a]; i < offset[a + 1] && around[i] < t; ++i) {
        const uint32_t u = around[i];
        if (m.triangleGroup(u) != m.triangleGroup(t) || !has(u, b)) continue;
        const uint32_t r0 = findRoot(parent, t), r1 = findRoot(parent, u);
        parent[std::max(r0, r1)] = std::min(r0, r1);  // the root is the chart's first triangle
      }
    }
  uint32_t charts = 0;
  std::vector<uint32_t> id_of_root(tn, UINT32_MAX);
  for (size_t t = 0; t < tn; ++t) {
    const uint32_t r = findRoot(parent, static_cast<uint32_t>(t));
    if (id_of_root[r] == UINT32_MAX) id_of_root[r] = charts++;
    triangle_chart[t] = id_of_root[r];
  }
  return charts;
}

}  // namespace scenelod
