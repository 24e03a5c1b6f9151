// The selector's SIMD passes, each compiled twice from one generic body: for SSE2 (the x86-64
// baseline) and with the AVX2 target, run when the CPU has AVX2 and the context allows it
// (SelectorConfig::sse2_only). Both forms do the same IEEE operations per lane in the same order
// (no FMA: -ffp-contract=off, and the AVX2 target does not enable it), so they give the same bits;
// Selector.AvxAndSse2PathsGiveTheSameBits compares them. The passes: the chain-index check of
// validate(), the frustum test and compaction, the slots' chain terms, the settling keys and test
// of the Lagrangian form's incremental case, and the budget write-out.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

// the AVX2 variants of the hot passes exist on x86 only; elsewhere they compile as plain copies
// that are never chosen (cpuHasAvx2 is false), and the "SSE2" ones lower to the target's vectors
#if defined(__x86_64__) || defined(__i386__)
#define SCENELOD_AVX2_TARGET __attribute__((target("avx2")))
#else
#define SCENELOD_AVX2_TARGET
#endif
typedef float V8f __attribute__((vector_size(32)));  // AVX2 functions only
typedef int32_t V8i __attribute__((vector_size(32)));

// lane masks (all bits set = true): range[f][n] holds lanes f..n-1, other[a + 1] every lane but a
struct LaneMasks {
  int32_t range[kLanes + 1][kLanes + 1][kLanes];
  int32_t other[kLanes + 1][kLanes];
};
constexpr LaneMasks makeLaneMasks() {
  LaneMasks m{};
  for (int f = 0; f <= kLanes; ++f)
    for (int n = 0; n <= kLanes; ++n)
      for (int l = 0; l < kLanes; ++l) m.range[f][n][l] = l >= f && l < n ? -1 : 0;
  for (int a = -1; a < kLanes; ++a)
    for (int l = 0; l < kLanes; ++l) m.other[a + 1][l] = l != a ? -1 : 0;
  return m;
}
constexpr LaneMasks kLaneMasks = makeLaneMasks();
// set bits per byte value
struct BitCount8 {
  uint8_t n[256];
  constexpr uint8_t operator[](int i) const { return n[i]; }
};
constexpr BitCount8 makeBitCount8() {
  BitCount8 t{};
  for (int i = 0; i < 256; ++i) t.n[i] = static_cast<uint8_t>((i & 1) + (i >> 1 & 1) + (i >> 2 & 1) + (i >> 3 & 1) +
                                                              (i >> 4 & 1) + (i >> 5 & 1) + (i >> 6 & 1) + (i >> 7 & 1));
  return t;
}
constexpr BitCount8 kBitCount8 = makeBitCount8();

// A slot's settling key, written by the slot pass in budget mode: kSettleIneligible, or the lane-mask row
// finest * (kLanes + 1) + level count in bits 4.. and the candidate (last frame's level) + 1 in bits 0..3.
// Eligible: a chain of at most kLanes levels, a level-independent cost > 0, not must-draw, and the
// candidate "not drawn" or a level in [finest, level count). Settling reads this one column instead
// of four byte columns and the cost. m keys of a block from its columns, in a loop that vectorises
// (16-bit lanes; the unsigned compare finest <= prev < level count as one, by wrap-around).
// Returns the count of slots with last frame's level "not drawn" and a benefit > 0: the settled
// slots' part of the dropped count comes from it (the write-out of the unsettled slots corrects it).
inline __attribute__((always_inline)) uint32_t settleKeys(const float* ga, const float* gb, const uint8_t* glevels,
                                                          const uint8_t* gfinest, const int8_t* gprev, size_t m,
                                                          uint16_t* gkey) {
  uint32_t dropped = 0;
  for (size_t j = 0; j < m; ++j) dropped += (gprev[j] < 0) & (gb[j] > 0.0f) ? 1u : 0u;
  for (size_t j = 0; j < m; ++j) {
    const uint16_t lc = glevels[j], fi = gfinest[j];
    const uint16_t p1 = static_cast<uint16_t>(gprev[j] + 1);  // 0: "not drawn"
    const bool eligible = (lc <= kLanes) & (ga[j] > 0.0f) &
                          ((p1 == 0) | (static_cast<uint16_t>(p1 - 1 - fi) < static_cast<uint16_t>(lc - fi)));
    const uint16_t key = static_cast<uint16_t>((fi * (kLanes + 1) + lc) << 4 | p1);
    gkey[j] = eligible ? key : kSettleIneligible;
  }
  return dropped;
}

