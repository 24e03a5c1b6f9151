// Adjustment of normals (Low & Tan 1997 §2 step 6): face normals of the simplified triangles, and
// vertex normals that average only faces within a crease angle of each other, splitting a cluster's
// vertex into one copy per distinct normal. Vertices only used by edges and points take the
// cluster's area-weighted normal of the original faces (edges are shaded with dynamic normals).
#include <algorithm>
#include <cmath>
#include <memory>

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

#if defined(__SSE2__)
// the sums of corners i0 .. i0 + 3 over faces 0 .. k - 1, one corner per lane
inline void laneSums(const ClusterFaces& f, size_t i0, size_t k, __m128 cosv, __m128& nx, __m128& ny, __m128& nz) {
  const __m128 tx = _mm_loadu_ps(&f.x[i0]), ty = _mm_loadu_ps(&f.y[i0]), tz = _mm_loadu_ps(&f.z[i0]);
  const __m128i lane = _mm_add_epi32(_mm_set1_epi32(int(i0)), _mm_set_epi32(3, 2, 1, 0));
  nx = _mm_setzero_ps(), ny = _mm_setzero_ps(), nz = _mm_setzero_ps();
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
}
#endif

// Corner normals of one cluster: for each corner i, the sum over the cluster's faces j, in order, of
// face j's unit normal times its double area, over the faces within the crease angle of face i (and
// face i itself). Four corners at a time, one per SIMD lane: each lane does the scalar loop's
// operations in the scalar loop's order (a skipped face adds +0, which never changes a sum that
// starts at +0), so the sums are bit-identical to it, without its unpredictable branch per pair.
void cornerNormals(const ClusterFaces& f, size_t k, float cos_crease, glm::vec3* n) {
#if defined(__SSE2__)
  const __m128 cosv = _mm_set1_ps(cos_crease);
  for (size_t i0 = 0; i0 < k; i0 += 4) {
    __m128 nx, ny, nz;
    laneSums(f, i0, k, cosv, nx, ny, nz);
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

// buildOutputMesh's cluster loop fetches the faces of the cluster this many ahead where the face
// array (16 bytes per output triangle) is larger than kFacePrefetchBytes
constexpr uint32_t kFacePrefetch = 4;
constexpr size_t kFacePrefetchBytes = size_t(1) << 20;

#if defined(__SSE2__)
// Clusters of at most this many corners (99 % at the bunny's 50 % level) take a fixed-size path.
constexpr uint32_t kSmall = 8;

// smoothCluster for a cluster of k <= kSmall faces held as rows (x, y, z, w; rows past k zero) and
// transposed into x0..w0 (faces 0-3) and x1..w1 (faces 4-7): the same ordered sum from +0, each
// row's x * w, y * w, z * w added in its lanes (a zero row adds +0), the same test.
SCENELOD_ALWAYS_INLINE bool smoothSmall(const __m128 row[kSmall], __m128 x0, __m128 y0, __m128 z0, __m128 w0, __m128 x1, __m128 y1,
                 __m128 z1, __m128 w1, size_t k, float cos_ref, glm::vec3& n) {
  __m128 s = _mm_setzero_ps();
  for (uint32_t j = 0; j < kSmall; ++j) s = _mm_add_ps(s, _mm_mul_ps(row[j], _mm_shuffle_ps(row[j], row[j], 0xff)));
  alignas(16) float sv[4];
  _mm_store_ps(sv, s);
  const glm::vec3 sum(sv[0], sv[1], sv[2]);
  const float l = glm::length(sum);
  if (!(l >= 1e-18f)) return false;
  n = sum / l;
  const __m128 nx = _mm_set1_ps(n.x), ny = _mm_set1_ps(n.y), nz = _mm_set1_ps(n.z);
  const __m128 ref = _mm_set1_ps(cos_ref), min_w = _mm_set1_ps(1e-18f);
  const __m128i kv = _mm_set1_epi32(int32_t(k));
  // lanes past k pass
  const __m128 past0 = _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_set_epi32(3, 2, 1, 0), _mm_sub_epi32(kv, _mm_set1_epi32(1))));
  const __m128 past1 = _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_set_epi32(7, 6, 5, 4), _mm_sub_epi32(kv, _mm_set1_epi32(1))));
  const __m128 d0 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(x0, nx), _mm_mul_ps(y0, ny)), _mm_mul_ps(z0, nz));
  const __m128 d1 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(x1, nx), _mm_mul_ps(y1, ny)), _mm_mul_ps(z1, nz));
  const __m128 ok0 = _mm_or_ps(past0, _mm_and_ps(_mm_cmpge_ps(w0, min_w), _mm_cmpge_ps(d0, ref)));
  const __m128 ok1 = _mm_or_ps(past1, _mm_and_ps(_mm_cmpge_ps(w1, min_w), _mm_cmpge_ps(d1, ref)));
  return _mm_movemask_ps(_mm_and_ps(ok0, ok1)) == 0xf;
}

