// Adjustment of normals (Low & Tan 1997 §2 step 6): face normals of the simplified triangles, and
// vertex normals that average only faces within a crease angle of each other, splitting a cluster's
// vertex into one copy per distinct normal. Vertices only used by edges and points take the
// cluster's area-weighted normal of the original faces (edges are shaded with dynamic normals).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "cluster_internal.h"
#include "test_hooks.h"

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

// The unit face normals (0 when degenerate) and double areas, in blocks of eight faces as
// structure-of-arrays (128 bytes a block; face t in block t / 8, lane t % 8): the face pass writes
// its lanes and the corner test reads them without a transpose (AoS entries took two 4 x 4
// transposes per four faces, 16 of the face pass's 49 shuffles there and 8 of the test's 32).
struct FaceBlock {
  float x[8], y[8], z[8], w[8];
};
inline glm::vec4 faceAt(const FaceBlock* f, size_t t) {
  const FaceBlock& b = f[t >> 3];
  const size_t l = t & 7;
  return glm::vec4(b.x[l], b.y[l], b.z[l], b.w[l]);
}
inline void setFace(FaceBlock* f, size_t t, const glm::vec4& v) {
  FaceBlock& b = f[t >> 3];
  const size_t l = t & 7;
  b.x[l] = v.x, b.y[l] = v.y, b.z[l] = v.z, b.w[l] = v.w;
}

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

// the output's edges and points: each cluster-level edge or point at its cluster's first output
// vertex (`base_vertex`), the edges' thicknesses moved over (zeros where the input had none)
void carryEdgesAndPoints(Eliminated& e, const uint32_t* base_vertex, Mesh& out) {
  out.edges.resize(e.edges.size());
  for (size_t i = 0; i < e.edges.size(); ++i) out.edges[i] = base_vertex[e.edges[i]];
  out.edge_thickness = std::move(e.edge_thickness);
  if (out.edge_thickness.size() != out.edges.size() / 2) out.edge_thickness.assign(out.edges.size() / 2, 0.0f);
  out.points.resize(e.points.size());
  for (size_t i = 0; i < e.points.size(); ++i) out.points[i] = base_vertex[e.points[i]];
}

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

// The smooth test: a cluster whose faces all lie within the crease angle of each other gives every
// corner the same sum in cornerNormals (each lane adds every face, in order, to +0), so it takes one
// vertex with that sum normalised. A sufficient test for "all within the crease angle": each face's
// unit normal u_j within alpha of the normalised sum m (float dot(u_j, m) >= cos_ref = cos alpha +
// 1e-5), so any two are within 2 alpha, whose cosine is cos_crease + 1e-4. The margins exceed the
// rounding of the float dot products (a few 1e-7 for normals of length 1 +- 4e-7; faces or sums
// shorter than 1e-18, whose normalisation could be less exact, fail the test), so a pass means the
// lanes' d >= cos_crease for every pair.

#if defined(__SSE2__)
// Listed clusters (those failing the smooth test) of at most this many corners take a fixed-size path.
constexpr uint32_t kSmall = 8;

