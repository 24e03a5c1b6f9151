// Synthesis of one representative per cluster (Rossignac & Borrel 1993; Low & Tan 1997 §2 step 4):
// the weighted mean of the cluster's vertices, its heaviest vertex (the floating cell's centre), or
// the point minimising the sum of the quadrics of the faces around the cluster (Lindstrom 2000,
// out-of-core clustering), solved with a truncated pseudo-inverse (per rank, in closed form) so that
// directions the faces do not constrain stay at the weighted mean, then clamped to the cell.
// Also the cluster's area-weighted colour (Reddy, SCROOGE §7.3) and normal.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cluster_internal.h"
#include "test_hooks.h"

namespace scenelod {

const char* synthesisName(Synthesis s) {
  switch (s) {
    case Synthesis::kMean: return "mean";
    case Synthesis::kHeaviest: return "heaviest";
    case Synthesis::kQuadric: return "quadric";
  }
  return "unknown";
}

const char* cellShapeName(CellShape s) {
  switch (s) {
    case CellShape::kCube: return "cube";
    case CellShape::kSphere: return "sphere";
  }
  return "unknown";
}

namespace {

// VertexFaceSums::decode, inlined into synthesis's per-vertex pass
inline void decodeFaceSums(const VertexFaceSums& f, float out[9]) {
  const float s = f.area * (1.0f / 32767.0f);
#if defined(__GNUC__)
  // four at a time (the same conversions and products as the loop below)
  typedef int16_t Short4 __attribute__((vector_size(8)));
  typedef float Float4 __attribute__((vector_size(16)));
  Short4 lo, hi;
  std::memcpy(&lo, f.q, sizeof lo);
  std::memcpy(&hi, f.q + 4, sizeof hi);
  const Float4 a = __builtin_convertvector(lo, Float4) * s, b = __builtin_convertvector(hi, Float4) * s;
  std::memcpy(out, &a, sizeof a);
  std::memcpy(out + 4, &b, sizeof b);
  out[8] = float(f.q[8]) * s;
#else
  for (int k = 0; k < 9; ++k) out[k] = float(f.q[k]) * s;
#endif
}

}  // namespace

void VertexFaceSums::decode(float out[9]) const { decodeFaceSums(*this, out); }

namespace detail {

namespace {

bool g_avx2_paths = cpuHasAvx2();

}  // namespace

bool avx2Paths() { return g_avx2_paths; }

// (test_hooks.h)
bool useAvx2Paths(bool on) {
  const bool was = g_avx2_paths;
  g_avx2_paths = on && cpuHasAvx2();
  return was;
}

namespace {

// whether the quadric solve takes the clusters that need their eigenvalues four at a time in lanes
// (solveByEigenvalues4) or one at a time (solveByEigenvalues), which give the same bits
bool g_eigen_lanes = true;

}  // namespace

// (test_hooks.h)
bool useEigenvalueLanes(bool on) {
  return std::exchange(g_eigen_lanes, on);
}

namespace {

// whether synthesize takes the grouped pass at fine levels (off: the single pass at every level, the
// reference the grouped pass is compared with)
bool g_grouped = true;

}  // namespace

// (test_hooks.h)
bool useGroupedSynthesis(bool on) {
  return std::exchange(g_grouped, on);
}

namespace {

// mean weights: the vertex weight plus this fraction of the heaviest weight, so that clusters of
// flat vertices (weight 0, Low & Tan) still average instead of dividing by zero
constexpr float kMeanWeightFloor = 0.05f;
// quadric: eigenvalues below this fraction of the largest are treated as zero (singular directions)
constexpr double kEigenCutoff = 1e-3;
// the closed-form full-rank test keeps this margin above the cutoff, so that its rounding never
// decides a case the eigenvalues would decide the other way
constexpr double kFullRankMargin = 1.0 + 1e-9;

struct Quadric {
  float a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;  // sum of area * n n^T
  float b0 = 0, b1 = 0, b2 = 0;                               // sum of area * n d, planes relative to the cell centre
};

// the eigenvalues of a symmetric 3x3 matrix, largest first, in closed form (the trigonometric
// solution of the characteristic cubic): accurate to rounding relative to the largest, which is all
// the truncation below compares against
void symmetricEigenvalues(const double a[3][3], double w[3]) {
  const double q = (a[0][0] + a[1][1] + a[2][2]) * (1.0 / 3.0);
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double d0 = a[0][0] - q, d1 = a[1][1] - q, d2 = a[2][2] - q;
  const double p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
  if (!(p2 > 0.0)) {  // a multiple of the identity
    w[0] = w[1] = w[2] = q;
    return;
  }
  const double p = std::sqrt(p2 * (1.0 / 6.0)), ip = 1.0 / p;
  // det((a - q I) / p) / 2, in [-1, 1] up to rounding
  const double b00 = d0 * ip, b11 = d1 * ip, b22 = d2 * ip;
  const double b01 = a[0][1] * ip, b02 = a[0][2] * ip, b12 = a[1][2] * ip;
  const double det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02);
  const double r = std::clamp(0.5 * det, -1.0, 1.0);
  const double c = std::cos(std::acos(r) * (1.0 / 3.0));  // cos(phi), phi in [0, pi/3]
  const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
  w[0] = q + 2.0 * p * c;
  w[2] = q + p * (-c - 1.7320508075688772 * s);  // q + 2p cos(phi + 2pi/3)
  w[1] = 3.0 * q - w[0] - w[2];
}

// unit eigenvector of the symmetric `a` for the eigenvalue `l`, which must be apart from the other
// two: the widest cross product of two rows of a - l I (rank 2). Returns false when all three are tiny.
bool eigenvector(const double a[3][3], double l, double v[3]) {
  const double r0[3] = {a[0][0] - l, a[0][1], a[0][2]};
  const double r1[3] = {a[0][1], a[1][1] - l, a[1][2]};
  const double r2[3] = {a[0][2], a[1][2], a[2][2] - l};
  const double c01[3] = {r0[1] * r1[2] - r0[2] * r1[1], r0[2] * r1[0] - r0[0] * r1[2], r0[0] * r1[1] - r0[1] * r1[0]};
  const double c02[3] = {r0[1] * r2[2] - r0[2] * r2[1], r0[2] * r2[0] - r0[0] * r2[2], r0[0] * r2[1] - r0[1] * r2[0]};
  const double c12[3] = {r1[1] * r2[2] - r1[2] * r2[1], r1[2] * r2[0] - r1[0] * r2[2], r1[0] * r2[1] - r1[1] * r2[0]};
  const double n01 = c01[0] * c01[0] + c01[1] * c01[1] + c01[2] * c01[2];
  const double n02 = c02[0] * c02[0] + c02[1] * c02[1] + c02[2] * c02[2];
  const double n12 = c12[0] * c12[0] + c12[1] * c12[1] + c12[2] * c12[2];
  const double* best = c01;
  double n = n01;
  if (n02 > n) best = c02, n = n02;
  if (n12 > n) best = c12, n = n12;
  if (!(n > 0.0)) return false;
  const double inv = 1.0 / std::sqrt(n);
  for (int i = 0; i < 3; ++i) v[i] = best[i] * inv;
  return true;
}

// y = m^-1 r for a symmetric m (by the adjugate); false when m is singular
bool solveSymmetric(const double m[3][3], const double r[3], double y[3]) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[1][2];
  const double c01 = m[0][2] * m[1][2] - m[0][1] * m[2][2];
  const double c02 = m[0][1] * m[1][2] - m[0][2] * m[1][1];
  const double c11 = m[0][0] * m[2][2] - m[0][2] * m[0][2];
  const double c12 = m[0][1] * m[0][2] - m[0][0] * m[1][2];
  const double c22 = m[0][0] * m[1][1] - m[0][1] * m[0][1];
  const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
  if (!(std::fabs(det) > 0.0)) return false;
  const double id = 1.0 / det;
  y[0] = (c00 * r[0] + c01 * r[1] + c02 * r[2]) * id;
  y[1] = (c01 * r[0] + c11 * r[1] + c12 * r[2]) * id;
  y[2] = (c02 * r[0] + c12 * r[1] + c22 * r[2]) * id;
  return true;
}

// minimiser of x^T A x + 2 b^T x nearest to x0 in the directions A leaves free: x0 + A^+ r with
// r = -(A x0 + b) and A^+ the pseudo-inverse that drops eigenvalues below kEigenCutoff x the
// largest. Each rank is solved without an eigen-decomposition: full rank by the adjugate (the
// condition number is at most 1 / kEigenCutoff); rank 2 by the adjugate of A with its dropped
// direction lifted to the largest eigenvalue, applied to r without that direction; rank 1 along the
// dominant eigenvector.
glm::vec3 solveByEigenvalues(const double a[3][3], double r[3], const glm::vec3& x0);

glm::vec3 solveQuadric(const Quadric& q, const glm::vec3& x0) {
  const double a[3][3] = {{q.a00, q.a01, q.a02}, {q.a01, q.a11, q.a12}, {q.a02, q.a12, q.a22}};
  double r[3] = {-(a[0][0] * x0.x + a[0][1] * x0.y + a[0][2] * x0.z + q.b0),
                 -(a[1][0] * x0.x + a[1][1] * x0.y + a[1][2] * x0.z + q.b1),
                 -(a[2][0] * x0.x + a[2][1] * x0.y + a[2][2] * x0.z + q.b2)};
  // a zero residual (one-vertex clusters: every plane passes through x0) leaves x0 unchanged
  if (r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0) return x0;
  double y[3] = {0.0, 0.0, 0.0};
  // full rank without the eigenvalues (most clusters): the smallest eigenvalue is at least
  // det / c1 (c1 the sum of the principal 2x2 minors, >= l1 l2) and the largest at most the trace
  {
    const double tr = a[0][0] + a[1][1] + a[2][2];
    const double m00 = a[1][1] * a[2][2] - a[1][2] * a[1][2], m11 = a[0][0] * a[2][2] - a[0][2] * a[0][2],
                 m22 = a[0][0] * a[1][1] - a[0][1] * a[0][1];
    const double c1 = m00 + m11 + m22;
    const double det = a[0][0] * m00 + a[0][1] * (a[0][2] * a[1][2] - a[0][1] * a[2][2]) +
                       a[0][2] * (a[0][1] * a[1][2] - a[0][2] * a[1][1]);
    if (tr > 0.0 && c1 > 0.0 && det >= kFullRankMargin * kEigenCutoff * tr * c1 && solveSymmetric(a, r, y))
      return glm::vec3(float(x0.x + y[0]), float(x0.y + y[1]), float(x0.z + y[2]));
  }
  return solveByEigenvalues(a, r, x0);
}

// solveQuadric where its closed-form full-rank test fails: the rank from the eigenvalues. `a` and
// `r` as solveQuadric makes them (r is consumed).
glm::vec3 solveByEigenvalues(const double a[3][3], double r[3], const glm::vec3& x0) {
  double y[3] = {0.0, 0.0, 0.0};
  double w[3];
  symmetricEigenvalues(a, w);
  // A is a sum of area x n n^T: positive semi-definite, so the largest eigenvalue is the largest in size
  const double wmax = std::max(w[0], -w[2]);
  if (!(wmax > 0.0)) return x0;
  const double cut = kEigenCutoff * wmax;
  bool solved = false;
  if (std::fabs(w[2]) >= cut && std::fabs(w[1]) >= cut) {
    solved = solveSymmetric(a, r, y);
  } else if (std::fabs(w[1]) >= cut) {
    double v[3];
    if (eigenvector(a, w[2], v)) {
      const double d = v[0] * r[0] + v[1] * r[1] + v[2] * r[2];
      double m[3][3];
      for (int i = 0; i < 3; ++i) {
        r[i] -= d * v[i];
        for (int j = 0; j < 3; ++j) m[i][j] = a[i][j] + (w[0] - w[2]) * v[i] * v[j];
      }
      solved = solveSymmetric(m, r, y);
    }
  }
  if (!solved) {  // rank 1, or the two small eigenvalues too close to tell apart: the dominant direction
    double v[3];
    if (!eigenvector(a, w[0], v)) return x0;
    const double d = (v[0] * r[0] + v[1] * r[1] + v[2] * r[2]) / w[0];
    for (int i = 0; i < 3; ++i) y[i] = v[i] * d;
  }
  return glm::vec3(float(x0.x + y[0]), float(x0.y + y[1]), float(x0.z + y[2]));
}

// Laid out for four-wide adds: each group of four floats below gets one vector add per vertex,
// lane by lane the same additions (and products) as the scalar form in the #else branch.
struct Sums {          // 92 bytes per cluster
  glm::vec3 centre;    // the heaviest vertex, the local origin
  float ws[4] = {0, 0, 0, 0};  // sum of weight x offset (x, y, z), then the sum of weights
  float sc[4] = {0, 0, 0, 0};  // sum of offsets (x, y, z), then the vertex count
  // quadric: sum of area n n^T (xx, xy, xz, yy, yz, zz), then the normal: sum of area n (x, y,
  // z), then the quadric's linear part: sum of area n d, planes relative to the centre (x, y, z)
  float q[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  Sums() = default;  // centre unset (the single pass sets it)
  explicit Sums(const glm::vec3& c) : centre(c) {}
  void reset(const glm::vec3& c) {  // as constructed from c (assigning a new Sums made a copy)
    centre = c;
    std::fill(ws, ws + 4, 0.0f), std::fill(sc, sc + 4, 0.0f), std::fill(q, q + 12, 0.0f);
  }
};

// the per-vertex inputs of the sums as plain pointers: the sums are stored through __m128, which may
// alias anything, so members of the PreparedMesh were reloaded after every vertex's stores
struct VertexArrays {
  const glm::vec3* pos;
  const float* weights;
  const VertexFaceSums* face_sums;
  const glm::vec4* face_colors;  // with colours only
  const glm::vec3* colors;
};

inline VertexArrays vertexArrays(const PreparedMesh& p) {
  return {p.mesh->positions.data(), p.weights.data(), p.face_sums.data(), p.face_colors.data(), p.mesh->colors.data()};
}

#if defined(__SSE2__)
// one vertex's terms of its cluster's sums, one register per four-float group of Sums (ws, sc,
// q[0..3], q[4..7], q[8..11]); q0, q4 and q8 are zero without face sums
// q0..q7 as one eight-float generic vector: in the AVX2 variants one sign extension, conversion,
// product and add of 256 bits (vpmovsxwd, vcvtdq2ps, vmulps, vaddps), where the SSE2 form takes
// two unpacks, two shifts and two of each of the others; the baseline lowers it to its four-wide
// operations (the same per lane, so the same bits either way)
typedef float Float8 __attribute__((vector_size(32)));
typedef int32_t Int8 __attribute__((vector_size(32)));
typedef int16_t Short8 __attribute__((vector_size(16)));
typedef float Float4 __attribute__((vector_size(16)));
struct Terms {
  __m128 ws, sc;
  Float8 q07;
  __m128 q8;
};

// `centre`: the cluster's centre in lanes 0-2 (lane 3 is masked off)
SCENELOD_ALWAYS_INLINE Terms vertexTerms(const VertexArrays& in, size_t v, __m128 centre, bool have_face_sums, bool quadric) {
  const __m128 xyz_mask = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
  const __m128 one_w = _mm_set_ps(1.0f, 0.0f, 0.0f, 0.0f);
  const __m128 sign = _mm_set1_ps(-0.0f);
  const glm::vec3* pos = in.pos;
  const float w = in.weights[v];
  Terms t;
  // d4 = (offset, 1): (ws, w) += d4 * w, (sum, count) += d4. The position is loaded as 8 + 4 bytes
  // (the last vertex ends the array).
  const __m128 pv = _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&pos[v].x)),
                                  _mm_load_ss(&pos[v].z));
  const __m128 d = _mm_sub_ps(pv, centre);
  const __m128 d4 = _mm_or_ps(_mm_and_ps(d, xyz_mask), one_w);
  t.ws = _mm_mul_ps(d4, _mm_set1_ps(w));
  t.sc = d4;
  t.q07 = Float8{};
  t.q8 = _mm_setzero_ps();
  if (have_face_sums) {
    // decodeFaceSums in lanes: q[0..7] sign-extended to int32, converted and scaled
    const VertexFaceSums& f = in.face_sums[v];
    const float scale = f.area * (1.0f / 32767.0f);
    Short8 q16;
    std::memcpy(&q16, f.q, sizeof q16);
    t.q07 = __builtin_convertvector(__builtin_convertvector(q16, Int8), Float8) * scale;
    const __m128 lo = __m128(Float4(__builtin_shufflevector(t.q07, t.q07, 0, 1, 2, 3)));
    const __m128 hi = __m128(Float4(__builtin_shufflevector(t.q07, t.q07, 4, 5, 6, 7)));
    const float fa8 = float(f.q[8]) * scale;
    // last group (normal z, b x, b y, b z) += (fa8, -t): b_i -= t_i = (A_i0 d.x + A_i1 d.y) + A_i2 d.z
    // (the quadric part is unused but harmless for mean)
    __m128 last = _mm_set_ss(fa8);
    if (quadric) {
      const __m128 col0 = _mm_castsi128_ps(_mm_slli_si128(_mm_castps_si128(lo), 4));  // (_, xx, xy, xz)
      const __m128 t34 = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(0, 0, 3, 3));               // (yy, yy, yz, yz)
      const __m128 col1 = _mm_shuffle_ps(lo, t34, _MM_SHUFFLE(2, 0, 1, 1));             // (_, xy, yy, yz)
      const __m128 col2 = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(1, 0, 2, 2));              // (_, xz, yz, zz)
      const __m128 dx = _mm_shuffle_ps(d, d, 0x00), dy = _mm_shuffle_ps(d, d, 0x55), dz = _mm_shuffle_ps(d, d, 0xaa);
      const __m128 tb = _mm_add_ps(_mm_add_ps(_mm_mul_ps(col0, dx), _mm_mul_ps(col1, dy)), _mm_mul_ps(col2, dz));
      last = _mm_move_ss(_mm_xor_ps(tb, sign), last);
    }
    t.q8 = last;
  }
  return t;
}
#endif

