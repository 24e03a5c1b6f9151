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
#include <memory>
#include <mutex>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "cluster_internal.h"
#include "grading_internal.h"

namespace scenelod {

using namespace grading;

namespace detail {
// lodcore/src/mesh.cpp: validateMesh's parts, for prepareMesh
bool coordinatesFinite(const Mesh& m);
bool indicesBelow(const uint32_t* idx, size_t count, size_t vertex_count);
Error validateMeshScanned(const Mesh& m, const std::string& what, bool coordinates_finite, bool indices_in_range);
}  // namespace detail

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

// vertex -> incidence rows: row v is incidence[offsets[v] .. offsets[v + 1]), its triangle corners
// in triangle order, then its input-edge ends in edge order; kRowPad more entries follow the last
// row, so that the lane path can read a row in whole blocks of 4
constexpr size_t kRowPad = 4;
struct IncidenceTable {
  std::vector<uint32_t> offsets;
  std::unique_ptr<Incidence[]> incidence;  // offsets[vn] + kRowPad entries
};

// One counting sort builds the rows, each holding the two other corners of the triangle in winding
// order (or the other end of an input edge). The table is not zeroed: every entry is written.
// In two steps, so that prepareMesh can run other work next to each: the count per vertex (split in
// two, each half of the triangles counted into its own array), then the offsets and the rows. The
// fill is serial (two halves of the triangles filled side by side share the rows' cache lines and
// took as long as one, bunny: 0.25 ms, 0.26 on two threads); prepareMesh runs the surface sums next
// to it. The indices must be below the vertex count.

// the corners of triangles [t0, t1) (and, with `edges`, the input edges' ends) counted per vertex
void countCorners(const Mesh& mesh, size_t t0, size_t t1, bool edges, uint32_t* count) {
  const uint32_t* tri = mesh.triangles.data();
  for (size_t k = 3 * t0; k < 3 * t1; ++k) ++count[tri[k]];
  if (edges)
    for (uint32_t v : mesh.edges) ++count[v];
}

// the rows, from the counts in table.offsets[v + 1] plus (when not null) more[v]; `more` is freed
// before the rows are allocated, so that it adds nothing to the prepare's peak
void fillIncidence(const Mesh& mesh, IncidenceTable& table, std::unique_ptr<uint32_t[]> more) {
  const size_t vn = mesh.vertexCount(), tn = mesh.triangleCount();
  std::vector<uint32_t>& offsets = table.offsets;
  if (more)
    for (size_t v = 0; v < vn; ++v) offsets[v + 1] += offsets[v] + more[v];
  else
    for (size_t v = 0; v < vn; ++v) offsets[v + 1] += offsets[v];
  more.reset();
  const size_t n = offsets[vn];
  table.incidence.reset(new Incidence[n + kRowPad]);
  Incidence* incidence = table.incidence.get();
  for (size_t i = 0; i < kRowPad; ++i) incidence[n + i] = {0, 0};
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


// per-row scratch of the scalar pass, grown to the longest row seen: plain arrays written by index,
// no push_back
struct RowScratch {
  std::vector<glm::vec3> dirs, normals;
  std::vector<uint32_t> nb, nb_tris;  // distinct neighbours, and how many incident triangles hold each
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
};
// what the grade of one row needs: its longest edge, whether some edge has a direction, the widest
// pair of directions, the boundary flag, and the count of face normals in the scratch
struct ScalarRow {
  float longest;
  bool any_dir;
  float cos_dirs;
  bool boundary;
  size_t normals;
};

// The scalar pass over vertex v's row incidence[b .. e) (rows the lanes do not take: longer than
// kLaneRow, with input edges or on coloured meshes; every row without SSE2): its face sums (and
// colour sums) into out, and the inputs of its grade
ScalarRow gradeRowScalar(const Mesh& mesh, const Incidence* incidence, uint32_t b, uint32_t e, size_t v, bool colors,
                         const GradeOutput& out, RowScratch& s) {
  const glm::vec3* pos = mesh.positions.data();
  const glm::vec3 pv = pos[v];
  const size_t row = e - b;
  if (s.nb.size() < 2 * row) {
    s.nb.resize(2 * row);
    s.nb_tris.resize(2 * row);
    s.dirs.resize(2 * row);
    s.normals.resize(row);
  }
  uint32_t* nbp = s.nb.data();
  uint32_t* trip = s.nb_tris.data();
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
    s.normals[nnormals++] = n;
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
  if (!scan) nn = mergeNeighbours(nbp, trip, nn, s.pairs);
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
      s.dirs[ndirs++] = d / len;
      longest_v = std::max(longest_v, len);
    }
  }
  return {longest_v, ndirs > 0, ndirs > 0 ? minPairDot(s.dirs.data(), ndirs) : 1.0f, boundary, nnormals};
}