// The corner loop of buildOutputMesh for a cluster of k <= kSmall faces held in f, zero-padded to
// kSmall: writes each corner's output vertex to local[0 .. kSmall) (indices from the cluster's first
// vertex; entries past k repeat corner k - 1's) and the normals of the new vertices, in order, to
// new_normals (which must hold kSmall: the entries past the count are written too); returns
// their count. The same values as that loop: the sums of cornerNormals over
// all kSmall faces (a zero face adds +0), normalised lane by lane as glm::length and the division
// do (the fallback where the length is 0), and each corner takes the vertex of the first earlier
// corner with an equal normal (== is transitive away from NaN, which equals nothing), else a new
// one; the pairs are compared in lanes, without a branch per pair.
uint32_t smallCorners(const ClusterFaces& f, size_t k, float cos_crease, const glm::vec3& fallback,
                      uint32_t local[kSmall], glm::vec3* new_normals) {
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

#if defined(__SSE2__)
// _MM_TRANSPOSE4_PS in each 128-bit half: rows r0 .. r3 of two 4 x 4 blocks become their columns
SCENELOD_AVX2_TARGET inline void transposeHalves(__m256& r0, __m256& r1, __m256& r2, __m256& r3) {
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpacklo_ps(r2, r3);
  const __m256 t2 = _mm256_unpackhi_ps(r0, r1), t3 = _mm256_unpackhi_ps(r2, r3);
  r0 = _mm256_shuffle_ps(t0, t1, 0x44), r1 = _mm256_shuffle_ps(t0, t1, 0xee);
  r2 = _mm256_shuffle_ps(t2, t3, 0x44), r3 = _mm256_shuffle_ps(t2, t3, 0xee);
}

// (p[i], 0, p[j], 0) by two masked loads, which read nothing past the array (lanes masked off
// never fault) and take no shuffle: the 128-bit path's movq, movss and movlhps per position were
// 12 of its 49 shuffles per four faces (the loop waits on the shuffle port: without its
// transposes the face pass took 0.093-0.103 ms instead of 0.138-0.144 at the bunny's 50 % level)
SCENELOD_AVX2_TARGET inline __m256 positionPair(const glm::vec3* p, uint32_t i, uint32_t j) {
  const __m256i lo = _mm256_setr_epi32(-1, -1, -1, 0, 0, 0, 0, 0), hi = _mm256_setr_epi32(0, 0, 0, 0, -1, -1, -1, 0);
  // the high half's three floats at p[j], the masked-off low half's address 16 bytes before it
  const float* before = reinterpret_cast<const float*>(reinterpret_cast<uintptr_t>(&p[j].x) - 16);
  return _mm256_or_ps(_mm256_maskload_ps(&p[i].x, lo), _mm256_maskload_ps(before, hi));
}

// The face pass of buildOutputMeshBody eight faces at a time (faces t and t + 4 of each group in
// one row's halves, so the transposes work in halves): each lane does the four-face loop's
// operations, and the sums are added to the clusters in corner order as there; returns the faces
// done (a multiple of 8; the caller does the rest)
SCENELOD_AVX2_TARGET size_t facePass8(const uint32_t* tri, size_t tn, const glm::vec3* rp, FaceBlock* face,
                                      glm::vec4* mean) {
  size_t t = 0;
  for (; t + 8 <= tn; t += 8) {
    const uint32_t* c = tri + 3 * t;
    __m256 ax = positionPair(rp, c[0], c[12]), ay = positionPair(rp, c[3], c[15]);
    __m256 az = positionPair(rp, c[6], c[18]), aw = positionPair(rp, c[9], c[21]);
    __m256 bx = positionPair(rp, c[1], c[13]), by = positionPair(rp, c[4], c[16]);
    __m256 bz = positionPair(rp, c[7], c[19]), bw = positionPair(rp, c[10], c[22]);
    __m256 cx = positionPair(rp, c[2], c[14]), cy = positionPair(rp, c[5], c[17]);
    __m256 cz = positionPair(rp, c[8], c[20]), cw = positionPair(rp, c[11], c[23]);
    transposeHalves(ax, ay, az, aw);
    transposeHalves(bx, by, bz, bw);
    transposeHalves(cx, cy, cz, cw);
    const __m256 ux = _mm256_sub_ps(bx, ax), uy = _mm256_sub_ps(by, ay), uz = _mm256_sub_ps(bz, az);
    const __m256 vx = _mm256_sub_ps(cx, ax), vy = _mm256_sub_ps(cy, ay), vz = _mm256_sub_ps(cz, az);
    const __m256 nx = _mm256_sub_ps(_mm256_mul_ps(uy, vz), _mm256_mul_ps(vy, uz));
    const __m256 ny = _mm256_sub_ps(_mm256_mul_ps(uz, vx), _mm256_mul_ps(vz, ux));
    const __m256 nz = _mm256_sub_ps(_mm256_mul_ps(ux, vy), _mm256_mul_ps(vx, uy));
    const __m256 l = _mm256_sqrt_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, nx), _mm256_mul_ps(ny, ny)), _mm256_mul_ps(nz, nz)));
    const __m256 pos = _mm256_cmp_ps(l, _mm256_setzero_ps(), _CMP_GT_OQ);
    const __m256 fx = _mm256_and_ps(pos, _mm256_div_ps(nx, l)), fy = _mm256_and_ps(pos, _mm256_div_ps(ny, l));
    const __m256 fz = _mm256_and_ps(pos, _mm256_div_ps(nz, l)), fw = _mm256_and_ps(pos, l);
    FaceBlock& fb = face[t >> 3];
    _mm256_storeu_ps(fb.x, fx), _mm256_storeu_ps(fb.y, fy), _mm256_storeu_ps(fb.z, fz), _mm256_storeu_ps(fb.w, fw);
    __m256 sx = _mm256_mul_ps(fx, fw), sy = _mm256_mul_ps(fy, fw), sz = _mm256_mul_ps(fz, fw);
    __m256 sw = _mm256_set1_ps(1.0f);
    transposeHalves(sx, sy, sz, sw);
    const __m128 add[8] = {_mm256_castps256_ps128(sx),   _mm256_castps256_ps128(sy),   _mm256_castps256_ps128(sz),
                           _mm256_castps256_ps128(sw),   _mm256_extractf128_ps(sx, 1), _mm256_extractf128_ps(sy, 1),
                           _mm256_extractf128_ps(sz, 1), _mm256_extractf128_ps(sw, 1)};
    // in corner order, as the four-face loop; unrolled (GCC leaves a 24-trip loop, whose exit was
    // mispredicted once per eight faces: 4,351 times at the bunny's 50 % level)
#pragma GCC unroll 24
    for (int i = 0; i < 24; ++i) {
      float* m = &mean[c[i]].x;
      _mm_storeu_ps(m, _mm_add_ps(_mm_loadu_ps(m), add[i / 3]));
    }
  }
  return t;
}

