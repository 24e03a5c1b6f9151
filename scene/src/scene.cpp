// The runtime scene graph: slot/generation handles, nodes kept in parent-before-child order so one
// linear pass updates world transforms (Filament / ozz-animation style flat hierarchies), and the
// objects' world bounding spheres as flat arrays.
#include "scenelod/scene/scene.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__SSE2__)
#include <immintrin.h>
#define SCENELOD_SCENE_AVX2 1
#endif

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/skin_pose.h"
#include "scene_wide.h"

namespace scenelod::scene {

glm::mat4 composeTrs(const Trs& trs) {
  glm::mat4 m = glm::mat4_cast(trs.rotation);
  m[0] *= trs.scale.x;
  m[1] *= trs.scale.y;
  m[2] *= trs.scale.z;
  m[3] = glm::vec4(trs.translation, 1.0f);
  return m;
}

namespace {

// a free slot of a handle table (generations and dense positions by slot), or a new one at its end
uint32_t takeSlot(std::vector<uint32_t>& free, std::vector<uint32_t>& generation, std::vector<uint32_t>& dense) {
  if (!free.empty()) {
    const uint32_t slot = free.back();
    free.pop_back();
    return slot;
  }
  generation.push_back(0);
  dense.push_back(kInvalidSlot);
  return static_cast<uint32_t>(generation.size() - 1);
}

// inlined into the update pass; see maxScaleBound
inline float scaleBound(const float* m) {
  const float a0 = m[0], a1 = m[1], a2 = m[2], b0 = m[4], b1 = m[5], b2 = m[6], c0 = m[8], c1 = m[9], c2 = m[10];
  const float aa = a0 * a0 + a1 * a1 + a2 * a2, bb = b0 * b0 + b1 * b1 + b2 * b2, cc = c0 * c0 + c1 * c1 + c2 * c2;
  const float ab = std::fabs(a0 * b0 + a1 * b1 + a2 * b2), ac = std::fabs(a0 * c0 + a1 * c1 + a2 * c2),
              bc = std::fabs(b0 * c0 + b1 * c1 + b2 * c2);
  // gershgorin: every eigenvalue of the gram matrix is at most its largest absolute row sum
  const float ra = aa + ab + ac, rb = bb + ab + bc, rc = cc + ac + bc;
  const float row = ra > rb ? (ra > rc ? ra : rc) : (rb > rc ? rb : rc);
  // a few ulps up so float rounding of the products never makes the bound too small
  return std::sqrt(row) * (1.0f + 4.0f * 1.1920929e-7f);
}

#if defined(__SSE2__)
// out = p * l for affine transforms stored as rows (see Scene::Affine): row r of the product is
// p_r0 * l_row0 + p_r1 * l_row1 + p_r2 * l_row2 + (0, 0, 0, p_r3). The sums are grouped as
// (x + y) + (z + t), the order the earlier 4x4 column product used, so the bits are the same.
inline void mulAffine(const float* p, const float* l, float* out) {
  const __m128 l0 = _mm_load_ps(l), l1 = _mm_load_ps(l + 4), l2 = _mm_load_ps(l + 8);
  const __m128 last = _mm_castsi128_ps(_mm_set_epi32(-1, 0, 0, 0));
  for (int r = 0; r < 3; ++r) {
    const __m128 pr = _mm_load_ps(p + 4 * r);
    const __m128 x = _mm_shuffle_ps(pr, pr, _MM_SHUFFLE(0, 0, 0, 0)), y = _mm_shuffle_ps(pr, pr, _MM_SHUFFLE(1, 1, 1, 1)),
                 z = _mm_shuffle_ps(pr, pr, _MM_SHUFFLE(2, 2, 2, 2));
    _mm_store_ps(out + 4 * r, _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, l0), _mm_mul_ps(y, l1)),
                                         _mm_add_ps(_mm_mul_ps(z, l2), _mm_and_ps(pr, last))));
  }
}

// a world transform prepared for the objects on its node: its columns (for centres) and its
// maxScaleBound
struct NodeSphereXform {
  __m128 c0, c1, c2, t;
  float scale;
};

// the rows of the 3x4 block are the transposed columns a, b, c (lane 3 holds the translation), so
// the Gram matrix's diagonal (aa, bb, cc) and off-diagonal (ab, bc, ca) come out as two vectors
// without horizontal sums; lane 3 never reaches the result
inline NodeSphereXform prepareXform(const float* w) {
  const __m128 r0 = _mm_load_ps(w), r1 = _mm_load_ps(w + 4), r2 = _mm_load_ps(w + 8);
  const __m128 diag = _mm_add_ps(_mm_add_ps(_mm_mul_ps(r0, r0), _mm_mul_ps(r1, r1)), _mm_mul_ps(r2, r2));
  const __m128 s0 = _mm_shuffle_ps(r0, r0, _MM_SHUFFLE(3, 0, 2, 1)), s1 = _mm_shuffle_ps(r1, r1, _MM_SHUFFLE(3, 0, 2, 1)),
               s2 = _mm_shuffle_ps(r2, r2, _MM_SHUFFLE(3, 0, 2, 1));
  __m128 off = _mm_add_ps(_mm_add_ps(_mm_mul_ps(r0, s0), _mm_mul_ps(r1, s1)), _mm_mul_ps(r2, s2));  // (ab, bc, ca, .)
  off = _mm_andnot_ps(_mm_set1_ps(-0.0f), off);
  // rows of |G|: (aa + ab + ca, bb + bc + ab, cc + ca + bc)
  const __m128 rows = _mm_add_ps(_mm_add_ps(diag, off), _mm_shuffle_ps(off, off, _MM_SHUFFLE(3, 1, 0, 2)));
  const __m128 m1 = _mm_max_ps(rows, _mm_shuffle_ps(rows, rows, _MM_SHUFFLE(3, 0, 2, 1)));
  const __m128 m2 = _mm_max_ps(m1, _mm_shuffle_ps(rows, rows, _MM_SHUFFLE(3, 1, 0, 2)));
  NodeSphereXform x;
  x.scale = _mm_cvtss_f32(_mm_sqrt_ss(m2)) * (1.0f + 4.0f * 1.1920929e-7f);
  x.c0 = r0;
  x.c1 = r1;
  x.c2 = r2;
  x.t = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(x.c0, x.c1, x.c2, x.t);
  return x;
}