// adds vertex v to its cluster's sums (the single pass and the grouped one make the same
// operations in the same order)
SCENELOD_ALWAYS_INLINE void addVertex(const VertexArrays& in, size_t v, bool have_face_sums, bool quadric, Sums& s) {
#if defined(__SSE2__)
  // the centre is loaded as 8 + 4 bytes: a 16-byte load would take in ws[0], which the previous
  // vertex may just have stored (a load straddling a pending store waits for it to retire)
  const __m128 centre = _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&s.centre.x)),
                                      _mm_load_ss(&s.centre.z));
  const Terms t = vertexTerms(in, v, centre, have_face_sums, quadric);
  _mm_storeu_ps(s.ws, _mm_add_ps(_mm_loadu_ps(s.ws), t.ws));
  _mm_storeu_ps(s.sc, _mm_add_ps(_mm_loadu_ps(s.sc), t.sc));
  if (have_face_sums) {
    Float8 q07;
    std::memcpy(&q07, s.q, sizeof q07);
    q07 += t.q07;
    std::memcpy(s.q, &q07, sizeof q07);
    _mm_storeu_ps(s.q + 8, _mm_add_ps(_mm_loadu_ps(s.q + 8), t.q8));
  }
#else
  const float w = in.weights[v];
  const glm::vec3 d = in.pos[v] - s.centre;
  s.ws[0] += d.x * w, s.ws[1] += d.y * w, s.ws[2] += d.z * w;
  s.ws[3] += w;
  s.sc[0] += d.x, s.sc[1] += d.y, s.sc[2] += d.z;
  s.sc[3] += 1.0f;
  if (have_face_sums) {
    float fa[9];  // quadric xx, xy, xz, yy, yz, zz, then the normal sum
    decodeFaceSums(in.face_sums[v], fa);
    for (int k = 0; k < 9; ++k) s.q[k] += fa[k];  // (the quadric part is unused but harmless for mean)
    if (quadric) {
      // the vertex lies on all its faces' planes: relative to the centre, b = -A d
      s.q[9] -= fa[0] * d.x + fa[1] * d.y + fa[2] * d.z;
      s.q[10] -= fa[1] * d.x + fa[3] * d.y + fa[4] * d.z;
      s.q[11] -= fa[2] * d.x + fa[4] * d.y + fa[5] * d.z;
    }
  }