// (m[i], m[j]) in a row's halves
SCENELOD_AVX2_TARGET inline __m256 meanPair(const glm::vec4* m, uint32_t i, uint32_t j) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&m[i].x)), _mm_loadu_ps(&m[j].x), 1);
}

// each 8-bit mask as eight bytes 0 or 1 (byte q is bit q), 2 KB built at compile time
struct MaskBytes {
  uint64_t bytes[256];
  constexpr MaskBytes() : bytes() {
    for (uint32_t mask = 0; mask < 256; ++mask)
      for (uint32_t q = 0; q < 8; ++q) bytes[mask] |= uint64_t((mask >> q) & 1u) << (8 * q);
  }
};
inline constexpr MaskBytes kMaskBytes;

// The normalisation pass of buildOutputMeshBody eight clusters at a time (clusters c and c + 4 of
// each group in one row's halves): per lane glm::length's products and sums in its order, the
// root, the division, the corner count's conversion and the first smooth verdict, as the scalar
// loop; the verdicts as eight bytes from a table. At the bunny's 50 % level 0.040 -> 0.013 ms (the
// scalar loop waited on a root and a division per cluster). Returns the clusters done (a multiple of 8).
SCENELOD_AVX2_TARGET size_t normaliseSums8(size_t nc, bool fast, glm::vec4* mean, uint32_t* count, uint8_t* smooth) {
  const __m256 min_l = _mm256_set1_ps(1e-18f);
  const __m256i fast_mask = _mm256_set1_epi32(fast ? -1 : 0);
  size_t c = 0;
  for (; c + 8 <= nc; c += 8) {
    glm::vec4* m = mean + c;
    __m256 x = meanPair(m, 0, 4), y = meanPair(m, 1, 5), z = meanPair(m, 2, 6), w = meanPair(m, 3, 7);
    transposeHalves(x, y, z, w);
    const __m256 l = _mm256_sqrt_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z)));
    const __m256i k = _mm256_cvttps_epi32(w);  // exact: a count below 2^24
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(count + c), k);
    const __m256i with_faces = _mm256_andnot_si256(_mm256_cmpeq_epi32(k, _mm256_setzero_si256()), fast_mask);
    const __m256 ok = _mm256_and_ps(_mm256_castsi256_ps(with_faces), _mm256_cmp_ps(l, min_l, _CMP_GE_OQ));
    const uint64_t bytes = kMaskBytes.bytes[_mm256_movemask_ps(ok)];
    std::memcpy(smooth + c, &bytes, 8);
    __m256 nx = _mm256_div_ps(x, l), ny = _mm256_div_ps(y, l), nz = _mm256_div_ps(z, l), nw = _mm256_setzero_ps();
    transposeHalves(nx, ny, nz, nw);
    _mm_storeu_ps(&m[0].x, _mm256_castps256_ps128(nx)), _mm_storeu_ps(&m[4].x, _mm256_extractf128_ps(nx, 1));
    _mm_storeu_ps(&m[1].x, _mm256_castps256_ps128(ny)), _mm_storeu_ps(&m[5].x, _mm256_extractf128_ps(ny, 1));
    _mm_storeu_ps(&m[2].x, _mm256_castps256_ps128(nz)), _mm_storeu_ps(&m[6].x, _mm256_extractf128_ps(nz, 1));
    _mm_storeu_ps(&m[3].x, _mm256_castps256_ps128(nw)), _mm_storeu_ps(&m[7].x, _mm256_extractf128_ps(nw, 1));
  }
  return c;
}

// The corner test of buildOutputMeshBody eight faces at a time: faces t .. t + 7 in the lanes, the
// sums of corner k of faces q and q + 4 loaded into one row's halves (a load and an insert from
// memory, no shuffle), one transpose in halves for eight corners; the four-face loop's products,
// sums and tests per lane. Returns the faces done (a multiple of 8).
SCENELOD_AVX2_TARGET size_t cornerTest8(const uint32_t* tri, size_t tn, const FaceBlock* face, const glm::vec4* mean,
                                        float cos_ref, uint8_t* smooth) {
  const __m256 ref = _mm256_set1_ps(cos_ref), min_w = _mm256_set1_ps(1e-18f);
  size_t t = 0;
  for (; t + 8 <= tn; t += 8) {
    const FaceBlock& fb = face[t >> 3];
    const __m256 ux = _mm256_loadu_ps(fb.x), uy = _mm256_loadu_ps(fb.y), uz = _mm256_loadu_ps(fb.z);
    const __m256 long_enough = _mm256_cmp_ps(_mm256_loadu_ps(fb.w), min_w, _CMP_GE_OQ);
    const uint32_t* c = tri + 3 * t;
    uint32_t fail = 0;  // bit 8 k + q: corner k of face q failed
#pragma GCC unroll 3
    for (int k = 0; k < 3; ++k) {
      __m256 mx = meanPair(mean, c[k], c[12 + k]), my = meanPair(mean, c[3 + k], c[15 + k]);
      __m256 mz = meanPair(mean, c[6 + k], c[18 + k]), mw = meanPair(mean, c[9 + k], c[21 + k]);
      transposeHalves(mx, my, mz, mw);
      const __m256 d =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ux, mx), _mm256_mul_ps(uy, my)), _mm256_mul_ps(uz, mz));
      const uint32_t pass =
          uint32_t(_mm256_movemask_ps(_mm256_and_ps(long_enough, _mm256_cmp_ps(d, ref, _CMP_GE_OQ))));
      fail |= (~pass & 0xffu) << (8 * k);
    }
    // the failed corners' clusters cleared one by one behind one branch per eight faces: at the
    // bunny's 50 % level 1,476 of 104,070 corners fail, and the loop's exits are mispredicted about
    // 1,725 times, where a byte clear per corner (and its bit extraction) took 6.6 instructions a
    // corner, 0.69 M: corner test 0.085 -> 0.058 ms
    for (; fail != 0; fail &= fail - 1) {
      const uint32_t bit = uint32_t(__builtin_ctz(fail));
      smooth[c[3 * (bit & 7) + (bit >> 3)]] = 0;
    }
  }
  return t;
}