// centre = M * c as (a * cx + b * cy) + (c * cz + t), radius = r * scale
inline void objectSphere(const NodeSphereXform& x, const Sphere& s, float* center_out, float& radius_out) {
  const __m128 center = _mm_add_ps(_mm_add_ps(_mm_mul_ps(x.c0, _mm_set1_ps(s.center.x)), _mm_mul_ps(x.c1, _mm_set1_ps(s.center.y))),
                                   _mm_add_ps(_mm_mul_ps(x.c2, _mm_set1_ps(s.center.z)), x.t));
  _mm_storel_pi(reinterpret_cast<__m64*>(center_out), center);
  _mm_store_ss(center_out + 2, _mm_movehl_ps(center, center));
  radius_out = s.radius * x.scale;
}
#else
inline void mulAffine(const float* p, const float* l, float* out) {
  for (int r = 0; r < 3; ++r) {
    const float* pr = p + 4 * r;
    for (int j = 0; j < 4; ++j)
      out[4 * r + j] = (pr[0] * l[j] + pr[1] * l[4 + j]) + (pr[2] * l[8 + j] + (j == 3 ? pr[3] : 0.0f));
  }
}

struct NodeSphereXform {
  float m[16];  // column-major 4x4, last row unused
  float scale;
};

inline NodeSphereXform prepareXform(const float* w) {
  NodeSphereXform x;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) x.m[4 * c + r] = w[4 * r + c];
  x.m[3] = x.m[7] = x.m[11] = 0.0f;
  x.m[15] = 1.0f;
  x.scale = scaleBound(x.m);
  return x;
}

inline void objectSphere(const NodeSphereXform& x, const Sphere& s, float* center_out, float& radius_out) {
  const float* w = x.m;
  const float cx = s.center.x, cy = s.center.y, cz = s.center.z;
  for (int r = 0; r < 3; ++r) center_out[r] = (w[r] * cx + w[4 + r] * cy) + (w[8 + r] * cz + w[12 + r]);
  radius_out = s.radius * x.scale;
}
#endif

// objects whose world spheres are due, a batch at a time: object l's world transform is
// b[l] * a[l] (both 3x4 rows), or a[l] alone when b[l] is null (a root, or a node that stores its
// world). A short batch repeats its last job in the unused slots
constexpr size_t kSphereBatch = 8;
struct alignas(32) SphereJobs {
  const float* a[kSphereBatch];
  const float* b[kSphereBatch];
  uint32_t object[kSphereBatch];
};

struct SphereOut {
  const Sphere* chains;
  const uint32_t* chain_of;
  float* centers;  // 3 floats per object
  float* radii;
  float* scales;
};

// one object at a time with the helpers above; the reference for the wide version's bits
void spheresNarrow(const SphereJobs& j, size_t count, const SphereOut& out) {
  for (size_t l = 0; l < count; ++l) {
    alignas(16) float w[12];
    const float* world = j.a[l];
    if (j.b[l]) {
      mulAffine(j.b[l], j.a[l], w);
      world = w;
    }
    const size_t k = j.object[l];
    const NodeSphereXform x = prepareXform(world);
    objectSphere(x, out.chains[out.chain_of[k]], out.centers + 3 * k, out.radii[k]);
    out.scales[k] = x.scale;
  }
}

#if defined(SCENELOD_SCENE_AVX2)
// the eight 16-byte rows at p[0..7] + offset as four 8-lane vectors: element c of lane l's row in
// lane l of out[c] (per 128-bit half a 4x4 transpose; lanes 0-3 low, 4-7 high)
__attribute__((target("avx2"))) inline void transposeWide(const float* const* p, size_t offset, __m256* out) {
  __m256 v[4];
  for (int l = 0; l < 4; ++l)
    v[l] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p[l] + offset)), _mm_loadu_ps(p[l + 4] + offset), 1);
  const __m256 t0 = _mm256_unpacklo_ps(v[0], v[1]), t1 = _mm256_unpacklo_ps(v[2], v[3]);
  const __m256 t2 = _mm256_unpackhi_ps(v[0], v[1]), t3 = _mm256_unpackhi_ps(v[2], v[3]);
  out[0] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  out[1] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  out[2] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  out[3] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

__attribute__((target("avx2"))) inline __m256 dotColumnsWide(const __m256 (*w)[4], int u, int v) {
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w[0][u], w[0][v]), _mm256_mul_ps(w[1][u], w[1][v])),
                       _mm256_mul_ps(w[2][u], w[2][v]));
}

