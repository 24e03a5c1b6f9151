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

namespace scenelod {

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

#if defined(__SSE2__)
// Rows of up to kLaneRow triangle corners and no input edge, on meshes without colours (all but
// a few vertices of a typical mesh), take a four-lane path: the same float operations as the
// scalar pass in gradeAndSum, in the same order where the order matters, four incidences or
// neighbours per SSE2 operation. Every lane does the scalar code's arithmetic (mulps / addps /
// divps / sqrtps round like their scalar forms; no FMA without -mfma), so the results are
// bit-identical:
// - the face sums add, in row order, the products of every incidence; a skipped face (zero area)
//   adds +0.0, which leaves a sum unchanged (a sum that starts at +0.0 is never -0.0);
// - the distinct neighbours come from comparing every candidate (the two other corners of each
//   incidence) with the later ones; their order does not matter here: the widest pair is the exact
//   minimum over pairs for up to 2 x kLaneRow <= kExactPairLimit directions, and min and max do not
//   depend on the order (up to the sign of a zero dot product, which 1 +- cos makes the same);
// - unused lanes (padding, repeated neighbours, zero-length edges, zero-area faces) hold NaN in the
//   direction and normal columns: their dot products are NaN, which the minimum skips.
constexpr size_t kLaneRow = 16;
static_assert(2 * kLaneRow <= kExactPairLimit, "the lane path needs the exact pair minimum");

struct alignas(16) LaneScratch {
  uint32_t ia[kLaneRow], ib[kLaneRow];  // per incidence the corners a and b (the vertex itself in padding lanes)
  float nrm[3][kLaneRow];         // unit face normals (x, y, z columns) per incidence; NaN if not a face
  float dir[3][2 * kLaneRow];     // unit directions per candidate; NaN unless a distinct non-zero edge
};

// coordinate c of four points, one per lane
inline __m128 column(const glm::vec3 p[4], int c) { return _mm_setr_ps(p[0][c], p[1][c], p[2][c], p[3][c]); }

// the lanes of bits 0..3 of `bits` set, as a float mask
inline __m128 bitLanes(uint32_t bits) {
  const __m128i bit = _mm_setr_epi32(1, 2, 4, 8);
  return _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(static_cast<int>(bits)), bit), bit));
}

// lanes of `keep` take x, the others NaN (all bits set)
inline __m128 orNan(__m128 keep, __m128 x) {
  return _mm_or_ps(_mm_and_ps(keep, x), _mm_andnot_ps(keep, _mm_castsi128_ps(_mm_set1_epi32(-1))));
}

// lane l of the result holds lane (l + k) % 4 of x
#define SCENELOD_ROT_PS(x, k) _mm_shuffle_ps(x, x, _MM_SHUFFLE((k + 3) % 4, (k + 2) % 4, (k + 1) % 4, k))
#define SCENELOD_ROT_EPI32(x, k) _mm_shuffle_epi32(x, _MM_SHUFFLE((k + 3) % 4, (k + 2) % 4, (k + 1) % 4, k))

// min(dot, best) for the four pairs (lane l of p, lane l of q): dot if dot < best, so a NaN dot keeps
// best (minps returns its second operand unless the first is less), as std::min(best, dot) does
inline __m128 minDot(__m128 best, __m128 px, __m128 py, __m128 pz, __m128 qx, __m128 qy, __m128 qz) {
  const __m128 d = _mm_add_ps(_mm_add_ps(_mm_mul_ps(px, qx), _mm_mul_ps(py, qy)), _mm_mul_ps(pz, qz));
  return _mm_min_ps(d, best);
}

// minPairDot over the vectors in columns x, y, z, blocks of 4 lanes; only the blocks in
// `live_blocks` hold vectors, and their unused lanes are NaN. Every pair of lanes meets in some
// rotation: within a block rotations by 1 and 2, between two blocks all four.
// inlined at both calls (directions, normals), which the compiler may then interleave
inline __attribute__((always_inline)) float minPairDotBlocks(const float* x, const float* y, const float* z,
                                                           uint32_t live_blocks) {
  // four running minima, so that the minps do not wait on each other (the minimum does not depend
  // on the order, up to the sign of a zero)
  const __m128 one = _mm_set1_ps(1.0f);
  __m128 b0 = one, b1 = one, b2 = one, b3 = one;
  for (uint32_t bp = live_blocks; bp;) {
    const int p = __builtin_ctz(bp);
    bp &= bp - 1;
    const __m128 px = _mm_load_ps(x + 4 * p), py = _mm_load_ps(y + 4 * p), pz = _mm_load_ps(z + 4 * p);
    b0 = minDot(b0, px, py, pz, SCENELOD_ROT_PS(px, 1), SCENELOD_ROT_PS(py, 1), SCENELOD_ROT_PS(pz, 1));
    b1 = minDot(b1, px, py, pz, SCENELOD_ROT_PS(px, 2), SCENELOD_ROT_PS(py, 2), SCENELOD_ROT_PS(pz, 2));
    for (uint32_t bq = bp; bq;) {
      const int q = __builtin_ctz(bq);
      bq &= bq - 1;
      const __m128 qx = _mm_load_ps(x + 4 * q), qy = _mm_load_ps(y + 4 * q), qz = _mm_load_ps(z + 4 * q);
      b0 = minDot(b0, px, py, pz, qx, qy, qz);
      b1 = minDot(b1, px, py, pz, SCENELOD_ROT_PS(qx, 1), SCENELOD_ROT_PS(qy, 1), SCENELOD_ROT_PS(qz, 1));
      b2 = minDot(b2, px, py, pz, SCENELOD_ROT_PS(qx, 2), SCENELOD_ROT_PS(qy, 2), SCENELOD_ROT_PS(qz, 2));
      b3 = minDot(b3, px, py, pz, SCENELOD_ROT_PS(qx, 3), SCENELOD_ROT_PS(qy, 3), SCENELOD_ROT_PS(qz, 3));
    }
  }
  __m128 best = _mm_min_ps(_mm_min_ps(b0, b1), _mm_min_ps(b2, b3));  // none is NaN
  best = _mm_min_ps(best, SCENELOD_ROT_PS(best, 2));
  best = _mm_min_ps(best, SCENELOD_ROT_PS(best, 1));
  return _mm_cvtss_f32(best);
}