// facePass8's baseline from face t0 on (the faces it leaves; returns where it stops): four faces at
// a time, one per lane, with the scalar loop's operations (glm::cross, glm::length, the division,
// the products by the area): bit-identical, and the divider does a quarter of the divisions and roots
SCENELOD_ALWAYS_INLINE size_t facePass4(const uint32_t* tri, size_t t0, size_t tn, const glm::vec3* rp,
                                        FaceBlock* face, glm::vec4* mean) {
  auto load = [&](uint32_t i) {  // (x, y, z, 0) without reading past the array
    return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(&rp[i].x)),
                         _mm_load_ss(&rp[i].z));
  };
  for (; t0 + 4 <= tn; t0 += 4) {
    const uint32_t* c = tri + 3 * t0;
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
    const __m128 fx = _mm_and_ps(pos, _mm_div_ps(nx, l)), fy = _mm_and_ps(pos, _mm_div_ps(ny, l));
    const __m128 fz = _mm_and_ps(pos, _mm_div_ps(nz, l)), fw = _mm_and_ps(pos, l);
    __m128 sx = _mm_mul_ps(fx, fw), sy = _mm_mul_ps(fy, fw), sz = _mm_mul_ps(fz, fw), sw = _mm_set1_ps(1.0f);
    _MM_TRANSPOSE4_PS(sx, sy, sz, sw);
    FaceBlock& fb = face[t0 >> 3];
    const size_t h = t0 & 4;  // the block's first or second half
    _mm_storeu_ps(fb.x + h, fx), _mm_storeu_ps(fb.y + h, fy), _mm_storeu_ps(fb.z + h, fz), _mm_storeu_ps(fb.w + h, fw);
    const __m128 add[4] = {sx, sy, sz, sw};
    for (int i = 0; i < 12; ++i) {  // in corner order: a cluster's sum as its corner list would give it
      float* m = &mean[c[i]].x;
      _mm_storeu_ps(m, _mm_add_ps(_mm_loadu_ps(m), add[i / 3]));
    }
  }
  return t0;
}

// cornerTest8's baseline from face t1 on (returns where it stops): four faces at a time, one per
// lane, and their corners k = 0, 1, 2 in turn: the scalar loop's products and sums in its order, its
// two tests; the lanes' verdicts cleared in smooth one byte at a time (scalar: 19 instructions a
// corner, 2.0 M of the bunny's 50 % level)
SCENELOD_ALWAYS_INLINE size_t cornerTest4(const uint32_t* tri, size_t t1, size_t tn, const FaceBlock* face,
                                          const glm::vec4* mean, float cos_ref, uint8_t* smooth) {
  const __m128 ref = _mm_set1_ps(cos_ref), min_w = _mm_set1_ps(1e-18f);
  for (; t1 + 4 <= tn; t1 += 4) {
    const FaceBlock& fb = face[t1 >> 3];
    const size_t h = t1 & 4;
    const __m128 ux = _mm_loadu_ps(fb.x + h), uy = _mm_loadu_ps(fb.y + h), uz = _mm_loadu_ps(fb.z + h);
    const __m128 long_enough = _mm_cmpge_ps(_mm_loadu_ps(fb.w + h), min_w);
    const uint32_t* c = tri + 3 * t1;
    for (int k = 0; k < 3; ++k) {
      __m128 mx = _mm_loadu_ps(&mean[c[k]].x), my = _mm_loadu_ps(&mean[c[3 + k]].x);
      __m128 mz = _mm_loadu_ps(&mean[c[6 + k]].x), mw = _mm_loadu_ps(&mean[c[9 + k]].x);
      _MM_TRANSPOSE4_PS(mx, my, mz, mw);
      const __m128 d = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ux, mx), _mm_mul_ps(uy, my)), _mm_mul_ps(uz, mz));
      const uint32_t pass = uint32_t(_mm_movemask_ps(_mm_and_ps(long_enough, _mm_cmpge_ps(d, ref))));
      for (int q = 0; q < 4; ++q) smooth[c[3 * q + k]] &= uint8_t((pass >> q) & 1u);
    }
  }
  return t1;
}
#endif