#endif
}

// one cluster's weighted mean (relative to the centre; the representative itself without a
// quadric) and unit normal: the scalar form of the four-lane code in synthesize
SCENELOD_ALWAYS_INLINE void meanAndNormal(const Sums& s, float heaviest_weight, bool mean, bool quadric, glm::vec3& position,
                          glm::vec3& normal_out) {
  glm::vec3 x(0.0f);  // relative to centre
  if (mean) {
    const float floor_w = kMeanWeightFloor * heaviest_weight;
    const glm::vec3 wsum(s.ws[0], s.ws[1], s.ws[2]), sum(s.sc[0], s.sc[1], s.sc[2]);
    const float total = s.ws[3] + floor_w * s.sc[3];
    x = total > 0.0f ? (wsum + floor_w * sum) / total : sum / s.sc[3];
  }
  position = quadric ? x : s.centre + x;
  const glm::vec3 normal(s.q[6], s.q[7], s.q[8]);
  const float nl = glm::length(normal);
  normal_out = nl > 0.0f ? normal / nl : glm::vec3(0.0f, 0.0f, 1.0f);
}

#if defined(__SSE2__)
// meanAndNormal for the four clusters s[0..3] (heaviest vertices h[0..3]), in lanes: its operations
// lane by lane, both sides of its selects computed and chosen by mask, so bit-identical, with a
// quarter of the divisions and roots
SCENELOD_ALWAYS_INLINE void meanAndNormal4(const Sums* s, const float* weights, const uint32_t* h, bool mean, bool quadric,
                           glm::vec3* positions, glm::vec3* normals) {
  auto store3 = [](glm::vec3& dst, __m128 v) {  // 12 bytes, not past the array's end
    _mm_storel_pi(reinterpret_cast<__m64*>(&dst.x), v);
    _mm_store_ss(&dst.z, _mm_movehl_ps(v, v));
  };
  const __m128 zero = _mm_setzero_ps(), floor_scale = _mm_set1_ps(kMeanWeightFloor);
  __m128 wx = _mm_loadu_ps(s[0].ws), wy = _mm_loadu_ps(s[1].ws), wz = _mm_loadu_ps(s[2].ws), wt = _mm_loadu_ps(s[3].ws);
  __m128 sx = _mm_loadu_ps(s[0].sc), sy = _mm_loadu_ps(s[1].sc), sz = _mm_loadu_ps(s[2].sc), n = _mm_loadu_ps(s[3].sc);
  __m128 cx = _mm_loadu_ps(&s[0].centre.x), cy = _mm_loadu_ps(&s[1].centre.x);
  __m128 cz = _mm_loadu_ps(&s[2].centre.x), cw = _mm_loadu_ps(&s[3].centre.x);
  __m128 nx = _mm_loadu_ps(s[0].q + 6), ny = _mm_loadu_ps(s[1].q + 6), nz = _mm_loadu_ps(s[2].q + 6);
  __m128 nw = _mm_loadu_ps(s[3].q + 6);
  _MM_TRANSPOSE4_PS(wx, wy, wz, wt);
  _MM_TRANSPOSE4_PS(sx, sy, sz, n);
  _MM_TRANSPOSE4_PS(cx, cy, cz, cw);
  _MM_TRANSPOSE4_PS(nx, ny, nz, nw);
  __m128 xx = zero, xy = zero, xz = zero;
  if (mean) {
    const __m128 fw = _mm_mul_ps(floor_scale, _mm_set_ps(weights[h[3]], weights[h[2]], weights[h[1]], weights[h[0]]));
    const __m128 total = _mm_add_ps(wt, _mm_mul_ps(fw, n));
    const __m128 pos = _mm_cmpgt_ps(total, zero);
    auto sel = [&](__m128 w, __m128 sm) {
      const __m128 weighted = _mm_div_ps(_mm_add_ps(w, _mm_mul_ps(fw, sm)), total);
      return _mm_or_ps(_mm_and_ps(pos, weighted), _mm_andnot_ps(pos, _mm_div_ps(sm, n)));
    };
    xx = sel(wx, sx), xy = sel(wy, sy), xz = sel(wz, sz);
  }
  if (!quadric) xx = _mm_add_ps(cx, xx), xy = _mm_add_ps(cy, xy), xz = _mm_add_ps(cz, xz);
  const __m128 nl = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, nx), _mm_mul_ps(ny, ny)), _mm_mul_ps(nz, nz)));
  const __m128 npos = _mm_cmpgt_ps(nl, zero);
  nx = _mm_and_ps(npos, _mm_div_ps(nx, nl));
  ny = _mm_and_ps(npos, _mm_div_ps(ny, nl));
  nz = _mm_or_ps(_mm_and_ps(npos, _mm_div_ps(nz, nl)), _mm_andnot_ps(npos, _mm_set1_ps(1.0f)));
  __m128 xw = zero;
  _MM_TRANSPOSE4_PS(xx, xy, xz, xw);
  store3(positions[0], xx), store3(positions[1], xy), store3(positions[2], xz), store3(positions[3], xw);
  nw = zero;
  _MM_TRANSPOSE4_PS(nx, ny, nz, nw);
  store3(normals[0], nx), store3(normals[1], ny), store3(normals[2], nz), store3(normals[3], nw);
}
#endif

inline Quadric quadricOf(const Sums& s) {
  Quadric q;
  q.a00 = s.q[0], q.a01 = s.q[1], q.a02 = s.q[2], q.a11 = s.q[3], q.a12 = s.q[4], q.a22 = s.q[5];
  q.b0 = s.q[9], q.b1 = s.q[10], q.b2 = s.q[11];
  return q;
}

// the solved point x (relative to the centre), clamped to the cell: the representative
SCENELOD_ALWAYS_INLINE glm::vec3 clampToCell(const Sums& s, glm::vec3 x, const Assignment& a, float half) {
  glm::vec3 lo, hi;
  a.cellBox(s.centre, lo, hi);
  x = glm::clamp(x, lo - s.centre, hi - s.centre);
  if (!a.uniform && a.shape == CellShape::kSphere) {
    const float l = glm::length(x);
    if (l > half) x *= half / l;
  }
  return s.centre + x;
}