// minPairDotBlocks over two blocks (8 lanes, every lane a vector or NaN; x[0] lanes 0..3) in 256-bit registers:
// lane i against lane (i + k) % 8 for k = 1..4 meets every pair; each dot product is the same
// expression as minDot's (and symmetric in its two vectors), the minimum independent of the order,
// so the same result. 4 dot products of 8 lanes and 12 permutes, where the blocks took 8 of 4 lanes
// and 21 shuffles. Inlined only into gradeTwoRowsAvx2.
SCENELOD_AVX2_TARGET inline float minPairDot8v(__m256 px, __m256 py, __m256 pz) {
  __m256 best = _mm256_set1_ps(1.0f);
  #pragma GCC unroll 4
  for (int k = 1; k <= 4; ++k) {
    const __m256i rot = _mm256_setr_epi32(k % 8, (k + 1) % 8, (k + 2) % 8, (k + 3) % 8, (k + 4) % 8, (k + 5) % 8,
                                          (k + 6) % 8, (k + 7) % 8);
    const __m256 qx = _mm256_permutevar8x32_ps(px, rot), qy = _mm256_permutevar8x32_ps(py, rot);
    const __m256 qz = _mm256_permutevar8x32_ps(pz, rot);
    const __m256 d = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(px, qx), _mm256_mul_ps(py, qy)), _mm256_mul_ps(pz, qz));
    best = _mm256_min_ps(d, best);  // a NaN dot keeps best, as in minDot
  }
  __m128 b = _mm_min_ps(_mm256_castps256_ps128(best), _mm256_extractf128_ps(best, 1));
  b = _mm_min_ps(b, SCENELOD_ROT_PS(b, 2));
  b = _mm_min_ps(b, SCENELOD_ROT_PS(b, 1));
  return _mm_cvtss_f32(b);
}

struct LaneRow {
  float sums[12];      // quadric xx..zz, normal x, y, z, then the summed area (10, 11 unused); not
                       // written by gradeTwoRowsAvx2 when it encodes them itself
  float longest;       // longest incident edge
  float cos_dirs;      // minPairDot of the directions (1 when fewer than two)
  float cos_normals;   // minPairDot of the face normals, when asked
  bool any_dir;        // some incident edge has non-zero length
  bool boundary;       // some neighbour is shared by only one incident triangle
};