// eight objects per call, structure of arrays across the lanes. Every lane evaluates exactly the
// expressions of mulAffine, prepareXform and objectSphere, in their order and without FMA, so the
// bits are spheresNarrow's
__attribute__((target("avx2"))) void spheresWide(const SphereJobs& j, size_t count, const SphereOut& out) {
  const __m256i b_lo = _mm256_load_si256(reinterpret_cast<const __m256i*>(j.b)),
                b_hi = _mm256_load_si256(reinterpret_cast<const __m256i*>(j.b + 4));
  const __m256i null = _mm256_setzero_si256();
  const int no_product = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(b_lo, null))) |
                         _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(b_hi, null))) << 4;
  const __m256i b0 = _mm256_set1_epi64x(reinterpret_cast<long long>(j.b[0]));
  const bool shared_b = (_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(b_lo, b0))) &
                         _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(b_hi, b0)))) == 0xf;
  __m256 A[3][4], W[3][4];
  for (int r = 0; r < 3; ++r) transposeWide(j.a, 4 * r, A[r]);
  if (no_product == 0xff) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) W[r][c] = A[r][c];
  } else {
    __m256 B[3][4];
    if (shared_b) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) B[r][c] = _mm256_broadcast_ss(j.b[0] + 4 * r + c);
    } else {
      const float* b[kSphereBatch];
      for (size_t l = 0; l < kSphereBatch; ++l) b[l] = j.b[l] ? j.b[l] : j.a[l];  // any readable rows; the lane keeps a
      for (int r = 0; r < 3; ++r) transposeWide(b, 4 * r, B[r]);
    }
    const __m256 zero = _mm256_setzero_ps();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        W[r][c] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(B[r][0], A[0][c]), _mm256_mul_ps(B[r][1], A[1][c])),
                                _mm256_add_ps(_mm256_mul_ps(B[r][2], A[2][c]), c == 3 ? B[r][3] : zero));
    if (no_product != 0) {
      const __m256 keep_a = _mm256_castsi256_ps(_mm256_cmpgt_epi32(
          _mm256_and_si256(_mm256_set1_epi32(no_product), _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)), null));
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) W[r][c] = _mm256_blendv_ps(W[r][c], A[r][c], keep_a);
    }
  }
  // the gram matrix of the columns (prepareXform's lanes become separate vectors)
  const __m256 sign = _mm256_set1_ps(-0.0f);
  const __m256 aa = dotColumnsWide(W, 0, 0), bb = dotColumnsWide(W, 1, 1), cc = dotColumnsWide(W, 2, 2);
  const __m256 ab = _mm256_andnot_ps(sign, dotColumnsWide(W, 0, 1)), bc = _mm256_andnot_ps(sign, dotColumnsWide(W, 1, 2)),
               ca = _mm256_andnot_ps(sign, dotColumnsWide(W, 2, 0));
  const __m256 ra = _mm256_add_ps(_mm256_add_ps(aa, ab), ca), rb = _mm256_add_ps(_mm256_add_ps(bb, bc), ab),
               rc = _mm256_add_ps(_mm256_add_ps(cc, ca), bc);
  const __m256 scale = _mm256_mul_ps(_mm256_sqrt_ps(_mm256_max_ps(_mm256_max_ps(ra, rb), rc)),
                                     _mm256_set1_ps(1.0f + 4.0f * 1.1920929e-7f));
  // the chain spheres, transposed like the rows
  const float* s[kSphereBatch];
  for (size_t l = 0; l < kSphereBatch; ++l) s[l] = &out.chains[out.chain_of[j.object[l]]].center.x;
  __m256 S[4];
  transposeWide(s, 0, S);
  __m256 C[3];
  for (int r = 0; r < 3; ++r)
    C[r] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(W[r][0], S[0]), _mm256_mul_ps(W[r][1], S[1])),
                         _mm256_add_ps(_mm256_mul_ps(W[r][2], S[2]), W[r][3]));
  const __m256 radius = _mm256_mul_ps(S[3], scale);
  const __m256i k = _mm256_load_si256(reinterpret_cast<const __m256i*>(j.object));
  const __m256i run = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(j.object[0])), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  if (count == kSphereBatch && _mm256_movemask_epi8(_mm256_cmpeq_epi32(k, run)) == -1) {
    const size_t k0 = j.object[0];
    _mm256_storeu_ps(out.radii + k0, radius);
    _mm256_storeu_ps(out.scales + k0, scale);
    // (x, y, z, radius) per lane; ascending 16-byte stores, each lane's fourth float is overwritten by
    // the next lane's x, the last lane stores 12 bytes
    const __m256 t0 = _mm256_unpacklo_ps(C[0], C[1]), t1 = _mm256_unpacklo_ps(C[2], radius);
    const __m256 t2 = _mm256_unpackhi_ps(C[0], C[1]), t3 = _mm256_unpackhi_ps(C[2], radius);
    const __m256 q[4] = {_mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0)), _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2)),
                         _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0)), _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2))};
    float* c = out.centers + 3 * k0;
    for (int l = 0; l < 4; ++l) _mm_storeu_ps(c + 3 * l, _mm256_castps256_ps128(q[l]));
    for (int l = 4; l < 7; ++l) _mm_storeu_ps(c + 3 * l, _mm256_extractf128_ps(q[l - 4], 1));
    const __m128 last = _mm256_extractf128_ps(q[3], 1);
    _mm_storel_pi(reinterpret_cast<__m64*>(c + 21), last);
    _mm_store_ss(c + 23, _mm_movehl_ps(last, last));
    return;
  }
  alignas(32) float lanes[5][kSphereBatch];
  for (int r = 0; r < 3; ++r) _mm256_store_ps(lanes[r], C[r]);
  _mm256_store_ps(lanes[3], radius);
  _mm256_store_ps(lanes[4], scale);
  for (size_t l = 0; l < count; ++l) {
    const size_t o = j.object[l];
    for (int r = 0; r < 3; ++r) out.centers[3 * o + r] = lanes[r][l];
    out.radii[o] = lanes[3][l];
    out.scales[o] = lanes[4][l];
  }
}
#endif