// Settled objects (incremental case, Lagrangian form): an object whose hull point is the unique
// maximiser of benefit - lambda cost for every price in the predicted bracket, widened by
// kSettleMargin at both ends, has no upgrade inside the bracket and takes that point in the exact
// hull walk too, so it needs no hull. The candidate is last frame's level (on a smooth camera most
// objects keep theirs); the test holds whatever the candidate: it must beat every cheaper point
// by a ratio above the top end and every costlier point by a ratio below the bottom end (float
// differences, exact to about 2^-22 relative, far inside the margin). A settled slot gets no hull:
// its chosen step is kSettledAtPrev (its hull would be "not drawn", the level, and the write-out
// reads the level from slot_prev); the others go, in slot order, to `unsettled`. Returns their
// count; settled_sums->cost sums the settled slots' costs (in slot order). kFuse (the write-out
// fused in, when the features are counted per row): also their benefits and pixels, and each
// drawn settled slot counted at its row in row_drawn; their levels (last frame's) are already in
// the levels out (the slot pass writes every slot's), so the write-out visits only the unsettled slots.
// Only slots with an eligible key (settleKey) may settle. kKeep: some keys may carry kSettleKeep (the
// drop policy is on); without it the kept slots' terms are compiled out.
// The body is generic over vectors VF of floats and VI of int32 masks (kLanes / their width parts
// per chain) and inlined into an SSE2 and an AVX2 function; the same IEEE operations per lane in
// both, so the same bits. No helper functions or lambdas inside: they would be compiled for the
// default target and take AVX vectors by value.
template <typename VF, typename VI, bool kFuse, bool kKeep>
inline __attribute__((always_inline)) size_t settleSlotsBody(const SettleInput& in, size_t slot_count,
                                                             uint8_t* chosen_step, uint32_t* unsettled,
                                                             SettleSums* settled_sums) {
  constexpr int kWidth = static_cast<int>(sizeof(VF) / sizeof(float)), kParts = kLanes / kWidth;
  static_assert(sizeof(VI) == sizeof(VF) && kParts * kWidth == kLanes, "lanes");
  size_t unsettled_count = 0;
  double total = 0.0, benefit = 0.0, pixels = 0.0;
  const float* const in_px = in.px;
  uint32_t* const row_drawn = in.row_drawn;
  if (kFuse) std::memset(row_drawn, 0, in.rows * sizeof(uint32_t));
  // every slot's step (an unsettled slot's is written again when its hull is built)
  std::memset(chosen_step, kSettledAtPrev, slot_count);
  const VF ones = VF{} + in.one;
  // the hysteresis factor per lane, row prev + 1 (row 0: no lane is the current level)
  alignas(32) float hyst[kLanes + 1][kLanes];
  for (int r = 0; r <= kLanes; ++r)
    for (int l = 0; l < kLanes; ++l) hyst[r][l] = l == r - 1 ? in.h1 : 1.0f;
  const float avail = in.avail, lo = in.lo, hi = in.hi, keep_avail = in.keep_avail;
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  const float* const in_spread = in.spread;
  const float* const row_cost = in.row_cost;
  const float* const row_inv_w = in.row_inv_w;
  alignas(32) float pc[kLanes + 1] = {}, pb[kLanes + 1] = {};
  const uint16_t* const in_key = in.key;
  const uint32_t* const in_row0 = in.row0;
  const float* const in_a = in.a;
  const float* const in_b = in.b;
  const float* const in_q = in.q;
  for (size_t s = 0; s < slot_count; ++s) {
    // No branch per slot: whether the slot may settle at all, whether its candidate fits and beats
    // "not drawn", and the vector test are one mask (about half of the candidates are "not drawn",
    // in no predictable order, so a branch on it mispredicted). An ineligible slot's table indices
    // are clamped to harmless rows; its result is discarded.
    // sa > 0 (in the key) and row costs >= 0 (checked by the caller): "not drawn" is the cheapest
    // point. An ineligible key reads the empty lane range and candidate "not drawn".
    const uint32_t key = in_key[s];
    const bool eligible = key < kSettleIneligible;
    const int cand = static_cast<int>(key & 15u) - 1;
    const float sa = in_a[s], sb = in_b[s], sq = in_q[s];
    const uint32_t row0 = in_row0[s];
    const int32_t* const range = kLaneMasks.range[0][0] + ((key >> 4) & 0x3FFu) * kLanes;
    // a slot kept by the drop policy: no "not drawn" point; it settles only where every level of
    // its chain fits alone above its cheapest (the hull's base), so that every lane "fits"
    // (every lane fits: its avail is +inf; and the candidate needs not beat "not drawn": that
    // test's price is -inf)
    const bool keep = kKeep && (key & kSettleKeep) != 0;
    const bool keep_ok = !keep || in_spread[row0] <= keep_avail;
    const float slot_avail = keep ? kInfinity : avail, drop_price = keep ? -kInfinity : hi;
    const int32_t* const other = kLaneMasks.other[cand + 1];
    // the points as pointAt computes them, lane l at pc[l + 1] / pb[l + 1]; pc[0] = pb[0] = +0 is
    // "not drawn", so the candidate's point is pc[cand + 1], pb[cand + 1] without a branch
    VF c[kParts], b[kParts];
    for (int k = 0; k < kParts; ++k) {
      VF rc, riw, hm;
      std::memcpy(&rc, row_cost + row0 + k * kWidth, sizeof(rc));
      std::memcpy(&riw, row_inv_w + row0 + k * kWidth, sizeof(riw));
      std::memcpy(&hm, hyst[cand + 1] + k * kWidth, sizeof(hm));
      c[k] = sa + rc;
      const VF t = sq * riw;
      b[k] = sb * ((t < ones ? t : ones) * hm);
      std::memcpy(pc + 1 + k * kWidth, &c[k], sizeof(VF));
      std::memcpy(pb + 1 + k * kWidth, &b[k], sizeof(VF));
    }
    const float cc = pc[cand + 1], cb = pb[cand + 1];
    VI fail = VI{};
    for (int k = 0; k < kParts; ++k) {
      VI in_range, not_cand;
      std::memcpy(&in_range, range + k * kWidth, sizeof(in_range));
      std::memcpy(&not_cand, other + k * kWidth, sizeof(not_cand));
      const VI fits = c[k] <= slot_avail;
      const VI v = in_range & not_cand & fits;  // the other points that fit alone
      // cheaper (dc > 0): db > hi dc; costlier (dc < 0): db > lo dc; both are db > max(hi dc, lo dc)
      const VF d = cc - c[k];
      const VF p = hi * d, q = lo * d;
      fail |= v & ~(cb - b[k] > (p > q ? p : q));
      // a drawn candidate (its own lane, c[k] = cc and b[k] = cb there) must fit alone and beat
      // "not drawn": cb > hi cc
      fail |= ~not_cand & ~(fits & (b[k] > drop_price * c[k]));
    }
    // any lane set: one vptest in the AVX2 form; otherwise the vector's halves ORed down to 16 bytes,
    // then two words
    bool none;
#if defined(__x86_64__) || defined(__i386__)
    if constexpr (sizeof(VI) == 32) {
      // the builtin, not _mm256_testz_si256: this body is compiled for the default target before it
      // is inlined into the AVX2 function, and the builtin is checked only where it is expanded
      typedef long long V4q __attribute__((vector_size(32)));
      V4q f;
      std::memcpy(&f, &fail, sizeof(f));
      none = __builtin_ia32_ptestz256(f, f) != 0;
    } else
#endif
    {
      V4i fail4 = V4i{};
      for (size_t k = 0; k < sizeof(VI) / sizeof(V4i); ++k) {
        V4i part;
        std::memcpy(&part, reinterpret_cast<const unsigned char*>(&fail) + k * sizeof(V4i), sizeof(part));
        fail4 |= part;
      }
      uint64_t words[2];
      std::memcpy(words, &fail4, sizeof(words));
      none = (words[0] | words[1]) == 0;
    }
    const bool settled = eligible & none & keep_ok;
    const int pick = (cand + 1) & -static_cast<int>(settled);  // cand + 1, or 0 for an unsettled slot
    total += pc[pick];  // cc, or pc[0] = +0
    if (kFuse) {
      // the write-out's terms of a settled slot (writeOutSlotsBody's operations on the same values:
      // cc and cb are its cost and benefit at its level); an unsettled slot adds +0 and its level is
      // written again by the write-out of the unsettled slots (the dropped count is settleKeys')
      const uint32_t drawn = pick != 0 ? 1u : 0u;
      benefit += pb[pick];
      pixels += maskFloat(in_px[s], 0u - drawn);
      row_drawn[row0 + static_cast<uint32_t>(pick) - drawn] += drawn;  // row0 + cand, or + 0 adding 0
      // (its level, cand = last frame's, is already in the levels out: the slot pass wrote it)
    }
    unsettled[unsettled_count] = static_cast<uint32_t>(s);
    unsettled_count += settled ? 0u : 1u;
  }
  *settled_sums = SettleSums{total, benefit, pixels};
  return unsettled_count;
}