// The vertex normals of the clusters whose corners are listed (offsets[c] .. offsets[c + 1] of
// corners, a cluster's corners in order): per listed corner its vertex among its cluster's
// (local_vertex), the clusters' distinct normals in cluster order into split_normals (their count
// returned), each listed cluster's vertex count in base_vertex[c]. Inlined into each build of
// buildOutputMeshBody.
SCENELOD_ALWAYS_INLINE size_t splitClusters(const std::vector<uint32_t>& offsets, const uint32_t* corners,
                                            const FaceBlock* face, const Representatives& r, float cos_crease,
                                            uint32_t* local_vertex, glm::vec3* split_normals,
                                            std::vector<uint32_t>& base_vertex) {
  const size_t nc = r.positions.size();
  size_t split_count = 0;
  ClusterFaces cf;
  std::vector<glm::vec3> sums;  // per corner of the current cluster
  const uint32_t* end_of = offsets.data() + 1;
  for (uint32_t c = 0; c < nc; ++c) {
    // the next listed cluster by a tight scan (3 % of the clusters at the bunny's 50 % level: the
    // loop's full test took 13 instructions a cluster, 0.22 M)
    while (c < nc && end_of[c] == offsets[c]) ++c;
    if (c == nc) break;
    const uint32_t b = offsets[c], en = end_of[c];
    const size_t k = en - b;
    const size_t first = split_count;
#if defined(__SSE2__)
    if (k <= kSmall) {
      // fixed trip counts: the loop exits of a varying k were about four mispredicted branches per
      // cluster. Rows past k repeat the last corner and are zeroed, where a zero face adds +0.
      __m128 row[kSmall];
      // row j's mask, all ones for j < k: entry j of a window onto kSmall ones, then kSmall zeros
      static const int32_t kRowValid[2 * kSmall] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0};
      const int32_t* valid = kRowValid + kSmall - k;
      for (uint32_t j = 0; j < kSmall; ++j) {
        const uint32_t corner = corners[b + std::min<uint32_t>(j, uint32_t(k) - 1)];
        const glm::vec4 fj = faceAt(face, corner / 3);
        row[j] = _mm_and_ps(_mm_setr_ps(fj.x, fj.y, fj.z, fj.w), _mm_castsi128_ps(_mm_set1_epi32(valid[j])));
      }
      __m128 x0 = row[0], y0 = row[1], z0 = row[2], w0 = row[3];
      __m128 x1 = row[4], y1 = row[5], z1 = row[6], w1 = row[7];
      _MM_TRANSPOSE4_PS(x0, y0, z0, w0);
      _MM_TRANSPOSE4_PS(x1, y1, z1, w1);
      cf.resize(kSmall);
      _mm_storeu_ps(&cf.x[0], x0), _mm_storeu_ps(&cf.y[0], y0), _mm_storeu_ps(&cf.z[0], z0), _mm_storeu_ps(&cf.w[0], w0);
      _mm_storeu_ps(&cf.x[4], x1), _mm_storeu_ps(&cf.y[4], y1), _mm_storeu_ps(&cf.z[4], z1), _mm_storeu_ps(&cf.w[4], w1);
      uint32_t local[kSmall];
      const uint32_t fresh = smallCorners(cf, k, cos_crease, r.normals[c], local, &split_normals[first]);
      split_count += fresh;
      for (uint32_t j = 0; j < kSmall; ++j) local_vertex[b + std::min<uint32_t>(j, uint32_t(k) - 1)] = local[j];
      base_vertex[c] = fresh;
      continue;
    }
#endif
    cf.resize(k);
    for (size_t j = 0; j < k; ++j) {
      const glm::vec4 fj = faceAt(face, corners[b + j] / 3);
      cf.x[j] = fj.x, cf.y[j] = fj.y, cf.z[j] = fj.z, cf.w[j] = fj.w;
    }
    if (sums.size() < k) sums.resize(k);
    cornerNormals(cf, k, cos_crease, sums.data());
    for (uint32_t i = b; i < en; ++i) {
      glm::vec3 n = sums[i - b];
      const float l = glm::length(n);
      n = l > 0.0f ? n / l : r.normals[c];
      size_t v = first;
      while (v < split_count && !(split_normals[v] == n)) ++v;
      if (v == split_count) split_normals[split_count++] = n;
      local_vertex[i] = static_cast<uint32_t>(v - first);
    }
    base_vertex[c] = static_cast<uint32_t>(split_count - first);
  }
  return split_count;
}

