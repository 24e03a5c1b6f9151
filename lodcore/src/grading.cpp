// Grading of vertices by visual importance, the once-per-mesh sort by weight, and the per-vertex
// face sums every level's synthesis reads.
// Low & Tan 1997 §3.1: weight = cos(theta/2) x longest incident edge, theta the largest angle
// between two incident edges (cos(theta/2) is the probability that the vertex lies on the silhouette
// from a random view direction). Rossignac & Borrel 1993: 1/theta in place of cos(theta/2).
// §4: the sort by weight happens once per mesh for all levels. Lindstrom 2000: a cluster's quadric is
// the sum of its faces' plane quadrics; summing per vertex first (once per mesh) gives the same sum.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_for.h>

#include "cluster_internal.h"

namespace scenelod {

const char* gradingName(Grading g) {
  switch (g) {
    case Grading::kLowTan: return "lowtan";
    case Grading::kRossignac: return "rossignac";
  }
  return "unknown";
}

namespace {

// x / scale rounded to the nearest snorm16 fraction in [-1, 1]; branch-free (the signs are random):
// shifted to be positive, truncation is the floor. A NaN (sums overflowed to infinity) gives -1
// rather than an undefined conversion.
int16_t toSnorm16(float x, float inv_scale) {
  const float c = x * inv_scale;
  const float f = (c > -1.0f ? (c < 1.0f ? c : 1.0f) : -1.0f) * 32767.0f;
  return static_cast<int16_t>(static_cast<int32_t>(f + 32768.5f) - 32768);
}

}  // namespace

void VertexFaceSums::encode(float face_area, const float sums[9]) {
  *this = VertexFaceSums();
  if (!(face_area > 0.0f)) return;
  area = face_area;
  const float inv = 1.0f / face_area;
#if defined(__GNUC__)
  // four at a time, the same arithmetic as toSnorm16
  typedef float Float4 __attribute__((vector_size(16)));
  typedef int32_t Int4 __attribute__((vector_size(16)));
  for (int k = 0; k < 8; k += 4) {
    Float4 c;
    std::memcpy(&c, sums + k, sizeof c);
    c *= inv;
    const Float4 one = {1.0f, 1.0f, 1.0f, 1.0f};
    c = c < one ? c : one;
    c = c > -one ? c : -one;
    const Int4 i = __builtin_convertvector(c * 32767.0f + 32768.5f, Int4) - 32768;
    for (int j = 0; j < 4; ++j) q[k + j] = static_cast<int16_t>(i[j]);
  }
  q[8] = toSnorm16(sums[8], inv);
#else
  for (int k = 0; k < 9; ++k) q[k] = toSnorm16(sums[k], inv);
#endif
}

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kMinTheta = 1e-3f;        // rossignac: 1/theta is capped at 1/kMinTheta
constexpr float kBoundaryFactor = 0.5f;   // boost: a boundary vertex is on the silhouette at least half the time
constexpr size_t kExactPairLimit = 64;    // above this many directions, the widest pair is found by two sweeps
constexpr uint32_t kScanLimit = 64;       // up to this many incidences, distinct neighbours by linear scan

// smallest dot product over pairs of unit vectors (cos of the largest angle between them)
float minPairDot(const glm::vec3* d, size_t n) {
  if (n < 2) return 1.0f;
  float best = 1.0f;
  if (n <= kExactPairLimit) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) best = std::min(best, glm::dot(d[i], d[j]));
    return best;
  }
  // two farthest-point sweeps: exact for the typical fan, within a factor 2 of the angle otherwise
  size_t a = 0;
  for (int sweep = 0; sweep < 2; ++sweep) {
    size_t far = a;
    float far_dot = 2.0f;
    for (size_t i = 0; i < n; ++i) {
      const float dd = glm::dot(d[a], d[i]);
      if (dd < far_dot) far_dot = dd, far = i;
    }
    best = std::min(best, far_dot);
    a = far;
  }
  return best;
}