// Nonzero when one of the n chain indices is above last_chain (validate's check, no early exit: the
// valid case reads the whole column anyway): two vectors at a time, unsigned order as signed order
// after flipping the sign bit (SSE2 has no unsigned compare). Compiled for SSE2 and AVX2.
template <typename VI>
inline __attribute__((always_inline)) uint32_t chainsAboveBody(const uint32_t* chain_of, size_t n,
                                                               uint32_t last_chain) {
  constexpr size_t kWidth = sizeof(VI) / sizeof(int32_t);
  const VI flip = VI{} + std::numeric_limits<int32_t>::min();
  const VI last = flip ^ static_cast<int32_t>(last_chain);
  VI bad0 = VI{}, bad1 = VI{};
  size_t i = 0;
  for (; i + 2 * kWidth <= n; i += 2 * kWidth) {
    VI v0, v1;
    std::memcpy(&v0, chain_of + i, sizeof(v0));
    std::memcpy(&v1, chain_of + i + kWidth, sizeof(v1));
    bad0 |= (v0 ^ flip) > last;
    bad1 |= (v1 ^ flip) > last;
  }
  bad0 |= bad1;
  uint32_t bad = 0;
  for (size_t l = 0; l < kWidth; ++l) bad |= static_cast<uint32_t>(bad0[l]);
  for (; i < n; ++i) bad |= chain_of[i] > last_chain ? 1u : 0u;
  return bad;
}