using SpheresFn = void (*)(const SphereJobs&, size_t, const SphereOut&);

// picked on first use (a static initialiser elsewhere may already update a scene); thread-safe
SpheresFn bestSpheres() {
  static const SpheresFn fn = [] {
#if defined(SCENELOD_SCENE_AVX2)
    __builtin_cpu_init();  // this may run before the CPU model is initialised
    if (__builtin_cpu_supports("avx2")) return &spheresWide;
#endif
    return &spheresNarrow;
  }();
  return fn;
}
SpheresFn g_forced_spheres = nullptr;  // detail::useWideSpheres(false), for tests

// collects due objects and computes their spheres a batch at a time
struct SphereBatcher {
  explicit SphereBatcher(const SphereOut& o) : out(o) {}
  const SphereOut& out;
  SpheresFn fn = g_forced_spheres ? g_forced_spheres : bestSpheres();
  size_t count = 0, done = 0;
  SphereJobs jobs;

  void add(uint32_t object, const float* a, const float* b) {
    jobs.a[count] = a;
    jobs.b[count] = b;
    jobs.object[count] = object;
    if (++count == kSphereBatch) {
      fn(jobs, kSphereBatch, out);
      done += kSphereBatch;
      count = 0;
    }
  }
  size_t finish() {
    if (count == 0) return done;
    for (size_t l = count; l < kSphereBatch; ++l) {
      jobs.a[l] = jobs.a[count - 1];
      jobs.b[l] = jobs.b[count - 1];
      jobs.object[l] = jobs.object[count - 1];
    }
    fn(jobs, count, out);
    return done + count;
  }
};

}  // namespace

namespace detail {
bool useWideSpheres(bool on) {
  const bool was = (g_forced_spheres ? g_forced_spheres : bestSpheres()) != &spheresNarrow;
  g_forced_spheres = on ? nullptr : &spheresNarrow;
  return was;
}
}  // namespace detail

float maxScaleBound(const glm::mat4& m) { return scaleBound(&m[0][0]); }

Sphere transformSphere(const Sphere& s, const glm::mat4& m) {
  Sphere out;
  out.center = glm::vec3(m * glm::vec4(s.center, 1.0f));
  out.radius = s.radius * maxScaleBound(m);
  return out;
}

namespace {
Error stale(const char* what) { return {Status::kNotFound, std::string("stale or invalid ") + what + " handle"}; }

template <class A>
A toAffine(const glm::mat4& m) {
  A a;
#if defined(__SSE2__)
  // the first three rows of the column-major matrix: a 4x4 transpose, last row dropped
  __m128 c0 = _mm_loadu_ps(&m[0][0]), c1 = _mm_loadu_ps(&m[1][0]), c2 = _mm_loadu_ps(&m[2][0]), c3 = _mm_loadu_ps(&m[3][0]);
  _MM_TRANSPOSE4_PS(c0, c1, c2, c3);
  _mm_store_ps(a.row[0], c0);
  _mm_store_ps(a.row[1], c1);
  _mm_store_ps(a.row[2], c2);
#else
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) a.row[r][c] = m[c][r];
#endif
  return a;
}

template <class A>
glm::mat4 toMat4(const A& a) {
  glm::mat4 m(1.0f);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m[c][r] = a.row[r][c];
  return m;
}
}  // namespace

inline bool Scene::nodeLive(NodeHandle h) const {
  return h.slot < node_generation_.size() && node_generation_[h.slot] == h.generation &&
         node_dense_[h.slot] != kInvalidSlot;
}

bool Scene::objectLive(ObjectHandle h) const {
  return h.slot < object_generation_.size() && object_generation_[h.slot] == h.generation &&
         object_dense_[h.slot] != kInvalidSlot;
}

bool Scene::isValid(NodeHandle node) const { return nodeLive(node); }
bool Scene::isValid(ObjectHandle object) const { return objectLive(object); }

NodeHandle Scene::nodeAt(size_t i) const {
  const uint32_t slot = order_[i];
  return NodeHandle{slot, node_generation_[slot]};
}

ObjectHandle Scene::objectAt(size_t i) const {
  const uint32_t slot = object_slot_[i];
  return ObjectHandle{slot, object_generation_[slot]};
}

void Scene::setChainCount(size_t n) {
  chain_spheres_.resize(n);
  all_objects_dirty_ = true;
}

Error Scene::setChainSphere(uint32_t chain, const Sphere& sphere) {
  if (chain >= chain_spheres_.size())
    return {Status::kInvalidArgument, "chain " + std::to_string(chain) + " out of range (" +
                                          std::to_string(chain_spheres_.size()) + " chains)"};
  if (!std::isfinite(sphere.radius) || sphere.radius < 0.0f)
    return {Status::kInvalidArgument, "chain " + std::to_string(chain) + ": sphere radius is negative or not finite"};
  chain_spheres_[chain] = sphere;
  for (size_t i = 0; i < object_chain_.size(); ++i)
    if (object_chain_[i] == chain) object_dirty_[i] = 1;
  some_objects_dirty_ = true;
  return {};
}

Error Scene::addNode(NodeHandle parent, const glm::mat4& local, NodeHandle& out) {
  int32_t parent_dense = -1;
  if (parent.slot != kInvalidSlot) {
    if (!nodeLive(parent)) return stale("parent node");
    parent_dense = static_cast<int32_t>(node_dense_[parent.slot]);
  }
  const uint32_t slot = takeSlot(node_free_, node_generation_, node_dense_);
  node_dense_[slot] = static_cast<uint32_t>(order_.size());
  order_.push_back(slot);
  parent_dense_.push_back(parent_dense);
  node_dirty_.push_back(0);
  local_.push_back(toAffine<Affine>(local));
  world_.push_back(local_.back());
  child_count_.push_back(0);
  node_first_object_.push_back(-1);
  markNodeDirty(order_.size() - 1);
  if (parent_dense >= 0) addChild(static_cast<size_t>(parent_dense));
  out = NodeHandle{slot, node_generation_[slot]};
  return {};
}