// sorts the n neighbours (u, triangle count) collected with repeats by u and merges the repeats,
// summing their counts; returns the number of distinct neighbours
size_t mergeNeighbours(uint32_t* nb, uint32_t* tris, size_t n, std::vector<std::pair<uint32_t, uint32_t>>& pairs) {
  pairs.resize(n);
  for (size_t i = 0; i < n; ++i) pairs[i] = {nb[i], tris[i]};
  std::sort(pairs.begin(), pairs.end());
  size_t m = 0;
  for (const auto& p : pairs) {
    if (m > 0 && nb[m - 1] == p.first) {
      tris[m - 1] += p.second;
    } else {
      nb[m] = p.first;
      tris[m] = p.second;
      ++m;
    }
  }
  return m;
}

struct GradeOutput {
  float* raw;                    // per vertex: angular x longest incident edge
  float* angular;                // per vertex, may be null
  float* longest_edge;           // the longest edge of the mesh
  VertexFaceSums* sums;          // per vertex, may be null
  glm::vec4* color_sums;         // per vertex, may be null
  uint8_t* in_rows = nullptr;    // per vertex, may be null: 1 when a triangle or an edge uses it
  Aabb* bounds = nullptr;        // may be null: of the vertices triangles or edges use (min > max if none)
};

struct Incidence {
  uint32_t a, b;  // triangle corner: the next two corners (winding order); edge end: other end, kNone
};

// vertex -> incidence rows: row v is incidence[offsets[v] .. offsets[v + 1]), its triangle corners
// in triangle order, then its input-edge ends in edge order
struct IncidenceTable {
  std::vector<uint32_t> offsets;
  std::vector<Incidence> incidence;
};

// One counting sort builds the rows, each holding the two other corners of the triangle in winding
// order (or the other end of an input edge). Serial (scattered writes); prepareMesh runs it next to
// the surface sums.
void buildIncidence(const Mesh& mesh, IncidenceTable& table) {
  const size_t vn = mesh.vertexCount(), tn = mesh.triangleCount();
  std::vector<uint32_t>& offsets = table.offsets;
  offsets.assign(vn + 1, 0);
  for (uint32_t v : mesh.triangles) ++offsets[v + 1];
  for (uint32_t v : mesh.edges) ++offsets[v + 1];
  for (size_t v = 0; v < vn; ++v) offsets[v + 1] += offsets[v];
  std::vector<Incidence>& incidence = table.incidence;
  incidence.resize(offsets[vn]);
  // fill row v through offsets[v + 1] (first shifted to the start of row v): afterwards it holds
  // the end of row v again, so no separate cursor array is needed
  uint32_t* fill = offsets.data() + 1;
  for (size_t v = vn; v > 0; --v) offsets[v] = offsets[v - 1];  // fill[v] = start of row v
  const uint32_t* tri = mesh.triangles.data();
  for (size_t t = 0; t < tn; ++t) {
    const uint32_t i0 = tri[3 * t], i1 = tri[3 * t + 1], i2 = tri[3 * t + 2];
    incidence[fill[i0]++] = {i1, i2};
    incidence[fill[i1]++] = {i2, i0};
    incidence[fill[i2]++] = {i0, i1};
  }
  for (size_t e = 0; e < mesh.edgeCount(); ++e) {
    const uint32_t x = mesh.edges[2 * e], y = mesh.edges[2 * e + 1];
    incidence[fill[x]++] = {y, detail::kNone};
    incidence[fill[y]++] = {x, detail::kNone};
  }
  offsets[0] = 0;
}