// The frustum test of the slot pass's object blocks (n <= 64 there): outside[i] = 1 when sphere i is
// outside one of the frustum's planes (sphereInFrustum's six tests without early exits). Blocks of
// 64 objects are first copied into local columns, so the six planes' tests are one plain loop over
// floats that the compiler vectorises (over the packed centres it managed only 2 wide; one loop per
// plane read the columns six times). Compiled twice, for SSE2 (4 wide) and AVX2 (8 wide): compares of the same
// products and sums (no FMA: -ffp-contract=off, and the AVX2 target does not enable it), so both
// give the same bits (Selector.AvxAndSse2PathsGiveTheSameBits).
// One block of m <= 64 spheres: their centres into local columns bx, by, bz, minus their radii
// into bnr, and bo[j] = 1 when sphere j is outside a plane.
inline __attribute__((always_inline)) void frustumBlock(const Frustum& frustum, const float* p, const float* rad,
                                                        size_t m, float* bx, float* by, float* bz, float* bnr,
                                                        uint32_t* bo) {
  float pa[6], pb[6], pc[6], pd[6];
  for (int k = 0; k < 6; ++k) {
    pa[k] = frustum.planes[k].x;
    pb[k] = frustum.planes[k].y;
    pc[k] = frustum.planes[k].z;
    pd[k] = frustum.planes[k].w;
  }
  for (size_t j = 0; j < m; ++j) {
    bx[j] = p[3 * j];
    by[j] = p[3 * j + 1];
    bz[j] = p[3 * j + 2];
    bnr[j] = -rad[j];
  }
  // the six planes in one loop over the block (each element's coordinates loaded once)
  for (size_t j = 0; j < m; ++j) {
    const float x = bx[j], y = by[j], z = bz[j], nr = bnr[j];
    uint32_t o = 0;
    for (int k = 0; k < 6; ++k)
      o |= pa[k] * x + pb[k] * y + pc[k] * z + pd[k] < nr ? 1u : 0u;
    bo[j] = o;
  }
}
// Queues the spheres of a block that frustumBlock tested from q's entry `count` on: branch-free,
// every sphere written and the count advanced past those in view. Returns the new count.
inline __attribute__((always_inline)) size_t queueInView(const float* bx, const float* by, const float* bz,
                                                         const float* bnr, const uint32_t* bo, size_t m,
                                                         uint32_t base, const SphereQueue& q, size_t count) {
  uint32_t* const dst = q.object;
  float* const qx = q.x;
  float* const qy = q.y;
  float* const qz = q.z;
  float* const qr = q.r;
  for (size_t j = 0; j < m; ++j) {
    dst[count] = base + static_cast<uint32_t>(j);
    qx[count] = bx[j];
    qy[count] = by[j];
    qz[count] = bz[j];
    qr[count] = -bnr[j];  // the radius again (a sign flip, exact)
    count += 1u - bo[j];
  }
  return count;
}
inline __attribute__((always_inline)) void frustumOutsideBody(const Frustum& frustum, const float* xyz,
                                                              const float* rad, size_t n, uint8_t* outside) {
  constexpr size_t kBlock = 64;
  alignas(32) float bx[kBlock], by[kBlock], bz[kBlock], bnr[kBlock];
  alignas(32) uint32_t bo[kBlock];
  auto testBlock = [&](size_t i0, size_t m) {
    frustumBlock(frustum, xyz + 3 * i0, rad + i0, m, bx, by, bz, bnr, bo);
    for (size_t j = 0; j < m; ++j) outside[i0 + j] = static_cast<uint8_t>(bo[j]);
  };
  // full blocks with a constant trip count (no loop-exit mispredictions), then the tail
  size_t i0 = 0;
  for (; i0 + kBlock <= n; i0 += kBlock) testBlock(i0, kBlock);
  if (i0 < n) testBlock(i0, n - i0);
}

#if defined(__x86_64__) || defined(__i386__)
// per 8-bit mask of kept lanes: their lane numbers in order, 3 bits each (the rest 0)
struct KeepPermutes {
  uint32_t lanes[256];
};
constexpr KeepPermutes makeKeepPermutes() {
  KeepPermutes t{};
  for (int mask = 0; mask < 256; ++mask) {
    uint32_t packed = 0;
    int k = 0;
    for (int l = 0; l < 8; ++l)
      if (mask >> l & 1) packed |= static_cast<uint32_t>(l) << (3 * k++);
    t.lanes[mask] = packed;
  }
  return t;
}
constexpr KeepPermutes kKeepPermutes = makeKeepPermutes();
#endif

// The coarsest level of accuracy 1 of a chain of more than kLanes levels (row_inv_w from its first
// row): a branch-free binary search (most objects are far: their coarsest level is accurate enough,
// one predictable test).
inline uint32_t finestBySearch(float q, const float* row_inv_w, uint32_t level_count) {
  uint32_t finest = level_count - 1;
  if (!(q * row_inv_w[finest] >= 1.0f)) finest = 0;
  for (uint32_t len = finest == 0 && level_count >= 2 ? level_count - 2 : 0; len > 0;) {
    const uint32_t half = len / 2;
    const uint32_t ok = q * row_inv_w[finest + half + 1] >= 1.0f ? 1u : 0u;
    // arithmetic instead of selects: compilers turn the selects into branches, which mispredict
    finest += ok * (half + 1);
    len = half + ok * (len - 2 * half - 1);  // ok: len - half - 1 (unsigned wrap-around is exact)
  }
  return finest;
}