void Scene::rebuildParentIndices() {
  // parent_dense_ is kept as parent slots during a reorder, then mapped back to positions here
  for (size_t i = 0; i < order_.size(); ++i) node_dense_[order_[i]] = static_cast<uint32_t>(i);
  for (size_t i = 0; i < order_.size(); ++i)
    if (parent_dense_[i] >= 0) parent_dense_[i] = static_cast<int32_t>(node_dense_[parent_dense_[i]]);
  for (size_t k = 0; k < object_node_slot_.size(); ++k) object_node_dense_[k] = node_dense_[object_node_slot_[k]];
  countChildren();
}

void Scene::countChildren() {
  child_count_.assign(order_.size(), 0);
  for (int32_t p : parent_dense_)
    if (p >= 0) ++child_count_[static_cast<size_t>(p)];
}

void Scene::addChild(size_t p) {
  // a leaf's world row is stale; from its first child on it must be current
  if (child_count_[p] == 0) world_[p] = currentWorld(p);
  ++child_count_[p];
}

Scene::Affine Scene::currentWorld(size_t i) const {
  // before dirty_from_ every stored world of a node with children is current. Otherwise the product
  // runs down from the nearest such ancestor (or from a root's local) in update()'s order, so the
  // bits are update()'s. The path is kept in chunks of kChunk nodes, taken from the top: no
  // allocation, O(depth^2 / kChunk) for very deep paths
  constexpr size_t kChunk = 32;
  auto stored = [&](size_t a) { return a < dirty_from_ && child_count_[a] > 0; };
  if (stored(i)) return world_[i];
  Affine w{};
  size_t done = kInvalidSlot;  // the lowest node of the path already in w
  for (;;) {
    uint32_t ring[kChunk];  // the last kChunk nodes seen walking up: the top of what is left
    size_t len = 0;
    int32_t a = static_cast<int32_t>(i);
    for (; a >= 0 && static_cast<size_t>(a) != done && !stored(static_cast<size_t>(a)); a = parent_dense_[a])
      ring[len++ % kChunk] = static_cast<uint32_t>(a);
    size_t avail = len < kChunk ? len : kChunk;
    if (done == kInvalidSlot) {
      if (a >= 0) {
        w = world_[static_cast<size_t>(a)];
      } else {
        done = ring[(len - 1) % kChunk];  // a root: its world is its local
        w = local_[done];
        --len;
        --avail;
      }
    }
    for (size_t t = 0; t < avail; ++t) {
      done = ring[(len - 1 - t) % kChunk];
      Affine next;
      mulAffine(&w.row[0][0], &local_[done].row[0][0], &next.row[0][0]);
      w = next;
    }
    if (done == i) return w;
  }
}

Error Scene::removeNode(NodeHandle node) {
  if (!nodeLive(node)) return stale("node");
  const size_t first = node_dense_[node.slot], n = order_.size();
  // descendants come after their ancestors: one forward pass marks the subtree
  std::vector<uint8_t> doomed(n, 0);
  doomed[first] = 1;
  for (size_t i = first + 1; i < n; ++i)
    if (parent_dense_[i] >= 0 && doomed[parent_dense_[i]]) doomed[i] = 1;
  // objects on removed nodes go first (swap-remove, walking backwards keeps it simple)
  for (size_t k = object_chain_.size(); k-- > 0;)
    if (doomed[object_node_dense_[k]]) removeObject(objectAt(k));
  // stable compaction of the node arrays; parent links become slots during the move
  for (size_t i = 0; i < n; ++i)
    if (parent_dense_[i] >= 0) parent_dense_[i] = static_cast<int32_t>(order_[parent_dense_[i]]);
  size_t w = 0;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t slot = order_[i];
    if (doomed[i]) {
      node_dense_[slot] = kInvalidSlot;
      ++node_generation_[slot];
      node_free_.push_back(slot);
      continue;
    }
    order_[w] = slot;
    parent_dense_[w] = parent_dense_[i];
    node_dirty_[w] = node_dirty_[i];
    local_[w] = local_[i];
    world_[w] = world_[i];
    node_first_object_[w] = node_first_object_[i];
    ++w;
  }
  order_.resize(w);
  parent_dense_.resize(w);
  node_dirty_.resize(w);
  local_.resize(w);
  world_.resize(w);
  node_first_object_.resize(w);
  // dirty rows only moved down to positions >= first
  if (first < dirty_from_) dirty_from_ = first;
  rebuildParentIndices();
  return {};
}