// Grades every vertex and, when asked, sums its incident faces. The per-vertex pass reads its rows
// of `table` contiguously, recomputes the face normal from the corner positions it reads anyway,
// and writes only its own vertex: no scattered writes, parallel over vertices.
void gradeAndSum(const Mesh& mesh, const IncidenceTable& table, Grading grading, bool boost_features,
                 GradeOutput out) {
  const size_t vn = mesh.vertexCount();
  const uint32_t* offsets = table.offsets.data();
  const Incidence* incidence = table.incidence.data();
  const glm::vec3* pos = mesh.positions.data();
  const bool colors = out.color_sums && !mesh.colors.empty();

  std::mutex longest_mutex;
  float longest_edge = 0.0f;
  glm::vec3 box_lo(std::numeric_limits<float>::max()), box_hi(-std::numeric_limits<float>::max());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, vn, 1024), [&](const tbb::blocked_range<size_t>& range) {
    // per-vertex scratch, grown to the longest row seen: plain arrays written by index, no push_back
    std::vector<glm::vec3> dirs, normals;
    std::vector<uint32_t> nb, nb_tris;  // distinct neighbours, and how many incident triangles hold each
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    float range_longest = 0.0f;
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (size_t v = range.begin(); v != range.end(); ++v) {
      const uint32_t b = offsets[v], e = offsets[v + 1];
      if (out.in_rows) out.in_rows[v] = b != e;
      if (b == e) {
        out.raw[v] = 0.0f;
        if (out.angular) out.angular[v] = 0.0f;
        if (out.sums) out.sums[v] = VertexFaceSums();
        if (colors) out.color_sums[v] = glm::vec4(0.0f);
        continue;
      }
      const size_t row = e - b;
      if (nb.size() < 2 * row) {
        nb.resize(2 * row);
        nb_tris.resize(2 * row);
        dirs.resize(2 * row);
        normals.resize(row);
      }
      uint32_t* nbp = nb.data();
      uint32_t* trip = nb_tris.data();
      size_t nn = 0, nnormals = 0;
      // distinct neighbours by a linear scan without early exit (rows are short; cheaper than sorting);
      // `tri` is 1 for a triangle's corner, 0 for an input edge's end. Long rows collect repeats and
      // sort them (mergeNeighbours), O(d log d).
      const bool scan = row <= kScanLimit;
      auto addNeighbour = [&](uint32_t u, uint32_t tri) {
        uint32_t found = 0;
        if (scan)
          for (size_t j = 0; j < nn; ++j) {
            const uint32_t same = nbp[j] == u;
            trip[j] += same & tri;
            found |= same;
          }
        nbp[nn] = u;
        trip[nn] = tri;
        nn += !found;
      };
      float qs[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, area_sum = 0.0f;  // quadric xx..zz, normal x, y, z
      glm::vec4 cs(0.0f);
      const glm::vec3 pv = pos[v];
      lo = glm::min(lo, pv);
      hi = glm::max(hi, pv);
      for (uint32_t i = b; i < e; ++i) {
        const Incidence inc = incidence[i];
        if (inc.b == detail::kNone) {
          addNeighbour(inc.a, 0);
          continue;
        }
        addNeighbour(inc.a, 1);
        addNeighbour(inc.b, 1);
        const glm::vec3 cr = glm::cross(pos[inc.a] - pv, pos[inc.b] - pv);
        const float nl = glm::length(cr);
        if (!(nl > 0.0f)) continue;
        const glm::vec3 n = cr / nl;
        normals[nnormals++] = n;
        const float area = 0.5f * nl;
        qs[0] += area * n.x * n.x; qs[1] += area * n.x * n.y; qs[2] += area * n.x * n.z;
        qs[3] += area * n.y * n.y; qs[4] += area * n.y * n.z; qs[5] += area * n.z * n.z;
        qs[6] += area * n.x; qs[7] += area * n.y; qs[8] += area * n.z;
        area_sum += area;
        if (colors) {
          const glm::vec3 fc = (mesh.colors[v] + mesh.colors[inc.a] + mesh.colors[inc.b]) * (1.0f / 3.0f);
          cs += glm::vec4(fc * area, area);
        }
      }
      if (out.sums) out.sums[v].encode(area_sum, qs);
      if (colors) out.color_sums[v] = cs;
      if (!scan) nn = mergeNeighbours(nbp, trip, nn, pairs);
      // boundary: some neighbour is shared by only one incident triangle
      bool boundary = false;
      for (size_t j = 0; j < nn; ++j) boundary |= trip[j] == 1;
      // the widest pair and the longest edge do not depend on the neighbours' order, except for the
      // estimate of minPairDot on long lists, whose neighbours mergeNeighbours left in index order
      size_t ndirs = 0;
      float longest_v = 0.0f;
      for (size_t j = 0; j < nn; ++j) {
        const glm::vec3 d = pos[nbp[j]] - pv;
        const float len = glm::length(d);
        if (len > 0.0f) {
          dirs[ndirs++] = d / len;
          longest_v = std::max(longest_v, len);
        }
      }
      range_longest = std::max(range_longest, longest_v);
      float a = 0.0f;
      if (ndirs > 0) {  // else only zero-length edges: no direction, weight 0
        const float cos_theta = std::clamp(minPairDot(dirs.data(), ndirs), -1.0f, 1.0f);
        if (grading == Grading::kLowTan) {
          a = std::sqrt(std::max(0.0f, (1.0f + cos_theta) * 0.5f));  // cos(theta/2)
          if (boost_features) {
            if (boundary) a = std::max(a, kBoundaryFactor);
            const float crease = (1.0f - std::clamp(minPairDot(normals.data(), nnormals), -1.0f, 1.0f)) * 0.5f;
            a = std::max(a, crease);
          }
        } else {
          a = kPi / std::max(std::acos(cos_theta), kMinTheta);
        }
      }
      if (out.angular) out.angular[v] = a;
      out.raw[v] = longest_v * a;
    }
    // maxima and minima: the same whatever the split between threads
    std::lock_guard<std::mutex> lock(longest_mutex);
    longest_edge = std::max(longest_edge, range_longest);
    box_lo = glm::min(box_lo, lo);
    box_hi = glm::max(box_hi, hi);
  });
  *out.longest_edge = longest_edge;
  if (out.bounds) out.bounds->min = box_lo, out.bounds->max = box_hi;
}