// Grades every vertex and, when asked, sums its incident faces. The per-vertex pass reads its rows
// of `table` contiguously, recomputes the face normal from the corner positions it reads anyway,
// and writes only its own vertex: no scattered writes, parallel over vertices.
void gradeAndSum(const Mesh& mesh, const IncidenceTable& table, Grading grading, bool boost_features,
                 GradeOutput out) {
  const size_t vn = mesh.vertexCount();
  const uint32_t* offsets = table.offsets.data();
  const Incidence* incidence = table.incidence.get();
  const glm::vec3* pos = mesh.positions.data();
  const bool colors = out.color_sums && !mesh.colors.empty();

  [[maybe_unused]] const bool want_normals = grading == Grading::kLowTan && boost_features;  // the crease term
  // the angular factor and the weight of vertex v from its longest edge, whether some edge has a
  // direction, the widest pair of directions, the boundary flag and (called only when needed) the
  // widest pair of face normals
  auto finish = [&](size_t v, float longest_v, bool any_dir, float cos_dirs, bool boundary, auto cos_normals) {
    float a = 0.0f;
    if (any_dir) {  // else only zero-length edges: no direction, weight 0
      const float cos_theta = std::clamp(cos_dirs, -1.0f, 1.0f);
      if (grading == Grading::kLowTan) {
        a = std::sqrt(std::max(0.0f, (1.0f + cos_theta) * 0.5f));  // cos(theta/2)
        if (boost_features) {
          if (boundary) a = std::max(a, kBoundaryFactor);
          const float crease = (1.0f - std::clamp(cos_normals(), -1.0f, 1.0f)) * 0.5f;
          a = std::max(a, crease);
        }
      } else {
        a = kPi / std::max(std::acos(cos_theta), kMinTheta);
      }
    }
    if (out.angular) out.angular[v] = a;
    out.raw[v] = longest_v * a;
  };
  std::mutex longest_mutex;
  float longest_edge = 0.0f;
  glm::vec3 box_lo(std::numeric_limits<float>::max()), box_hi(-std::numeric_limits<float>::max());
#if defined(__SSE2__)
  const bool avx2 = detail::avx2Paths() && vn < (size_t(1) << 31) / 3;
#endif
  tbb::parallel_for(tbb::blocked_range<size_t>(0, vn, 1024), [&](const tbb::blocked_range<size_t>& range) {
    RowScratch scratch;
    float range_longest = 0.0f;
#if defined(__SSE2__)
    // the box of the rows' vertices in lanes 0..2: minps(p, lo) and maxps(p, hi) are glm::min(lo, p)
    // and glm::max(hi, p) exactly (p < lo ? p : lo; hi < p ? p : hi)
    __m128 lo = _mm_set1_ps(std::numeric_limits<float>::max()), hi = _mm_set1_ps(-std::numeric_limits<float>::max());
    auto addToBox = [&](const glm::vec3& p) {
      // (movq through _mm_loadl_epi64, whose pointer type is unaligned: _mm_load_sd would dereference
      // a double* at a float's alignment, undefined behaviour UBSan reports)
      const __m128 xy = _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&p.x)));
      const __m128 q = _mm_movelh_ps(xy, _mm_load_ss(&p.z));  // x y z 0, no read past the point
      lo = _mm_min_ps(q, lo);
      hi = _mm_max_ps(q, hi);
    };
    LaneScratch lanes, two_lanes[2];
    LaneRow lr, two_lr[2];
    auto laneDone = [&](size_t v, const LaneRow& l, bool encoded) {
      if (out.sums && !encoded) out.sums[v].encode(l.sums[9], l.sums);
      range_longest = std::max(range_longest, l.longest);
      finish(v, l.longest, l.any_dir, l.cos_dirs, l.boundary, [&] { return l.cos_normals; });
    };
    // finish for a pair's rows v, v + 1 under kLowTan, in two lanes: the same operations (std::clamp
    // as maxps then minps, std::max(x, y) as maxps(y, x): equal for these non-NaN values); with the
    // box in lanes, the bunny's pass outside gradeTwoRowsAvx2 took 263 -> 208 instructions a pair.
    // Rossignac's acos stays scalar.
    auto pairDone = [&](size_t v, const LaneRow (&l)[2]) {
      if (grading != Grading::kLowTan) {
        laneDone(v, l[0], true);
        laneDone(v + 1, l[1], true);
        return;
      }
      const __m128 one = _mm_set1_ps(1.0f), minus_one = _mm_set1_ps(-1.0f), half = _mm_set1_ps(0.5f);
      auto clampUnit = [&](__m128 c) { return _mm_min_ps(_mm_max_ps(c, minus_one), one); };
      auto laneMask = [](bool x0, bool x1) { return _mm_castsi128_ps(_mm_setr_epi32(-int(x0), -int(x1), 0, 0)); };
      const __m128 cos_dirs = _mm_setr_ps(l[0].cos_dirs, l[1].cos_dirs, 0.0f, 0.0f);
      __m128 a = _mm_sqrt_ps(_mm_max_ps(_mm_mul_ps(_mm_add_ps(one, clampUnit(cos_dirs)), half), _mm_setzero_ps()));
      if (boost_features) {
        const __m128 boundary = laneMask(l[0].boundary, l[1].boundary);
        a = _mm_or_ps(_mm_and_ps(boundary, _mm_max_ps(a, half)), _mm_andnot_ps(boundary, a));
        const __m128 cos_normals = _mm_setr_ps(l[0].cos_normals, l[1].cos_normals, 0.0f, 0.0f);
        a = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(one, clampUnit(cos_normals)), half), a);
      }
      a = _mm_and_ps(laneMask(l[0].any_dir, l[1].any_dir), a);  // no direction: 0
      const __m128 raw = _mm_mul_ps(_mm_setr_ps(l[0].longest, l[1].longest, 0.0f, 0.0f), a);
      _mm_storel_pi(reinterpret_cast<__m64*>(out.raw + v), raw);
      if (out.angular) _mm_storel_pi(reinterpret_cast<__m64*>(out.angular + v), a);
      range_longest = std::max(std::max(range_longest, l[0].longest), l[1].longest);
    };
