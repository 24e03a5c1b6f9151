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
  out.normals.assign(nc, glm::vec3(0.0f));
  const bool colors = !m.colors.empty();
  if (colors) out.colors.assign(nc, glm::vec3(0.0f)); else out.colors.clear();

  // weighted mean, relative to each cluster's heaviest vertex for precision; each vertex weighs its
  // grade plus kMeanWeightFloor x the cluster's heaviest grade (scale-free, so the result does not
  // depend on the weights' normaliser), and a cluster of weight-0 vertices takes the plain mean
  std::vector<glm::vec4> wsum(nc, glm::vec4(0.0f));  // xyz: sum of w * offset, w: sum of w
  std::vector<glm::vec4> sum(nc, glm::vec4(0.0f));   // xyz: sum of offsets, w: vertex count
  std::vector<glm::vec4> vertex_color;  // fallback colour when the cluster's faces have no area
  if (colors) vertex_color.assign(nc, glm::vec4(0.0f));
  std::vector<glm::vec3> centre(nc);  // the heaviest vertex of each cluster, the local origin
  for (uint32_t c = 0; c < nc; ++c) centre[c] = pos[a.heaviest[c]];
  for (size_t i = 0; i < p.order.size(); ++i) {
    const uint32_t v = p.order[i];
    const uint32_t c = a.cluster_of[v];
    const float w = p.weights[v];
    const glm::vec3 d = p.sorted_positions[i] - centre[c];
    wsum[c] += glm::vec4(d * w, w);
    sum[c] += glm::vec4(d, 1.0f);
    if (colors) vertex_color[c] += glm::vec4(m.colors[v], 1.0f);
  }

  const bool quadric = synthesis == Synthesis::kQuadric;
  std::vector<Quadric> quadrics(quadric ? nc : 0);
  std::vector<float> color_area(colors ? nc : 0, 0.0f);
  const size_t tn = m.triangleCount();
  for (size_t t = 0; t < tn; ++t) {
    const uint32_t i0 = m.triangles[3 * t], i1 = m.triangles[3 * t + 1], i2 = m.triangles[3 * t + 2];
    const glm::vec3 cr = glm::cross(pos[i1] - pos[i0], pos[i2] - pos[i0]);
    const float len = glm::length(cr);
    if (!(len > 0.0f)) continue;
    const float area = 0.5f * len;
    const glm::vec3 n = cr / len;
    const glm::vec3 face_color = colors ? (m.colors[i0] + m.colors[i1] + m.colors[i2]) * (1.0f / 3.0f) : glm::vec3(0.0f);
    const uint32_t corners[3] = {i0, i1, i2};
    for (uint32_t i : corners) {
      const uint32_t c = a.cluster_of[i];
      out.normals[c] += n * area;
      if (colors) {
        out.colors[c] += face_color * area;
        color_area[c] += area;
      }
      if (quadric) {
        Quadric& q = quadrics[c];
        const float d = -glm::dot(n, pos[i0] - centre[c]);
        q.a00 += area * n.x * n.x; q.a01 += area * n.x * n.y; q.a02 += area * n.x * n.z;
        q.a11 += area * n.y * n.y; q.a12 += area * n.y * n.z; q.a22 += area * n.z * n.z;
        q.b0 += area * n.x * d; q.b1 += area * n.y * d; q.b2 += area * n.z * d;
      }
    }
  }

  const float half = 0.5f * a.cell_width;
  for (uint32_t c = 0; c < nc; ++c) {
    const glm::vec3 cc = centre[c];
    glm::vec3 x(0.0f);  // relative to centre
    if (synthesis != Synthesis::kHeaviest) {
      const float floor_w = kMeanWeightFloor * p.weights[a.heaviest[c]];
      const float total = wsum[c].w + floor_w * sum[c].w;
      x = total > 0.0f ? (glm::vec3(wsum[c]) + floor_w * glm::vec3(sum[c])) / total : glm::vec3(sum[c]) / sum[c].w;
    }
    if (quadric) {
      x = solveQuadric(quadrics[c], x);
      glm::vec3 lo, hi;
      a.cellBox(m, c, lo, hi);
      x = glm::clamp(x, lo - cc, hi - cc);
      if (!a.uniform && a.shape == CellShape::kSphere) {
        const float l = glm::length(x);
        if (l > half) x *= half / l;
      }
    }
    out.positions[c] = cc + x;
    const float nl = glm::length(out.normals[c]);
    out.normals[c] = nl > 0.0f ? out.normals[c] / nl : glm::vec3(0.0f, 0.0f, 1.0f);
    if (colors) {
      if (color_area[c] > 0.0f) out.colors[c] /= color_area[c];
      else if (vertex_color[c].w > 0.0f) out.colors[c] = glm::vec3(vertex_color[c]) / vertex_color[c].w;
    }
  }
}

}  // namespace detail
}  // namespace scenelod
