// The grading pass's lane paths (grading_internal.h): the same arithmetic as gradeAndSum's scalar
// pass, four incidences per SSE2 operation, and two rows per pass of eight AVX2 lanes.
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "grading_internal.h"

#if defined(__SSE2__)

namespace scenelod::grading {

namespace {

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

}  // namespace

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

SCENELOD_AVX2_TARGET __attribute__((flatten)) bool gradeTwoRowsAvx2(const glm::vec3* pos, uint32_t v0,
                                                                    const Incidence* row0, size_t r0, size_t r1,
                                                                    bool want_normals, LaneScratch s[2],
                                                                    LaneRow out[2], VertexFaceSums* sums) {
  return gradeTwoRowsBody(pos, v0, row0, r0, r1, want_normals, s, out, sums);
}

}  // namespace scenelod::grading

#endif