Error Scene::reparent(NodeHandle node, NodeHandle new_parent) {
  if (!nodeLive(node)) return stale("node");
  const bool to_root = new_parent.slot == kInvalidSlot;
  if (!to_root && !nodeLive(new_parent)) return stale("new parent node");
  const size_t i = node_dense_[node.slot], n = order_.size();
  const size_t p = to_root ? 0 : node_dense_[new_parent.slot];
  if (!to_root && p == i) return {Status::kInvalidArgument, "a node cannot be its own parent"};
  if (!to_root && p > i) {
    // is the new parent inside the subtree? walk up from it
    for (int32_t a = static_cast<int32_t>(p); a >= 0; a = parent_dense_[a])
      if (static_cast<size_t>(a) == i)
        return {Status::kInvalidArgument, "cannot move a node under one of its own descendants"};
  }
  markNodeDirty(i);  // the subtree's rows stay at positions >= i
  if (to_root || p < i) {
    if (parent_dense_[i] >= 0) --child_count_[static_cast<size_t>(parent_dense_[i])];
    parent_dense_[i] = to_root ? -1 : static_cast<int32_t>(p);
    if (!to_root) addChild(p);
    return {};
  }
  const bool parent_was_leaf = child_count_[p] == 0;
  // the parent comes later: move the subtree (marked in one forward pass over [i, p]) to just after
  // p, keeping relative order on both sides; nodes outside [i, p] keep their positions
  for (size_t k = 0; k < n; ++k)
    if (parent_dense_[k] >= 0) parent_dense_[k] = static_cast<int32_t>(order_[parent_dense_[k]]);
  parent_dense_[i] = static_cast<int32_t>(new_parent.slot);
  std::vector<uint8_t> in_subtree(p - i + 1, 0);
  in_subtree[0] = 1;
  for (size_t k = i + 1; k <= p; ++k) {
    const uint32_t parent_slot = static_cast<uint32_t>(parent_dense_[k]);
    if (parent_dense_[k] >= 0 && node_dense_[parent_slot] >= i && node_dense_[parent_slot] < k &&
        in_subtree[node_dense_[parent_slot] - i])
      in_subtree[k - i] = 1;
  }
  struct Row { uint32_t slot; int32_t parent; uint8_t dirty; int32_t first_object; Affine local, world; };
  std::vector<Row> keep, moved;
  for (size_t k = i; k <= p; ++k) {
    Row r{order_[k], parent_dense_[k], node_dirty_[k], node_first_object_[k], local_[k], world_[k]};
    (in_subtree[k - i] ? moved : keep).push_back(r);
  }
  size_t w = i;
  for (const auto* group : {&keep, &moved})
    for (const Row& r : *group) {
      order_[w] = r.slot;
      parent_dense_[w] = r.parent;
      node_dirty_[w] = r.dirty;
      node_first_object_[w] = r.first_object;
      local_[w] = r.local;
      world_[w] = r.world;
      ++w;
    }
  rebuildParentIndices();
  if (parent_was_leaf) {
    const size_t q = node_dense_[new_parent.slot];
    world_[q] = currentWorld(q);
  }
  return {};
}

Error Scene::setLocal(NodeHandle node, const glm::mat4& local) {
  if (!nodeLive(node)) return stale("node");
  const uint32_t i = node_dense_[node.slot];
  local_[i] = toAffine<Affine>(local);
  markNodeDirty(i);
  return {};
}

Error Scene::setLocal(NodeHandle node, const Trs& trs) { return setLocal(node, composeTrs(trs)); }

Error Scene::setLocals(Span<const NodeHandle> nodes, StridedSpan<const glm::mat4> locals) {
  if (nodes.count != locals.count)
    return {Status::kInvalidArgument, "setLocals got " + std::to_string(nodes.count) + " nodes and " +
                                          std::to_string(locals.count) + " local transforms"};
  const uint32_t* generation = node_generation_.data();
  const uint32_t* dense = node_dense_.data();
  const size_t slots = node_generation_.size();
  Affine* local = local_.data();
  uint8_t* dirty = node_dirty_.data();
  size_t first = dirty_from_;
  for (size_t k = 0; k < nodes.count; ++k) {
    const NodeHandle h = nodes[k];
    // nodeLive, with the arrays in registers
    if (h.slot >= slots || generation[h.slot] != h.generation || dense[h.slot] == kInvalidSlot) {
      dirty_from_ = first;
      return stale(("node (setLocals, node " + std::to_string(k) + ")").c_str());
    }
    const uint32_t i = dense[h.slot];
    local[i] = toAffine<Affine>(locals[k]);
    dirty[i] = 1;
    if (i < first) first = i;
  }
  dirty_from_ = first;
  return {};
}

Error Scene::getLocal(NodeHandle node, glm::mat4& out) const {
  if (!nodeLive(node)) return stale("node");
  out = toMat4(local_[node_dense_[node.slot]]);
  return {};
}

Error Scene::getWorld(NodeHandle node, glm::mat4& out) const {
  if (!nodeLive(node)) return stale("node");
  out = toMat4(currentWorld(node_dense_[node.slot]));
  return {};
}

Error Scene::getParent(NodeHandle node, NodeHandle& out) const {
  if (!nodeLive(node)) return stale("node");
  const int32_t p = parent_dense_[node_dense_[node.slot]];
  out = p < 0 ? NodeHandle{} : nodeAt(static_cast<size_t>(p));
  return {};
}

Error Scene::addObject(const ObjectDesc& d, ObjectHandle& out) {
  if (!nodeLive(d.node)) return stale("node");
  if (d.chain >= chain_spheres_.size())
    return {Status::kInvalidArgument, "chain " + std::to_string(d.chain) + " out of range (" +
                                          std::to_string(chain_spheres_.size()) + " chains)"};
  if (!std::isfinite(d.importance) || d.importance < 0.0f)
    return {Status::kInvalidArgument, "object importance must be finite and >= 0"};
  const uint32_t slot = takeSlot(object_free_, object_generation_, object_dense_);
  object_dense_[slot] = static_cast<uint32_t>(object_chain_.size());
  world_center_.push_back(glm::vec3(0.0f));
  world_radius_.push_back(0.0f);
  max_scale_.push_back(1.0f);
  object_chain_.push_back(d.chain);
  object_node_slot_.push_back(d.node.slot);
  object_node_dense_.push_back(node_dense_[d.node.slot]);
  object_dirty_.push_back(1);
  object_next_.push_back(-1);
  importance_.push_back(d.importance);
  must_draw_.push_back(d.must_draw ? 1 : 0);
  user_data_.push_back(d.user_data);
  object_slot_.push_back(slot);
  linkObject(static_cast<uint32_t>(object_chain_.size() - 1));
  some_objects_dirty_ = true;
  out = ObjectHandle{slot, object_generation_[slot]};
  return {};
}