// Grades one row of r (1 <= r <= kLaneRow) triangle corners; false (and nothing computed) when the
// row holds an input edge. `row` may be read up to the next multiple of 4.
// NB = (r + 3) / 4 blocks of incidences, a constant so that the block loops unroll into registers;
// candidate block c < NB: the a of incidence block c, else the b of block c - NB.
template <size_t NB>
inline bool gradeRowLanesBody(const glm::vec3* pos, uint32_t v, const Incidence* row, size_t r, bool want_normals,
                              LaneScratch& s, LaneRow& out) {
  constexpr size_t nb = NB;
  __m128i cand[2 * NB];
  const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
  const __m128i none = _mm_set1_epi32(-1);  // detail::kNone
  const __m128i self = _mm_set1_epi32(static_cast<int>(v));
  __m128i edge = _mm_setzero_si128();
  #pragma GCC unroll 8
  for (size_t k = 0; k < nb; ++k) {
    const __m128 lo = _mm_loadu_ps(reinterpret_cast<const float*>(row + 4 * k));      // a0 b0 a1 b1
    const __m128 hi = _mm_loadu_ps(reinterpret_cast<const float*>(row + 4 * k + 2));  // a2 b2 a3 b3
    const __m128i valid = _mm_cmplt_epi32(_mm_add_epi32(lane, _mm_set1_epi32(static_cast<int>(4 * k))),
                                          _mm_set1_epi32(static_cast<int>(r)));
    const __m128i a = _mm_castps_si128(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0)));
    const __m128i b = _mm_castps_si128(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1)));
    edge = _mm_or_si128(edge, _mm_and_si128(valid, _mm_cmpeq_epi32(b, none)));
    // padding lanes get kNone, which no vertex index equals
    cand[k] = _mm_or_si128(a, _mm_andnot_si128(valid, none));
    cand[nb + k] = _mm_or_si128(b, _mm_andnot_si128(valid, none));
    // the corners whose positions are read: the vertex itself in padding lanes (zero edges, zero area)
    const __m128i pad = _mm_andnot_si128(valid, self);
    _mm_store_si128(reinterpret_cast<__m128i*>(s.ia + 4 * k), _mm_or_si128(_mm_and_si128(valid, a), pad));
    _mm_store_si128(reinterpret_cast<__m128i*>(s.ib + 4 * k), _mm_or_si128(_mm_and_si128(valid, b), pad));
  }
  if (_mm_movemask_epi8(edge)) return false;

  // distinct neighbours: a candidate equal to an earlier one is a repeat; one equal to no other is
  // held by one triangle only (each incidence holds two different candidates of its triangle).
  // Blocks are compared in all rotations; lane l of a block against lane (l + k) % 4 of itself is
  // a comparison with an earlier candidate when l + k >= 4 (the rotation wrapped).
  constexpr size_t nc = 2 * nb;
  __m128i other[nc], earlier[nc];
  #pragma GCC unroll 8
  for (size_t c = 0; c < nc; ++c) other[c] = earlier[c] = _mm_setzero_si128();
  const __m128i wrap1 = _mm_setr_epi32(0, 0, 0, -1), wrap2 = _mm_setr_epi32(0, 0, -1, -1);
  const __m128i wrap3 = _mm_setr_epi32(0, -1, -1, -1);
  // block p against itself and the later blocks q
  auto compare = [&](size_t p) {
    const __m128i cp = cand[p];
    const __m128i e1 = _mm_cmpeq_epi32(cp, SCENELOD_ROT_EPI32(cp, 1));
    const __m128i e2 = _mm_cmpeq_epi32(cp, SCENELOD_ROT_EPI32(cp, 2));
    const __m128i e3 = _mm_cmpeq_epi32(cp, SCENELOD_ROT_EPI32(cp, 3));
    __m128i op = _mm_or_si128(other[p], _mm_or_si128(e1, _mm_or_si128(e2, e3)));
    const __m128i wrapped =
        _mm_or_si128(_mm_and_si128(e1, wrap1), _mm_or_si128(_mm_and_si128(e2, wrap2), _mm_and_si128(e3, wrap3)));
    earlier[p] = _mm_or_si128(earlier[p], wrapped);
    #pragma GCC unroll 8
    for (size_t q = p + 1; q < nc; ++q) {  // every lane of q is later than every lane of p
      const __m128i cq = cand[q];
      const __m128i f0 = _mm_cmpeq_epi32(cp, cq);
      const __m128i f1 = _mm_cmpeq_epi32(cp, SCENELOD_ROT_EPI32(cq, 1));
      const __m128i f2 = _mm_cmpeq_epi32(cp, SCENELOD_ROT_EPI32(cq, 2));
      const __m128i f3 = _mm_cmpeq_epi32(cp, SCENELOD_ROT_EPI32(cq, 3));
      op = _mm_or_si128(op, _mm_or_si128(_mm_or_si128(f0, f1), _mm_or_si128(f2, f3)));
      // lane m of q met lane (m - k) % 4 of p in f_k: rotate back by 4 - k
      const __m128i fq = _mm_or_si128(_mm_or_si128(f0, SCENELOD_ROT_EPI32(f1, 3)),
                                      _mm_or_si128(SCENELOD_ROT_EPI32(f2, 2), SCENELOD_ROT_EPI32(f3, 1)));
      other[q] = _mm_or_si128(other[q], fq);
      earlier[q] = _mm_or_si128(earlier[q], fq);
    }
    other[p] = op;
  };
  #pragma GCC unroll 8
  for (size_t p = 0; p < nb; ++p) compare(p);
  // the b blocks among themselves decide only for a b equal to no a: in a closed fan every b is
  // some a (already a repeat, already shared), so they are skipped then
  const uint32_t row_bits = (1u << r) - 1;
  const uint32_t valid_bits = row_bits | (row_bits << (4 * nb));
  uint32_t b_matched = 0;
  #pragma GCC unroll 8
  for (size_t c = nb; c < nc; ++c)
    b_matched |= static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(earlier[c]))) << (4 * (c - nb));
  if ((b_matched & row_bits) != row_bits) {
    #pragma GCC unroll 8
    for (size_t p = nb; p < nc; ++p) compare(p);
  }
  uint32_t repeat = 0, shared = 0;
  #pragma GCC unroll 8
  for (size_t c = 0; c < nc; ++c) {
    repeat |= static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(earlier[c]))) << (4 * c);
    shared |= static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(other[c]))) << (4 * c);
  }
  const uint32_t first = valid_bits & ~repeat;
  out.boundary = (first & ~shared) != 0;

  const __m128 vx = _mm_set1_ps(pos[v].x), vy = _mm_set1_ps(pos[v].y), vz = _mm_set1_ps(pos[v].z);
  const __m128 zero = _mm_setzero_ps();
  __m128 q0 = zero, q1 = zero, q2 = zero;  // quadric xx xy xz yy; yz zz, normal x y; normal z, area
  __m128 longest = zero;
  uint32_t normal_blocks = 0, dir_blocks = 0;  // the blocks holding some normal, some direction
  int any_dir = 0;
  #pragma GCC unroll 8
  for (size_t k = 0; k < nb; ++k) {
    __m128 ax, ay, az, bx, by, bz;  // the corners a and b, one incidence per lane
    glm::vec3 pa[4], pb[4];
    #pragma GCC unroll 8
    for (int l = 0; l < 4; ++l) {
      pa[l] = pos[s.ia[4 * k + l]];
      pb[l] = pos[s.ib[4 * k + l]];
    }
    ax = column(pa, 0), ay = column(pa, 1), az = column(pa, 2);
    bx = column(pb, 0), by = column(pb, 1), bz = column(pb, 2);
    const __m128 ux = _mm_sub_ps(ax, vx), uy = _mm_sub_ps(ay, vy), uz = _mm_sub_ps(az, vz);
    const __m128 wx = _mm_sub_ps(bx, vx), wy = _mm_sub_ps(by, vy), wz = _mm_sub_ps(bz, vz);
    // glm::cross(u, w), glm::length, / as in the scalar pass
    const __m128 cx = _mm_sub_ps(_mm_mul_ps(uy, wz), _mm_mul_ps(wy, uz));
    const __m128 cy = _mm_sub_ps(_mm_mul_ps(uz, wx), _mm_mul_ps(wz, ux));
    const __m128 cz = _mm_sub_ps(_mm_mul_ps(ux, wy), _mm_mul_ps(wx, uy));
    const __m128 nl = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(cx, cx), _mm_mul_ps(cy, cy)), _mm_mul_ps(cz, cz)));
    const __m128 face = _mm_cmpgt_ps(nl, zero);  // false for NaN, as !(nl > 0) in the scalar pass
    const __m128 nx = _mm_div_ps(cx, nl), ny = _mm_div_ps(cy, nl), nz = _mm_div_ps(cz, nl);
    const __m128 area = _mm_mul_ps(_mm_set1_ps(0.5f), nl);
    const __m128 anx = _mm_mul_ps(area, nx), any = _mm_mul_ps(area, ny), anz = _mm_mul_ps(area, nz);
    // per incidence (row) the ten addends, zero where not a face; transposed to add in row order
    __m128 t0 = _mm_and_ps(face, _mm_mul_ps(anx, nx)), t1 = _mm_and_ps(face, _mm_mul_ps(anx, ny));
    __m128 t2 = _mm_and_ps(face, _mm_mul_ps(anx, nz)), t3 = _mm_and_ps(face, _mm_mul_ps(any, ny));
    _MM_TRANSPOSE4_PS(t0, t1, t2, t3);
    __m128 t4 = _mm_and_ps(face, _mm_mul_ps(any, nz)), t5 = _mm_and_ps(face, _mm_mul_ps(anz, nz));
    __m128 t6 = _mm_and_ps(face, anx), t7 = _mm_and_ps(face, any);
    _MM_TRANSPOSE4_PS(t4, t5, t6, t7);
    // the last two columns (normal z, area) need lanes 0 and 1 of q2 only: the pairs of incidence
    // l in lanes 0, 1 of t8 .. t11, lanes 2, 3 of q2 unused (a transpose with two zero columns
    // compiled, for AVX2, to a vmovq register move that valgrind 3.19 cannot decode)
    const __m128 t8_9 = _mm_and_ps(face, anz), t9_9 = _mm_and_ps(face, area);
    const __m128 t8 = _mm_unpacklo_ps(t8_9, t9_9), t10 = _mm_unpackhi_ps(t8_9, t9_9);
    const __m128 t9 = _mm_movehl_ps(t8, t8), t11 = _mm_movehl_ps(t10, t10);
    q0 = _mm_add_ps(q0, t0), q1 = _mm_add_ps(q1, t4), q2 = _mm_add_ps(q2, t8);
    q0 = _mm_add_ps(q0, t1), q1 = _mm_add_ps(q1, t5), q2 = _mm_add_ps(q2, t9);
    q0 = _mm_add_ps(q0, t2), q1 = _mm_add_ps(q1, t6), q2 = _mm_add_ps(q2, t10);
    q0 = _mm_add_ps(q0, t3), q1 = _mm_add_ps(q1, t7), q2 = _mm_add_ps(q2, t11);
    if (want_normals) {
      const __m128 fx = orNan(face, nx), fy = orNan(face, ny), fz = orNan(face, nz);
      _mm_store_ps(s.nrm[0] + 4 * k, fx);
      _mm_store_ps(s.nrm[1] + 4 * k, fy);
      _mm_store_ps(s.nrm[2] + 4 * k, fz);
      normal_blocks |= static_cast<uint32_t>(_mm_movemask_ps(face) != 0) << k;
    }
    // directions to the distinct neighbours: the a of block k (candidate block k), the b (nb + k)
    #pragma GCC unroll 8
    for (int side = 0; side < 2; ++side) {
      const size_t c = side ? nb + k : k;
      if (!((first >> (4 * c)) & 0xfu)) continue;  // all repeats (the b of a closed fan)
      const __m128 dx = side ? wx : ux, dy = side ? wy : uy, dz = side ? wz : uz;
      const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128 len = _mm_sqrt_ps(len2);
      const __m128 use = _mm_and_ps(bitLanes(first >> (4 * c)), _mm_cmpgt_ps(len, zero));
      longest = _mm_max_ps(longest, _mm_and_ps(use, len));
      const __m128 ex = orNan(use, _mm_div_ps(dx, len)), ey = orNan(use, _mm_div_ps(dy, len));
      const __m128 ez = orNan(use, _mm_div_ps(dz, len));
      _mm_store_ps(s.dir[0] + 4 * c, ex);
      _mm_store_ps(s.dir[1] + 4 * c, ey);
      _mm_store_ps(s.dir[2] + 4 * c, ez);
      const int used = _mm_movemask_ps(use);
      any_dir |= used;
      dir_blocks |= static_cast<uint32_t>(used != 0) << c;
    }
  }
  _mm_storeu_ps(out.sums, q0);
  _mm_storeu_ps(out.sums + 4, q1);
  _mm_storeu_ps(out.sums + 8, q2);
  longest = _mm_max_ps(longest, _mm_shuffle_ps(longest, longest, _MM_SHUFFLE(1, 0, 3, 2)));
  longest = _mm_max_ps(longest, _mm_shuffle_ps(longest, longest, _MM_SHUFFLE(2, 3, 0, 1)));
  out.longest = _mm_cvtss_f32(longest);
  out.any_dir = any_dir != 0;
  out.cos_dirs = minPairDotBlocks(s.dir[0], s.dir[1], s.dir[2], dir_blocks);
  out.cos_normals = want_normals ? minPairDotBlocks(s.nrm[0], s.nrm[1], s.nrm[2], normal_blocks) : 1.0f;
  return true;
}