// Pass 1c's per-slot chain terms for m slots: first row, level count, previous level and the
// finest candidate. The coarsest level of accuracy 1 (level 0, w = 0, always is): widths do not
// fall with the level, so the accurate-enough levels 1.. are a prefix (q * (1 / w) >= 1 falls with
// w, NaN included) and its length is their count: for a chain of up to kLanes levels, counted over
// the chain's lanes at once without a branch (the binary search it replaces had a loop of varying
// length per object, which mispredicted), in two SSE2 vectors or one AVX2 vector (the same compares).
template <bool kAvx2>
inline __attribute__((always_inline)) void chainTermsBody(const uint32_t* gobj, const float* gq, size_t m,
                                                          const uint32_t* chain_of, const uint32_t* chain_offset,
                                                          const float* row_inv_w, const int8_t* prev_level,
                                                          uint8_t* gfinest, uint32_t* grow0, int8_t* gprev,
                                                          uint8_t* glevels, int8_t* level_of) {
  static_assert(kLanes == 8, "two SSE2 vectors or one AVX2 vector per chain");
  for (size_t j = 0; j < m; ++j) {
    const size_t i = gobj[j];
    const uint32_t chain = chain_of[i];
    const uint32_t row0 = chain_offset[chain];
    const uint32_t level_count = chain_offset[chain + 1] - row0;
    const float q = gq[j];
    uint32_t finest;
    if (level_count <= kLanes) {
      if constexpr (kAvx2) {
        V8i range;
        V8f riw;
        std::memcpy(&range, kLaneMasks.range[1][level_count], sizeof(range));
        std::memcpy(&riw, row_inv_w + row0, sizeof(riw));
        const V8i ok = (q * riw >= 1.0f) & range;  // -1 per level
#if defined(__x86_64__) || defined(__i386__)
        V8f okf;
        std::memcpy(&okf, &ok, sizeof(okf));
        finest = static_cast<uint32_t>(__builtin_popcount(static_cast<unsigned>(__builtin_ia32_movmskps256(okf))));
#else
        finest = static_cast<uint32_t>(-(ok[0] + ok[1] + ok[2] + ok[3] + ok[4] + ok[5] + ok[6] + ok[7]));
#endif
      } else {
        V4i range0, range1;
        V4f riw0, riw1;
        std::memcpy(&range0, kLaneMasks.range[1][level_count], sizeof(range0));
        std::memcpy(&range1, kLaneMasks.range[1][level_count] + 4, sizeof(range1));
        std::memcpy(&riw0, row_inv_w + row0, sizeof(riw0));
        std::memcpy(&riw1, row_inv_w + row0 + 4, sizeof(riw1));
        const V4i ok0 = (q * riw0 >= 1.0f) & range0, ok1 = (q * riw1 >= 1.0f) & range1;  // -1 per level
#if defined(__x86_64__) || defined(__i386__)
        // the lanes' sign bits as a byte (movmskps), counted by a table
        V4f okf0, okf1;
        std::memcpy(&okf0, &ok0, sizeof(okf0));
        std::memcpy(&okf1, &ok1, sizeof(okf1));
        finest = kBitCount8[__builtin_ia32_movmskps(okf0) | (__builtin_ia32_movmskps(okf1) << 4)];
#else
        const V4i ok = ok0 + ok1;
        finest = static_cast<uint32_t>(-(ok[0] + ok[1] + ok[2] + ok[3]));
#endif
      }
    } else {
      finest = finestBySearch(q, row_inv_w + row0, level_count);
    }
    gfinest[j] = static_cast<uint8_t>(finest);
    grow0[j] = row0;
    const int8_t prev = prev_level[i];
    gprev[j] = prev;
    glevels[j] = static_cast<uint8_t>(level_count);
    // the slot's level starts at last frame's: a settled slot's in the fused write-out (the
    // settling pass does not write it); every other path writes every slot's level again
    level_of[i] = prev;
  }
}