Error Scene::removeObject(ObjectHandle h) {
  if (!objectLive(h)) return stale("object");
  const size_t k = object_dense_[h.slot], last = object_chain_.size() - 1;
  unlinkObject(static_cast<uint32_t>(k));
  if (k != last) {
    // the last object takes index k: its node's list must name k instead of last
    int32_t* link = &node_first_object_[object_node_dense_[last]];
    while (*link != static_cast<int32_t>(last)) link = &object_next_[static_cast<size_t>(*link)];
    *link = static_cast<int32_t>(k);
    object_next_[k] = object_next_[last];
    world_center_[k] = world_center_[last];
    world_radius_[k] = world_radius_[last];
    max_scale_[k] = max_scale_[last];
    object_chain_[k] = object_chain_[last];
    object_node_slot_[k] = object_node_slot_[last];
    object_node_dense_[k] = object_node_dense_[last];
    object_dirty_[k] = object_dirty_[last];
    importance_[k] = importance_[last];
    must_draw_[k] = must_draw_[last];
    user_data_[k] = user_data_[last];
    object_slot_[k] = object_slot_[last];
    object_dense_[object_slot_[k]] = static_cast<uint32_t>(k);
  }
  world_center_.pop_back();
  world_radius_.pop_back();
  max_scale_.pop_back();
  object_chain_.pop_back();
  object_node_slot_.pop_back();
  object_node_dense_.pop_back();
  object_dirty_.pop_back();
  object_next_.pop_back();
  importance_.pop_back();
  must_draw_.pop_back();
  user_data_.pop_back();
  object_slot_.pop_back();
  object_dense_[h.slot] = kInvalidSlot;
  ++object_generation_[h.slot];
  object_free_.push_back(h.slot);
  return {};
}

Error Scene::setObjectNode(ObjectHandle h, NodeHandle node) {
  if (!objectLive(h)) return stale("object");
  if (!nodeLive(node)) return stale("node");
  const uint32_t k = object_dense_[h.slot];
  unlinkObject(k);
  object_node_slot_[k] = node.slot;
  object_node_dense_[k] = node_dense_[node.slot];
  linkObject(k);
  object_dirty_[k] = 1;
  some_objects_dirty_ = true;
  return {};
}

Error Scene::setObjectChain(ObjectHandle h, uint32_t chain) {
  if (!objectLive(h)) return stale("object");
  if (chain >= chain_spheres_.size())
    return {Status::kInvalidArgument, "chain " + std::to_string(chain) + " out of range"};
  const uint32_t k = object_dense_[h.slot];
  object_chain_[k] = chain;
  object_dirty_[k] = 1;
  some_objects_dirty_ = true;
  return {};
}

Error Scene::setImportance(ObjectHandle h, float importance) {
  if (!objectLive(h)) return stale("object");
  if (!std::isfinite(importance) || importance < 0.0f)
    return {Status::kInvalidArgument, "object importance must be finite and >= 0"};
  importance_[object_dense_[h.slot]] = importance;
  return {};
}

Error Scene::setMustDraw(ObjectHandle h, bool must_draw) {
  if (!objectLive(h)) return stale("object");
  must_draw_[object_dense_[h.slot]] = must_draw ? 1 : 0;
  return {};
}

Error Scene::setUserData(ObjectHandle h, uint64_t user_data) {
  if (!objectLive(h)) return stale("object");
  user_data_[object_dense_[h.slot]] = user_data;
  return {};
}

Error Scene::getObject(ObjectHandle h, ObjectDesc& out) const {
  if (!objectLive(h)) return stale("object");
  const uint32_t k = object_dense_[h.slot];
  out.node = NodeHandle{object_node_slot_[k], node_generation_[object_node_slot_[k]]};
  out.chain = object_chain_[k];
  out.importance = importance_[k];
  out.must_draw = must_draw_[k] != 0;
  out.user_data = user_data_[k];
  return {};
}

Error Scene::objectIndex(ObjectHandle h, size_t& out) const {
  if (!objectLive(h)) return stale("object");
  out = object_dense_[h.slot];
  return {};
}

void Scene::linkObject(uint32_t k) {
  int32_t& head = node_first_object_[object_node_dense_[k]];
  object_next_[k] = head;
  head = static_cast<int32_t>(k);
}

void Scene::unlinkObject(uint32_t k) {
  int32_t* link = &node_first_object_[object_node_dense_[k]];
  while (*link != static_cast<int32_t>(k)) link = &object_next_[static_cast<size_t>(*link)];
  *link = object_next_[k];
}