// one instance per block count. (An AVX2 build of it, with gathers and 8-lane pair searches, took
// 32.7 M instructions of the bunny's grading pass against 48.8 M, but no less time: each row is one
// long dependency chain, which gradeTwoRowsAvx2 below overlaps with the next row's.)
bool gradeRowLanes(const glm::vec3* pos, uint32_t v, const Incidence* row, size_t r, bool want_normals,
                   LaneScratch& s, LaneRow& out) {
  static_assert(kLaneRow == 16, "one instance per block count");
  switch ((r + 3) / 4) {
    case 1: return gradeRowLanesBody<1>(pos, v, row, r, want_normals, s, out);
    case 2: return gradeRowLanesBody<2>(pos, v, row, r, want_normals, s, out);
    case 3: return gradeRowLanesBody<3>(pos, v, row, r, want_normals, s, out);
    default: return gradeRowLanesBody<4>(pos, v, row, r, want_normals, s, out);
  }
}

// helpers of gradeTwoRowsAvx2 (lambdas would not carry its target attribute)
// lane l of each half holds lane (l + k) % 4 of that half of x
#define SCENELOD_ROT8_EPI32(x, k) _mm256_shuffle_epi32(x, _MM_SHUFFLE((k + 3) % 4, (k + 2) % 4, (k + 1) % 4, k))
SCENELOD_AVX2_TARGET inline __m256 loadTwo(const Incidence* const row[2], size_t off) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(reinterpret_cast<const float*>(row[0] + off))),
                              _mm_loadu_ps(reinterpret_cast<const float*>(row[1] + off)), 1);
}
// the blocks' comparisons of gradeRowLanesBody, in each half
SCENELOD_AVX2_TARGET inline void compareTwo(const __m256i* cand, __m256i* other, __m256i* earlier, size_t p, size_t nc) {
  const __m256i wrap1 = _mm256_setr_epi32(0, 0, 0, -1, 0, 0, 0, -1), wrap2 = _mm256_setr_epi32(0, 0, -1, -1, 0, 0, -1, -1);
  const __m256i wrap3 = _mm256_setr_epi32(0, -1, -1, -1, 0, -1, -1, -1);
  const __m256i cp = cand[p];
  const __m256i e1 = _mm256_cmpeq_epi32(cp, SCENELOD_ROT8_EPI32(cp, 1));
  const __m256i e2 = _mm256_cmpeq_epi32(cp, SCENELOD_ROT8_EPI32(cp, 2));
  const __m256i e3 = _mm256_cmpeq_epi32(cp, SCENELOD_ROT8_EPI32(cp, 3));
  __m256i op = _mm256_or_si256(other[p], _mm256_or_si256(e1, _mm256_or_si256(e2, e3)));
  earlier[p] = _mm256_or_si256(earlier[p], _mm256_or_si256(_mm256_and_si256(e1, wrap1),
                                                           _mm256_or_si256(_mm256_and_si256(e2, wrap2),
                                                                           _mm256_and_si256(e3, wrap3))));
  for (size_t q = p + 1; q < nc; ++q) {
    const __m256i cq = cand[q];
    const __m256i f0 = _mm256_cmpeq_epi32(cp, cq), f1 = _mm256_cmpeq_epi32(cp, SCENELOD_ROT8_EPI32(cq, 1));
    const __m256i f2 = _mm256_cmpeq_epi32(cp, SCENELOD_ROT8_EPI32(cq, 2));
    const __m256i f3 = _mm256_cmpeq_epi32(cp, SCENELOD_ROT8_EPI32(cq, 3));
    op = _mm256_or_si256(op, _mm256_or_si256(_mm256_or_si256(f0, f1), _mm256_or_si256(f2, f3)));
    const __m256i fq = _mm256_or_si256(_mm256_or_si256(f0, SCENELOD_ROT8_EPI32(f1, 3)),
                                       _mm256_or_si256(SCENELOD_ROT8_EPI32(f2, 2), SCENELOD_ROT8_EPI32(f3, 1)));
    other[q] = _mm256_or_si256(other[q], fq);
    earlier[q] = _mm256_or_si256(earlier[q], fq);
  }
  other[p] = op;
}
// Whether both rows are closed manifold fans, decided from the a-by-b comparisons alone: the
// matrix M (a_j == b_l) over a row's incidences is a permutation exactly when every a equals one b
// and every b one a (each row and column sum is 1). Then the a are distinct (two equal a would
// both equal the b that matches one), so are the b, and both are the same set: every neighbour is
// held by two triangles, the a are the first occurrences and the b the repeats, which is what
// compareTwo's all-pairs search finds (first = the a lanes, no boundary). 16 compares against its
// 26 and none of its per-row bit bookkeeping. Padding lanes hold kNone in a and b, which no valid
// lane does (a valid b of kNone is an input edge, which returned false before), so they add to no
// valid lane's sum. Bunny: the pair pass 1,167 -> 1,037 instructions a pair of rows.
SCENELOD_AVX2_TARGET inline bool closedFans(const __m256i cand[4], const __m256i valid[2]) {
  __m256i rows[2], cols[2][4];  // rows[p]: -matches of a-block p's lanes; cols[q][k]: rotation k's, of b-block q
  #pragma GCC unroll 2
  for (int q = 0; q < 2; ++q) {
    const __m256i b = cand[2 + q];
    const __m256i b1 = SCENELOD_ROT8_EPI32(b, 1), b2 = SCENELOD_ROT8_EPI32(b, 2), b3 = SCENELOD_ROT8_EPI32(b, 3);
    #pragma GCC unroll 2
    for (int p = 0; p < 2; ++p) {
      const __m256i a = cand[p];
      // lane l of f_k: a lane l against b lane (l + k) % 4
      const __m256i f0 = _mm256_cmpeq_epi32(a, b), f1 = _mm256_cmpeq_epi32(a, b1);
      const __m256i f2 = _mm256_cmpeq_epi32(a, b2), f3 = _mm256_cmpeq_epi32(a, b3);
      const __m256i sum = _mm256_add_epi32(_mm256_add_epi32(f0, f1), _mm256_add_epi32(f2, f3));
      rows[p] = q ? _mm256_add_epi32(rows[p], sum) : sum;
      if (p) {
        cols[q][0] = _mm256_add_epi32(cols[q][0], f0), cols[q][1] = _mm256_add_epi32(cols[q][1], f1);
        cols[q][2] = _mm256_add_epi32(cols[q][2], f2), cols[q][3] = _mm256_add_epi32(cols[q][3], f3);
      } else {
        cols[q][0] = f0, cols[q][1] = f1, cols[q][2] = f2, cols[q][3] = f3;
      }
    }
  }
  const __m256i minus_one = _mm256_set1_epi32(-1);
  __m256i bad = _mm256_setzero_si256();  // valid lanes whose sum is not one match
  #pragma GCC unroll 2
  for (int p = 0; p < 2; ++p) {
    // b lane m met a lane (m - k) % 4 in rotation k: rotated back by 4 - k
    const __m256i col = _mm256_add_epi32(_mm256_add_epi32(cols[p][0], SCENELOD_ROT8_EPI32(cols[p][1], 3)),
                                         _mm256_add_epi32(SCENELOD_ROT8_EPI32(cols[p][2], 2),
                                                          SCENELOD_ROT8_EPI32(cols[p][3], 1)));
    const __m256i wrong = _mm256_xor_si256(_mm256_and_si256(_mm256_cmpeq_epi32(rows[p], minus_one),
                                                            _mm256_cmpeq_epi32(col, minus_one)),
                                           minus_one);
    bad = _mm256_or_si256(bad, _mm256_and_si256(valid[p], wrong));  // block p's a and b lanes are valid alike
  }
  return _mm256_testz_si256(bad, bad);
}