// the quadric's minimiser from x0 (relative to the centre), clamped to the cell: the representative
inline glm::vec3 quadricRepresentative(const Sums& s, const glm::vec3& x0, const Assignment& a, float half) {
  return clampToCell(s, solveQuadric(quadricOf(s), x0), a, half);
}

#if defined(__SSE2__)
// The quadric solve four clusters at a time, in GCC generic vectors of four doubles: one 256-bit
// operation a step in the AVX2 variants, two SSE2 ones in the baseline (GCC lowers them), the same
// operations lane by lane either way. The square roots and lane masks go through SSE2 halves
// (generic vectors have neither). On the 1 M sphere's 10 % level, where nearly every cluster needs
// the eigenvalues, the solve took 410 instructions a cluster as pairs for the cheap cases and then
// one cluster at a time, 277 as pairs throughout, and takes 209 so (acos and cos not counted).
// (32-byte vectors are passed by reference and returned through references: by value, without AVX,
// GCC warns that the ABI changes, -Wpsabi)
typedef double Double4 __attribute__((vector_size(32)));
typedef int64_t Mask4 __attribute__((vector_size(32)));
typedef float Float4v __attribute__((vector_size(16)));

// (selects are the vector conditional m ? a : b, lane by lane; |a| is a & kAbs4)
const Mask4 kAbs4 = {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX};
SCENELOD_ALWAYS_INLINE void sqrt4(Double4& a) {  // in place
  __m128d lo, hi;
  std::memcpy(&lo, &a, 16);
  std::memcpy(&hi, reinterpret_cast<const char*>(&a) + 16, 16);
  lo = _mm_sqrt_pd(lo), hi = _mm_sqrt_pd(hi);
  std::memcpy(&a, &lo, 16);
  std::memcpy(reinterpret_cast<char*>(&a) + 16, &hi, 16);
}
// the lanes' sign bits (a test of each lane took 28 instructions for the four)
SCENELOD_ALWAYS_INLINE int bits4(const Mask4& m) {
  __m128d lo, hi;
  std::memcpy(&lo, &m, 16);
  std::memcpy(&hi, reinterpret_cast<const char*>(&m) + 16, 16);
  return _mm_movemask_pd(lo) | _mm_movemask_pd(hi) << 2;
}

// eigenvector in four lanes: the same cross products, norms and first-widest choice (strict >, as
// there), the unit vector in v; in ok the mask of the lanes where the widest norm is > 0
SCENELOD_ALWAYS_INLINE void eigenvector4(const Double4 a[6], const Double4& l, Double4 v[3], Mask4& ok) {
  const Double4 r0[3] = {a[0] - l, a[1], a[2]};
  const Double4 r1[3] = {a[1], a[3] - l, a[4]};
  const Double4 r2[3] = {a[2], a[4], a[5] - l};
  auto cross = [](const Double4* p, const Double4* q, Double4* c) {
    c[0] = p[1] * q[2] - p[2] * q[1];
    c[1] = p[2] * q[0] - p[0] * q[2];
    c[2] = p[0] * q[1] - p[1] * q[0];
  };
  Double4 c01[3], c02[3], c12[3];
  cross(r0, r1, c01), cross(r0, r2, c02), cross(r1, r2, c12);
  Double4 n = c01[0] * c01[0] + c01[1] * c01[1] + c01[2] * c01[2];
  const Double4 n02 = c02[0] * c02[0] + c02[1] * c02[1] + c02[2] * c02[2];
  const Double4 n12 = c12[0] * c12[0] + c12[1] * c12[1] + c12[2] * c12[2];
  const Mask4 g02 = n02 > n;
  n = g02 ? n02 : n;
  const Mask4 g12 = n12 > n;
  n = g12 ? n12 : n;
  Double4 root = n;
  sqrt4(root);
  const Double4 inv = 1.0 / root;
  for (int i = 0; i < 3; ++i) v[i] = (g12 ? c12[i] : (g02 ? c02[i] : c01[i])) * inv;
  ok = n > 0.0;
}

// solveSymmetric's y = m^-1 r in four lanes (m's upper triangle m00, m01, m02, m11, m12, m22), with
// its operations; in ok the mask of the lanes where m is not singular
SCENELOD_ALWAYS_INLINE void solveSymmetric4(const Double4 m[6], const Double4 r[3], Double4 y[3], Mask4& ok) {
  const Double4 c00 = m[3] * m[5] - m[4] * m[4];
  const Double4 c01 = m[2] * m[4] - m[1] * m[5];
  const Double4 c02 = m[1] * m[4] - m[2] * m[3];
  const Double4 c11 = m[0] * m[5] - m[2] * m[2];
  const Double4 c12 = m[1] * m[2] - m[0] * m[4];
  const Double4 c22 = m[0] * m[3] - m[1] * m[1];
  const Double4 det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  const Double4 id = 1.0 / det;
  y[0] = (c00 * r[0] + c01 * r[1] + c02 * r[2]) * id;
  y[1] = (c01 * r[0] + c11 * r[1] + c12 * r[2]) * id;
  y[2] = (c02 * r[0] + c12 * r[1] + c22 * r[2]) * id;
  ok = Double4(Mask4(det) & kAbs4) > 0.0;
}

// solveByEigenvalues in four lanes, for the lanes of `want` (a: a00, a01, a02, a11, a12, a22; r the
// residual; xd the means widened; full_x: the full-rank solution, as solveSymmetric(a, r) gives it,
// and its mask): the scalar form's operations lane by lane in its order (its std::clamp, std::max,
// the rank-2 lift of the upper triangle, a failed rank-2 solve falling back to rank 1 with the
// reduced residual), its branches as masks (each case skipped when no lane takes it), acos and cos
// called per lane as it calls them, so bit-identical. The solved lanes' representatives (relative
// to the centre) go to xs as floats; returns their bits (the others keep x0).
SCENELOD_ALWAYS_INLINE int solveByEigenvalues4(const Double4 a[6], const Double4 r[3], const Double4 xd[3],
                                               const Float4v full_x[3], const Mask4& full_ok, int want,
                                               Float4v xs[3]) {
  const Double4 a00 = a[0], a01 = a[1], a02 = a[2], a11 = a[3], a12 = a[4], a22 = a[5];
  const Double4 q = (a00 + a11 + a22) * (1.0 / 3.0);
  const Double4 p1 = a01 * a01 + a02 * a02 + a12 * a12;
  const Double4 d0 = a00 - q, d1 = a11 - q, d2 = a22 - q;
  const Double4 p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
  const Mask4 spread = p2 > 0.0;
  Double4 p = p2 * (1.0 / 6.0);
  sqrt4(p);
  const Double4 ip = 1.0 / p;
  const Double4 b00 = d0 * ip, b11 = d1 * ip, b22 = d2 * ip;
  const Double4 b01 = a01 * ip, b02 = a02 * ip, b12 = a12 * ip;
  const Double4 det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02);
  const Double4 half_det = 0.5 * det;
  const Double4 minus_one = Double4{} - 1.0, one = Double4{} + 1.0;
  const Double4 rc = half_det < minus_one ? minus_one : (one < half_det ? one : half_det);
  alignas(32) double rv[4], cv[4] = {1.0, 1.0, 1.0, 1.0};
  std::memcpy(rv, &rc, sizeof rv);
  const int acos_lanes = bits4(spread) & want;
  for (int k = 0; k < 4; ++k)
    if (acos_lanes & (1 << k)) cv[k] = std::cos(std::acos(rv[k]) * (1.0 / 3.0));
  Double4 c;
  std::memcpy(&c, cv, sizeof c);
  const Double4 sq = 1.0 - c * c;
  Double4 sn = sq > 0.0 ? sq : Double4{};  // std::max(0, x): (0 < x ? x : 0)
  sqrt4(sn);
  Double4 w0 = q + 2.0 * p * c;
  Double4 w2 = q + p * (-c - 1.7320508075688772 * sn);
  Double4 w1 = 3.0 * q - w0 - w2;
  w0 = spread ? w0 : q, w1 = spread ? w1 : q, w2 = spread ? w2 : q;
  const Double4 minus_w2 = -w2;
  const Double4 wmax = w0 < minus_w2 ? minus_w2 : w0;
  const Mask4 live = wmax > 0.0;
  const Double4 cut = kEigenCutoff * wmax;
  const Mask4 big1 = Double4(Mask4(w1) & kAbs4) >= cut, big2 = Double4(Mask4(w2) & kAbs4) >= cut;
  const Mask4 rank3 = big1 & big2, rank2 = big1 & ~big2;
  Mask4 done = ~live, solved = Mask4{};
  for (int k = 0; k < 4; ++k)
    if (!(want & (1 << k))) done[k] = -1;  // lanes not asked for: never taken
  Float4v out[3] = {Float4v{}, Float4v{}, Float4v{}};
  typedef int32_t Mask4f __attribute__((vector_size(16)));
  auto take = [&](const Mask4& mask, const Float4v v[3]) {
    const Mask4 m = mask & ~done;
    const Mask4f mf = __builtin_convertvector(m, Mask4f);
    for (int i = 0; i < 3; ++i) out[i] = Float4v((Mask4f(v[i]) & mf) | (Mask4f(out[i]) & ~mf));
    done |= m, solved |= m;
  };
  auto finish = [&](const Double4 y[3], Float4v v[3]) {
    for (int i = 0; i < 3; ++i) v[i] = __builtin_convertvector(xd[i] + y[i], Float4v);
  };
  take(rank3 & full_ok, full_x);
  Double4 rs[3] = {r[0], r[1], r[2]};
  if (bits4(rank2 & ~done)) {
    Double4 v[3];
    Mask4 vok;
    eigenvector4(a, w2, v, vok);
    vok &= rank2;
    const Double4 d = v[0] * r[0] + v[1] * r[1] + v[2] * r[2];
    Double4 r2[3];
    for (int i = 0; i < 3; ++i) r2[i] = r[i] - d * v[i];
    const Double4 lift = w0 - w2;
    Double4 lv[3];
    for (int i = 0; i < 3; ++i) lv[i] = lift * v[i];
    const Double4 m[6] = {a00 + lv[0] * v[0], a01 + lv[0] * v[1], a02 + lv[0] * v[2],
                          a11 + lv[1] * v[1], a12 + lv[1] * v[2], a22 + lv[2] * v[2]};
    Double4 y[3];
    Mask4 ok;
    solveSymmetric4(m, r2, y, ok);
    ok &= vok;
    Float4v x2[3];
    finish(y, x2);
    take(ok, x2);
    for (int i = 0; i < 3; ++i) rs[i] = vok ? r2[i] : r[i];
  }
  if (bits4(~done)) {
    Double4 v[3];
    Mask4 vok;
    eigenvector4(a, w0, v, vok);
    const Double4 d = (v[0] * rs[0] + v[1] * rs[1] + v[2] * rs[2]) / w0;
    Double4 y[3];
    for (int i = 0; i < 3; ++i) y[i] = v[i] * d;
    Float4v x1[3];
    finish(y, x1);
    take(vok, x1);
  }
  for (int i = 0; i < 3; ++i) xs[i] = out[i];
  return bits4(solved);
}