// The corner loop of buildOutputMesh for a cluster of k <= kSmall faces held in f, zero-padded to
// kSmall: writes each corner's output vertex to local[0 .. kSmall) (indices from the cluster's first
// vertex; entries past k repeat corner k - 1's) and the normals of the new vertices, in order, to
// new_normals; returns their count. The same values as that loop: the sums of cornerNormals over
// all kSmall faces (a zero face adds +0), normalised lane by lane as glm::length and the division
// do (the fallback where the length is 0), and each corner takes the vertex of the first earlier
// corner with an equal normal (== is transitive away from NaN, which equals nothing), else a new
// one; the pairs are compared in lanes, without a branch per pair.
uint32_t smallCorners(const ClusterFaces& f, size_t k, float cos_crease, const glm::vec3& fallback,
                      uint32_t local[kSmall], glm::vec3 new_normals[kSmall]) {
  const __m128 cosv = _mm_set1_ps(cos_crease);
  const __m128 fx = _mm_set1_ps(fallback.x), fy = _mm_set1_ps(fallback.y), fz = _mm_set1_ps(fallback.z);
  __m128 gx[2], gy[2], gz[2];
  for (int g = 0; g < 2; ++g) {
    __m128 nx, ny, nz;
    laneSums(f, 4 * size_t(g), kSmall, cosv, nx, ny, nz);
    const __m128 l = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, nx), _mm_mul_ps(ny, ny)), _mm_mul_ps(nz, nz)));
    const __m128 pos = _mm_cmpgt_ps(l, _mm_setzero_ps());
    gx[g] = _mm_or_ps(_mm_and_ps(pos, _mm_div_ps(nx, l)), _mm_andnot_ps(pos, fx));
    gy[g] = _mm_or_ps(_mm_and_ps(pos, _mm_div_ps(ny, l)), _mm_andnot_ps(pos, fy));
    gz[g] = _mm_or_ps(_mm_and_ps(pos, _mm_div_ps(nz, l)), _mm_andnot_ps(pos, fz));
  }
  alignas(16) float x[kSmall], y[kSmall], z[kSmall];
  _mm_store_ps(x, gx[0]), _mm_store_ps(x + 4, gx[1]);
  _mm_store_ps(y, gy[0]), _mm_store_ps(y + 4, gy[1]);
  _mm_store_ps(z, gz[0]), _mm_store_ps(z + 4, gz[1]);
  uint32_t v[kSmall + 1] = {};
  uint32_t count = 0;
  for (uint32_t i = 0; i < kSmall; ++i) {
    const __m128 xi = _mm_set1_ps(x[i]), yi = _mm_set1_ps(y[i]), zi = _mm_set1_ps(z[i]);
    const __m128 e0 = _mm_and_ps(_mm_and_ps(_mm_cmpeq_ps(gx[0], xi), _mm_cmpeq_ps(gy[0], yi)), _mm_cmpeq_ps(gz[0], zi));
    const __m128 e1 = _mm_and_ps(_mm_and_ps(_mm_cmpeq_ps(gx[1], xi), _mm_cmpeq_ps(gy[1], yi)), _mm_cmpeq_ps(gz[1], zi));
    const uint32_t earlier = uint32_t(_mm_movemask_ps(e0) | (_mm_movemask_ps(e1) << 4)) & ((1u << i) - 1u);
    const uint32_t fresh = uint32_t(earlier == 0) & uint32_t(i < k);
    new_normals[count] = glm::vec3(x[i], y[i], z[i]);  // kept only when fresh
    v[i] = fresh ? count : v[__builtin_ctz(earlier | (1u << kSmall))];
    count += fresh;
  }
  for (uint32_t j = 0; j < kSmall; ++j) local[j] = v[std::min<uint32_t>(j, uint32_t(k) - 1)];
  return count;
}
#endif