// 4 bits of row i's half of mask m, shifted to candidate block c
SCENELOD_AVX2_TARGET inline uint32_t halfBits(__m256i m, int i, size_t c) {
  return ((static_cast<uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(m))) >> (4 * i)) & 0xfu) << (4 * c);
}
SCENELOD_AVX2_TARGET inline __m256 orNan8(__m256 keep, __m256 x) {
  return _mm256_or_ps(_mm256_and_ps(keep, x), _mm256_andnot_ps(keep, _mm256_castsi256_ps(_mm256_set1_epi32(-1))));
}
// _MM_TRANSPOSE4_PS in each half
SCENELOD_AVX2_TARGET inline void transposeTwo(__m256& r0, __m256& r1, __m256& r2, __m256& r3) {
  const __m256 t3 = _mm256_unpacklo_ps(r0, r1), t2 = _mm256_unpacklo_ps(r2, r3);
  const __m256 t1 = _mm256_unpackhi_ps(r0, r1), t0 = _mm256_unpackhi_ps(r2, r3);
  r0 = _mm256_shuffle_ps(t3, t2, _MM_SHUFFLE(1, 0, 1, 0)), r1 = _mm256_shuffle_ps(t3, t2, _MM_SHUFFLE(3, 2, 3, 2));
  r2 = _mm256_shuffle_ps(t1, t0, _MM_SHUFFLE(1, 0, 1, 0)), r3 = _mm256_shuffle_ps(t1, t0, _MM_SHUFFLE(3, 2, 3, 2));
}
SCENELOD_AVX2_TARGET inline __m128 halfOf(__m256 x, int i) {
  return i ? _mm256_extractf128_ps(x, 1) : _mm256_castps256_ps128(x);
}
// row i's halves of blocks 0 and 1 as one 8-lane vector
SCENELOD_AVX2_TARGET inline __m256 rowOf(const __m256 (&x)[2], int i) {
  return i ? _mm256_permute2f128_ps(x[0], x[1], 0x31) : _mm256_permute2f128_ps(x[0], x[1], 0x20);
}

// minPairDot8v of each row's blocks 0 and 1 (row i in half i of x[0] and x[1]; every lane a vector or
// NaN), both rows at once in that layout: within a block lane l against lanes (l + 1) % 4 and
// (l + 2) % 4, across the blocks all four rotations, which meets every pair of a row's 8 lanes and
// no lane with itself. The same dot products (each symmetric in its two vectors) and, the minimum
// not depending on the order (up to the sign of a zero), the same result as minPairDot8v per row,
// with in-half shuffles (1 cycle) in place of its vpermps (3) and the halves' regrouping
// (vperm2f128), and one reduction for both rows.
SCENELOD_AVX2_TARGET inline __m256 minDot8(__m256 best, __m256 px, __m256 py, __m256 pz, __m256 qx, __m256 qy,
                                           __m256 qz) {
  const __m256 d = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(px, qx), _mm256_mul_ps(py, qy)), _mm256_mul_ps(pz, qz));
  return _mm256_min_ps(d, best);  // a NaN dot keeps best, as in minDot
}
#define SCENELOD_ROT8_PS(x, k) _mm256_permute_ps(x, _MM_SHUFFLE((k + 3) % 4, (k + 2) % 4, (k + 1) % 4, k))
SCENELOD_AVX2_TARGET inline void minPairDotTwo(const __m256 (&x)[2], const __m256 (&y)[2], const __m256 (&z)[2],
                                               float out[2]) {
  const __m256 one = _mm256_set1_ps(1.0f);
  __m256 b0 = one, b1 = one, b2 = one, b3 = one;  // four running minima, none waiting on another
  #pragma GCC unroll 2
  for (int k = 0; k < 2; ++k) {
    b0 = minDot8(b0, x[k], y[k], z[k], SCENELOD_ROT8_PS(x[k], 1), SCENELOD_ROT8_PS(y[k], 1), SCENELOD_ROT8_PS(z[k], 1));
    b1 = minDot8(b1, x[k], y[k], z[k], SCENELOD_ROT8_PS(x[k], 2), SCENELOD_ROT8_PS(y[k], 2), SCENELOD_ROT8_PS(z[k], 2));
  }
  b2 = minDot8(b2, x[0], y[0], z[0], x[1], y[1], z[1]);
  b3 = minDot8(b3, x[0], y[0], z[0], SCENELOD_ROT8_PS(x[1], 1), SCENELOD_ROT8_PS(y[1], 1), SCENELOD_ROT8_PS(z[1], 1));
  b2 = minDot8(b2, x[0], y[0], z[0], SCENELOD_ROT8_PS(x[1], 2), SCENELOD_ROT8_PS(y[1], 2), SCENELOD_ROT8_PS(z[1], 2));
  b3 = minDot8(b3, x[0], y[0], z[0], SCENELOD_ROT8_PS(x[1], 3), SCENELOD_ROT8_PS(y[1], 3), SCENELOD_ROT8_PS(z[1], 3));
  __m256 best = _mm256_min_ps(_mm256_min_ps(b0, b1), _mm256_min_ps(b2, b3));  // none is NaN
  best = _mm256_min_ps(best, SCENELOD_ROT8_PS(best, 2));
  best = _mm256_min_ps(best, SCENELOD_ROT8_PS(best, 1));
  out[0] = _mm256_cvtss_f32(best);
  out[1] = _mm_cvtss_f32(_mm256_extractf128_ps(best, 1));
}
#undef SCENELOD_ROT8_PS