// solveQuadric for the clusters s[0..3] (means x0[0..3]) in four lanes: the zero residual (x0) and
// the closed-form full rank with its operations in its order (the adjugate's cofactors are the
// full-rank test's minors, computed once), so bit-identical; the lanes in neither case (a rank the
// eigenvalues decide: about a quarter of the clusters at the bunny's 50 % level, nearly all on the
// 1 M sphere's 10 %) go to solveByEigenvalues4 together, or one at a time to solveByEigenvalues
// with the lanes off
SCENELOD_ALWAYS_INLINE void solveQuadric4Body(const Sums* s, const glm::vec3* x0, glm::vec3* x) {
  // the four clusters' floats transposed into lanes, then widened (a lane insert each took twice the
  // instructions)
  auto widen = [](__m128 v, Double4& d) {
    Float4v f;
    std::memcpy(&f, &v, sizeof f);
    d = __builtin_convertvector(f, Double4);
  };
  auto load3 = [](const glm::vec3& v) {  // (x, y, z, 0), 8 + 4 bytes as they were stored
    return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&v.x)), _mm_load_ss(&v.z));
  };
  __m128 q00 = _mm_loadu_ps(s[0].q), q01 = _mm_loadu_ps(s[1].q), q02 = _mm_loadu_ps(s[2].q), q03 = _mm_loadu_ps(s[3].q);
  __m128 q40 = _mm_loadu_ps(s[0].q + 4), q41 = _mm_loadu_ps(s[1].q + 4), q42 = _mm_loadu_ps(s[2].q + 4),
         q43 = _mm_loadu_ps(s[3].q + 4);
  __m128 q80 = _mm_loadu_ps(s[0].q + 8), q81 = _mm_loadu_ps(s[1].q + 8), q82 = _mm_loadu_ps(s[2].q + 8),
         q83 = _mm_loadu_ps(s[3].q + 8);
  __m128 m0 = load3(x0[0]), m1 = load3(x0[1]), m2 = load3(x0[2]), m3 = load3(x0[3]);
  _MM_TRANSPOSE4_PS(q00, q01, q02, q03);  // xx, xy, xz, yy
  _MM_TRANSPOSE4_PS(q40, q41, q42, q43);  // yz, zz, (normal x, y)
  _MM_TRANSPOSE4_PS(q80, q81, q82, q83);  // (normal z), b0, b1, b2
  _MM_TRANSPOSE4_PS(m0, m1, m2, m3);      // x, y, z, 0
  Double4 a00, a01, a02, a11, a12, a22, b0, b1, b2, xx, xy, xz;
  widen(q00, a00), widen(q01, a01), widen(q02, a02), widen(q03, a11), widen(q40, a12), widen(q41, a22);
  widen(q81, b0), widen(q82, b1), widen(q83, b2), widen(m0, xx), widen(m1, xy), widen(m2, xz);
  const Double4 r0 = -(a00 * xx + a01 * xy + a02 * xz + b0);
  const Double4 r1 = -(a01 * xx + a11 * xy + a12 * xz + b1);
  const Double4 r2 = -(a02 * xx + a12 * xy + a22 * xz + b2);
  const Mask4 still = (r0 == 0.0) & (r1 == 0.0) & (r2 == 0.0);
  const Double4 tr = a00 + a11 + a22;
  const Double4 m00 = a11 * a22 - a12 * a12, m11 = a00 * a22 - a02 * a02, m22 = a00 * a11 - a01 * a01;
  const Double4 c01 = a02 * a12 - a01 * a22, c02 = a01 * a12 - a02 * a11, c12 = a01 * a02 - a00 * a12;
  const Double4 c1 = m00 + m11 + m22;
  const Double4 det = a00 * m00 + a01 * c01 + a02 * c02;
  const Double4 thr = kFullRankMargin * kEigenCutoff * tr * c1;
  const Mask4 full = (tr > 0.0) & (c1 > 0.0) & (det >= thr) & (det > 0.0);
  const Double4 id = 1.0 / det;
  const Float4v px = __builtin_convertvector(xx + (m00 * r0 + c01 * r1 + c02 * r2) * id, Float4v);
  const Float4v py = __builtin_convertvector(xy + (c01 * r0 + m11 * r1 + c12 * r2) * id, Float4v);
  const Float4v pz = __builtin_convertvector(xz + (c02 * r0 + c12 * r1 + m22 * r2) * id, Float4v);
  const int still_mask = bits4(still), full_mask = bits4(full);
  const int eigen = ~(still_mask | full_mask) & 15;
  int lanes = 0;
  Float4v ex[3] = {Float4v{}, Float4v{}, Float4v{}};
  if (eigen && g_eigen_lanes) {
    const Double4 am[6] = {a00, a01, a02, a11, a12, a22}, rm[3] = {r0, r1, r2}, xm[3] = {xx, xy, xz};
    const Float4v fx[3] = {px, py, pz};
    const Mask4 det_ok = Double4(Mask4(det) & kAbs4) > 0.0;  // solveSymmetric's test
    lanes = solveByEigenvalues4(am, rm, xm, fx, det_ok, eigen, ex);
  }
  if (g_eigen_lanes) {
    // each lane's result chosen by mask, the cases of the loop below in its order (x0 for a zero
    // residual, else the full-rank solution, else the eigenvalue lanes' or x0), the same floats;
    // a branch per lane mispredicted where full rank and eigenvalues mix at random (the bunny's 50 %
    // level: 60 / 40 in the listed clusters)
    typedef int32_t Mask4i __attribute__((vector_size(16)));
    const Mask4i bit = {1, 2, 4, 8};
    const Mask4i use_full = ((Mask4i{} + (full_mask & ~still_mask)) & bit) != 0;
    const Mask4i use_eigen = ((Mask4i{} + lanes) & bit) != 0;
    const Float4v p[3] = {px, py, pz}, x0v[3] = {Float4v(m0), Float4v(m1), Float4v(m2)};
    __m128 c[4];
    for (int i = 0; i < 3; ++i) {
      const Float4v v = use_full ? p[i] : (use_eigen ? ex[i] : x0v[i]);
      c[i] = __m128(v);
    }
    c[3] = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(c[0], c[1], c[2], c[3]);
    for (int k = 0; k < 4; ++k) {  // 12 bytes each
      _mm_storel_pi(reinterpret_cast<__m64*>(&x[k].x), c[k]);
      _mm_store_ss(&x[k].z, _mm_movehl_ps(c[k], c[k]));
    }
    return;
  }
  for (int k = 0; k < 4; ++k) {  // the lanes off (test hook): the eigenvalue cases one cluster at a time
    if (still_mask & (1 << k)) {
      x[k] = x0[k];
    } else if (full_mask & (1 << k)) {
      x[k] = glm::vec3(px[k], py[k], pz[k]);
    } else if (g_eigen_lanes) {
      x[k] = (lanes & (1 << k)) ? glm::vec3(ex[0][k], ex[1][k], ex[2][k]) : x0[k];
    } else {
      const double a3[3][3] = {{a00[k], a01[k], a02[k]}, {a01[k], a11[k], a12[k]}, {a02[k], a12[k], a22[k]}};
      double r3[3] = {r0[k], r1[k], r2[k]};
      x[k] = solveByEigenvalues(a3, r3, x0[k]);
    }
  }
}
// the baseline and the AVX2 variant (see synthesizeGrouped); avx2 picks the latter
void solveQuadric4Sse2(const Sums* s, const glm::vec3* x0, glm::vec3* x) { solveQuadric4Body(s, x0, x); }
SCENELOD_AVX2_TARGET void solveQuadric4Avx2(const Sums* s, const glm::vec3* x0, glm::vec3* x) {
  solveQuadric4Body(s, x0, x);
}
template <bool avx2>
inline void solveQuadric4(const Sums* s, const glm::vec3* x0, glm::vec3* x) {
  if (avx2) solveQuadric4Avx2(s, x0, x);
  else solveQuadric4Sse2(s, x0, x);
}