// buildOutputMesh, compiled into a baseline function and an AVX2 one (as synthesize's loops; see
// synthesis.cpp), chosen at run time
SCENELOD_ALWAYS_INLINE void buildOutputMeshBody(Eliminated& e, const Representatives& r, float crease_angle_deg,
                                                Mesh& out) {
  out = Mesh();
  const size_t nc = r.positions.size();
  const size_t tn = e.triangles.size() / 3;
  const bool colors = !r.colors.empty();
  const float cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0f, 180.0f) * 3.14159265358979f / 180.0f);

  // xyz: unit face normal (0 when degenerate), w: twice the area; every entry is written below: not zeroed
  std::unique_ptr<glm::vec4[]> face(new glm::vec4[tn]);
  // cluster -> incident triangle corners (a counting sort): corners of cluster c are counted in
  // offsets[c + 2] by the face pass (its loads of the indices serve both), so that after the prefix
  // sum offsets[c + 1] is where c's list starts and, advanced as the fill's cursor, where it ends:
  // then c's corners are offsets[c] .. offsets[c + 1] with no copy of the starts
  std::vector<uint32_t> offsets(nc + 2, 0);
  uint32_t* count = offsets.data() + 2;
  size_t t0 = 0;
#if defined(__SSE2__)
  // four faces at a time, one per lane, with the scalar loop's operations (glm::cross, glm::length,
  // the division): bit-identical, and the divider does a quarter of the divisions and roots
  {
    const glm::vec3* rp = r.positions.data();
    const uint32_t* tri = e.triangles.data();
    auto load = [&](uint32_t i) {  // (x, y, z, 0) without reading past the array
      return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&rp[i].x)),
                           _mm_load_ss(&rp[i].z));
    };
    for (; t0 + 4 <= tn; t0 += 4) {
      const uint32_t* c = tri + 3 * t0;
      for (int i = 0; i < 12; ++i) ++count[c[i]];
      __m128 ax = load(c[0]), ay = load(c[3]), az = load(c[6]), aw = load(c[9]);
      __m128 bx = load(c[1]), by = load(c[4]), bz = load(c[7]), bw = load(c[10]);
      __m128 cx = load(c[2]), cy = load(c[5]), cz = load(c[8]), cw = load(c[11]);
      _MM_TRANSPOSE4_PS(ax, ay, az, aw);
      _MM_TRANSPOSE4_PS(bx, by, bz, bw);
      _MM_TRANSPOSE4_PS(cx, cy, cz, cw);
      const __m128 ux = _mm_sub_ps(bx, ax), uy = _mm_sub_ps(by, ay), uz = _mm_sub_ps(bz, az);
      const __m128 vx = _mm_sub_ps(cx, ax), vy = _mm_sub_ps(cy, ay), vz = _mm_sub_ps(cz, az);
      const __m128 nx = _mm_sub_ps(_mm_mul_ps(uy, vz), _mm_mul_ps(vy, uz));
      const __m128 ny = _mm_sub_ps(_mm_mul_ps(uz, vx), _mm_mul_ps(vz, ux));
      const __m128 nz = _mm_sub_ps(_mm_mul_ps(ux, vy), _mm_mul_ps(vx, uy));
      const __m128 l = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, nx), _mm_mul_ps(ny, ny)), _mm_mul_ps(nz, nz)));
      const __m128 pos = _mm_cmpgt_ps(l, _mm_setzero_ps());
      __m128 fx = _mm_and_ps(pos, _mm_div_ps(nx, l)), fy = _mm_and_ps(pos, _mm_div_ps(ny, l));
      __m128 fz = _mm_and_ps(pos, _mm_div_ps(nz, l)), fw = _mm_and_ps(pos, l);
      _MM_TRANSPOSE4_PS(fx, fy, fz, fw);
      _mm_storeu_ps(&face[t0].x, fx), _mm_storeu_ps(&face[t0 + 1].x, fy);
      _mm_storeu_ps(&face[t0 + 2].x, fz), _mm_storeu_ps(&face[t0 + 3].x, fw);
    }
  }