// Stable LSD radix sort of the referenced vertices by descending raw weight (weights are >= 0
// floats, whose bit patterns sort like the values); stability keeps ties in vertex-index order.
void sortByWeight(const std::vector<float>& raw, const std::vector<uint8_t>& referenced, size_t count,
                  std::vector<uint32_t>& order) {
  std::vector<uint32_t> keys(count), keys2(count), idx2(count);
  order.resize(count);
  size_t n = 0;
  for (size_t v = 0; v < raw.size(); ++v) {
    if (!referenced[v]) continue;
    uint32_t bits;
    std::memcpy(&bits, &raw[v], sizeof bits);
    keys[n] = ~bits;
    order[n] = static_cast<uint32_t>(v);
    ++n;
  }
  constexpr int kBits = 11, kBuckets = 1 << kBits;
  std::vector<uint32_t> hist(3 * kBuckets, 0);
  for (uint32_t k : keys)
    for (int pass = 0; pass < 3; ++pass) ++hist[pass * kBuckets + ((k >> (pass * kBits)) & (kBuckets - 1))];
  for (int pass = 0; pass < 3; ++pass) {
    uint32_t* h = hist.data() + pass * kBuckets;
    if (h[(keys.empty() ? 0 : (keys[0] >> (pass * kBits))) & (kBuckets - 1)] == count) continue;  // one bucket: skip
    uint32_t sum = 0;
    for (int b = 0; b < kBuckets; ++b) {
      const uint32_t c = h[b];
      h[b] = sum;
      sum += c;
    }
    for (size_t i = 0; i < count; ++i) {
      const uint32_t slot = h[(keys[i] >> (pass * kBits)) & (kBuckets - 1)]++;
      keys2[slot] = keys[i];
      idx2[slot] = order[i];
    }
    keys.swap(keys2);
    order.swap(idx2);
  }
}

// Surface area and summed length of the triangles' edges, in double per fixed chunk of triangles
// and then over the chunks in order: the same sums whatever the number of threads.
void surfaceSums(const Mesh& in, double& area_out, double& length_out) {
  const glm::vec3* pos = in.positions.data();
  const size_t tn = in.triangleCount();
  constexpr size_t kChunk = 4096;
  const size_t chunks = (tn + kChunk - 1) / kChunk;
  std::vector<double> chunk_length(chunks), chunk_area(chunks);
  const uint32_t* tri = in.triangles.data();
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    double sum = 0.0, area = 0.0;
    for (size_t t = c * kChunk, end = std::min(tn, t + kChunk); t < end; ++t) {
      const glm::vec3 a = pos[tri[3 * t]], b = pos[tri[3 * t + 1]], cc = pos[tri[3 * t + 2]];
      sum += double(glm::length(b - a)) + double(glm::length(cc - b)) + double(glm::length(a - cc));
      area += 0.5 * double(glm::length(glm::cross(b - a, cc - a)));
    }
    chunk_length[c] = sum;
    chunk_area[c] = area;
  });
  double sum = 0.0, area = 0.0;
  for (size_t c = 0; c < chunks; ++c) sum += chunk_length[c], area += chunk_area[c];
  area_out = area;
  length_out = sum;
}

}  // namespace