#else
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    auto addToBox = [&](const glm::vec3& p) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    };
#endif
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
      const glm::vec3 pv = pos[v];
      addToBox(pv);
#if defined(__SSE2__)
      // two rows of two blocks each (most of a closed mesh's), v and v + 1, in one 8-lane pass
      if (avx2 && !colors && row - 5 < 4 && v + 1 != range.end() && offsets[v + 2] - e - 5 < 4) {
        if (gradeTwoRowsAvx2(pos, static_cast<uint32_t>(v), incidence + b, row, offsets[v + 2] - e, want_normals, two_lanes,
                    two_lr, out.sums ? out.sums + v : nullptr)) {
          pairDone(v, two_lr);
          ++v;
          if (out.in_rows) out.in_rows[v] = 1;
          addToBox(pos[v]);
          continue;
        }
      }
      if (!colors && row <= kLaneRow &&
          gradeRowLanes(pos, static_cast<uint32_t>(v), incidence + b, row, want_normals, lanes, lr)) {
        laneDone(v, lr, false);
        continue;
      }
#endif
      const ScalarRow g = gradeRowScalar(mesh, incidence, b, e, v, colors, out, scratch);
      range_longest = std::max(range_longest, g.longest);
      finish(v, g.longest, g.any_dir, g.cos_dirs, g.boundary, [&] { return minPairDot(scratch.normals.data(), g.normals); });
    }
    // maxima and minima: the same whatever the split between threads
    std::lock_guard<std::mutex> lock(longest_mutex);
    longest_edge = std::max(longest_edge, range_longest);
#if defined(__SSE2__)
    float l4[4], h4[4];
    _mm_storeu_ps(l4, lo);
    _mm_storeu_ps(h4, hi);
    box_lo = glm::min(box_lo, glm::vec3(l4[0], l4[1], l4[2]));
    box_hi = glm::max(box_hi, glm::vec3(h4[0], h4[1], h4[2]));
#else
    box_lo = glm::min(box_lo, lo);
    box_hi = glm::max(box_hi, hi);