size_t Scene::update() {
  const size_t n = order_.size();
  const bool all = all_objects_dirty_, edited = some_objects_dirty_;
  if (dirty_from_ >= n && !all && !edited) return 0;
  uint8_t* object_dirty = object_dirty_.data();
  const int32_t* parent = parent_dense_.data();
  const uint32_t* children = child_count_.data();
  const Affine* local = local_.data();
  Affine* world = world_.data();
  // (a vec3 is three floats; data() is null while there are no objects)
  const SphereOut out{chain_spheres_.data(), object_chain_.data(), reinterpret_cast<float*>(world_center_.data()),
                      world_radius_.data(), max_scale_.data()};
  SphereBatcher batch(out);
  if (dirty_from_ < n) {
    uint8_t* dirty = node_dirty_.data();
    const int32_t* first_object = node_first_object_.data();
    const int32_t* next_object = object_next_.data();
    // parents come first, so a parent's flag is final when its children are visited; nothing
    // before dirty_from_ is dirty
    for (size_t i = dirty_from_; i < n; ++i) {
      const int32_t p = parent[i];
      if (p >= 0 && dirty[p]) dirty[i] = 1;
      if (!dirty[i]) continue;
      const float* a = &local[i].row[0][0];
      const float* b = p >= 0 ? &world[p].row[0][0] : nullptr;
      if (children[i]) {
        // children read it later in this pass, getWorld after it
        if (b) {
          mulAffine(b, a, &world[i].row[0][0]);
        } else {
          world[i] = local[i];
        }
        a = &world[i].row[0][0];
        b = nullptr;
      }
      if (all) continue;
      for (int32_t k = first_object[i]; k >= 0; k = next_object[k]) {
        batch.add(static_cast<uint32_t>(k), a, b);
        if (edited) object_dirty[k] = 0;  // else every flag is clear already
      }
    }
    std::fill(node_dirty_.begin() + static_cast<std::ptrdiff_t>(dirty_from_), node_dirty_.end(), uint8_t(0));
    dirty_from_ = kNoneDirty;
  }
  if (all || edited) {
    // objects edited themselves (chain, node, chain sphere, new): one pass over the flags
    const size_t m = object_chain_.size();
    const uint32_t* node_of = object_node_dense_.data();
    for (size_t k = 0; k < m; ++k) {
      if (!(all | object_dirty[k])) continue;
      const uint32_t i = node_of[k];
      const int32_t p = parent[i];
      if (children[i] || p < 0) {
        batch.add(static_cast<uint32_t>(k), children[i] ? &world[i].row[0][0] : &local[i].row[0][0], nullptr);
      } else {
        batch.add(static_cast<uint32_t>(k), &local[i].row[0][0], &world[p].row[0][0]);
      }
      object_dirty[k] = 0;
    }
  }
  all_objects_dirty_ = false;
  some_objects_dirty_ = false;
  return batch.finish();
}

Error Scene::fromSceneData(const SceneData& data, Scene& out, const std::string& what) {
  if (Error e = validateSceneData(data, what); !e.ok()) return e;
  if (Error e = validateSkinning(data, what); !e.ok()) return e;
  out = Scene{};
  const size_t n = data.nodes.size();
  // insert parents before children: a depth-first walk from every parentless node (roots of the
  // default scene first, then any other parentless node), so node i gets slot i
  std::vector<int32_t> order;
  order.reserve(n);
  std::vector<int32_t> stack;
  std::vector<uint8_t> listed(n, 0);
  auto walk = [&](int32_t r) {
    stack.push_back(r);
    while (!stack.empty()) {
      const int32_t i = stack.back();
      stack.pop_back();
      if (listed[i]) continue;
      listed[i] = 1;
      order.push_back(i);
      const auto& ch = data.nodes[i].children;
      for (auto c = ch.rbegin(); c != ch.rend(); ++c) stack.push_back(*c);
    }
  };
  for (int32_t r : data.roots) walk(r);
  for (size_t i = 0; i < n; ++i)
    if (data.nodes[i].parent < 0) walk(static_cast<int32_t>(i));
  // nodes whose parent does not list them as a child: attach after their parent by repeated passes
  for (bool progress = true; progress && order.size() < n;) {
    progress = false;
    for (size_t i = 0; i < n; ++i)
      if (!listed[i] && listed[data.nodes[i].parent]) { walk(static_cast<int32_t>(i)); progress = true; }
  }
  // slots equal SceneData node indices: allocate all slots first, then fill the order
  out.node_generation_.assign(n, 0);
  out.node_dense_.assign(n, kInvalidSlot);
  for (int32_t i : order) {
    out.node_dense_[i] = static_cast<uint32_t>(out.order_.size());
    out.order_.push_back(static_cast<uint32_t>(i));
    const int32_t p = data.nodes[i].parent;
    out.parent_dense_.push_back(p < 0 ? -1 : static_cast<int32_t>(out.node_dense_[p]));
    out.node_dirty_.push_back(1);
    out.local_.push_back(toAffine<Affine>(data.nodes[i].local));
    out.world_.push_back(out.local_.back());
    out.node_first_object_.push_back(-1);
  }
  out.countChildren();
  out.dirty_from_ = 0;
  out.setChainCount(data.meshes.size());
  const std::vector<uint8_t> skinned = meshesDrawnWithSkin(data);
  for (size_t m = 0; m < data.meshes.size(); ++m) {
    const Mesh& mesh = data.meshes[m].mesh;
    const int32_t mi = static_cast<int32_t>(m);
    if (!skinned[m]) {
      out.chain_spheres_[m] = minimalSphere(Span<const glm::vec3>(mesh.positions.data(), mesh.positions.size()));
      continue;
    }
    const Mesh* levels[] = {&mesh};
    const std::string name = what + " mesh " + std::to_string(m);
    if (Error e = animatedMeshSphere(data, mi, Span<const Mesh* const>(levels, 1), out.chain_spheres_[m], name); !e.ok())
      return e;
  }
  for (int32_t node : objectNodes(data)) {
    ObjectDesc d;
    d.node = NodeHandle{static_cast<uint32_t>(node), 0};
    d.chain = static_cast<uint32_t>(data.nodes[node].mesh);
    ObjectHandle h;
    if (Error e = out.addObject(d, h); !e.ok()) return e;
  }
  out.update();
  return {};
}

}  // namespace scenelod::scene