// The budget write-out when the settling pass did not sum the settled slots (a cold frame, a miss
// of the predicted bracket, more rows than slots, the ½ guarantee's fallback): each slot's level
// into level_of and its share of the frame's sums, in slot order, with the same operations as
// the write-out of the unsettled slots and distance mode's sums (selector.cpp; so the same bits).
// Every pointer and sum in a local: otherwise the loop runs out of registers and keeps the integer
// sums and the column pointers on the stack (a load or a read-modify-write each per slot).
// kCountRows: the integer features as Σ (drawn slots of the row) × feature over the rows instead of
// three gathers per slot (fewer rows than slots); integer sums, so the same values in any order.
// Compiled twice like the settling test: for SSE2 and with the AVX2 target (the same V4f
// operations, VEX-encoded: three-operand forms, fewer register copies; the same bits).
template <bool kCountRows>
inline __attribute__((always_inline)) SlotSums writeOutSlotsBody(const WriteOutInput& in, size_t slot_count,
                                                                 double predicted0, int8_t* level_of) {
  const uint8_t* const chosen = in.chosen;
  const uint8_t* const hull = in.hull;
  const size_t hull_stride = in.hull_stride;
  const uint32_t* const slot_object = in.slot_object;
  const float* const slot_a = in.a;
  const float* const slot_b = in.b;
  const float* const slot_q = in.q;
  const float* const slot_px = in.px;
  const uint32_t* const slot_row0 = in.row0;
  const int8_t* const slot_prev = in.prev;
  const float* const row_cost = in.row_cost;
  const float* const row_inv_w = in.row_inv_w;
  const uint32_t* const tri = in.tri;
  const uint32_t* const vert = in.vert;
  const uint32_t* const lines = in.lines;
  uint32_t* const row_drawn = in.row_drawn;
  const float h_mult[2] = {1.0f, in.h1};
  double predicted = predicted0, benefit = 0.0, pixels = 0.0;
  uint64_t tri_sum = 0, vert_sum = 0, line_sum = 0;
  uint32_t dropped = 0, drawn = 0;
  if (kCountRows) std::memset(row_drawn, 0, in.rows * sizeof(uint32_t));
  // blocks of kBlock slots in two loops: the levels, row gathers and integer sums (scalar); then the
  // float terms masked to +0 for slots not drawn, four slots at a time in vectors, and their double
  // sums lane by lane (slot order)
  constexpr size_t kBlock = 64;
  alignas(32) float lrc[kBlock], lriw[kBlock], lh[kBlock];
  alignas(32) uint32_t lkeep[kBlock];
  for (size_t s0 = 0; s0 < slot_count; s0 += kBlock) {
    const size_t m = std::min(kBlock, slot_count - s0);
    for (size_t j = 0; j < m; ++j) {
      const size_t s = s0 + j;
      // settled slots (about 97 % on a smooth camera, a predictable branch) have no hull
      const uint8_t c = chosen[s];
      const int8_t prev = slot_prev[s];
      uint8_t level = c == kSettledAtPrev ? static_cast<uint8_t>(prev) : kNotDrawn;
      if (c < kSettledAtBase) level = hull[s * hull_stride + c];
      level_of[slot_object[s]] = static_cast<int8_t>(level);  // kNotDrawn is -1
      // all ones if drawn: levels are below 64, kNotDrawn is the one negative int8
      const uint32_t keep = ~static_cast<uint32_t>(static_cast<int32_t>(static_cast<int8_t>(level)) >> 31);
      const uint32_t row = slot_row0[s] + (level & keep);
      lrc[j] = row_cost[row];
      lriw[j] = row_inv_w[row];
      lh[j] = h_mult[level == static_cast<uint8_t>(prev)];
      std::memcpy(lkeep + j, &keep, sizeof(keep));  // the mask's bits
      if (kCountRows) {
        row_drawn[row] -= keep;  // + 1 (mod 2^32); a slot not drawn adds 0 to its chain's first row
      } else {
        tri_sum += tri[row] & keep;
        vert_sum += vert[row] & keep;
        line_sum += lines[row] & keep;
      }
    }
    const float* const ba = slot_a + s0;
    const float* const bb = slot_b + s0;
    const float* const bq = slot_q + s0;
    const float* const bpx = slot_px + s0;
    // ctx.pointCost / ctx.pointBenefit at a drawn level, +0 when not drawn (x + 0.0 == x): four
    // slots at a time in vectors (the same IEEE operations per lane), the tail one at a time
    size_t j = 0;
    const V4f ones = {1.0f, 1.0f, 1.0f, 1.0f};
    const V4f zeros = {};
    V4i dropped4 = {}, drawn4 = {};
    for (; j + 4 <= m; j += 4) {
      V4f a4, b4, q4, px4, rc4, riw4, h4;
      V4i k4;
      std::memcpy(&a4, ba + j, sizeof(a4));
      std::memcpy(&b4, bb + j, sizeof(b4));
      std::memcpy(&q4, bq + j, sizeof(q4));
      std::memcpy(&px4, bpx + j, sizeof(px4));
      std::memcpy(&rc4, lrc + j, sizeof(rc4));
      std::memcpy(&riw4, lriw + j, sizeof(riw4));
      std::memcpy(&h4, lh + j, sizeof(h4));
      std::memcpy(&k4, lkeep + j, sizeof(k4));
      const V4f cost = a4 + rc4;
      const V4f t = q4 * riw4;
      const V4f acc = (t < ones ? t : ones) * h4;  // std::min(1.0f, t): 1 for NaN
      const V4f ben = b4 * acc;
      V4i ci, bi, pi;
      std::memcpy(&ci, &cost, sizeof(ci));
      std::memcpy(&bi, &ben, sizeof(bi));
      std::memcpy(&pi, &px4, sizeof(pi));
      ci &= k4;
      bi &= k4;
      pi &= k4;
      V4f cm, bm, pm;
      std::memcpy(&cm, &ci, sizeof(cm));
      std::memcpy(&bm, &bi, sizeof(bm));
      std::memcpy(&pm, &pi, sizeof(pm));
      for (int l = 0; l < 4; ++l) {
        predicted += cm[l];
        benefit += bm[l];
        pixels += pm[l];
      }
      dropped4 -= ~k4 & (b4 > zeros);  // -1 per dropped lane
      drawn4 -= k4;
    }
    dropped += static_cast<uint32_t>(dropped4[0] + dropped4[1] + dropped4[2] + dropped4[3]);
    drawn += static_cast<uint32_t>(drawn4[0] + drawn4[1] + drawn4[2] + drawn4[3]);
    for (; j < m; ++j) {
      uint32_t keep;
      std::memcpy(&keep, lkeep + j, sizeof(keep));
      const float b = bb[j];
      dropped += (keep ^ 1u) & (b > 0.0f ? 1u : 0u);
      drawn += keep & 1u;
      const float cost = ba[j] + lrc[j];
      const float acc = std::min(1.0f, bq[j] * lriw[j]) * lh[j];
      predicted += maskFloat(cost, keep);
      benefit += maskFloat(b * acc, keep);
      pixels += maskFloat(bpx[j], keep);
    }
  }
  if (kCountRows) {
    for (size_t r = 0; r < in.rows; ++r) {
      const uint64_t k = row_drawn[r];
      tri_sum += k * tri[r];
      vert_sum += k * vert[r];
      line_sum += k * lines[r];
    }
  }
  return SlotSums{predicted, benefit, pixels, tri_sum, vert_sum, line_sum, dropped, drawn};
}

template <bool kFuse, bool kKeep>
size_t settleSlotsSse2(const SettleInput& in, size_t slot_count, uint8_t* chosen_step, uint32_t* unsettled,
                       SettleSums* settled_sums) {
  return settleSlotsBody<V4f, V4i, kFuse, kKeep>(in, slot_count, chosen_step, unsettled, settled_sums);
}
template <bool kFuse, bool kKeep>
SCENELOD_AVX2_TARGET size_t settleSlotsAvx2(const SettleInput& in, size_t slot_count, uint8_t* chosen_step,
                                            uint32_t* unsettled, SettleSums* settled_sums) {
  return settleSlotsBody<V8f, V8i, kFuse, kKeep>(in, slot_count, chosen_step, unsettled, settled_sums);
}
template <bool kCountRows>
__attribute__((noinline)) SlotSums writeOutSlotsSse2(const WriteOutInput& in, size_t slot_count, double predicted0,
                                                     int8_t* level_of) {
  return writeOutSlotsBody<kCountRows>(in, slot_count, predicted0, level_of);
}
template <bool kCountRows>
SCENELOD_AVX2_TARGET __attribute__((noinline)) SlotSums writeOutSlotsAvx2(const WriteOutInput& in, size_t slot_count,
                                                                          double predicted0, int8_t* level_of) {
  return writeOutSlotsBody<kCountRows>(in, slot_count, predicted0, level_of);
}
}  // namespace