// clampToCell for the clusters s[0..3] and their solved points x[0..3], in lanes where the cells
// float (a uniform grid's take the scalar form: floor has no SSE2 instruction; so do all with the
// eigenvalue lanes off, the one-cluster reference): cellBox's bounds, glm::clamp's max then min
// ((x < lo) ? lo : x is maxps(lo, x), (hi < t) ? hi : t is minps(hi, t), NaN included), the
// sphere's length ((x x + y y) + z z, as glm::dot), division and product, then the centre added:
// the same operations lane by lane. Per cluster 30 instructions as the scalar form, about 10 so.
SCENELOD_ALWAYS_INLINE void clampToCell4(const Sums* s, const glm::vec3* x, const Assignment& a, float half,
                                         glm::vec3* out) {
  if (a.uniform || !g_eigen_lanes) {
    for (uint32_t k = 0; k < 4; ++k) out[k] = clampToCell(s[k], x[k], a, half);
    return;
  }
  auto load3 = [](const glm::vec3& v) {  // (x, y, z, 0), 8 + 4 bytes
    return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&v.x)), _mm_load_ss(&v.z));
  };
  __m128 cx = load3(s[0].centre), cy = load3(s[1].centre), cz = load3(s[2].centre), cw = load3(s[3].centre);
  __m128 tx = load3(x[0]), ty = load3(x[1]), tz = load3(x[2]), tw = load3(x[3]);
  _MM_TRANSPOSE4_PS(cx, cy, cz, cw);
  _MM_TRANSPOSE4_PS(tx, ty, tz, tw);
  const __m128 w = _mm_set1_ps(0.5f * a.cell_width);  // as cellBox makes it
  __m128 c[3] = {cx, cy, cz}, t[3] = {tx, ty, tz};
  for (int i = 0; i < 3; ++i) {
    const __m128 lo = _mm_sub_ps(_mm_sub_ps(c[i], w), c[i]), hi = _mm_sub_ps(_mm_add_ps(c[i], w), c[i]);
    t[i] = _mm_min_ps(hi, _mm_max_ps(lo, t[i]));
  }
  if (a.shape == CellShape::kSphere) {
    const __m128 h = _mm_set1_ps(half);
    const __m128 l = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(t[0], t[0]), _mm_mul_ps(t[1], t[1])),
                                            _mm_mul_ps(t[2], t[2])));
    const __m128 over = _mm_cmpgt_ps(l, h), scale = _mm_div_ps(h, l);
    for (int i = 0; i < 3; ++i) t[i] = _mm_or_ps(_mm_and_ps(over, _mm_mul_ps(t[i], scale)), _mm_andnot_ps(over, t[i]));
  }
  __m128 r0 = _mm_add_ps(c[0], t[0]), r1 = _mm_add_ps(c[1], t[1]), r2 = _mm_add_ps(c[2], t[2]), r3 = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  const __m128 r[4] = {r0, r1, r2, r3};
  for (int k = 0; k < 4; ++k) {  // 12 bytes each
    _mm_storel_pi(reinterpret_cast<__m64*>(&out[k].x), r[k]);
    _mm_store_ss(&out[k].z, _mm_movehl_ps(r[k], r[k]));
  }
}

#endif

inline void finishColor(const glm::vec4& face_color, const glm::vec4& vertex_color, glm::vec3& out) {
  if (face_color.w > 0.0f) out = glm::vec3(face_color) / face_color.w;
  else if (vertex_color.w > 0.0f) out = glm::vec3(vertex_color) / vertex_color.w;
}

// the clusters are summed one at a time, from a list of their vertices, where the per-cluster sums
// of synthesize's single pass would take more than this per vertex (fine levels)
constexpr size_t kGroupedSumsBytesPerVertex = 16;
constexpr size_t kGroupedPrefetch = 8;

#if defined(__SSE2__)
// whether solveQuadric4 would find a zero residual in all four lanes, tested in floats without its
// widening and transposes (about 150 instructions a group): a mean x0 of zeros (+-0), a linear part
// b of zeros and a finite quadric A make every product a_ij x0_j +-0 in doubles, so r = -(+-0) == 0,
// and the solve returns x0 (an infinite or NaN entry makes a_ij x 0 NaN: false, and the solve
// decides). A one-vertex cluster has all three (its vertex is the centre); the normal sums in
// lanes 6-8 are tested with A (finite for any face sums of finite area).
SCENELOD_ALWAYS_INLINE bool zeroResiduals(const Sums* s, const glm::vec3* x0) {
  const __m128 zero = _mm_setzero_ps();
  __m128 all = _mm_castsi128_ps(_mm_set1_epi32(-1));
  for (int k = 0; k < 4; ++k) {
    const __m128 a03 = _mm_mul_ps(_mm_loadu_ps(s[k].q), zero), a47 = _mm_mul_ps(_mm_loadu_ps(s[k].q + 4), zero);
    // (normal z, b0, b1, b2) with the normal's lane made 0
    const __m128 b = _mm_move_ss(_mm_loadu_ps(s[k].q + 8), zero);
    const __m128 x = _mm_movelh_ps(_mm_loadl_pi(zero, reinterpret_cast<const __m64*>(&x0[k].x)), _mm_load_ss(&x0[k].z));
    all = _mm_and_ps(all, _mm_and_ps(_mm_and_ps(_mm_cmpeq_ps(a03, zero), _mm_cmpeq_ps(a47, zero)),
                                     _mm_and_ps(_mm_cmpeq_ps(b, zero), _mm_cmpeq_ps(x, zero))));
  }
  return _mm_movemask_ps(all) == 15;
}
#endif

// the representatives, normals and colours of the four clusters ids[0..3] (heaviest vertices
// h[0..3]) from their sums, stored for the first k_n (a short group's other lanes repeat its last
// cluster): meanAndNormal4, the solve in lanes and the clamp, as the single pass finishes them
template <bool avx2, bool colors, bool quadric, bool single>
SCENELOD_ALWAYS_INLINE void finishGroup(const Sums* s, const float* weights, const uint32_t* h, const uint32_t* ids,
                                        uint32_t k_n, const glm::vec4* face_color, const glm::vec4* vertex_color,
                                        const Assignment& a, float half, bool mean, Representatives& out) {
  glm::vec3 position[4], normal[4];
#if defined(__SSE2__)
  meanAndNormal4(s, weights, h, mean, quadric, position, normal);
#else
  for (uint32_t k = 0; k < 4; ++k) meanAndNormal(s[k], weights[h[k]], mean, quadric, position[k], normal[k]);
#endif
  if (quadric) {
#if defined(__SSE2__)
    glm::vec3 x[4];  // solved, then clamped below; a short group's unused lanes are solved too (as x0)
    if (!single || !zeroResiduals(s, position)) solveQuadric4<avx2>(s, position, x);
    else std::copy(position, position + 4, x);
    clampToCell4(s, x, a, half, position);
#else
    for (uint32_t k = 0; k < 4; ++k) position[k] = quadricRepresentative(s[k], position[k], a, half);
#endif
  }
  // a fixed count, each cluster under a test that only the last group fails (a loop to k_n
  // mispredicted its exit once per group)
#pragma GCC unroll 4
  for (uint32_t k = 0; k < 4; ++k) {
    if (k >= k_n) break;
    const uint32_t c = ids[k];
    out.positions[c] = position[k];
    out.normals[c] = normal[k];
    if (colors) finishColor(face_color[k], vertex_color[k], out.colors[c]);
  }
}