// The output vertices, cluster by cluster: one for a smooth cluster (its mean normal) or for one
// only used by edges and points (its synthesized normal), a split cluster's copies in order (its
// normals from split_normals, base_vertex[c] of them); base_vertex[c] becomes c's first vertex
SCENELOD_ALWAYS_INLINE void writeVertices(const Representatives& r, const uint8_t* smooth, const uint8_t* needs_vertex,
                                          const uint32_t* offsets, const glm::vec4* mean, const glm::vec3* split,
                                          size_t vertex_count, uint32_t* base_vertex, Mesh& out) {
  const size_t nc = r.positions.size();
  const bool colors = !r.colors.empty();
  out.normals.resize(vertex_count);
  out.positions.resize(vertex_count);
  if (colors) out.colors.resize(vertex_count);
  glm::vec3* normals = out.normals.data();
  glm::vec3* positions = out.positions.data();
  glm::vec3* out_colors = out.colors.data();
  uint32_t v = 0;
  for (uint32_t c = 0; c < nc; ++c) {
    uint32_t n;
    if (smooth[c]) {  // (97 % of the clusters at the bunny's 50 % level) one vertex, without the copy loops
      normals[v] = glm::vec3(mean[c]), positions[v] = r.positions[c];
      if (colors) out_colors[v] = r.colors[c];
      base_vertex[c] = v++;
      continue;
    } else if (offsets[c + 1] != offsets[c]) {
      n = base_vertex[c];
      for (uint32_t q = 0; q < n; ++q) normals[v + q] = *split++;
    } else if (needs_vertex[c]) n = 1, normals[v] = r.normals[c];
    else continue;
    base_vertex[c] = v;
    for (uint32_t q = 0; q < n; ++q) positions[v + q] = r.positions[c];
    if (colors)
      for (uint32_t q = 0; q < n; ++q) out_colors[v + q] = r.colors[c];
    v += n;
  }
}

// buildOutputMesh, compiled into a baseline function and an AVX2 one (as synthesize's loops; see
// synthesis.cpp), chosen at run time.
//
// Most clusters at the fine levels are smooth (bunny 50 %: all but about 600 of 34,684), so the
// smooth test runs in two passes over the faces in corner order instead of per cluster: the face
// pass adds each face's weighted normal to its corners' cluster sums (the corners in increasing
// order, which is the order of each cluster's corner list: the same ordered sum from +0), and a
// second pass tests each corner's face against its cluster's normalised sum. Only the clusters
// that fail it are sorted into corner lists (a counting sort over the failing clusters alone) and
// take the per-corner path. Their vertices are made before any output array, so the normals,
// positions and colours are allocated at the exact count and filled in one cluster loop, with no
// reserve and no shrink. (Before: a counting sort of every corner, 9 instructions a corner, and an
// eight-row gather, two transposes and the test per cluster, about 150 instructions a cluster.)
template <bool avx2>
SCENELOD_ALWAYS_INLINE void buildOutputMeshBody(Eliminated& e, const Representatives& r, float crease_angle_deg,
                                                Mesh& out) {
  out = Mesh();
  const size_t nc = r.positions.size();
  const size_t tn = e.triangles.size() / 3;
  const size_t corner_count = e.triangles.size();
  const float cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0f, 180.0f) * 3.14159265358979f / 180.0f);
  // the sufficient test (see above): faces within alpha of their mean direction are within 2 alpha
  // of each other; 2 alpha is the crease angle less a margin that covers the rounding of the float
  // dot products
  const double cos_2alpha = double(cos_crease) + 1e-4;
  const bool fast = cos_2alpha < 1.0;
  const float cos_ref = fast ? float(std::cos(0.5 * std::acos(std::max(-1.0, cos_2alpha))) + 1e-5) : 2.0f;
  uint32_t* tri = e.triangles.data();

  // every face is written below: not zeroed (the last block's lanes past tn are never read)
  std::unique_ptr<FaceBlock[]> face(new FaceBlock[(tn + 7) / 8]);
  // per cluster, 16 bytes: xyz the sum over its faces, in corner order, of the unit normal times
  // twice the area, then (after the face pass) that sum normalised; w its corner count (a float,
  // exact below 2^24 corners: the face pass adds it in the sums' spare lane, not in a second array)
  std::unique_ptr<glm::vec4[]> mean(new glm::vec4[nc]);
  std::fill_n(mean.get(), nc, glm::vec4(0.0f));
  // corners of the clusters that fail the smooth test are counted in offsets[c + 2] and sorted: after the prefix sum offsets[c + 1] is where c's
  // list starts and, advanced as the fill's cursor, where it ends, so c's corners are offsets[c] ..
  // offsets[c + 1] with no copy of the starts
  std::vector<uint32_t> offsets(nc + 2, 0);
  uint32_t* count = offsets.data() + 2;
  size_t t0 = 0;
#if defined(__SSE2__)
  if constexpr (avx2) t0 = facePass8(tri, tn, r.positions.data(), face.get(), mean.get());
  t0 = facePass4(tri, t0, tn, r.positions.data(), face.get(), mean.get());