#endif
  for (size_t t = t0; t < tn; ++t) {
    for (int i = 0; i < 3; ++i) ++count[e.triangles[3 * t + i]];
    const glm::vec3& a = r.positions[e.triangles[3 * t]];
    const glm::vec3 n = glm::cross(r.positions[e.triangles[3 * t + 1]] - a, r.positions[e.triangles[3 * t + 2]] - a);
    const float l = glm::length(n);
    face[t] = l > 0.0f ? glm::vec4(n / l, l) : glm::vec4(0.0f);
  }
  for (size_t c = 0; c < nc; ++c) offsets[c + 2] += offsets[c + 1];
  std::unique_ptr<uint32_t[]> corners(new uint32_t[e.triangles.size()]);  // all written: not zeroed
  {
    uint32_t* cursor = offsets.data() + 1;
    for (size_t i = 0; i < e.triangles.size(); ++i) corners[cursor[e.triangles[i]]++] = static_cast<uint32_t>(i);
  }
  offsets.pop_back();  // (nc + 1 entries: offsets[c] .. offsets[c + 1] are c's corners)
  std::vector<uint8_t> needs_vertex(nc, 0);
  for (uint32_t c : e.edges) needs_vertex[c] = 1;
  for (uint32_t c : e.points) needs_vertex[c] = 1;

  // each cluster's output vertices are base_vertex[c] .. the next used cluster's base_vertex
  std::vector<uint32_t> base_vertex(nc, kNone);
  // one vertex per used cluster, plus its copies split at creases (a few per cent on scanned meshes):
  // reserving that, not the cluster count, keeps the normals from doubling on the first split. Only
  // the normals are made in the cluster loop; the positions and colours, copies of the cluster's,
  // are made after it at the exact count (made beside the normals, the three arrays doubled where
  // the splits outgrew the reserve, as on the 1 M sphere's 10 % level, and all three were copied
  // again by shrink_to_fit: 3.9 MB of copies there).
  size_t used_count = 0;
  for (size_t c = 0; c < nc; ++c) used_count += offsets[c + 1] != offsets[c] || needs_vertex[c];
  const size_t expected_vertices = used_count + used_count / 16 + 16;
  out.normals.reserve(expected_vertices);
  auto addVertex = [&](const glm::vec3& n) {
    out.normals.push_back(n);
    return static_cast<uint32_t>(out.normals.size() - 1);
  };
  // the sufficient test of smoothCluster: faces within alpha of their mean direction are within
  // 2 alpha of each other; 2 alpha is the crease angle less a margin that covers the rounding of
  // the float dot products (see smoothCluster)
  const double cos_2alpha = double(cos_crease) + 1e-4;
  const bool fast = cos_2alpha < 1.0;
  const float cos_ref = fast ? float(std::cos(0.5 * std::acos(std::max(-1.0, cos_2alpha))) + 1e-5) : 2.0f;
  ClusterFaces cf;
  std::vector<glm::vec3> sums;  // per corner of the current cluster
  // Clusters are numbered by weight, not in space, so each cluster's faces (and its corners'
  // entries of e.triangles) are read at random; where the face array outgrows the caches, the first,
  // middle and last of the faces of the cluster kFacePrefetch ahead are fetched (its list is read
  // in order anyway).
  const size_t corner_count = e.triangles.size();
  const bool prefetch_faces = tn * sizeof(glm::vec4) > kFacePrefetchBytes;
  for (uint32_t c = 0; c < nc; ++c) {
    if (prefetch_faces && c + kFacePrefetch < nc) {
      const uint32_t pb = std::min<uint32_t>(offsets[c + kFacePrefetch], uint32_t(corner_count - 1));
      const uint32_t pl = std::max(offsets[c + kFacePrefetch + 1], pb + 1) - 1;
      const uint32_t first = corners[pb], middle = corners[(pb + pl) / 2], last = corners[pl];
      __builtin_prefetch(&face[first / 3]);
      __builtin_prefetch(&face[middle / 3]);
      __builtin_prefetch(&face[last / 3]);
      __builtin_prefetch(&e.triangles[first], 1);
      __builtin_prefetch(&e.triangles[last], 1);
    }
    const uint32_t b = offsets[c], en = offsets[c + 1];
    const uint32_t first_vertex = static_cast<uint32_t>(out.normals.size());
    const size_t k = en - b;
    if (k == 0) {
      if (needs_vertex[c]) base_vertex[c] = addVertex(r.normals[c]);
      continue;
    }
#if defined(__SSE2__)
    if (k <= kSmall) {
      // fixed trip counts: the loop exits of a varying k were about four mispredicted branches per
      // cluster. Rows past k repeat the last corner (its reads and writes stay in the cluster) and
      // are zeroed for the sums, where a zero face adds +0.
      uint32_t corner_of[kSmall];
      __m128 row[kSmall];
      // row j's mask, all ones for j < k: entry j of a window onto kSmall ones, then kSmall zeros
      static const int32_t kRowValid[2 * kSmall] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0};
      const int32_t* valid = kRowValid + kSmall - k;
      for (uint32_t j = 0; j < kSmall; ++j) {
        corner_of[j] = corners[b + std::min<uint32_t>(j, uint32_t(k) - 1)];
        row[j] = _mm_and_ps(_mm_loadu_ps(&face[corner_of[j] / 3].x), _mm_castsi128_ps(_mm_set1_epi32(valid[j])));
      }
      __m128 x0 = row[0], y0 = row[1], z0 = row[2], w0 = row[3];
      __m128 x1 = row[4], y1 = row[5], z1 = row[6], w1 = row[7];
      _MM_TRANSPOSE4_PS(x0, y0, z0, w0);
      _MM_TRANSPOSE4_PS(x1, y1, z1, w1);
      glm::vec3 n;  // as smoothCluster
      if (fast && smoothSmall(row, x0, y0, z0, w0, x1, y1, z1, w1, k, cos_ref, n)) {
        const uint32_t v = addVertex(n);
        for (uint32_t j = 0; j < kSmall; ++j) e.triangles[corner_of[j]] = v;
        base_vertex[c] = v;
        continue;
      }
      cf.resize(kSmall);
      _mm_storeu_ps(&cf.x[0], x0), _mm_storeu_ps(&cf.y[0], y0), _mm_storeu_ps(&cf.z[0], z0), _mm_storeu_ps(&cf.w[0], w0);
      _mm_storeu_ps(&cf.x[4], x1), _mm_storeu_ps(&cf.y[4], y1), _mm_storeu_ps(&cf.z[4], z1), _mm_storeu_ps(&cf.w[4], w1);
      uint32_t local[kSmall];
      glm::vec3 new_normals[kSmall];
      const uint32_t fresh = smallCorners(cf, k, cos_crease, r.normals[c], local, new_normals);
      for (uint32_t q = 0; q < fresh; ++q) addVertex(new_normals[q]);
      for (uint32_t j = 0; j < kSmall; ++j) e.triangles[corner_of[j]] = first_vertex + local[j];
      base_vertex[c] = first_vertex;
      continue;
    } else