#endif
  });
  *out.longest_edge = longest_edge;
  if (out.bounds) out.bounds->min = box_lo, out.bounds->max = box_hi;
}

// Stable LSD radix sort of the referenced vertices among [begin, end) by descending raw weight
// (weights are >= 0 floats, whose bit patterns sort like the values); stability keeps ties in
// vertex-index order. Key and vertex travel packed in one 64-bit word (key high), one scatter per
// element and pass. `a` and `b` hold count + 1 words (the key build writes an unreferenced vertex
// at a[n] before dropping it; the two-half sort puts a sentinel after the sorted words), count the
// number of referenced vertices in the range. With
// `order`, the last pass writes the vertices straight into it and null is returned; else the
// sorted words are left in a or b and that one is returned. The key build also writes the
// normalised weights of the range (weights[v] = raw[v] x inv), to save a pass over the vertices.
uint64_t* sortRangeByWeight(const float* raw, const uint8_t* referenced, size_t begin, size_t end, size_t count,
                            float inv, float* weights, uint64_t* a, uint64_t* b, uint32_t* order) {
  constexpr int kBits = 11, kBuckets = 1 << kBits;
  uint32_t hist[3 * kBuckets] = {};
  uint64_t* src = a;
  uint64_t* dst = b;
  size_t n = 0;
  for (size_t v = begin; v < end; ++v) {
    // weights = raw * inv: rounding is monotone, so the normalised weights keep the raw order
    weights[v] = raw[v] * inv;
    uint32_t bits;
    std::memcpy(&bits, &raw[v], sizeof bits);
    const uint32_t key = ~bits;
    src[n] = (uint64_t(key) << 32) | v;  // written always, kept only when referenced (no branch)
    if (referenced[v])
      for (int pass = 0; pass < 3; ++pass) ++hist[pass * kBuckets + ((key >> (pass * kBits)) & (kBuckets - 1))];
    n += referenced[v] != 0;
  }
  if (count == 0) return src;
  int last = -1;  // the last pass that moves anything (a pass whose digit is the same for all is skipped)
  for (int pass = 0; pass < 3; ++pass)
    if (hist[pass * kBuckets + ((uint32_t(src[0] >> 32) >> (pass * kBits)) & (kBuckets - 1))] != count) last = pass;
  for (int pass = 0; pass <= last; ++pass) {
    uint32_t* h = hist + pass * kBuckets;
    if (h[(uint32_t(src[0] >> 32) >> (pass * kBits)) & (kBuckets - 1)] == count) continue;
    uint32_t sum = 0;
    for (int k = 0; k < kBuckets; ++k) {
      const uint32_t c = h[k];
      h[k] = sum;
      sum += c;
    }
    const int shift = 32 + pass * kBits;
    if (pass == last && order) {
      for (size_t i = 0; i < count; ++i) order[h[(src[i] >> shift) & (kBuckets - 1)]++] = static_cast<uint32_t>(src[i]);
      return nullptr;
    }
    for (size_t i = 0; i < count; ++i) dst[h[(src[i] >> shift) & (kBuckets - 1)]++] = src[i];
    std::swap(src, dst);
  }
  if (!order) return src;
  for (size_t i = 0; i < count; ++i) order[i] = static_cast<uint32_t>(src[i]);  // nothing moved
  return nullptr;
}

// how many of x's words are among the k smallest of x and y (ascending, all distinct): the merge
// path's split, so that two threads can each merge one half of the output
size_t mergeSplit(const uint64_t* x, size_t nx, const uint64_t* y, size_t ny, size_t k) {
  size_t lo = k > ny ? k - ny : 0, hi = std::min(k, nx);
  while (lo < hi) {
    const size_t i = lo + (hi - lo) / 2;  // x[i] is among them when it is below y's (k - i)-th
    if (x[i] < y[k - i - 1]) lo = i + 1;
    else hi = i;
  }
  return lo;
}

// Below this many referenced vertices the sort runs on the calling thread. Sort and sorted copy,
// best of 2,000 on two threads, serial / two halves: 2 k vertices 13 / 11 us (too little to risk
// waiting for a busy second thread), 10 k 63 / 41 us, 20 k 104 / 63 us, bunny (35 k) 226 / 131 us;
// on one thread the halves and the merge cost 255 us on the bunny (the merge's 0.65 M instructions),
// so the two halves are taken only where a second thread may run.
constexpr size_t kParallelSortMin = 8192;

