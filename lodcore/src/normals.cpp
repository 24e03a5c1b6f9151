// Adjustment of normals (Low & Tan 1997 §2 step 6): face normals of the simplified triangles, and
// vertex normals that average only faces within a crease angle of each other, splitting a cluster's
// vertex into one copy per distinct normal. Vertices only used by edges and points take the
// cluster's area-weighted normal of the original faces (edges are shaded with dynamic normals).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cluster_internal.h"

namespace scenelod::detail {

namespace {

// One cluster's incident faces as structure-of-arrays, padded with zeros to a multiple of 4.
struct ClusterFaces {
  std::vector<float> x, y, z, w;
  void resize(size_t k) {
    const size_t padded = (k + 3) & ~size_t(3);
    if (x.size() < padded) x.resize(padded), y.resize(padded), z.resize(padded), w.resize(padded);
    for (size_t j = k; j < padded; ++j) x[j] = y[j] = z[j] = w[j] = 0.0f;
  }
};

// Corner normals of one cluster: for each corner i, the sum over the cluster's faces j, in order, of
// face j's unit normal times its double area, over the faces within the crease angle of face i (and
// face i itself). Four corners at a time, one per SIMD lane: each lane does the scalar loop's
// operations in the scalar loop's order (a skipped face adds +0, which never changes a sum that
// starts at +0), so the sums are bit-identical to it, without its unpredictable branch per pair.
void cornerNormals(const ClusterFaces& f, size_t k, float cos_crease, glm::vec3* n) {
#if defined(__SSE2__)
  const __m128 cosv = _mm_set1_ps(cos_crease);
  for (size_t i0 = 0; i0 < k; i0 += 4) {
    const __m128 tx = _mm_loadu_ps(&f.x[i0]), ty = _mm_loadu_ps(&f.y[i0]), tz = _mm_loadu_ps(&f.z[i0]);
    const __m128i lane = _mm_add_epi32(_mm_set1_epi32(int(i0)), _mm_set_epi32(3, 2, 1, 0));
    __m128 nx = _mm_setzero_ps(), ny = _mm_setzero_ps(), nz = _mm_setzero_ps();
    for (size_t j = 0; j < k; ++j) {
      const __m128 ux = _mm_set1_ps(f.x[j]), uy = _mm_set1_ps(f.y[j]), uz = _mm_set1_ps(f.z[j]);
      const __m128 d = _mm_add_ps(_mm_add_ps(_mm_mul_ps(tx, ux), _mm_mul_ps(ty, uy)), _mm_mul_ps(tz, uz));
      const __m128 self = _mm_castsi128_ps(_mm_cmpeq_epi32(lane, _mm_set1_epi32(int(j))));
      const __m128 take = _mm_or_ps(self, _mm_cmpge_ps(d, cosv));
      const float wj = f.w[j];
      nx = _mm_add_ps(nx, _mm_and_ps(take, _mm_set1_ps(f.x[j] * wj)));
      ny = _mm_add_ps(ny, _mm_and_ps(take, _mm_set1_ps(f.y[j] * wj)));
      nz = _mm_add_ps(nz, _mm_and_ps(take, _mm_set1_ps(f.z[j] * wj)));
    }
    alignas(16) float ox[4], oy[4], oz[4];
    _mm_store_ps(ox, nx), _mm_store_ps(oy, ny), _mm_store_ps(oz, nz);
    for (size_t l = 0; l < 4 && i0 + l < k; ++l) n[i0 + l] = glm::vec3(ox[l], oy[l], oz[l]);
  }
#else
  for (size_t i = 0; i < k; ++i) {
    const glm::vec3 ut(f.x[i], f.y[i], f.z[i]);
    glm::vec3 s(0.0f);
    for (size_t j = 0; j < k; ++j) {
      const glm::vec3 uu(f.x[j], f.y[j], f.z[j]);
      if (j == i || glm::dot(ut, uu) >= cos_crease) s += uu * f.w[j];
    }
    n[i] = s;
  }
#endif
}

// A cluster whose faces all lie within the crease angle of each other gives every corner the same
// sum in cornerNormals: each lane adds every face, in order, to +0. This computes that sum once,
// normalised as the corner loop does, and returns true if the faces pass a sufficient test for
// "all within the crease angle": each face's unit normal u_j within alpha of the normalised sum m
// (float dot(u_j, m) >= cos_ref = cos alpha + 1e-5), so any two are within 2 alpha, whose cosine
// is cos_crease + 1e-4. The margins exceed the rounding of the float dot products (a few 1e-7 for
// normals of length 1 +- 4e-7; faces or sums shorter than 1e-18, whose normalisation could be less
// exact, fail the test), so a pass means the lanes' d >= cos_crease for every pair.
bool smoothCluster(const ClusterFaces& f, size_t k, float cos_ref, glm::vec3& n) {
  glm::vec3 s(0.0f);
  for (size_t j = 0; j < k; ++j) {
    const float wj = f.w[j];
    s.x += f.x[j] * wj, s.y += f.y[j] * wj, s.z += f.z[j] * wj;
  }
  const float l = glm::length(s);
  if (!(l >= 1e-18f)) return false;
  n = s / l;
  bool all = true;
  for (size_t j = 0; j < k; ++j) all &= (f.w[j] >= 1e-18f) & (f.x[j] * n.x + f.y[j] * n.y + f.z[j] * n.z >= cos_ref);
  return all;
}

}  // namespace

void buildOutputMesh(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  out = Mesh();
  const size_t nc = r.positions.size();
  const size_t tn = e.triangles.size() / 3;
  const bool colors = !r.colors.empty();
  const float cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0f, 180.0f) * 3.14159265358979f / 180.0f);

  std::vector<glm::vec4> face(tn);  // xyz: unit face normal (0 when degenerate), w: twice the area
  for (size_t t = 0; t < tn; ++t) {
    const glm::vec3& a = r.positions[e.triangles[3 * t]];
    const glm::vec3 n = glm::cross(r.positions[e.triangles[3 * t + 1]] - a, r.positions[e.triangles[3 * t + 2]] - a);
    const float l = glm::length(n);
    face[t] = l > 0.0f ? glm::vec4(n / l, l) : glm::vec4(0.0f);
  }
  // cluster -> incident triangle corners
  std::vector<uint32_t> offsets(nc + 1, 0);
  for (uint32_t c : e.triangles) ++offsets[c + 1];
  for (size_t c = 0; c < nc; ++c) offsets[c + 1] += offsets[c];
  std::vector<uint32_t> corners(e.triangles.size());
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t i = 0; i < e.triangles.size(); ++i) corners[fill[e.triangles[i]]++] = static_cast<uint32_t>(i);
  }
  std::vector<uint8_t> needs_vertex(nc, 0);
  for (uint32_t c : e.edges) needs_vertex[c] = 1;
  for (uint32_t c : e.points) needs_vertex[c] = 1;

  std::vector<uint32_t> base_vertex(nc, kNone);
  // one vertex per used cluster, plus its copies split at creases (a few per cent on scanned meshes):
  // reserving that, not the cluster count, keeps the arrays from doubling on the first split
  size_t used_count = 0;
  for (size_t c = 0; c < nc; ++c) used_count += offsets[c + 1] != offsets[c] || needs_vertex[c];
  const size_t expected_vertices = used_count + used_count / 16 + 16;
  out.positions.reserve(expected_vertices);
  out.normals.reserve(expected_vertices);
  if (colors) out.colors.reserve(expected_vertices);
  auto addVertex = [&](uint32_t c, const glm::vec3& n) {
    out.positions.push_back(r.positions[c]);
    out.normals.push_back(n);
    if (colors) out.colors.push_back(r.colors[c]);
    return static_cast<uint32_t>(out.positions.size() - 1);
  };
  // the sufficient test of smoothCluster: faces within alpha of their mean direction are within
  // 2 alpha of each other; 2 alpha is the crease angle less a margin that covers the rounding of
  // the float dot products (see smoothCluster)
  const double cos_2alpha = double(cos_crease) + 1e-4;
  const bool fast = cos_2alpha < 1.0;
  const float cos_ref = fast ? float(std::cos(0.5 * std::acos(std::max(-1.0, cos_2alpha))) + 1e-5) : 2.0f;
  ClusterFaces cf;
  std::vector<glm::vec3> sums;  // per corner of the current cluster
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t b = offsets[c], en = offsets[c + 1];
    const uint32_t first_vertex = static_cast<uint32_t>(out.positions.size());
    const size_t k = en - b;
    cf.resize(k);
    if (sums.size() < k) sums.resize(k);
    for (size_t j = 0; j < k; ++j) {
      const glm::vec4& fj = face[corners[b + j] / 3];
      cf.x[j] = fj.x, cf.y[j] = fj.y, cf.z[j] = fj.z, cf.w[j] = fj.w;
    }
    if (k > 0 && fast) {
      // the cluster's faces all within the crease angle of each other: every corner's sum is the
      // same ordered sum (see smoothCluster), so the cluster takes one vertex
      glm::vec3 n;
      if (smoothCluster(cf, k, cos_ref, n)) {
        const uint32_t v = addVertex(c, n);
        for (uint32_t i = b; i < en; ++i) e.triangles[corners[i]] = v;
        base_vertex[c] = v;
        continue;
      }
    }
    cornerNormals(cf, k, cos_crease, sums.data());
    for (uint32_t i = b; i < en; ++i) {
      glm::vec3 n = sums[i - b];
      const float l = glm::length(n);
      n = l > 0.0f ? n / l : r.normals[c];
      uint32_t v = kNone;
      for (uint32_t q = first_vertex; q < out.positions.size(); ++q)
        if (out.normals[q] == n) {
          v = q;
          break;
        }
      if (v == kNone) v = addVertex(c, n);
      // each corner's cluster id is no longer read once the corner lists exist: the output
      // vertex takes its place, so the output triangles need no second array
      e.triangles[corners[i]] = v;
    }
    if (b != en) base_vertex[c] = first_vertex;
    else if (needs_vertex[c]) base_vertex[c] = addVertex(c, r.normals[c]);
  }
  std::vector<glm::vec4>().swap(face);
  // split vertices may have grown the arrays past the reserve: the chain keeps every level, so
  // give back the slack
  out.positions.shrink_to_fit();
  out.normals.shrink_to_fit();
  out.colors.shrink_to_fit();
  out.triangles = std::move(e.triangles);
  out.triangles.shrink_to_fit();  // elimination reserved for about 2 triangles per cluster
  out.edges.resize(e.edges.size());
  for (size_t i = 0; i < e.edges.size(); ++i) out.edges[i] = base_vertex[e.edges[i]];
  out.edge_thickness = std::move(e.edge_thickness);
  if (out.edge_thickness.size() != out.edges.size() / 2) out.edge_thickness.assign(out.edges.size() / 2, 0.0f);
  out.points.resize(e.points.size());
  for (size_t i = 0; i < e.points.size(); ++i) out.points[i] = base_vertex[e.points[i]];
}

}  // namespace scenelod::detail
