// Synthesis of one representative per cluster (Rossignac & Borrel 1993; Low & Tan 1997 §2 step 4):
// the weighted mean of the cluster's vertices, its heaviest vertex (the floating cell's centre), or
// the point minimising the sum of the quadrics of the faces around the cluster (Lindstrom 2000,
// out-of-core clustering), solved with a truncated eigen-decomposition so that directions the faces
// do not constrain stay at the weighted mean, then clamped to the cell.
// Also the cluster's area-weighted colour (Reddy, SCROOGE §7.3) and normal.
#include <algorithm>
#include <cmath>

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

namespace detail {

namespace {

// mean weights: the vertex weight plus this fraction of the heaviest weight, so that clusters of
// flat vertices (weight 0, Low & Tan) still average instead of dividing by zero
constexpr float kMeanWeightFloor = 0.05f;
// quadric: eigenvalues below this fraction of the largest are treated as zero (singular directions)
constexpr double kEigenCutoff = 1e-3;

struct Quadric {
  float a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;  // sum of area * n n^T
  float b0 = 0, b1 = 0, b2 = 0;                               // sum of area * n d, planes relative to the cell centre
};

// eigen-decomposition of a symmetric 3x3 matrix by Jacobi rotations: a = v diag(w) v^T
void symmetricEigen(double a[3][3], double w[3], double v[3][3]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
  const double scale = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2] +
                       2.0 * (a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2]);
  for (int sweep = 0; sweep < 16; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if (off <= 1e-24 * scale) break;  // off-diagonal part negligible relative to the matrix
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (std::fabs(a[p][q]) < 1e-300) continue;
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a = J^T a J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  for (int i = 0; i < 3; ++i) w[i] = a[i][i];
}

// minimiser of x^T A x + 2 b^T x nearest to x0 in the directions A leaves free
glm::vec3 solveQuadric(const Quadric& q, const glm::vec3& x0) {
  double a[3][3] = {{q.a00, q.a01, q.a02}, {q.a01, q.a11, q.a12}, {q.a02, q.a12, q.a22}};
  // residual at x0: r = -(A x0 + b); x = x0 + A^+ r
  const double r[3] = {-(a[0][0] * x0.x + a[0][1] * x0.y + a[0][2] * x0.z + q.b0),
                       -(a[1][0] * x0.x + a[1][1] * x0.y + a[1][2] * x0.z + q.b1),
                       -(a[2][0] * x0.x + a[2][1] * x0.y + a[2][2] * x0.z + q.b2)};
  // a zero residual (one-vertex clusters: every plane passes through x0) leaves x0 unchanged
  if (r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0) return x0;
  double w[3], v[3][3];
  symmetricEigen(a, w, v);
  const double wmax = std::max({std::fabs(w[0]), std::fabs(w[1]), std::fabs(w[2])});
  if (!(wmax > 0.0)) return x0;
  double x[3] = {x0.x, x0.y, x0.z};
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(w[k]) < kEigenCutoff * wmax) continue;  // singular direction: stay at x0
    const double proj = (v[0][k] * r[0] + v[1][k] * r[1] + v[2][k] * r[2]) / w[k];
    for (int i = 0; i < 3; ++i) x[i] += v[i][k] * proj;
  }
  return glm::vec3(float(x[0]), float(x[1]), float(x[2]));
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
  struct Sums {          // 92 bytes per cluster
    glm::vec3 centre;    // the heaviest vertex, the local origin
    float w = 0.0f;      // sum of weights
    glm::vec3 wsum{0.0f};  // sum of weight x offset
    float count = 0.0f;
    glm::vec3 sum{0.0f};   // sum of offsets
    float a[6] = {0, 0, 0, 0, 0, 0};  // quadric: sum of area n n^T
    float b[3] = {0, 0, 0};           // quadric: sum of area n d, planes relative to the centre
    glm::vec3 normal{0.0f};           // sum of area n
  };
  std::vector<Sums> sums(nc);
  for (uint32_t c = 0; c < nc; ++c) sums[c].centre = pos[a.heaviest[c]];
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
      const VertexFaceSums& f = p.face_sums[v];
      s.normal += glm::vec3(f.normal[0], f.normal[1], f.normal[2]);
      if (quadric) {
        for (int k = 0; k < 6; ++k) s.a[k] += f.a[k];
        // the vertex lies on all its faces' planes: relative to the centre, b = -A d
        s.b[0] -= f.a[0] * d.x + f.a[1] * d.y + f.a[2] * d.z;
        s.b[1] -= f.a[1] * d.x + f.a[3] * d.y + f.a[4] * d.z;
        s.b[2] -= f.a[2] * d.x + f.a[4] * d.y + f.a[5] * d.z;
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
    const float nl = glm::length(s.normal);
    out.normals[c] = nl > 0.0f ? s.normal / nl : glm::vec3(0.0f, 0.0f, 1.0f);
    if (colors) {
      if (face_color[c].w > 0.0f) out.colors[c] = glm::vec3(face_color[c]) / face_color[c].w;
      else if (vertex_color[c].w > 0.0f) out.colors[c] = glm::vec3(vertex_color[c]) / vertex_color[c].w;
    }
  }
}

}  // namespace detail
}  // namespace scenelod