// (a full block of the slot pass gets its constant trip count: loops that predict)
uint32_t settleKeysSse2(const float* ga, const float* gb, const uint8_t* glevels, const uint8_t* gfinest,
                        const int8_t* gprev, size_t m, uint16_t* gkey) {
  if (m == kSlotBlock) return settleKeys(ga, gb, glevels, gfinest, gprev, kSlotBlock, gkey);
  return settleKeys(ga, gb, glevels, gfinest, gprev, m, gkey);
}
SCENELOD_AVX2_TARGET uint32_t settleKeysAvx2(const float* ga, const float* gb, const uint8_t* glevels,
                                             const uint8_t* gfinest, const int8_t* gprev, size_t m, uint16_t* gkey) {
  if (m == kSlotBlock) return settleKeys(ga, gb, glevels, gfinest, gprev, kSlotBlock, gkey);
  return settleKeys(ga, gb, glevels, gfinest, gprev, m, gkey);
}
size_t settleSlots(bool avx2, bool fuse, const SettleInput& in, size_t slot_count, uint8_t* chosen_step,
                   uint32_t* unsettled, SettleSums* settled_sums) {
  // without the drop policy no slot is kept: the form without its per-slot terms
  typedef size_t (*Settle)(const SettleInput&, size_t, uint8_t*, uint32_t*, SettleSums*);
  static const Settle kForms[2][2][2] = {
      {{settleSlotsSse2<false, false>, settleSlotsSse2<false, true>},
       {settleSlotsSse2<true, false>, settleSlotsSse2<true, true>}},
      {{settleSlotsAvx2<false, false>, settleSlotsAvx2<false, true>},
       {settleSlotsAvx2<true, false>, settleSlotsAvx2<true, true>}}};
  return kForms[avx2][fuse][in.keep](in, slot_count, chosen_step, unsettled, settled_sums);
}
uint32_t chainsAboveSse2(const uint32_t* chain_of, size_t n, uint32_t last_chain) {
  return chainsAboveBody<V4i>(chain_of, n, last_chain);
}
SCENELOD_AVX2_TARGET uint32_t chainsAboveAvx2(const uint32_t* chain_of, size_t n, uint32_t last_chain) {
  return chainsAboveBody<V8i>(chain_of, n, last_chain);
}
void frustumOutsideSse2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint8_t* outside) {
  frustumOutsideBody(frustum, xyz, rad, n, outside);
}
SCENELOD_AVX2_TARGET void frustumOutsideAvx2(const Frustum& frustum, const float* xyz, const float* rad, size_t n,
                                             uint8_t* outside) {
  frustumOutsideBody(frustum, xyz, rad, n, outside);
}
// The frustum test and the compaction of the slot pass's object blocks when no chain is empty (n <= 64):
// the indices base + j of the spheres in view, in order, and their centres and radii to q; returns
// their count.
size_t frustumCompactSse2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint32_t base,
                          const SphereQueue& q) {
  alignas(16) float bx[64], by[64], bz[64], bnr[64];
  alignas(16) uint32_t bo[64];
  // a full block with a constant trip count (no loop-exit mispredictions)
  if (n == 64)
    frustumBlock(frustum, xyz, rad, 64, bx, by, bz, bnr, bo);
  else
    frustumBlock(frustum, xyz, rad, n, bx, by, bz, bnr, bo);
  return queueInView(bx, by, bz, bnr, bo, n, base, q, 0);
}
#if defined(__x86_64__) || defined(__i386__)
// eight objects at a time: the kept lanes' indices, centres and radii moved to the front of a
// vector (vpermd / vpermps, the lane numbers from the table) and stored whole; the next store
// starts after the kept ones, so the result is frustumCompactSse2's (moves only)
// The centres are de-interleaved in registers (three loads, two blends and a lane permutation per
// coordinate: the three coordinates of 8 packed centres sit in distinct lanes of the three vectors),
// tested against the six planes there (frustumBlock's operations in its order: ((a x + b y) + c z)
// + d < -r, so the same bits) and moved to the queue from there; the tail of fewer than 8 spheres
// goes through frustumBlock.
__attribute__((target("avx2,popcnt"))) size_t frustumCompactAvx2(const Frustum& frustum, const float* xyz,
                                                                 const float* rad, size_t n, uint32_t base,
                                                                 const SphereQueue& q) {
  alignas(32) float plane[4][6][8];  // each coefficient on all lanes
  for (int k = 0; k < 6; ++k)
    for (int l = 0; l < 8; ++l) {
      plane[0][k][l] = frustum.planes[k].x;
      plane[1][k][l] = frustum.planes[k].y;
      plane[2][k][l] = frustum.planes[k].z;
      plane[3][k][l] = frustum.planes[k].w;
    }
  uint32_t* const dst = q.object;
  float* const qx = q.x;
  float* const qy = q.y;
  float* const qz = q.z;
  float* const qr = q.r;
  const __m256 sign = _mm256_set1_ps(-0.0f);
  size_t count = 0, j = 0;
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i shifts = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
  const __m256i seven = _mm256_set1_epi32(7);
  // after the blends, lane l holds the coordinate of centre (x) 0 3 6 1 4 7 2 5, (y) 5 0 3 6 1 4 7 2,
  // (z) 2 5 0 3 6 1 4 7; these put centre i in lane i
  const __m256i order_x = _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5);
  const __m256i order_y = _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6);
  const __m256i order_z = _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7);
  for (; j + 8 <= n; j += 8) {
    const __m256 v0 = _mm256_loadu_ps(xyz + 3 * j), v1 = _mm256_loadu_ps(xyz + 3 * j + 8),
                 v2 = _mm256_loadu_ps(xyz + 3 * j + 16);
    const __m256 x = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(v0, v1, 0x92), v2, 0x24), order_x);
    const __m256 y = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(v0, v1, 0x24), v2, 0x49), order_y);
    const __m256 z = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(v0, v1, 0x49), v2, 0x92), order_z);
    const __m256 r = _mm256_loadu_ps(rad + j);
    const __m256 nr = _mm256_xor_ps(r, sign);
    __m256 out = _mm256_setzero_ps();
    for (int k = 0; k < 6; ++k) {
      const __m256 d = _mm256_add_ps(
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_load_ps(plane[0][k]), x),
                                      _mm256_mul_ps(_mm256_load_ps(plane[1][k]), y)),
                        _mm256_mul_ps(_mm256_load_ps(plane[2][k]), z)),
          _mm256_load_ps(plane[3][k]));
      out = _mm256_or_ps(out, _mm256_cmp_ps(d, nr, _CMP_LT_OQ));
    }
    const int keep = ~_mm256_movemask_ps(out) & 0xFF;
    const __m256i perm = _mm256_and_si256(
        _mm256_srlv_epi32(_mm256_set1_epi32(static_cast<int32_t>(kKeepPermutes.lanes[keep])), shifts), seven);
    const __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int32_t>(base + j)), lane);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + count), _mm256_permutevar8x32_epi32(idx, perm));
    _mm256_storeu_ps(qx + count, _mm256_permutevar8x32_ps(x, perm));
    _mm256_storeu_ps(qy + count, _mm256_permutevar8x32_ps(y, perm));
    _mm256_storeu_ps(qz + count, _mm256_permutevar8x32_ps(z, perm));
    _mm256_storeu_ps(qr + count, _mm256_permutevar8x32_ps(r, perm));
    count += static_cast<size_t>(__builtin_popcount(static_cast<unsigned>(keep)));
  }
  if (j < n) {
    alignas(32) float bx[8], by[8], bz[8], bnr[8];
    alignas(32) uint32_t bo[8];
    const size_t m = n - j;
    frustumBlock(frustum, xyz + 3 * j, rad + j, m, bx, by, bz, bnr, bo);
    count = queueInView(bx, by, bz, bnr, bo, m, base + static_cast<uint32_t>(j), q, count);
  }
  return count;
}
#else
size_t frustumCompactAvx2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint32_t base,
                          const SphereQueue& q) {
  return frustumCompactSse2(frustum, xyz, rad, n, base, q);
}
#endif
bool cpuHasAvx2() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}
void chainTermsSse2(const uint32_t* gobj, const float* gq, size_t m, const uint32_t* chain_of,
                    const uint32_t* chain_offset, const float* row_inv_w, const int8_t* prev_level,
                    uint8_t* gfinest, uint32_t* grow0, int8_t* gprev, uint8_t* glevels, int8_t* level_of) {
  if (m == kSlotBlock)  // a full block of the slot pass: loops of a constant trip count
    chainTermsBody<false>(gobj, gq, kSlotBlock, chain_of, chain_offset, row_inv_w, prev_level, gfinest, grow0, gprev,
                         glevels, level_of);
  else
    chainTermsBody<false>(gobj, gq, m, chain_of, chain_offset, row_inv_w, prev_level, gfinest, grow0, gprev, glevels,
                         level_of);
}
#if defined(__x86_64__) || defined(__i386__)
__attribute__((target("avx2,popcnt")))
#endif
void chainTermsAvx2(const uint32_t* gobj, const float* gq, size_t m, const uint32_t* chain_of,
                    const uint32_t* chain_offset, const float* row_inv_w, const int8_t* prev_level,
                    uint8_t* gfinest, uint32_t* grow0, int8_t* gprev, uint8_t* glevels, int8_t* level_of) {
  if (m == kSlotBlock)  // a full block of the slot pass: loops of a constant trip count
    chainTermsBody<true>(gobj, gq, kSlotBlock, chain_of, chain_offset, row_inv_w, prev_level, gfinest, grow0, gprev,
                         glevels, level_of);
  else
    chainTermsBody<true>(gobj, gq, m, chain_of, chain_offset, row_inv_w, prev_level, gfinest, grow0, gprev, glevels,
                         level_of);
}
SlotSums writeOutSlots(bool avx2, bool count_rows, const WriteOutInput& in, size_t slot_count, double predicted0,
                       int8_t* level_of) {
  if (avx2)
    return count_rows ? writeOutSlotsAvx2<true>(in, slot_count, predicted0, level_of)
                      : writeOutSlotsAvx2<false>(in, slot_count, predicted0, level_of);
  return count_rows ? writeOutSlotsSse2<true>(in, slot_count, predicted0, level_of)
                    : writeOutSlotsSse2<false>(in, slot_count, predicted0, level_of);
}

}  // namespace scenelod::selection