#endif
  for (size_t t = t0; t < tn; ++t) {
    const glm::vec3& a = r.positions[tri[3 * t]];
    const glm::vec3 n = glm::cross(r.positions[tri[3 * t + 1]] - a, r.positions[tri[3 * t + 2]] - a);
    const float l = glm::length(n);
    const glm::vec4 f = l > 0.0f ? glm::vec4(n / l, l) : glm::vec4(0.0f);
    setFace(face.get(), t, f);
    const glm::vec4 add(f.x * f.w, f.y * f.w, f.z * f.w, 1.0f);
    for (int i = 0; i < 3; ++i) mean[tri[3 * t + i]] += add;
  }
  std::vector<uint8_t> needs_vertex(nc, 0);
  for (uint32_t c : e.edges) needs_vertex[c] = 1;
  for (uint32_t c : e.points) needs_vertex[c] = 1;
  // 1 while a cluster with faces may be smooth: its sum long enough, then every face passing
  std::vector<uint8_t> smooth(nc, 0);
  size_t c0 = 0;
#if defined(__SSE2__)
  if constexpr (avx2) c0 = normaliseSums8(nc, fast, mean.get(), count, smooth.data());
#endif
  for (size_t c = c0; c < nc; ++c) {
    const glm::vec3 s(mean[c]);
    const float l = glm::length(s);
    count[c] = static_cast<uint32_t>(mean[c].w);
    smooth[c] = uint8_t(fast & (count[c] != 0) & (l >= 1e-18f));
    mean[c] = glm::vec4(s / l, 0.0f);  // (NaN where l is 0: then not smooth, and NaN passes no test)
  }
  size_t t1 = 0;
#if defined(__SSE2__)
  if constexpr (avx2) t1 = cornerTest8(tri, tn, face.get(), mean.get(), cos_ref, smooth.data());
  t1 = cornerTest4(tri, t1, tn, face.get(), mean.get(), cos_ref, smooth.data());
#endif
  for (size_t t = t1; t < tn; ++t) {
    const glm::vec4 u = faceAt(face.get(), t);
    const bool long_enough = u.w >= 1e-18f;
    for (int i = 0; i < 3; ++i) {
      const uint32_t c = tri[3 * t + i];
      const glm::vec4& m = mean[c];
      smooth[c] &= uint8_t(long_enough & (u.x * m.x + u.y * m.y + u.z * m.z >= cos_ref));
    }
  }
  // the counting sort of the clusters that failed; the output vertex count
  size_t vertex_count = 0;
  for (size_t c = 0; c < nc; ++c) {
    const bool no_faces = count[c] == 0;
    vertex_count += smooth[c] | (no_faces & needs_vertex[c]);  // the split clusters' vertices are added below
    if (smooth[c]) count[c] = 0;
  }
  for (size_t c = 0; c < nc; ++c) offsets[c + 2] += offsets[c + 1];
  const size_t listed = offsets[nc + 1];
  // all written: not zeroed
  std::unique_ptr<uint32_t[]> corners(new uint32_t[listed]);
  // per listed corner: its vertex among its cluster's vertices (one more: the fill lists the
  // corners here first)
  std::unique_ptr<uint32_t[]> local_vertex(new uint32_t[listed + 1]);
  {
    // the listed corners packed in order without a branch (every corner written, the count moved on
    // for the listed ones), then sorted by cluster: a branch on smooth[c] per corner was mispredicted
    // about 4,100 times at the bunny's 50 % level (3 % of the corners listed, spread out), and its
    // branch-free select took 12 instructions a corner: the fill 0.074 -> 0.044 ms there, 0.023 ->
    // 0.017 at level 2. (Eight corners at a time, their verdicts gathered, packed by kLaneCompaction:
    // 0.073-0.080 ms, 0.027 at level 2; a gather took about 20 cycles here.)
    uint32_t* cursor = offsets.data() + 1;
    const uint8_t* sm = smooth.data();
    uint32_t* list = corners.get();
    uint32_t* found = local_vertex.get();
    size_t n = 0;
    for (size_t i = 0; i < corner_count; ++i) {
      found[n] = static_cast<uint32_t>(i);
      n += sm[tri[i]] == 0;
    }
    for (size_t j = 0; j < n; ++j) {
      const uint32_t i = found[j];
      list[cursor[tri[i]]++] = i;
    }
  }
  offsets.pop_back();  // (nc + 1 entries: offsets[c] .. offsets[c + 1] are c's listed corners)

  // the listed clusters' vertex normals, in cluster order; each one's vertex count in base_vertex
  // until the output loop below gives it its first vertex
  std::vector<uint32_t> base_vertex(nc, kNone);
  // at most one per listed corner, plus 8 (kSmall): the small path writes a candidate normal per
  // corner in place, past its count; written, not zeroed (a vector grown by insert took 210 k instructions at the 1 M sphere's 1 % level)
  std::unique_ptr<glm::vec3[]> split_normals(new glm::vec3[listed + 8]);
  const size_t split_count =
      splitClusters(offsets, corners.get(), face.get(), r, cos_crease, local_vertex.get(), split_normals.get(), base_vertex);
  face.reset();
  vertex_count += split_count;

  // each cluster's output vertices are base_vertex[c] .. the next used cluster's base_vertex: one
  // for a smooth cluster or one only used by edges and points, the split ones' copies in order
  writeVertices(r, smooth.data(), needs_vertex.data(), offsets.data(), mean.get(), split_normals.get(), vertex_count,
                base_vertex.data(), out);
  mean.reset();
  // each corner's cluster id is no longer read: the output vertex takes its place, so the output
  // triangles need no second array
  {
    const uint32_t* base = base_vertex.data();
    for (size_t i = 0; i < corner_count; ++i) tri[i] = base[tri[i]];
    const uint32_t* list = corners.get();
    const uint32_t* local = local_vertex.get();
    for (size_t j = 0; j < listed; ++j) tri[list[j]] += local[j];
  }
  corners.reset();
  local_vertex.reset();
  out.triangles = std::move(e.triangles);
  // elimination reserved for about 2 triangles per cluster: the slack is dropped only where it is
  // more than an eighth of the triangles, since dropping it copies the whole array (the bunny's 50 %
  // level: 416 KB copied, old and new at once, to free 31 KB)
  if (out.triangles.capacity() - out.triangles.size() > out.triangles.size() / 8) out.triangles.shrink_to_fit();
  carryEdgesAndPoints(e, base_vertex.data(), out);
}