#endif
    {
      cf.resize(k);
      for (size_t j = 0; j < k; ++j) {
        const glm::vec4& fj = face[corners[b + j] / 3];
        cf.x[j] = fj.x, cf.y[j] = fj.y, cf.z[j] = fj.z, cf.w[j] = fj.w;
      }
      // the cluster's faces all within the crease angle of each other: every corner's sum is the
      // same ordered sum (see smoothCluster), so the cluster takes one vertex
      glm::vec3 n;
      if (fast && smoothCluster(cf, k, cos_ref, n)) {
        const uint32_t v = addVertex(n);
        for (uint32_t i = b; i < en; ++i) e.triangles[corners[i]] = v;
        base_vertex[c] = v;
        continue;
      }
    }
    if (sums.size() < k) sums.resize(k);
    cornerNormals(cf, k, cos_crease, sums.data());
    for (uint32_t i = b; i < en; ++i) {
      glm::vec3 n = sums[i - b];
      const float l = glm::length(n);
      n = l > 0.0f ? n / l : r.normals[c];
      uint32_t v = kNone;
      for (uint32_t q = first_vertex; q < out.normals.size(); ++q)
        if (out.normals[q] == n) {
          v = q;
          break;
        }
      if (v == kNone) v = addVertex(n);
      // each corner's cluster id is no longer read once the corner lists exist: the output
      // vertex takes its place, so the output triangles need no second array
      e.triangles[corners[i]] = v;
    }
    base_vertex[c] = first_vertex;
  }
  face.reset();
  corners.reset();
  // the chain keeps every level: the normals give back the reserve's slack
  out.normals.shrink_to_fit();
  {
    const size_t vertex_count = out.normals.size();
    out.positions.reserve(vertex_count);
    if (colors) out.colors.reserve(vertex_count);
    uint32_t prev = kNone;  // the last cluster seen with vertices: its run ends where the next one's starts
    auto fill = [&](uint32_t c, size_t end) {  // (vector's fill insert took about 60 instructions a call)
      const glm::vec3 p = r.positions[c];
      for (size_t v = out.positions.size(); v < end; ++v) out.positions.push_back(p);
      if (colors)
        for (size_t v = out.colors.size(); v < end; ++v) out.colors.push_back(r.colors[c]);
    };
    for (uint32_t c = 0; c < nc; ++c) {
      if (base_vertex[c] == kNone) continue;
      if (prev != kNone) fill(prev, base_vertex[c]);
      prev = c;
    }
    if (prev != kNone) fill(prev, vertex_count);
  }
  out.triangles = std::move(e.triangles);
  out.triangles.shrink_to_fit();  // elimination reserved for about 2 triangles per cluster
  out.edges.resize(e.edges.size());
  for (size_t i = 0; i < e.edges.size(); ++i) out.edges[i] = base_vertex[e.edges[i]];
  out.edge_thickness = std::move(e.edge_thickness);
  if (out.edge_thickness.size() != out.edges.size() / 2) out.edge_thickness.assign(out.edges.size() / 2, 0.0f);
  out.points.resize(e.points.size());
  for (size_t i = 0; i < e.points.size(); ++i) out.points[i] = base_vertex[e.points[i]];
}

void buildOutputMeshSse2(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  buildOutputMeshBody(e, r, crease_angle_deg, out);
}
SCENELOD_AVX2_TARGET void buildOutputMeshAvx2(Eliminated& e, const Representatives& r, float crease_angle_deg,
                                              Mesh& out) {
  buildOutputMeshBody(e, r, crease_angle_deg, out);
}

}  // namespace

void buildOutputMesh(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  if (avx2Paths()) buildOutputMeshAvx2(e, r, crease_angle_deg, out);
  else buildOutputMeshSse2(e, r, crease_angle_deg, out);
}

}  // namespace scenelod::detail