void gradeVertices(const Mesh& mesh, Grading grading, bool boost_features, std::vector<float>& weights,
                   std::vector<float>* angular_out, float* longest_edge_out, std::vector<float>* raw_out) {
  const size_t vn = mesh.vertexCount();
  weights.assign(vn, 0.0f);
  if (angular_out) angular_out->assign(vn, 0.0f);
  if (vn == 0) {
    if (longest_edge_out) *longest_edge_out = 0.0f;
    return;
  }
  std::vector<float> raw(vn), angular(vn);
  float longest_edge = 0.0f;
  IncidenceTable table;
  buildIncidence(mesh, table);
  gradeAndSum(mesh, table, grading, boost_features, {raw.data(), angular.data(), &longest_edge, nullptr, nullptr});
  const float inv = longest_edge > 0.0f ? 1.0f / longest_edge : 0.0f;
  // weights = raw * inv: rounding is monotone, so the normalised weights keep the raw order
  for (size_t v = 0; v < vn; ++v) weights[v] = raw[v] * inv;
  if (raw_out) raw_out->swap(raw);
  if (angular_out) angular_out->swap(angular);
  if (longest_edge_out) *longest_edge_out = longest_edge;
}

Error prepareMesh(const Mesh& in, const ClusterParams& params, PreparedMesh& out, const std::string& what) {
  if (Error e = validateMesh(in, what)) return e;
  out = PreparedMesh();
  out.mesh = &in;
  out.grading = params.grading;
  out.boost_features = params.boost_features;
  const size_t vn = in.vertexCount();
  out.weights.assign(vn, 0.0f);
  if (vn == 0) return {};
  // the sort uses the unnormalised product: normalising a factor by a constant cannot change the
  // order, and this way the order does not depend on other parts of the mesh (whose longest edge
  // would be the normaliser) even by rounding
  std::vector<float> raw(vn);
  out.face_sums.resize(vn);
  if (!in.colors.empty()) out.face_colors.resize(vn);
  float longest_edge = 0.0f;
  std::vector<uint8_t> referenced(vn);
  Aabb rows_box;
  // the surface sums need only the mesh: they run next to the serial counting sort
  IncidenceTable table;
  double area = 0.0, sum = 0.0;
  tbb::parallel_invoke([&] { buildIncidence(in, table); }, [&] { surfaceSums(in, area, sum); });
  gradeAndSum(in, table, params.grading, params.boost_features,
              {raw.data(), nullptr, &longest_edge, out.face_sums.data(),
               in.colors.empty() ? nullptr : out.face_colors.data(), referenced.data(), &rows_box});
  table = IncidenceTable();  // 8 bytes per corner, not needed any more
  out.longest_edge = longest_edge;
  const float inv = longest_edge > 0.0f ? 1.0f / longest_edge : 0.0f;
  for (size_t v = 0; v < vn; ++v) out.weights[v] = raw[v] * inv;

  // referenced: used by a triangle or an edge (the grading rows) or by a point
  glm::vec3 lo = rows_box.min, hi = rows_box.max;
  for (uint32_t v : in.points) {
    referenced[v] = 1;
    lo = glm::min(lo, in.positions[v]);
    hi = glm::max(hi, in.positions[v]);
  }
  size_t count = 0;
  for (size_t v = 0; v < vn; ++v) count += referenced[v];
  if (count > 0) out.bounds.min = lo, out.bounds.max = hi;
  sortByWeight(raw, referenced, count, out.order);
  out.sorted_positions.resize(count);
  const glm::vec3* pos = in.positions.data();
  const uint32_t* order = out.order.data();
  glm::vec3* sorted = out.sorted_positions.data();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) sorted[i] = pos[order[i]];
  });

  out.surface_area = area;
  for (size_t e = 0; e < in.edgeCount(); ++e)
    sum += glm::length(in.positions[in.edges[2 * e]] - in.positions[in.edges[2 * e + 1]]);
  const size_t count_e = 3 * in.triangleCount() + in.edgeCount();
  out.mean_edge_length = count_e ? static_cast<float>(sum / double(count_e)) : 0.0f;
  return {};
}

}  // namespace scenelod