// `order` (the referenced vertices, heaviest first, ties by index), `sorted` (their positions in
// that order) and the normalised weights of all vertices. `count_lo` of the `count` referenced
// vertices lie below vertex vn / 2.
// Large meshes: the two halves of the vertex range are sorted side by side (each a stable radix
// sort of its own), then merged by two threads, each writing one half of the output; a word's
// low half is its vertex, so the words are distinct and ascending words are exactly the stable
// order: the same result as one sort over all. The merge writes the sorted positions too.
void sortByWeight(const std::vector<float>& raw, const std::vector<uint8_t>& referenced, size_t count,
                  size_t count_lo, float inv, const glm::vec3* pos, std::vector<float>& weights,
                  std::vector<uint32_t>& order, std::vector<glm::vec3>& sorted) {
  const size_t vn = raw.size();
  // the sorted positions (12 bytes per vertex) are allocated before the sort's buffers (16) are
  // freed, which stays below the grading's peak (the incidence table): the prepare's peak is
  // unchanged, 2.962 MB on the bunny, 44.06 MB on the 1 M sphere
  order.resize(count);
  sorted.resize(count);
  uint32_t* ord = order.data();
  glm::vec3* out = sorted.data();
  const size_t threads = std::min<size_t>(tbb::this_task_arena::max_concurrency(),
                                          tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  if (count < kParallelSortMin || threads < 2) {
    std::unique_ptr<uint64_t[]> buf_a(new uint64_t[count + 1]), buf_b(new uint64_t[count + 1]);
    sortRangeByWeight(raw.data(), referenced.data(), 0, vn, count, inv, weights.data(), buf_a.get(), buf_b.get(), ord);
    for (size_t i = 0; i < count; ++i) out[i] = pos[ord[i]];
    return;
  }
  // half 0 in words [0, count_lo] of each buffer, half 1 in [count_lo + 1, count + 1]: each with
  // its spare word, which after the sort holds a sentinel above every real word (a real word's low
  // half is a vertex index, never 2^32 - 1)
  const size_t count_hi = count - count_lo, vmid = vn / 2;
  std::unique_ptr<uint64_t[]> buf_a(new uint64_t[count + 2]), buf_b(new uint64_t[count + 2]);
  const uint64_t* x = nullptr;
  const uint64_t* y = nullptr;
  tbb::parallel_invoke(
      [&] {
        uint64_t* s = sortRangeByWeight(raw.data(), referenced.data(), 0, vmid, count_lo, inv, weights.data(),
                                        buf_a.get(), buf_b.get(), nullptr);
        s[count_lo] = ~uint64_t(0);
        x = s;
      },
      [&] {
        const size_t o = count_lo + 1;
        uint64_t* s = sortRangeByWeight(raw.data(), referenced.data(), vmid, vn, count_hi, inv, weights.data(),
                                        buf_a.get() + o, buf_b.get() + o, nullptr);
        s[count_hi] = ~uint64_t(0);
        y = s;
      });
  // each thread merges its half of the output as two quarters in one loop: a merge step waits for
  // the comparison before it can load the next words, so two independent chains run side by side
  auto merge = [&](size_t k0, size_t k1) {
    const size_t km = k0 + (k1 - k0) / 2;
    size_t i0 = mergeSplit(x, count_lo, y, count_hi, k0), j0 = k0 - i0;
    size_t i1 = mergeSplit(x, count_lo, y, count_hi, km), j1 = km - i1;
    auto step = [&](size_t k, size_t& i, size_t& j) {
      const uint64_t xi = x[i], yj = y[j];
      const bool take_x = xi < yj;  // the sentinels keep both reads in range
      const uint32_t v = static_cast<uint32_t>(take_x ? xi : yj);
      i += take_x;
      j += !take_x;
      ord[k] = v;
      out[k] = pos[v];
    };
    for (size_t k = 0; k < km - k0; ++k) {
      step(k0 + k, i0, j0);
      step(km + k, i1, j1);
    }
    if (k1 - km > km - k0) step(k1 - 1, i1, j1);
  };
  tbb::parallel_invoke([&] { merge(0, count / 2); }, [&] { merge(count / 2, count); });
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
    size_t t = c * kChunk;
    const size_t end = std::min(tn, t + kChunk);
#if defined(__SSE2__)
    // four triangles at a time: the float lengths in lanes (sqrtps rounds like sqrtss), widened to
    // double and added to the sums in triangle order, as the scalar loop below does
    for (; t + 4 <= end; t += 4) {
      glm::vec3 a[4], b[4], cc[4];
      for (int l = 0; l < 4; ++l) {
        const uint32_t* corner = tri + 3 * (t + l);
        a[l] = pos[corner[0]], b[l] = pos[corner[1]], cc[l] = pos[corner[2]];
      }
      const __m128 ax = column(a, 0), ay = column(a, 1), az = column(a, 2);
      const __m128 bx = column(b, 0), by = column(b, 1), bz = column(b, 2);
      const __m128 cx = column(cc, 0), cy = column(cc, 1), cz = column(cc, 2);
      auto length = [](__m128 x, __m128 y, __m128 z) {
        return _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)), _mm_mul_ps(z, z)));
      };
      const __m128 ux = _mm_sub_ps(bx, ax), uy = _mm_sub_ps(by, ay), uz = _mm_sub_ps(bz, az);  // b - a
      const __m128 wx = _mm_sub_ps(cx, ax), wy = _mm_sub_ps(cy, ay), wz = _mm_sub_ps(cz, az);  // cc - a
      const __m128 l0 = length(ux, uy, uz);
      const __m128 l1 = length(_mm_sub_ps(cx, bx), _mm_sub_ps(cy, by), _mm_sub_ps(cz, bz));
      const __m128 l2 = length(_mm_sub_ps(ax, cx), _mm_sub_ps(ay, cy), _mm_sub_ps(az, cz));
      // glm::cross(b - a, cc - a)
      const __m128 nl = length(_mm_sub_ps(_mm_mul_ps(uy, wz), _mm_mul_ps(wy, uz)),
                               _mm_sub_ps(_mm_mul_ps(uz, wx), _mm_mul_ps(wz, ux)),
                               _mm_sub_ps(_mm_mul_ps(ux, wy), _mm_mul_ps(wx, uy)));
      const __m128d half = _mm_set1_pd(0.5);
      for (int h = 0; h < 2; ++h) {  // triangles t + 2h, t + 2h + 1
        auto wide = [h](__m128 x) { return _mm_cvtps_pd(h ? _mm_movehl_ps(x, x) : x); };
        const __m128d len = _mm_add_pd(_mm_add_pd(wide(l0), wide(l1)), wide(l2));
        const __m128d ar = _mm_mul_pd(half, wide(nl));
        sum += _mm_cvtsd_f64(len);
        area += _mm_cvtsd_f64(ar);
        sum += _mm_cvtsd_f64(_mm_unpackhi_pd(len, len));
        area += _mm_cvtsd_f64(_mm_unpackhi_pd(ar, ar));
      }
    }