// synthesize at fine levels, where its per-cluster sums (92 bytes each: 46 per vertex at a level of
// half the triangles) were the largest array of a level: the vertices are listed by cluster (a
// stable counting sort, 4 bytes per vertex and per cluster) and clusters are summed four at a time
// in locals and finished with the single pass's functions (meanAndNormal4 included), each cluster's
// vertices in index order, so the results are bit-identical. At coarse levels the single pass is
// faster (its sums stay in cache while this reads the vertex arrays out of order).
// Clusters of one vertex (the bunny's 50 % level: 5,604 of 17,342) are summed apart, four at a
// time, from their heaviest vertex (every cluster is made by its heaviest vertex, so it is the one):
// they are not listed, and a group of four has a zero residual in every lane, which the solve
// returns before its full-rank test and eigenvalues (about 580 instructions a group). The same
// sums and the same functions per cluster, only grouped differently, and the lanes are
// independent: the same bits.
// The flags (colours, quadric synthesis, face sums present) are template arguments: tested per
// vertex, they were a few instructions of a vertex's 90 or so.
template <bool avx2, bool colors, bool quadric, bool have_face_sums>
SCENELOD_ALWAYS_INLINE void synthesizeGroupedBody(const PreparedMesh& p, const Assignment& a, bool mean,
                                                  Representatives& out) {
  const Mesh& m = *p.mesh;
  const uint32_t nc = a.cluster_count;
  const VertexArrays in = vertexArrays(p);
  const glm::vec3* pos = in.pos;
  const size_t vn = m.vertexCount();
  const uint32_t* cluster_of = a.cluster_of.data();
  // first[c + 1]: cluster c's vertex count; then first[c]: where c's vertices start in `members`
  std::vector<uint32_t> first(size_t(nc) + 1, 0);
  // counted without a test: an unreferenced vertex (kNone + 1 wraps to 0) counts in first[0], unread
#pragma GCC unroll 4
  for (size_t v = 0; v < vn; ++v) ++first[uint32_t(cluster_of[v] + 1)];
  // the clusters in the order they are summed: those of two or more vertices in id order, then
  // those of one from the back (in reverse id order); the one-vertex clusters' cursor is members[0],
  // a spare entry each writes once, and the others' lists start at 1. No branch: a third of the
  // clusters have one vertex, spread out.
  std::unique_ptr<uint32_t[]> order(new uint32_t[nc]);  // every entry is written: not zeroed
  uint32_t listed = 1, multi_count = 0, back = nc;
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t n = first[c + 1];
    const uint32_t multi = n != 1, keep = 0u - multi;  // all ones for a listed cluster
    first[c] = listed & keep;
    listed += n & keep;
    back -= 1 - multi;
    order[multi ? multi_count : back] = c;
    multi_count += multi;
  }
  const size_t member_count = listed;
  std::unique_ptr<uint32_t[]> members(new uint32_t[member_count]);  // every entry is written below: not zeroed
  for (size_t v = 0; v < vn; ++v)
    if (cluster_of[v] != kNone) members[first[cluster_of[v]]++] = static_cast<uint32_t>(v);
  // now first[c] is where a listed cluster c's vertices end
  const float half = 0.5f * a.cell_width;
  const uint32_t* heaviest = a.heaviest.data();
  Sums s[4] = {Sums(glm::vec3(0.0f)), Sums(glm::vec3(0.0f)), Sums(glm::vec3(0.0f)), Sums(glm::vec3(0.0f))};
  glm::vec4 face_color[4], vertex_color[4];
  // Four listed clusters at a time: their vertices are one run of `members`, each added to its
  // cluster's sums (the slot from the four ends, no branch on a cluster's end, which a short,
  // varying list mispredicts), then the four are finished in lanes as the single pass does.
  uint32_t begin = 1;
  for (uint32_t g = 0; g < multi_count; g += 4) {
    const uint32_t k_n = std::min<uint32_t>(4, multi_count - g);  // fewer in the last group
    // the centres are read out of order too: fetch those of the group after next
    if (g + 12 <= multi_count)
      for (uint32_t k = 8; k < 12; ++k) __builtin_prefetch(&pos[heaviest[order[g + k]]]);
    uint32_t ids[4], h[4], e[4];
    for (uint32_t k = 0; k < 4; ++k) {
      ids[k] = order[g + std::min(k, k_n - 1)];  // a short group repeats its last cluster (unused lanes)
      e[k] = first[ids[k]];
      h[k] = heaviest[ids[k]];
      s[k].reset(pos[h[k]]);
      face_color[k] = vertex_color[k] = glm::vec4(0.0f);
    }
    const uint32_t end = e[3];
    // the slot steps on at each end (a listed cluster has at least two vertices: never two steps at
    // once): one compare and add a vertex, where three compares against the ends took six instructions
    uint32_t k = 0;
    for (uint32_t j = begin; j < end; ++j) {
      // the vertex arrays are read out of order here: fetch those of a vertex a few ahead
      const uint32_t ahead = members[std::min<size_t>(j + kGroupedPrefetch, member_count - 1)];
      if (have_face_sums) __builtin_prefetch(&in.face_sums[ahead]);
      __builtin_prefetch(&pos[ahead]);
      __builtin_prefetch(&in.weights[ahead]);
      const uint32_t v = members[j];
      k += uint32_t(j >= e[k]);
      addVertex(in, v, have_face_sums, quadric, s[k]);
      if (colors) {
        face_color[k] += in.face_colors[v];
        vertex_color[k] += glm::vec4(in.colors[v], 1.0f);
      }
    }
    begin = end;
    finishGroup<avx2, colors, quadric, false>(s, in.weights, h, ids, k_n, face_color, vertex_color, a, half, mean, out);
  }
  // the one-vertex clusters, four at a time: each its heaviest vertex
  for (uint32_t g = multi_count; g < nc; g += 4) {
    const uint32_t k_n = std::min<uint32_t>(4, nc - g);
    if (g + 12 <= nc)
      for (uint32_t k = 8; k < 12; ++k) {
        const uint32_t v = heaviest[order[g + k]];
        if (have_face_sums) __builtin_prefetch(&in.face_sums[v]);
        __builtin_prefetch(&pos[v]);
        __builtin_prefetch(&in.weights[v]);
      }
    uint32_t ids[4], h[4];
    for (uint32_t k = 0; k < 4; ++k) {
      ids[k] = order[g + std::min(k, k_n - 1)];
      h[k] = heaviest[ids[k]];
      s[k].reset(pos[h[k]]);
      addVertex(in, h[k], have_face_sums, quadric, s[k]);  // (a repeated lane's sums are not stored)
      if (colors) {
        // added to zeros as the listed clusters' are (+0 + x is x but for x = -0)
        face_color[k] = glm::vec4(0.0f) + in.face_colors[h[k]];
        vertex_color[k] = glm::vec4(0.0f) + glm::vec4(in.colors[h[k]], 1.0f);
      }
    }
    finishGroup<avx2, colors, quadric, true>(s, in.weights, h, ids, k_n, face_color, vertex_color, a, half, mean, out);
  }
}

// The clusters are numbered in the assignment's order (by weight), not in space, so the single
// pass reads its sums at random: where they outgrow the caches (the 1 M sphere's 10 % level: 50 k
// clusters, 4.7 MB) that was most of its time. There the first two lines (of two or three) of the
// sums of the vertex this many ahead are fetched; below that size the fetch only costs instructions.
constexpr size_t kSumsPrefetch = 16;
constexpr size_t kSumsPrefetchBytes = size_t(1) << 20;

template <bool colors, bool quadric, bool have_face_sums>
SCENELOD_ALWAYS_INLINE void addVertexAndColor(const VertexArrays& in, size_t v, uint32_t c, Sums* sums,
                                              glm::vec4* face_color, glm::vec4* vertex_color) {
  addVertex(in, v, have_face_sums, quadric, sums[c]);
  if (colors) {
    face_color[c] += in.face_colors[v];
    vertex_color[c] += glm::vec4(in.colors[v], 1.0f);
  }
}

// The per-vertex streams (face sums 24 bytes, position 12) are fetched this many vertices ahead:
// without it the 1 M sphere's 1 % level (519 k vertices, 4.6 k clusters: the sums stay in cache)
// waited on memory, not on its arithmetic: synthesis 5.6-5.9 ms, with it 2.7-2.9 (32 ahead: 3.05-3.14;
// 64 and 128 alike; fetching the weights and cluster ids too gained nothing).
constexpr size_t kStreamPrefetch = 128;

SCENELOD_ALWAYS_INLINE void prefetchStreams(const VertexArrays& in, size_t v, bool have_face_sums) {
  // (addresses made as integers: near the end they are past the arrays, where a fetch does nothing)
  const uintptr_t ahead = v + kStreamPrefetch;
  if (have_face_sums)
    __builtin_prefetch(reinterpret_cast<const void*>(reinterpret_cast<uintptr_t>(in.face_sums) + ahead * sizeof(VertexFaceSums)));
  __builtin_prefetch(reinterpret_cast<const void*>(reinterpret_cast<uintptr_t>(in.pos) + ahead * sizeof(glm::vec3)));
}