// VertexFaceSums::encode of both rows' sums (the quadric and normal sums in q0, q1 and lane 0 of q2,
// the area in lane 1 of q2; row 0 in the low half) into sums[0] and sums[1]: the same arithmetic in
// lanes. minps / maxps are the encode's `c < one ? c : one` and `c > -one ? c : -one` exactly
// (NaN gives +1); q[8] takes toSnorm16's order, max then min (NaN gives -1). The rounded values lie
// in [-32767, 32767], so packssdw's saturation never acts. A row whose area is not above zero gets
// all zeros, as the encode's early return leaves it. The encode called per row took 94
// instructions a vertex (its lane stores and scalar tail), 6 % of the bunny's one-thread prepare.
SCENELOD_AVX2_TARGET inline void encodeTwo(__m256 q0, __m256 q1, __m256 q2, VertexFaceSums* sums) {
  const __m256 one = _mm256_set1_ps(1.0f), minus_one = _mm256_set1_ps(-1.0f);
  const __m256 scale = _mm256_set1_ps(32767.0f), offset = _mm256_set1_ps(32768.5f);
  const __m256i bias = _mm256_set1_epi32(32768);
  const __m256 area = _mm256_shuffle_ps(q2, q2, _MM_SHUFFLE(1, 1, 1, 1));
  const __m256 inv = _mm256_div_ps(one, area);
  const __m256 c0 = _mm256_max_ps(_mm256_min_ps(_mm256_mul_ps(q0, inv), one), minus_one);
  const __m256 c1 = _mm256_max_ps(_mm256_min_ps(_mm256_mul_ps(q1, inv), one), minus_one);
  const __m256 c2 = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(q2, inv), minus_one), one);
  const __m256i i0 = _mm256_sub_epi32(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(c0, scale), offset)), bias);
  const __m256i i1 = _mm256_sub_epi32(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(c1, scale), offset)), bias);
  const __m256i i2 = _mm256_sub_epi32(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(c2, scale), offset)), bias);
  const __m256 face = _mm256_cmp_ps(area, _mm256_setzero_ps(), _CMP_GT_OQ);  // false for NaN, as !(area > 0)
  const __m256i keep = _mm256_castps_si256(face);
  const __m256i q07 = _mm256_and_si256(keep, _mm256_packs_epi32(i0, i1));  // per half q[0..7]
  const __m256i q8 = _mm256_and_si256(keep, i2);
  const __m256 kept_area = _mm256_and_ps(face, area);
  for (int i = 0; i < 2; ++i) {
    VertexFaceSums& o = sums[i];
    o = VertexFaceSums();
    o.area = _mm_cvtss_f32(i ? _mm256_extractf128_ps(kept_area, 1) : _mm256_castps256_ps128(kept_area));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(o.q), i ? _mm256_extracti128_si256(q07, 1) : _mm256_castsi256_si128(q07));
    o.q[8] = static_cast<int16_t>(_mm_cvtsi128_si32(i ? _mm256_extracti128_si256(q8, 1) : _mm256_castsi256_si128(q8)));
  }
}