#endif
    for (; t < end; ++t) {
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
  table.offsets.assign(vn + 1, 0);
  countCorners(mesh, 0, mesh.triangleCount(), true, table.offsets.data() + 1);
  fillIncidence(mesh, table, nullptr);
  gradeAndSum(mesh, table, grading, boost_features, {raw.data(), angular.data(), &longest_edge, nullptr, nullptr});
  const float inv = longest_edge > 0.0f ? 1.0f / longest_edge : 0.0f;
  // weights = raw * inv: rounding is monotone, so the normalised weights keep the raw order
  for (size_t v = 0; v < vn; ++v) weights[v] = raw[v] * inv;
  if (raw_out) raw_out->swap(raw);
  if (angular_out) angular_out->swap(angular);
  if (longest_edge_out) *longest_edge_out = longest_edge;
}

Error prepareMesh(const Mesh& in, const ClusterParams& params, PreparedMesh& out, const std::string& what) {
  // validation: the checks of sizes and of the small arrays first; the scans of every coordinate and
  // of every triangle and edge index (validateMesh's largest) ride on the first passes below, before
  // anything is written to `out`. On any failure validateMesh itself gives the error, so it names
  // the same first bad element.
  const size_t vn = in.vertexCount();
  if (vn == 0 || !detail::validateMeshScanned(in, what, true, true).ok()) {
    if (Error e = validateMesh(in, what); !e.ok()) return e;
  }
  // the sort uses the unnormalised product: normalising a factor by a constant cannot change the
  // order, and this way the order does not depend on other parts of the mesh (whose longest edge
  // would be the normaliser) even by rounding
  std::vector<float> raw, weights;
  std::vector<VertexFaceSums> face_sums;
  std::vector<glm::vec4> face_colors;
  std::vector<uint8_t> referenced;
  IncidenceTable table;
  double area = 0.0, sum = 0.0;
  // validateMesh's scans and the counting sort's count pass, each half of the triangles checked and
  // counted by one thread (into its own counts), the second also checking the coordinates; then
  // the sort's fill next to the surface sums (which read positions through the checked indices)
  // and the output arrays' allocation. Bunny, ms, best of 1000 on two threads: check + count
  // 0.055 | 0.066, then fill 0.26 | sums + allocation 0.30; before, validation + allocation 0.08,
  // then count + fill 0.40 | sums 0.26. The count with the index check folded in (an index out of
  // range counted in one more slot, by std::min) took 0.13 for all triangles, against 0.03 + 0.09.
  const size_t tn = in.triangleCount(), mid = tn / 2;
  bool low_in_range = true, high_in_range = true, coordinates_finite = true;
  std::unique_ptr<uint32_t[]> high_count(new uint32_t[vn]);
  tbb::parallel_invoke(
      [&] {
        low_in_range = detail::indicesBelow(in.triangles.data(), 3 * mid, vn);
        table.offsets.assign(vn + 1, 0);
        if (low_in_range) countCorners(in, 0, mid, false, table.offsets.data() + 1);
      },
      [&] {
        high_in_range = detail::indicesBelow(in.triangles.data() + 3 * mid, 3 * (tn - mid), vn) &&
                        detail::indicesBelow(in.edges.data(), in.edges.size(), vn);
        coordinates_finite = detail::coordinatesFinite(in);
        std::memset(high_count.get(), 0, vn * sizeof(uint32_t));
        if (high_in_range) countCorners(in, mid, tn, true, high_count.get());
      });
  if (!low_in_range || !high_in_range || !coordinates_finite) return validateMesh(in, what);
  tbb::parallel_invoke(
      [&] { fillIncidence(in, table, std::move(high_count)); },
      [&] {
        surfaceSums(in, area, sum);
        raw.resize(vn);
        weights.resize(vn);
        face_sums.resize(vn);
        if (!in.colors.empty()) face_colors.resize(vn);
        referenced.resize(vn);
      });
  out = PreparedMesh();
  out.mesh = &in;
  out.grading = params.grading;
  out.boost_features = params.boost_features;
  if (vn == 0) return {};
  out.weights = std::move(weights);
  out.face_sums = std::move(face_sums);
  out.face_colors = std::move(face_colors);
  float longest_edge = 0.0f;
  Aabb rows_box;
  gradeAndSum(in, table, params.grading, params.boost_features,
              {raw.data(), nullptr, &longest_edge, out.face_sums.data(),
               in.colors.empty() ? nullptr : out.face_colors.data(), referenced.data(), &rows_box});
  table = IncidenceTable();  // 8 bytes per corner, not needed any more
  out.longest_edge = longest_edge;
  const float inv = longest_edge > 0.0f ? 1.0f / longest_edge : 0.0f;

  // referenced: used by a triangle or an edge (the grading rows) or by a point
  glm::vec3 lo = rows_box.min, hi = rows_box.max;
  for (uint32_t v : in.points) {
    referenced[v] = 1;
    lo = glm::min(lo, in.positions[v]);
    hi = glm::max(hi, in.positions[v]);
  }
  size_t count = 0, count_lo = 0;
  for (size_t v = 0; v < vn / 2; ++v) count_lo += referenced[v];
  count = count_lo;
  for (size_t v = vn / 2; v < vn; ++v) count += referenced[v];
  if (count > 0) out.bounds.min = lo, out.bounds.max = hi;
  sortByWeight(raw, referenced, count, count_lo, inv, in.positions.data(), out.weights, out.order,
               out.sorted_positions);

  out.surface_area = area;
  for (size_t e = 0; e < in.edgeCount(); ++e)
    sum += glm::length(in.positions[in.edges[2 * e]] - in.positions[in.edges[2 * e + 1]]);
  const size_t count_e = 3 * in.triangleCount() + in.edgeCount();
  out.mean_edge_length = count_e ? static_cast<float>(sum / double(count_e)) : 0.0f;
  return {};
}

}  // namespace scenelod