// synthesize's single pass over the vertices, with its flags as template arguments (as above)
template <bool colors, bool quadric, bool have_face_sums>
SCENELOD_ALWAYS_INLINE void sumVerticesBody(const VertexArrays& arrays, const uint32_t* cluster_of, size_t vn,
                                            size_t nc, Sums* sums, glm::vec4* face_color, glm::vec4* vertex_color) {
  const VertexArrays in = arrays;  // a local copy: the stores cannot reach it, so it stays in registers
  size_t v = 0;
  if (nc * sizeof(Sums) > kSumsPrefetchBytes && vn > kSumsPrefetch) {
    // (the address is made as an integer: an unreferenced vertex ahead, kNone, fetches a stray line)
    const uintptr_t base = reinterpret_cast<uintptr_t>(sums);
    for (; v < vn - kSumsPrefetch; ++v) {
      const uintptr_t ahead = base + uintptr_t(cluster_of[v + kSumsPrefetch]) * sizeof(Sums);
      __builtin_prefetch(reinterpret_cast<const void*>(ahead), 1);
      __builtin_prefetch(reinterpret_cast<const void*>(ahead + 64), 1);
      prefetchStreams(in, v, have_face_sums);
      const uint32_t c = cluster_of[v];
      if (c != kNone) addVertexAndColor<colors, quadric, have_face_sums>(in, v, c, sums, face_color, vertex_color);
    }
  }
  for (; v < vn; ++v) {
    prefetchStreams(in, v, have_face_sums);
    const uint32_t c = cluster_of[v];
    if (c != kNone) addVertexAndColor<colors, quadric, have_face_sums>(in, v, c, sums, face_color, vertex_color);
  }
}

// each pass twice: as the baseline (SSE2) and, chosen at run time, the same source compiled for AVX2
// (its three-operand forms spare the register copies of the two-operand SSE2 code: about a fifth of
// the single pass's instructions); without FMA, so the same operations and the same bits
template <bool colors, bool quadric, bool have_face_sums>
void synthesizeGrouped(const PreparedMesh& p, const Assignment& a, bool mean, Representatives& out) {
  synthesizeGroupedBody<false, colors, quadric, have_face_sums>(p, a, mean, out);
}
template <bool colors, bool quadric, bool have_face_sums>
SCENELOD_AVX2_TARGET void synthesizeGroupedAvx2(const PreparedMesh& p, const Assignment& a, bool mean,
                                                Representatives& out) {
  synthesizeGroupedBody<true, colors, quadric, have_face_sums>(p, a, mean, out);
}
// synthesize's single pass (below the grouped test) and its finish
template <bool avx2, bool colors, bool quadric, bool have_face_sums>
SCENELOD_ALWAYS_INLINE void synthesizeSingleBody(const PreparedMesh& p, const Assignment& a, bool mean,
                                                 Representatives& out) {
  const Mesh& m = *p.mesh;
  const uint32_t nc = a.cluster_count;
  const glm::vec3* pos = m.positions.data();
  // sums zeroed by their constructor, then the centres: vector's emplace_back (a capacity test and
  // an end pointer per cluster) took about 50 instructions a cluster
  std::unique_ptr<Sums[]> sums(new Sums[nc]);
  for (uint32_t c = 0; c < nc; ++c) sums[c].centre = pos[a.heaviest[c]];
  std::vector<glm::vec4> face_color;    // xyz: sum of area x face colour, w: sum of area
  std::vector<glm::vec4> vertex_color;  // fallback colour when the cluster's faces have no area
  if (colors) {
    face_color.assign(nc, glm::vec4(0.0f));
    vertex_color.assign(nc, glm::vec4(0.0f));
  }
  sumVerticesBody<colors, quadric, have_face_sums>(vertexArrays(p), a.cluster_of.data(), m.vertexCount(), nc,
                                                   sums.get(), face_color.data(), vertex_color.data());

  // First the weighted mean (relative to the centre; the representative itself when there is no
  // quadric) and the normal of every cluster, four clusters at a time where SSE2 is there: the
  // scalar form's operations lane by lane, both sides of its selects computed and chosen by mask,
  // so bit-identical, with a quarter of the divisions and roots. Then the quadric solve per cluster.
  uint32_t c0 = 0;
#if defined(__SSE2__)
  for (; c0 + 4 <= nc; c0 += 4)
    meanAndNormal4(&sums[c0], p.weights.data(), &a.heaviest[c0], mean, quadric, &out.positions[c0], &out.normals[c0]);
#endif
  for (uint32_t c = c0; c < nc; ++c)
    meanAndNormal(sums[c], p.weights[a.heaviest[c]], mean, quadric, out.positions[c], out.normals[c]);

  const float half = 0.5f * a.cell_width;
  if (quadric) {
    uint32_t c = 0;
#if defined(__SSE2__)
    for (; c + 4 <= nc; c += 4) {
      glm::vec3 x[4];
      solveQuadric4<avx2>(&sums[c], &out.positions[c], x);
      clampToCell4(&sums[c], x, a, half, &out.positions[c]);
    }
#endif
    for (; c < nc; ++c) out.positions[c] = quadricRepresentative(sums[c], out.positions[c], a, half);
  }
  if (colors)
    for (uint32_t c = 0; c < nc; ++c) finishColor(face_color[c], vertex_color[c], out.colors[c]);
}
template <bool colors, bool quadric, bool have_face_sums>
void synthesizeSingle(const PreparedMesh& p, const Assignment& a, bool mean, Representatives& out) {
  synthesizeSingleBody<false, colors, quadric, have_face_sums>(p, a, mean, out);
}
template <bool colors, bool quadric, bool have_face_sums>
SCENELOD_AVX2_TARGET void synthesizeSingleAvx2(const PreparedMesh& p, const Assignment& a, bool mean,
                                               Representatives& out) {
  synthesizeSingleBody<true, colors, quadric, have_face_sums>(p, a, mean, out);
}

// the instance of F<colors, quadric, have_face_sums> for the run-time flags
#define SCENELOD_SYNTHESIS_INSTANCE(F, colors, quadric, have_face_sums)                                      \
  ((colors) ? ((quadric) ? ((have_face_sums) ? F<true, true, true> : F<true, true, false>)                   \
                         : ((have_face_sums) ? F<true, false, true> : F<true, false, false>))                \
            : ((quadric) ? ((have_face_sums) ? F<false, true, true> : F<false, true, false>)                 \
                         : ((have_face_sums) ? F<false, false, true> : F<false, false, false>)))

}  // namespace

void synthesize(const PreparedMesh& p, const Assignment& a, Synthesis synthesis, Representatives& out) {
  const Mesh& m = *p.mesh;
  const uint32_t nc = a.cluster_count;
  out.positions.resize(nc);
  out.normals.resize(nc);
  const bool colors = !m.colors.empty() && p.face_colors.size() == m.vertexCount();
  if (colors) out.colors.assign(nc, glm::vec3(0.0f)); else out.colors.clear();

  // One pass over the vertices in index order (every per-vertex array streams; only the per-cluster
  // sums are scattered). The face sums were made per vertex once per mesh (PreparedMesh::face_sums):
  // summing them over a cluster's vertices is the sum over its faces, each counted once per corner
  // in the cluster, as Lindstrom's per-face accumulation does. Offsets are relative to each cluster's
  // heaviest vertex, so float sums keep their precision.
  // Weighted mean: each vertex weighs its grade plus kMeanWeightFloor x the cluster's heaviest grade
  // (scale-free, so the result does not depend on the weights' normaliser); a cluster of weight-0
  // vertices takes the plain mean.
  const bool quadric = synthesis == Synthesis::kQuadric;
  const bool mean = synthesis != Synthesis::kHeaviest;
  const bool have_face_sums = p.face_sums.size() == m.vertexCount();
  if (g_grouped && size_t(nc) * sizeof(Sums) > kGroupedSumsBytesPerVertex * m.vertexCount()) {
    if (avx2Paths()) SCENELOD_SYNTHESIS_INSTANCE(synthesizeGroupedAvx2, colors, quadric, have_face_sums)(p, a, mean, out);
    else SCENELOD_SYNTHESIS_INSTANCE(synthesizeGrouped, colors, quadric, have_face_sums)(p, a, mean, out);
    return;
  }
  if (avx2Paths()) SCENELOD_SYNTHESIS_INSTANCE(synthesizeSingleAvx2, colors, quadric, have_face_sums)(p, a, mean, out);
  else SCENELOD_SYNTHESIS_INSTANCE(synthesizeSingle, colors, quadric, have_face_sums)(p, a, mean, out);
}

#undef SCENELOD_SYNTHESIS_INSTANCE

}  // namespace detail
}  // namespace scenelod