void buildOutputMeshSse2(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  buildOutputMeshBody<false>(e, r, crease_angle_deg, out);
}
SCENELOD_AVX2_TARGET void buildOutputMeshAvx2(Eliminated& e, const Representatives& r, float crease_angle_deg,
                                              Mesh& out) {
  buildOutputMeshBody<true>(e, r, crease_angle_deg, out);
}

// The output pass without its shortcuts, for the tests (useOutputReference): every cluster's
// corners listed in order, every corner's sum by the scalar loop of cornerNormals, normalised, and
// a vertex per distinct normal; the vertex arrays pushed together.
void buildOutputMeshReference(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  out = Mesh();
  const size_t nc = r.positions.size();
  const size_t tn = e.triangles.size() / 3;
  const float cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0f, 180.0f) * 3.14159265358979f / 180.0f);
  std::vector<glm::vec4> face(tn);
  for (size_t t = 0; t < tn; ++t) {
    const glm::vec3& a = r.positions[e.triangles[3 * t]];
    const glm::vec3 n = glm::cross(r.positions[e.triangles[3 * t + 1]] - a, r.positions[e.triangles[3 * t + 2]] - a);
    const float l = glm::length(n);
    face[t] = l > 0.0f ? glm::vec4(n / l, l) : glm::vec4(0.0f);
  }
  std::vector<std::vector<uint32_t>> lists(nc);
  for (size_t i = 0; i < e.triangles.size(); ++i) lists[e.triangles[i]].push_back(static_cast<uint32_t>(i));
  std::vector<uint8_t> needs_vertex(nc, 0);
  for (uint32_t c : e.edges) needs_vertex[c] = 1;
  for (uint32_t c : e.points) needs_vertex[c] = 1;
  std::vector<uint32_t> base_vertex(nc, kNone);
  auto addVertex = [&](uint32_t c, const glm::vec3& n) {
    out.positions.push_back(r.positions[c]);
    out.normals.push_back(n);
    if (!r.colors.empty()) out.colors.push_back(r.colors[c]);
    return static_cast<uint32_t>(out.normals.size() - 1);
  };
  for (uint32_t c = 0; c < nc; ++c) {
    const std::vector<uint32_t>& list = lists[c];
    if (list.empty()) {
      if (needs_vertex[c]) base_vertex[c] = addVertex(c, r.normals[c]);
      continue;
    }
    const uint32_t first = static_cast<uint32_t>(out.normals.size());
    std::vector<uint32_t> vertex_of(list.size());
    for (size_t i = 0; i < list.size(); ++i) {
      const glm::vec3 ui(face[list[i] / 3]);
      glm::vec3 s(0.0f);
      for (size_t j = 0; j < list.size(); ++j) {
        const glm::vec4& fj = face[list[j] / 3];
        const glm::vec3 uj(fj);
        if (j == i || glm::dot(ui, uj) >= cos_crease) s += uj * fj.w;
      }
      const float l = glm::length(s);
      const glm::vec3 n = l > 0.0f ? s / l : r.normals[c];
      uint32_t v = first;
      while (v < out.normals.size() && !(out.normals[v] == n)) ++v;
      vertex_of[i] = v == out.normals.size() ? addVertex(c, n) : v;
    }
    for (size_t i = 0; i < list.size(); ++i) e.triangles[list[i]] = vertex_of[i];
    base_vertex[c] = first;
  }
  out.triangles = std::move(e.triangles);
  carryEdgesAndPoints(e, base_vertex.data(), out);
}

bool g_output_reference = false;

}  // namespace

// (test_hooks.h)
bool useOutputReference(bool on) {
  return std::exchange(g_output_reference, on);
}

void buildOutputMesh(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  if (g_output_reference) buildOutputMeshReference(e, r, crease_angle_deg, out);
  else if (avx2Paths()) buildOutputMeshAvx2(e, r, crease_angle_deg, out);
  else buildOutputMeshSse2(e, r, crease_angle_deg, out);
}

}  // namespace scenelod::detail
