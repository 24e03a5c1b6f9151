// Synthesis of one representative per cluster (Rossignac & Borrel 1993; Low & Tan 1997 §2 step 4):
// the weighted mean of the cluster's vertices, its heaviest vertex (the floating cell's centre), or
// the point minimising the sum of the quadrics of the faces around the cluster (Lindstrom 2000,
// out-of-core clustering), solved with a truncated pseudo-inverse (per rank, in closed form) so that
// directions the faces do not constrain stay at the weighted mean, then clamped to the cell.
// Also the cluster's area-weighted colour (Reddy, SCROOGE §7.3) and normal.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

#include "cluster_internal.h"

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

// per-cluster sums of synthesize (see there)
struct Sums {          // 92 bytes per cluster
  glm::vec3 centre;    // the heaviest vertex, the local origin
  float w = 0.0f;      // sum of weights
  glm::vec3 wsum{0.0f};  // sum of weight x offset
  float count = 0.0f;
  glm::vec3 sum{0.0f};   // sum of offsets
  // quadric: sum of area n n^T (xx, xy, xz, yy, yz, zz), then the normal: sum of area n; one
  // array so that the per-vertex adds go four at a time
  float a[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  float b[3] = {0, 0, 0};  // quadric: sum of area n d, planes relative to the centre
  explicit Sums(const glm::vec3& c) : centre(c) {}
};

// the clusters are summed one at a time, from a list of their vertices, where the per-cluster sums
// of synthesize's single pass would take more than this per vertex (fine levels)
constexpr size_t kGroupedSumsBytesPerVertex = 16;
constexpr size_t kGroupedPrefetch = 8;

// synthesize at fine levels, where its per-cluster sums (92 bytes each: 46 per vertex at a level of
// half the triangles) were the largest array of a level: the vertices are listed by cluster (a
// stable counting sort, 4 bytes per vertex and per cluster) and each cluster is summed and finished
// at once in locals, with synthesize's operations in synthesize's order (a cluster's vertices in
// index order), so the results are bit-identical (add and finish below repeat synthesize's loops
// and must stay in step with them). At coarse levels the single pass is faster (its sums stay in
// cache while this reads the vertex arrays out of order).
void synthesizeGrouped(const PreparedMesh& p, const Assignment& a, Synthesis synthesis, Representatives& out) {
  const Mesh& m = *p.mesh;
  const uint32_t nc = a.cluster_count;
  const glm::vec3* pos = m.positions.data();
  const bool colors = !m.colors.empty() && p.face_colors.size() == m.vertexCount();
  const bool quadric = synthesis == Synthesis::kQuadric;
  const bool have_face_sums = p.face_sums.size() == m.vertexCount();
  const size_t vn = m.vertexCount();
  const uint32_t* cluster_of = a.cluster_of.data();
  std::vector<uint32_t> first(size_t(nc) + 1, 0);  // where each cluster's vertices start
  for (size_t v = 0; v < vn; ++v)
    if (cluster_of[v] != kNone) ++first[cluster_of[v] + 1];
  for (uint32_t c = 0; c < nc; ++c) first[c + 1] += first[c];
  std::vector<uint32_t> members(first[nc]);
  for (size_t v = 0; v < vn; ++v)
    if (cluster_of[v] != kNone) members[first[cluster_of[v]]++] = static_cast<uint32_t>(v);
  auto add = [&](Sums& s, size_t v, glm::vec4* face_color, glm::vec4* vertex_color) {
    const float w = p.weights[v];
    const glm::vec3 d = pos[v] - s.centre;
    s.wsum += d * w;
    s.w += w;
    s.sum += d;
    s.count += 1.0f;
    if (have_face_sums) {
      float fa[9];
      decodeFaceSums(p.face_sums[v], fa);
      for (int k = 0; k < 9; ++k) s.a[k] += fa[k];
      if (quadric) {
        s.b[0] -= fa[0] * d.x + fa[1] * d.y + fa[2] * d.z;
        s.b[1] -= fa[1] * d.x + fa[3] * d.y + fa[4] * d.z;
        s.b[2] -= fa[2] * d.x + fa[4] * d.y + fa[5] * d.z;
      }
    }
    if (colors) {
      *face_color += p.face_colors[v];
      *vertex_color += glm::vec4(m.colors[v], 1.0f);
    }
  };
  const float half = 0.5f * a.cell_width;
  auto finish = [&](uint32_t c, const Sums& s, const glm::vec4& face_color, const glm::vec4& vertex_color) {
    glm::vec3 x(0.0f);
    if (synthesis != Synthesis::kHeaviest) {
      const float floor_w = kMeanWeightFloor * p.weights[a.heaviest[c]];
      const float total = s.w + floor_w * s.count;
      x = total > 0.0f ? (s.wsum + floor_w * s.sum) / total : s.sum / s.count;
    }
    if (quadric) {
      Quadric q;
      q.a00 = s.a[0], q.a01 = s.a[1], q.a02 = s.a[2], q.a11 = s.a[3], q.a12 = s.a[4], q.a22 = s.a[5];
      q.b0 = s.b[0], q.b1 = s.b[1], q.b2 = s.b[2];
      x = solveQuadric(q, x);
      glm::vec3 lo, hi;
      a.cellBox(s.centre, lo, hi);
      x = glm::clamp(x, lo - s.centre, hi - s.centre);
      if (!a.uniform && a.shape == CellShape::kSphere) {
        const float l = glm::length(x);
        if (l > half) x *= half / l;
      }
    }
    out.positions[c] = s.centre + x;
    const glm::vec3 normal(s.a[6], s.a[7], s.a[8]);
    const float nl = glm::length(normal);
    out.normals[c] = nl > 0.0f ? normal / nl : glm::vec3(0.0f, 0.0f, 1.0f);
    if (colors) {
      if (face_color.w > 0.0f) out.colors[c] = glm::vec3(face_color) / face_color.w;
      else if (vertex_color.w > 0.0f) out.colors[c] = glm::vec3(vertex_color) / vertex_color.w;
    }
  };
  uint32_t begin = 0;  // first[c] is now where cluster c + 1 starts
  for (uint32_t c = 0; c < nc; ++c) {
    Sums s(pos[a.heaviest[c]]);
    glm::vec4 face_color(0.0f), vertex_color(0.0f);
    const uint32_t end = first[c];
    for (uint32_t j = begin; j < end; ++j) {
      // the vertex arrays are read out of order here: fetch those of a vertex a few ahead
      const uint32_t ahead = members[std::min<size_t>(j + kGroupedPrefetch, members.size() - 1)];
      __builtin_prefetch(&p.face_sums[ahead]);
      __builtin_prefetch(&pos[ahead]);
      __builtin_prefetch(&p.weights[ahead]);
      add(s, members[j], &face_color, &vertex_color);
    }
    begin = end;
    finish(c, s, face_color, vertex_color);
  }
}

}  // namespace