// Two rows of 5 to 8 triangle corners (two blocks each) in one pass of 8-lane AVX2 operations:
// lanes 0..3 hold row 0's block, lanes 4..7 row 1's. Every operation the body above does on four
// lanes is here in-lane (the 256-bit unpacks, shuffles and compares work on each 128-bit half
// alone), so each half computes exactly what gradeRowLanesBody<2> computes for its row.
// The point is time: one row's work is a dependency chain (gathers -> cross products -> sqrt ->
// divisions -> pair minima -> reductions) that the reorder window hardly overlaps with the next
// row's (lane pass alone, bunny: ~80 ns per row at 700 or 1,155 instructions; a chain of 20
// dependent imuls, 18 ns, put in front of each row's position loads added 9-15 ns to the row).
// Two independent rows in the same instructions run side by side: bunny prepare on one thread
// 4.6 -> 3.3 ms. Rows are paired as they come (v, v + 1), so no reordering and no extra memory.
// Since then two paired rows are about three instructions per cycle (bunny: 1,138 instructions a
// pair in ~100 ns, one thread), so instructions count again: 764 a pair after the closed-fan test,
// the joint pair searches, the encode in lanes and the unrolled loops below.
// False (nothing computed) when either row holds an input edge. With `sums` (else null), the rows'
// face sums are encoded into sums[0] and sums[1] here, and out[i].sums is not written.
SCENELOD_AVX2_TARGET inline __attribute__((always_inline)) bool gradeTwoRowsBody(
    const glm::vec3* pos, uint32_t v0, const Incidence* row0, size_t r0, size_t r1, bool want_normals,
    LaneScratch s[2], LaneRow out[2], VertexFaceSums* sums) {
  constexpr size_t nb = 2, nc = 4;
  // rows v0 and v0 + 1, one after the other in the table (passed as scalars: the caller's arrays
  // cost 34 instructions a pair)
  const uint32_t v[2] = {v0, v0 + 1};
  const Incidence* const row[2] = {row0, row0 + r0};
  const size_t r[2] = {r0, r1};
  const __m256i none = _mm256_set1_epi32(-1);
  const __m256i self = _mm256_setr_epi32(int(v[0]), int(v[0]), int(v[0]), int(v[0]), int(v[1]), int(v[1]), int(v[1]),
                                         int(v[1]));
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3);
  const __m256i rows = _mm256_setr_epi32(int(r[0]), int(r[0]), int(r[0]), int(r[0]), int(r[1]), int(r[1]), int(r[1]),
                                         int(r[1]));
  __m256i cand[nc], valid[nb];
  __m256i edge = _mm256_setzero_si256();
  // the loops over blocks, sides and rows here and in the helpers are unrolled by pragma: GCC left
  // some rolled, and their arrays (cand, ra, rn, the pair minima) in stack memory (bunny: 859 -> 777
  // instructions a pair; 130 of the 859 were vector moves to and from the stack)
  #pragma GCC unroll 2
  for (size_t k = 0; k < nb; ++k) {
    const __m256 lo = loadTwo(row, 4 * k), hi = loadTwo(row, 4 * k + 2);
    valid[k] = _mm256_cmpgt_epi32(rows, _mm256_add_epi32(lane, _mm256_set1_epi32(int(4 * k))));
    const __m256i a = _mm256_castps_si256(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0)));
    const __m256i b = _mm256_castps_si256(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1)));
    edge = _mm256_or_si256(edge, _mm256_and_si256(valid[k], _mm256_cmpeq_epi32(b, none)));
    cand[k] = _mm256_or_si256(a, _mm256_andnot_si256(valid[k], none));
    cand[nb + k] = _mm256_or_si256(b, _mm256_andnot_si256(valid[k], none));
  }
  if (_mm256_movemask_epi8(edge)) return false;

  uint32_t row_bits[2], first[2];
  __m256 first_lanes[nc];  // per candidate block, its first occurrences of distinct neighbours
  for (int i = 0; i < 2; ++i) row_bits[i] = (1u << r[i]) - 1;
  if (closedFans(cand, valid)) {
    // every neighbour once an a and once a b: the a are the distinct neighbours, all shared
    for (int i = 0; i < 2; ++i) first[i] = row_bits[i], out[i].boundary = false;
    for (size_t k = 0; k < nb; ++k)
      first_lanes[k] = _mm256_castsi256_ps(valid[k]), first_lanes[nb + k] = _mm256_setzero_ps();
  } else {
    __m256i other[nc], earlier[nc];
    for (size_t c = 0; c < nc; ++c) other[c] = earlier[c] = _mm256_setzero_si256();
    for (size_t p = 0; p < nb; ++p) compareTwo(cand, other, earlier, p, nc);
    uint32_t valid_bits[2];
    bool need_b = false;
    for (int i = 0; i < 2; ++i) {
      valid_bits[i] = row_bits[i] | (row_bits[i] << (4 * nb));
      uint32_t b_matched = 0;
      for (size_t c = nb; c < nc; ++c) b_matched |= halfBits(earlier[c], i, c - nb);
      need_b |= (b_matched & row_bits[i]) != row_bits[i];
    }
    if (need_b)  // the b blocks compared for both rows: for a closed fan's row that finds nothing new
      for (size_t p = nb; p < nc; ++p) compareTwo(cand, other, earlier, p, nc);
    for (int i = 0; i < 2; ++i) {
      uint32_t repeat = 0, shared = 0;
      for (size_t c = 0; c < nc; ++c) repeat |= halfBits(earlier[c], i, c), shared |= halfBits(other[c], i, c);
      first[i] = valid_bits[i] & ~repeat;
      out[i].boundary = (first[i] & ~shared) != 0;
    }
    const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 1, 2, 4, 8);
    for (size_t c = 0; c < nc; ++c) {
      const int f0 = int((first[0] >> (4 * c)) & 0xfu), f1 = int((first[1] >> (4 * c)) & 0xfu);
      const __m256i fb = _mm256_setr_epi32(f0, f0, f0, f0, f1, f1, f1, f1);
      first_lanes[c] = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(fb, bit), bit));
    }
  }

  const __m256 vx = _mm256_setr_ps(pos[v[0]].x, pos[v[0]].x, pos[v[0]].x, pos[v[0]].x, pos[v[1]].x, pos[v[1]].x,
                                    pos[v[1]].x, pos[v[1]].x);
  const __m256 vy = _mm256_setr_ps(pos[v[0]].y, pos[v[0]].y, pos[v[0]].y, pos[v[0]].y, pos[v[1]].y, pos[v[1]].y,
                                    pos[v[1]].y, pos[v[1]].y);
  const __m256 vz = _mm256_setr_ps(pos[v[0]].z, pos[v[0]].z, pos[v[0]].z, pos[v[0]].z, pos[v[1]].z, pos[v[1]].z,
                                    pos[v[1]].z, pos[v[1]].z);
  const __m256 zero = _mm256_setzero_ps();
  const float* base = &pos[0].x;
  __m256 q0 = zero, q1 = zero, q2 = zero, longest = zero;
  __m256 ra[3][2] = {{zero, zero}, {zero, zero}, {zero, zero}}, rn[3][2];
  uint32_t used_bits = 0, dir_stored = 0;  // bits 8 c + 4 i + l: lane l of row i, candidate block c, has a direction
  #pragma GCC unroll 2
  for (size_t k = 0; k < nb; ++k) {
    // the corners whose positions are read, from the candidates (a valid lane's a and b): the vertex
    // itself in padding lanes (zero edges, zero area); made here rather than kept from the loads,
    // which left four more vectors live across the neighbour search
    const __m256i pad = _mm256_andnot_si256(valid[k], self);
    const __m256i ia = _mm256_or_si256(_mm256_and_si256(valid[k], cand[k]), pad);
    const __m256i ib = _mm256_or_si256(_mm256_and_si256(valid[k], cand[nb + k]), pad);
    const __m256i a3 = _mm256_add_epi32(ia, _mm256_add_epi32(ia, ia));
    const __m256i b3 = _mm256_add_epi32(ib, _mm256_add_epi32(ib, ib));
    const __m256 ax = _mm256_i32gather_ps(base, a3, 4), ay = _mm256_i32gather_ps(base + 1, a3, 4);
    const __m256 az = _mm256_i32gather_ps(base + 2, a3, 4);
    const __m256 bx = _mm256_i32gather_ps(base, b3, 4), by = _mm256_i32gather_ps(base + 1, b3, 4);
    const __m256 bz = _mm256_i32gather_ps(base + 2, b3, 4);
    const __m256 ux = _mm256_sub_ps(ax, vx), uy = _mm256_sub_ps(ay, vy), uz = _mm256_sub_ps(az, vz);
    const __m256 wx = _mm256_sub_ps(bx, vx), wy = _mm256_sub_ps(by, vy), wz = _mm256_sub_ps(bz, vz);
    const __m256 cx = _mm256_sub_ps(_mm256_mul_ps(uy, wz), _mm256_mul_ps(wy, uz));
    const __m256 cy = _mm256_sub_ps(_mm256_mul_ps(uz, wx), _mm256_mul_ps(wz, ux));
    const __m256 cz = _mm256_sub_ps(_mm256_mul_ps(ux, wy), _mm256_mul_ps(wx, uy));
    const __m256 nl = _mm256_sqrt_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(cx, cx), _mm256_mul_ps(cy, cy)), _mm256_mul_ps(cz, cz)));
    const __m256 face = _mm256_cmp_ps(nl, zero, _CMP_GT_OQ);
    const __m256 nx = _mm256_div_ps(cx, nl), ny = _mm256_div_ps(cy, nl), nz = _mm256_div_ps(cz, nl);
    const __m256 area = _mm256_mul_ps(_mm256_set1_ps(0.5f), nl);
    const __m256 anx = _mm256_mul_ps(area, nx), any = _mm256_mul_ps(area, ny), anz = _mm256_mul_ps(area, nz);
    __m256 t0 = _mm256_and_ps(face, _mm256_mul_ps(anx, nx)), t1 = _mm256_and_ps(face, _mm256_mul_ps(anx, ny));
    __m256 t2 = _mm256_and_ps(face, _mm256_mul_ps(anx, nz)), t3 = _mm256_and_ps(face, _mm256_mul_ps(any, ny));
    transposeTwo(t0, t1, t2, t3);
    __m256 t4 = _mm256_and_ps(face, _mm256_mul_ps(any, nz)), t5 = _mm256_and_ps(face, _mm256_mul_ps(anz, nz));
    __m256 t6 = _mm256_and_ps(face, anx), t7 = _mm256_and_ps(face, any);
    transposeTwo(t4, t5, t6, t7);
    const __m256 t8_9 = _mm256_and_ps(face, anz), t9_9 = _mm256_and_ps(face, area);
    const __m256 t8 = _mm256_unpacklo_ps(t8_9, t9_9), t10 = _mm256_unpackhi_ps(t8_9, t9_9);
    const __m256 t9 = _mm256_shuffle_ps(t8, t8, _MM_SHUFFLE(3, 2, 3, 2)), t11 = _mm256_shuffle_ps(t10, t10, _MM_SHUFFLE(3, 2, 3, 2));
    q0 = _mm256_add_ps(q0, t0), q1 = _mm256_add_ps(q1, t4), q2 = _mm256_add_ps(q2, t8);
    q0 = _mm256_add_ps(q0, t1), q1 = _mm256_add_ps(q1, t5), q2 = _mm256_add_ps(q2, t9);
    q0 = _mm256_add_ps(q0, t2), q1 = _mm256_add_ps(q1, t6), q2 = _mm256_add_ps(q2, t10);
    q0 = _mm256_add_ps(q0, t3), q1 = _mm256_add_ps(q1, t7), q2 = _mm256_add_ps(q2, t11);
    if (want_normals) rn[0][k] = orNan8(face, nx), rn[1][k] = orNan8(face, ny), rn[2][k] = orNan8(face, nz);
    #pragma GCC unroll 2
    for (int side = 0; side < 2; ++side) {
      const size_t c = side ? nb + k : k;
      if (!(((first[0] | first[1]) >> (4 * c)) & 0xfu)) continue;
      const __m256 dx = side ? wx : ux, dy = side ? wy : uy, dz = side ? wz : uz;
      const __m256 len = _mm256_sqrt_ps(
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz)));
      const __m256 use = _mm256_and_ps(first_lanes[c], _mm256_cmp_ps(len, zero, _CMP_GT_OQ));
      longest = _mm256_max_ps(longest, _mm256_and_ps(use, len));
      const __m256 ex = orNan8(use, _mm256_div_ps(dx, len)), ey = orNan8(use, _mm256_div_ps(dy, len));
      const __m256 ez = orNan8(use, _mm256_div_ps(dz, len));
      if (c < 2) {
        ra[0][c] = ex, ra[1][c] = ey, ra[2][c] = ez;
      } else {
        for (int i = 0; i < 2; ++i) {  // for the 4-lane pair search (a row with directions beyond block 1)
          _mm_store_ps(s[i].dir[0] + 4 * c, halfOf(ex, i));
          _mm_store_ps(s[i].dir[1] + 4 * c, halfOf(ey, i));
          _mm_store_ps(s[i].dir[2] + 4 * c, halfOf(ez, i));
        }
      }
      used_bits |= static_cast<uint32_t>(_mm256_movemask_ps(use)) << (8 * c);
      dir_stored |= 1u << c;
    }
  }
  longest = _mm256_max_ps(longest, _mm256_shuffle_ps(longest, longest, _MM_SHUFFLE(1, 0, 3, 2)));
  longest = _mm256_max_ps(longest, _mm256_shuffle_ps(longest, longest, _MM_SHUFFLE(2, 3, 0, 1)));
  if (sums) encodeTwo(q0, q1, q2, sums);
  // the directions in blocks 0 and 1 only, both stored (block 0 always is: its lane 0 is a first
  // occurrence), for both rows (a closed fan's): one pair search in registers for the two
  const bool in_regs[2] = {(used_bits & 0x0f0f0000u) == 0 && (dir_stored & 2u),
                           (used_bits & 0xf0f00000u) == 0 && (dir_stored & 2u)};
  float cos_dirs[2], cos_normals[2] = {1.0f, 1.0f};
  if (in_regs[0] && in_regs[1]) {
    minPairDotTwo(ra[0], ra[1], ra[2], cos_dirs);
  } else {
    for (int i = 0; i < 2; ++i) {
      if (in_regs[i]) {
        cos_dirs[i] = minPairDot8v(rowOf(ra[0], i), rowOf(ra[1], i), rowOf(ra[2], i));
        continue;
      }
      for (size_t c = 0; c < 2; ++c)
        if (dir_stored & (1u << c))
          for (int d = 0; d < 3; ++d) _mm_store_ps(s[i].dir[d] + 4 * c, halfOf(ra[d][c], i));
      uint32_t dir_blocks = 0;  // the candidate blocks holding some direction of row i
      for (size_t c = 0; c < nc; ++c) dir_blocks |= static_cast<uint32_t>(((used_bits >> (8 * c + 4 * i)) & 0xfu) != 0) << c;
      cos_dirs[i] = minPairDotBlocks(s[i].dir[0], s[i].dir[1], s[i].dir[2], dir_blocks);
    }
  }
  if (want_normals) minPairDotTwo(rn[0], rn[1], rn[2], cos_normals);
  for (int i = 0; i < 2; ++i) {
    out[i].longest = _mm_cvtss_f32(halfOf(longest, i));
    out[i].any_dir = (used_bits & (0x0f0f0f0fu << (4 * i))) != 0;
    out[i].cos_dirs = cos_dirs[i];
    out[i].cos_normals = cos_normals[i];
  }
  return true;
}

SCENELOD_AVX2_TARGET __attribute__((flatten)) bool gradeTwoRowsAvx2(const glm::vec3* pos, uint32_t v0,
                                                                    const Incidence* row0, size_t r0, size_t r1,
                                                                    bool want_normals, LaneScratch s[2],
                                                                    LaneRow out[2], VertexFaceSums* sums) {
  return gradeTwoRowsBody(pos, v0, row0, r0, r1, want_normals, s, out, sums);
}
#endif


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
    // per-vertex scratch, grown to the longest row seen: plain arrays written by index, no push_back
    std::vector<glm::vec3> dirs, normals;
    std::vector<uint32_t> nb, nb_tris;  // distinct neighbours, and how many incident triangles hold each
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
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
      finish(v, longest_v, ndirs > 0, ndirs > 0 ? minPairDot(dirs.data(), ndirs) : 1.0f, boundary,
             [&] { return minPairDot(normals.data(), nnormals); });
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
    if (Error e = validateMesh(in, what)) return e;
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