void synthesize(const PreparedMesh& p, const Assignment& a, Synthesis synthesis, Representatives& out) {
  const Mesh& m = *p.mesh;
  const uint32_t nc = a.cluster_count;
  const glm::vec3* pos = m.positions.data();
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
  if (size_t(nc) * sizeof(Sums) > kGroupedSumsBytesPerVertex * m.vertexCount()) {
    synthesizeGrouped(p, a, synthesis, out);
    return;
  }
  std::vector<Sums> sums;  // made in one pass (no zeroing pass before the centres)
  sums.reserve(nc);
  for (uint32_t c = 0; c < nc; ++c) sums.emplace_back(pos[a.heaviest[c]]);
  std::vector<glm::vec4> face_color;    // xyz: sum of area x face colour, w: sum of area
  std::vector<glm::vec4> vertex_color;  // fallback colour when the cluster's faces have no area
  if (colors) {
    face_color.assign(nc, glm::vec4(0.0f));
    vertex_color.assign(nc, glm::vec4(0.0f));
  }
  const bool quadric = synthesis == Synthesis::kQuadric;
  const bool have_face_sums = p.face_sums.size() == m.vertexCount();
  const size_t vn = m.vertexCount();
  const uint32_t* cluster_of = a.cluster_of.data();
  for (size_t v = 0; v < vn; ++v) {
    const uint32_t c = cluster_of[v];
    if (c == kNone) continue;
    Sums& s = sums[c];
    const float w = p.weights[v];
    const glm::vec3 d = pos[v] - s.centre;
    s.wsum += d * w;
    s.w += w;
    s.sum += d;
    s.count += 1.0f;
    if (have_face_sums) {
      float fa[9];  // quadric xx, xy, xz, yy, yz, zz, then the normal sum
      decodeFaceSums(p.face_sums[v], fa);
      for (int k = 0; k < 9; ++k) s.a[k] += fa[k];  // (the quadric part is unused but harmless for mean)
      if (quadric) {
        // the vertex lies on all its faces' planes: relative to the centre, b = -A d
        s.b[0] -= fa[0] * d.x + fa[1] * d.y + fa[2] * d.z;
        s.b[1] -= fa[1] * d.x + fa[3] * d.y + fa[4] * d.z;
        s.b[2] -= fa[2] * d.x + fa[4] * d.y + fa[5] * d.z;
      }
    }
    if (colors) {
      face_color[c] += p.face_colors[v];
      vertex_color[c] += glm::vec4(m.colors[v], 1.0f);
    }
  }

  const float half = 0.5f * a.cell_width;
  for (uint32_t c = 0; c < nc; ++c) {
    const Sums& s = sums[c];
    glm::vec3 x(0.0f);  // relative to centre
    if (synthesis != Synthesis::kHeaviest) {
      const float floor_w = kMeanWeightFloor * p.weights[a.heaviest[c]];
      const float total = s.w + floor_w * s.count;
      x = total > 0.0f ? (s.wsum + floor_w * s.sum) / total : s.sum / s.count;
    }
    if (quadric) {
      Quadric q;
      q.a00 = s.a[0], q.a01 = s.a[1], q.a02 = s.a[2], q.a11 = s.a[3], q.a12 = s.a[4], q.a22 = s.a[5];
      q.b0 = s.b[0], q.b1 = s.b[1], q.b2 = s.b[2];
      x = solveQuadric(q, x);
      glm::vec3 lo, hi;
      a.cellBox(s.centre, lo, hi);
      x = glm::clamp(x, lo - s.centre, hi - s.centre);
      if (!a.uniform && a.shape == CellShape::kSphere) {
        const float l = glm::length(x);
        if (l > half) x *= half / l;
      }
    }
    out.positions[c] = s.centre + x;
    const glm::vec3 normal(s.a[6], s.a[7], s.a[8]);
    const float nl = glm::length(normal);
    out.normals[c] = nl > 0.0f ? normal / nl : glm::vec3(0.0f, 0.0f, 1.0f);
    if (colors) {
      if (face_color[c].w > 0.0f) out.colors[c] = glm::vec3(face_color[c]) / face_color[c].w;
      else if (vertex_color[c].w > 0.0f) out.colors[c] = glm::vec3(vertex_color[c]) / vertex_color[c].w;
    }
  }
}

}  // namespace detail
}  // namespace scenelod
