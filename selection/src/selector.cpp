// Per-frame LOD selection.
//   Distance mode: the coarsest level whose cell width is accurate enough, w_k * scale <= X * R with
//   R = 2 D tan(fov/2) / H (Low & Tan 1997 §4).
//   Budget mode: Funkhouser & Sequin 1993 ("Adaptive display algorithm for interactive frame rates
//   during visualization of complex virtual environments"), cost/benefit choice as a multiple-choice
//   knapsack, solved on each object's upper convex hull of (cost, benefit) by upgrades in decreasing
//   marginal ratio (Mason & Blake 1997, "Adaptive visualization of multiresolution models"), with the
//   classical 1/2 guarantee of max(greedy, first non-fitting upgrade alone) (Sinha & Zoltners 1979 for
//   the multiple-choice knapsack's LP relaxation). The Lagrangian form (docs/SELECTION.md) brackets the
//   price lambda at the budget's edge with a few linear passes, then runs the same greedy on the
//   upgrades inside the bracket only.
#include "scenelod/selection/selector.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace scenelod::selection {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr size_t kRingSize = 16;   // frames whose features are kept for late time reports
constexpr uint8_t kNotDrawn = 0xFF;
// chosen[] values of settled slots (no hull is written for them; hull steps are below 65): at last
// frame's level, or at their base ("not drawn", the ½ guarantee's alternative)
constexpr uint8_t kSettledAtPrev = 0xFE;
constexpr uint8_t kSettledAtBase = 0xFD;
// price histogram: a window of kHistBinades binades (powers of two) of the ratio, each cut into up to
// 2^kHistMaxSubBits buckets by the top mantissa bits
constexpr int kHistBinades = 32;
constexpr int kHistMaxSubBits = 9;
constexpr size_t kHistMaxBuckets = (size_t(kHistBinades) << kHistMaxSubBits) + 2;
// predicted bracket (lambda_prev / (1 + w), lambda_prev * (1 + w)]: starting w, and its bounds
constexpr double kPredictWidthStart = 1.0 / 16.0;
constexpr double kPredictWidthMin = 1.0 / 4096.0;
constexpr double kPredictWidthMax = 4.0;
constexpr int kPredictRetries = 2;  // wider (after a miss) or narrower (after an overflow) brackets
                                    // tried before the full search

void* mallocAllocate(void*, size_t bytes, size_t alignment) {
  const size_t a = std::max<size_t>(alignment, alignof(std::max_align_t));
  const size_t rounded = (bytes + a - 1) / a * a;
  return std::aligned_alloc(a, rounded);
}
void mallocFree(void*, void* p) { std::free(p); }

struct HeapEntry {
  float ratio;
  uint32_t slot;
};
// max-heap on ratio, then the lower slot first (a total order: deterministic)
struct HeapLess {
  bool operator()(const HeapEntry& x, const HeapEntry& y) const {
    if (x.ratio != y.ratio) return x.ratio < y.ratio;
    return x.slot > y.slot;
  }
};

struct BracketEntry {
  float ratio;
  uint32_t slot;
  uint32_t step;  // upgrade from hull point `step` to `step + 1`
};
// Sorts the bracket's entries, collected in (slot, step) order, by ratio descending, then slot,
// then step (a total order: deterministic): a stable LSD radix sort on the ratio's bits,
// descending (bracket ratios are above the bracket's lower end >= 0: positive floats, whose bits
// are in their order), four passes of 8 bits through `scratch` (as many entries), a pass skipped
// when all keys share its byte. The order std::sort gave with that comparison, without an
// unpredictable branch per comparison. The four bytes' histograms are counted in one pass (a
// histogram does not depend on the entries' order); in the bracket's narrow range of ratios most
// of them hold a single byte value, and their passes cost nothing more.
void sortBracket(BracketEntry* entries, BracketEntry* scratch, size_t count) {
  if (count == 0) return;
  uint32_t histogram[4][256] = {};
  for (size_t e = 0; e < count; ++e) {
    uint32_t bits;
    std::memcpy(&bits, &entries[e].ratio, sizeof(bits));
    bits = ~bits;
    ++histogram[0][bits & 0xFF];
    ++histogram[1][(bits >> 8) & 0xFF];
    ++histogram[2][(bits >> 16) & 0xFF];
    ++histogram[3][bits >> 24];
  }
  uint32_t first_bits;
  std::memcpy(&first_bits, &entries[0].ratio, sizeof(first_bits));
  BracketEntry* from = entries;
  BracketEntry* to = scratch;
  for (int shift = 0; shift < 32; shift += 8) {
    uint32_t* const offsets = histogram[shift / 8];
    if (offsets[(~first_bits >> shift) & 0xFF] == count) continue;  // every key has this byte
    uint32_t first = 0;
    for (int b = 0; b < 256; ++b) {
      const uint32_t c = offsets[b];
      offsets[b] = first;
      first += c;
    }
    for (size_t e = 0; e < count; ++e) {
      uint32_t bits;
      std::memcpy(&bits, &from[e].ratio, sizeof(bits));
      to[offsets[(~bits >> shift) & 0xFF]++] = from[e];
    }
    std::swap(from, to);
  }
  if (from != entries) std::memcpy(entries, from, count * sizeof(BracketEntry));
}

// levels of one chain side by side: kLanes floats, two SSE2 vectors or one AVX2 vector (GCC vector
// extensions; only IEEE adds, multiplies, compares and selects, so the bits do not depend on how
// the compiler lowers them)
constexpr int kLanes = 8;
// the AVX2 variants of the hot passes exist on x86 only; elsewhere they compile as plain copies
// that are never chosen (cpuHasAvx2 is false), and the "SSE2" ones lower to the target's vectors
#if defined(__x86_64__) || defined(__i386__)
#define SCENELOD_AVX2_TARGET __attribute__((target("avx2")))
#else
#define SCENELOD_AVX2_TARGET
#endif
typedef float V4f __attribute__((vector_size(16)));
typedef int32_t V4i __attribute__((vector_size(16)));
typedef float V8f __attribute__((vector_size(32)));  // AVX2 functions only
typedef int32_t V8i __attribute__((vector_size(32)));
// a settled object's choice is the unique maximiser of benefit - lambda cost on the predicted bracket
// widened by this factor at both ends; far above the float ratios' rounding (about 2^-22 relative)
constexpr double kSettleMargin = 1.0 / 4096.0;

inline bool anyLane(V4i m) {
  uint64_t w[2];
  std::memcpy(w, &m, sizeof(w));
  return (w[0] | w[1]) != 0;
}
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

// x where mask is all ones, +0 where it is 0
inline float maskFloat(float x, uint32_t mask) {
  // in a vector register (an and of the float's register with the mask's), not through an integer one
  const V4f v = {x, 0.0f, 0.0f, 0.0f};
  const V4i m = {static_cast<int32_t>(mask), 0, 0, 0};
  V4i vi;
  std::memcpy(&vi, &v, sizeof(vi));
  vi &= m;
  V4f r;
  std::memcpy(&r, &vi, sizeof(r));
  return r[0];
}

// the largest float at most v
float floatAtMost(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

// A slot's settling key, written by pass 1c in budget mode: kSettleIneligible, or the lane-mask row
// finest * (kLanes + 1) + level count in bits 4.. and the candidate (last frame's level) + 1 in bits 0..3.
// Eligible: a chain of at most kLanes levels, a level-independent cost > 0, not must-draw, and the
// candidate "not drawn" or a level in [finest, level count). Settling reads this one column instead
// of four byte columns and the cost. m keys of a block from its columns, in a loop that vectorises
// (16-bit lanes; the unsigned compare finest <= prev < level count as one, by wrap-around).
constexpr uint16_t kSettleIneligible = 0x8000;
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
SCENELOD_AVX2_TARGET uint32_t settleKeysAvx2(const float* ga, const float* gb, const uint8_t* glevels,
                                             const uint8_t* gfinest, const int8_t* gprev, size_t m, uint16_t* gkey) {
  return settleKeys(ga, gb, glevels, gfinest, gprev, m, gkey);
}

// What settleSlotsSse2 / settleSlotsAvx2 read: the slot columns of pass 1c, this frame's row terms and the widened
// bracket ends.
struct SettleInput {
  const uint16_t* key;     // settleKey per slot
  const uint32_t* row0;
  const float* a;
  const float* b;
  const float* q;
  const float* row_cost;   // kLanes readable past the last row
  const float* row_inv_w;
  float h1;
  float one;               // 1.0f (from the caller: GCC lowers t < 1 ? t : 1 to minps only when 1 is not a constant)
  float avail;             // largest float <= the budget left after the mandatory part
  float lo, hi;            // the predicted bracket's ends, widened by kSettleMargin
  // the fused write-out's (settleSlots*<true> only): pixels per slot and the per-row counters of
  // drawn slots (zeroed here)
  const float* px;
  uint32_t* row_drawn;
  size_t rows;
};
// The settled slots' share of the frame's sums, in slot order (with kFuse; else only cost).
struct SettleSums {
  double cost, benefit, pixels;
};

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
// the levels out (pass 1c writes every slot's), so the write-out visits only the unsettled slots.
// Only slots with an eligible key (settleKey) may settle.
// The body is generic over vectors VF of floats and VI of int32 masks (kLanes / their width parts
// per chain) and inlined into an SSE2 and an AVX2 function; the same IEEE operations per lane in
// both, so the same bits. No helper functions or lambdas inside: they would be compiled for the
// default target and take AVX vectors by value.
template <typename VF, typename VI, bool kFuse>
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
  const float avail = in.avail, lo = in.lo, hi = in.hi;
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
    const int32_t* const range = kLaneMasks.range[0][0] + ((key >> 4) & 0x7FFu) * kLanes;
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
      const VI fits = c[k] <= avail;
      const VI v = in_range & not_cand & fits;  // the other points that fit alone
      // cheaper (dc > 0): db > hi dc; costlier (dc < 0): db > lo dc; both are db > max(hi dc, lo dc)
      const VF d = cc - c[k];
      const VF p = hi * d, q = lo * d;
      fail |= v & ~(cb - b[k] > (p > q ? p : q));
      // a drawn candidate (its own lane, c[k] = cc and b[k] = cb there) must fit alone and beat
      // "not drawn": cb > hi cc
      fail |= ~not_cand & ~(fits & (b[k] > hi * c[k]));
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
    const bool settled = eligible & none;
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
      // (its level, cand = last frame's, is already in the levels out: pass 1c wrote it)
    }
    unsettled[unsettled_count] = static_cast<uint32_t>(s);
    unsettled_count += settled ? 0u : 1u;
  }
  *settled_sums = SettleSums{total, benefit, pixels};
  return unsettled_count;
}
template <bool kFuse>
size_t settleSlotsSse2(const SettleInput& in, size_t slot_count, uint8_t* chosen_step, uint32_t* unsettled,
                       SettleSums* settled_sums) {
  return settleSlotsBody<V4f, V4i, kFuse>(in, slot_count, chosen_step, unsettled, settled_sums);
}
template <bool kFuse>
SCENELOD_AVX2_TARGET size_t settleSlotsAvx2(const SettleInput& in, size_t slot_count, uint8_t* chosen_step,
                                            uint32_t* unsettled, SettleSums* settled_sums) {
  return settleSlotsBody<V8f, V8i, kFuse>(in, slot_count, chosen_step, unsettled, settled_sums);
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
uint32_t chainsAboveSse2(const uint32_t* chain_of, size_t n, uint32_t last_chain) {
  return chainsAboveBody<V4i>(chain_of, n, last_chain);
}
SCENELOD_AVX2_TARGET uint32_t chainsAboveAvx2(const uint32_t* chain_of, size_t n, uint32_t last_chain) {
  return chainsAboveBody<V8i>(chain_of, n, last_chain);
}

// The frustum test of run()'s fused object blocks (n <= 64 there): outside[i] = 1 when sphere i is
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
void frustumOutsideSse2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint8_t* outside) {
  frustumOutsideBody(frustum, xyz, rad, n, outside);
}
SCENELOD_AVX2_TARGET void frustumOutsideAvx2(const Frustum& frustum, const float* xyz, const float* rad, size_t n,
                                             uint8_t* outside) {
  frustumOutsideBody(frustum, xyz, rad, n, outside);
}
// Where the frustum compaction queues the spheres in view (room for n more entries each): their
// object indices, and their centres and radii, which pass 1c then reads in order instead of
// gathering them again by object.
struct SphereQueue {
  uint32_t* object;
  float* x;
  float* y;
  float* z;
  float* r;
};
// The frustum test and the compaction of run()'s object blocks when no chain is empty (n <= 64):
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
  uint32_t* const dst = q.object;
  float* const qx = q.x;
  float* const qy = q.y;
  float* const qz = q.z;
  float* const qr = q.r;
  size_t count = 0;
  for (size_t j = 0; j < n; ++j) {
    dst[count] = base + static_cast<uint32_t>(j);
    qx[count] = bx[j];
    qy[count] = by[j];
    qz[count] = bz[j];
    qr[count] = -bnr[j];  // the radius again (a sign flip, exact)
    count += 1u - bo[j];
  }
  return count;
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
    for (size_t t = 0; t < m; ++t) {
      dst[count] = base + static_cast<uint32_t>(j + t);
      qx[count] = bx[t];
      qy[count] = by[t];
      qz[count] = bz[t];
      qr[count] = -bnr[t];  // the radius again (a sign flip, exact)
      count += 1u - bo[t];
    }
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

struct HullSums {
  double top_cost, base_total, base_benefit, ptotal;
  size_t segments, pcount;
  size_t pwanted;  // the upgrades inside the predicted bracket, stored or not (>= pcount)
  bool poverflow;
  // fused: the settling pass wrote the settled slots' levels and summed their write-out terms
  // (settled); the unsettled slots, in slot order, are the first unsettled_count of ctx.heap's list
  bool fused;
  size_t unsettled_count;
  SettleSums settled;
};

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

// Pass 1c's per-slot chain terms for m slots, AVX2 (the SSE2 form is inline in SelectionJob::run):
// first row, level count, previous level and the finest candidate, the count of accurate-enough
// levels 1.. over the chain's 8 lanes in one vector (the same compares as the SSE2 form's two).
#if defined(__x86_64__) || defined(__i386__)
__attribute__((target("avx2,popcnt")))
#endif
void chainTermsAvx2(const uint32_t* gobj, const float* gq, size_t m, const uint32_t* chain_of,
                    const uint32_t* chain_offset, const float* row_inv_w, const int8_t* prev_level,
                    uint8_t* gfinest, uint32_t* grow0, int8_t* gprev, uint8_t* glevels, int8_t* level_of) {
  static_assert(kLanes == 8, "one AVX2 vector per chain");
  for (size_t j = 0; j < m; ++j) {
    const size_t i = gobj[j];
    const uint32_t chain = chain_of[i];
    const uint32_t row0 = chain_offset[chain];
    const uint32_t level_count = chain_offset[chain + 1] - row0;
    const float q = gq[j];
    uint32_t finest;
    if (level_count <= kLanes) {
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
      finest = finestBySearch(q, row_inv_w + row0, level_count);
    }
    gfinest[j] = static_cast<uint8_t>(finest);
    grow0[j] = row0;
    const int8_t prev = prev_level[i];
    gprev[j] = prev;
    glevels[j] = static_cast<uint8_t>(level_count);
    level_of[i] = prev;  // a settled slot's level (the others' are written again)
  }
}

// What writeOutSlots reads: the slot columns, the hulls' level bytes and the row tables.
struct WriteOutInput {
  const uint8_t* chosen;     // per slot: hull step, or kSettledAtPrev / kSettledAtBase
  const uint8_t* hull;       // hull_stride level bytes per slot
  size_t hull_stride;
  const uint32_t* slot_object;
  const float* a;
  const float* b;
  const float* q;
  const float* px;
  const uint32_t* row0;
  const int8_t* prev;
  const float* row_cost;
  const float* row_inv_w;
  const uint32_t* tri;
  const uint32_t* vert;
  const uint32_t* lines;
  float h1;
  // null: the integer features gathered per slot; else `rows` counters, one per level-table row:
  // the drawn slots per row are counted and the features summed per row at the end
  uint32_t* row_drawn;
  size_t rows;
};

// The frame's sums over the slots in slot order (addSlot's terms).
struct SlotSums {
  double predicted, benefit, pixels;
  uint64_t tri, vert, lines;
  uint32_t dropped, drawn;
};

// The budget write-out when the settling pass did not sum the settled slots (a cold frame, a miss
// of the predicted bracket, more rows than slots, the ½ guarantee's fallback): each slot's level
// into level_of and its share of the frame's sums, in slot order, with the same operations as
// addSlot in SelectionJob::run (so the same bits). A function of
// its own with every pointer and sum in a local: inside run() the loop ran out of registers and kept
// the integer sums and the column pointers on the stack (a load or a read-modify-write each per slot).
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

struct PassResult {
  double cost = 0.0;        // total object cost with every upgrade of ratio > lambda taken
  size_t below = 0;         // upgrades with ratio in (lo, lambda]
  size_t above = 0;         // upgrades with ratio in (lambda, hi]
};

}  // namespace

class SelectorContext {
 public:
  // configuration
  Allocator allocator;
  size_t max_objects = 0;
  size_t hull_stride = 0;  // max levels per chain + 1 (the not-drawn point)
  size_t bracket_capacity = 0;
  size_t total_bytes = 0;
  size_t per_object_bytes = 0;
  bool use_avx2 = false;   // the AVX2 code paths (the CPU has it and the config allows it)

  // persistent per-object state
  int8_t* prev_level = nullptr;  // level chosen last frame, -1 = not drawn

  // per-frame scratch, indexed by slot (objects in the frustum, in object order)
  uint32_t* slot_object = nullptr;
  float* slot_a = nullptr;       // level-independent cost: per_object + per_pixel * pixels
  float* slot_b = nullptr;       // level-independent benefit: pixels * importance * focus * motion * visibility
  float* slot_q = nullptr;       // X * R / scale: the coarsest accurate-enough cell width
  float* slot_px = nullptr;      // projected pixels
  uint8_t* slot_finest = nullptr;  // finest candidate level (the coarsest accurate-enough one)
  uint8_t* slot_must = nullptr;
  uint32_t* slot_row0 = nullptr;   // first level-table row of the slot's chain
  int8_t* slot_prev = nullptr;     // last frame's level of the slot's object
  uint8_t* slot_levels = nullptr;  // level count of the slot's chain
  uint16_t* slot_key = nullptr;    // settleKey (the settling pass's eligibility, lane masks and candidate)
  // per level-table row, this frame: geometry cost (triangles, vertices, lines) and 1 / cell width
  float* row_cost = nullptr;
  float* row_inv_w = nullptr;
  uint32_t* row_drawn = nullptr;  // per row: the drawn slots at it (the budget write-out's counters)
  size_t max_rows = 0;
  uint8_t* hull = nullptr;       // hull_stride bytes per slot: levels along the hull, kNotDrawn = -1
  uint8_t* hull_count = nullptr;
  uint8_t* chosen = nullptr;     // index into the slot's hull
  HeapEntry* heap = nullptr;
  BracketEntry* bracket = nullptr;
  BracketEntry* bracket_scratch = nullptr;  // as many: the radix sort's other buffer
  // price histogram of this frame's hull segments (Lagrangian form): per bucket of the ratio's float
  // bits, the summed cost step (8 bytes) and the segment count (4 bytes); kHistBuckets + 2 entries,
  // the first and last for ratios below and above the window
  double* hist_cost = nullptr;
  uint32_t* hist_count = nullptr;

  // cost model and calibration
  CostCalibrator calibrator;
  CostFeatures ring_features[kRingSize];
  uint64_t ring_frame[kRingSize];
  std::atomic<uint64_t> mailbox{0};  // (frame + 1) << 32 | float bits of the time; 0 = empty

  // history
  uint64_t frame = 0;
  double last_lambda = 0.0;
  bool has_history = false;
  bool last_was_budget = false;
  double predict_width = 0.0;  // relative half-width of the predicted bracket around last frame's price
  size_t last_slot_count = 0;

  // per-frame constants, valid during run() and until the next one
  float h1 = 1.0f;

  uint32_t firstRow(size_t slot) const { return slot_row0[slot]; }

  // cost of drawing slot `s` at level `l` (-1: not drawn)
  float pointCost(size_t s, int l) const {
    if (l < 0) return 0.0f;
    return slot_a[s] + row_cost[slot_row0[s] + static_cast<uint32_t>(l)];
  }
  // min(1, X R / (w scale)): 1 for every accurate-enough level (and for w = 0, where 1/w = inf)
  float accuracy(size_t s, int l) const {
    return std::min(1.0f, slot_q[s] * row_inv_w[slot_row0[s] + static_cast<uint32_t>(l)]);
  }
  float pointBenefit(size_t s, int l) const {
    if (l < 0) return 0.0f;
    float acc = accuracy(s, l);
    if (l == slot_prev[s]) acc *= h1;
    return slot_b[s] * acc;
  }
  int hullLevel(size_t s, size_t k) const {
    const uint8_t v = hull[s * hull_stride + k];
    return v == kNotDrawn ? -1 : static_cast<int>(v);
  }
  static float ratio(float c0, float b0, float c1, float b1) { return (b1 - b0) / (c1 - c0); }

  PassResult pass(size_t slot_count, double lambda, double lo, double hi) const;
  void greedy(size_t slot_count, double total, double cap, bool stop, int64_t* split_slot, uint32_t* split_step) const;
};

namespace {

size_t alignUp(size_t v, size_t a) { return (v + a - 1) / a * a; }

}  // namespace

Allocator defaultAllocator() {
  Allocator a;
  a.allocate = mallocAllocate;
  a.free = mallocFree;
  return a;
}

SelectorContext* createSelectorContext(const SelectorConfig& config) {
  if (config.max_object_count == 0 || config.max_object_count > 0x7fffffffu) return nullptr;
  if (config.max_levels_per_chain < 1 || config.max_levels_per_chain > 64) return nullptr;
  if (config.bracket_capacity < 1 || config.max_level_rows < 1 || config.max_level_rows > (size_t(1) << 31)) return nullptr;
  if (!(config.calibration.forgetting > 0.0 && config.calibration.forgetting <= 1.0) ||
      !(config.calibration.prior_weight > 0.0))
    return nullptr;
  Allocator alloc = config.allocator;
  if (!alloc.allocate || !alloc.free) alloc = defaultAllocator();

  const size_t n = config.max_object_count, stride = config.max_levels_per_chain + 1;
  // one block: the context, then each array aligned to 16 bytes
  size_t offset = alignUp(sizeof(SelectorContext), 16);
  struct Part { size_t bytes; size_t at; };
  const size_t rows = config.max_level_rows;
  // per-object parts first (they define the bytes per object), then the fixed ones
  constexpr size_t kPerObjectParts = 16;
  Part parts[23] = {
      {n * sizeof(int8_t), 0},     {n * sizeof(uint32_t), 0}, {n * sizeof(float), 0},
      {n * sizeof(float), 0},      {n * sizeof(float), 0},    {n * sizeof(float), 0},
      {n, 0},                      {n, 0},                    {n * stride, 0},
      {n, 0},                      {n, 0},                    {n * sizeof(HeapEntry), 0},
      {n * sizeof(uint32_t), 0},   {n, 0},                    {n, 0},
      {n * sizeof(uint16_t), 0},
      {config.bracket_capacity * sizeof(BracketEntry), 0}, {(rows + kLanes) * sizeof(float), 0},
      {(rows + kLanes) * sizeof(float), 0},
      {kHistMaxBuckets * sizeof(double), 0}, {kHistMaxBuckets * sizeof(uint32_t), 0},
      {config.bracket_capacity * sizeof(BracketEntry), 0}, {rows * sizeof(uint32_t), 0}};
  size_t per_object = 0;
  for (size_t i = 0; i < 23; ++i) {
    parts[i].at = offset;
    offset = alignUp(offset + parts[i].bytes, 16);
    if (i < kPerObjectParts) per_object += parts[i].bytes;
  }
  void* block = alloc.allocate(alloc.user, offset, 64);
  if (!block) return nullptr;
  auto* c = new (block) SelectorContext();
  auto* base = static_cast<unsigned char*>(block);
  c->allocator = alloc;
  c->max_objects = n;
  c->hull_stride = stride;
  c->bracket_capacity = config.bracket_capacity;
  c->total_bytes = offset;
  c->per_object_bytes = per_object;
  c->prev_level = reinterpret_cast<int8_t*>(base + parts[0].at);
  c->slot_object = reinterpret_cast<uint32_t*>(base + parts[1].at);
  c->slot_a = reinterpret_cast<float*>(base + parts[2].at);
  c->slot_b = reinterpret_cast<float*>(base + parts[3].at);
  c->slot_q = reinterpret_cast<float*>(base + parts[4].at);
  c->slot_px = reinterpret_cast<float*>(base + parts[5].at);
  c->slot_finest = base + parts[6].at;
  c->slot_must = base + parts[7].at;
  c->hull = base + parts[8].at;
  c->hull_count = base + parts[9].at;
  c->chosen = base + parts[10].at;
  c->heap = reinterpret_cast<HeapEntry*>(base + parts[11].at);
  c->slot_row0 = reinterpret_cast<uint32_t*>(base + parts[12].at);
  c->slot_prev = reinterpret_cast<int8_t*>(base + parts[13].at);
  c->slot_levels = base + parts[14].at;
  c->slot_key = reinterpret_cast<uint16_t*>(base + parts[15].at);
  c->bracket = reinterpret_cast<BracketEntry*>(base + parts[16].at);
  c->row_cost = reinterpret_cast<float*>(base + parts[17].at);
  c->row_inv_w = reinterpret_cast<float*>(base + parts[18].at);
  c->hist_cost = reinterpret_cast<double*>(base + parts[19].at);
  c->hist_count = reinterpret_cast<uint32_t*>(base + parts[20].at);
  c->bracket_scratch = reinterpret_cast<BracketEntry*>(base + parts[21].at);
  c->row_drawn = reinterpret_cast<uint32_t*>(base + parts[22].at);
  c->max_rows = rows;
  c->use_avx2 = !config.sse2_only && cpuHasAvx2();
  c->calibrator = CostCalibrator(config.initial_cost, config.calibration);
  for (size_t i = 0; i < kRingSize; ++i) c->ring_frame[i] = ~uint64_t(0);
  resetSelectorHistory(c);
  return c;
}

void destroySelectorContext(SelectorContext* c) {
  if (!c) return;
  const Allocator alloc = c->allocator;
  c->~SelectorContext();
  alloc.free(alloc.user, c);
}

void resetSelectorHistory(SelectorContext* c) {
  if (!c) return;
  std::memset(c->prev_level, 0xFF, c->max_objects);  // all -1
  c->last_lambda = 0.0;
  c->predict_width = kPredictWidthStart;
  c->has_history = false;
  c->last_was_budget = false;
  c->last_slot_count = 0;
}

size_t selectorMemoryBytes(const SelectorContext* c) { return c ? c->total_bytes : 0; }
double selectorBytesPerObject(const SelectorContext* c) {
  return c ? static_cast<double>(c->per_object_bytes) / static_cast<double>(c->max_objects) : 0.0;
}

CostCoefficients selectorCostModel(const SelectorContext* c) { return c ? c->calibrator.coefficients() : CostCoefficients(); }
void setSelectorCostModel(SelectorContext* c, const CostCoefficients& k) {
  if (c) c->calibrator.reset(k);
}

void reportFrameTime(SelectorContext* c, uint64_t frame, float measured_ms) {
  if (!c) return;
  uint32_t bits;
  std::memcpy(&bits, &measured_ms, sizeof(bits));
  const uint64_t word = (((frame + 1) & 0xffffffffu) << 32) | bits;
  c->mailbox.store(word, std::memory_order_release);
}

bool selectorLastPoint(const SelectorContext* c, size_t object, int level, double* cost_ms, double* benefit) {
  if (!c || !c->last_was_budget || object >= c->max_objects) return false;
  // slots are in object order: binary search
  const uint32_t* first = c->slot_object;
  const uint32_t* last = c->slot_object + c->last_slot_count;
  const uint32_t* it = std::lower_bound(first, last, static_cast<uint32_t>(object));
  if (it == last || *it != object) return false;
  const size_t s = static_cast<size_t>(it - first);
  if (level < -1 || level >= static_cast<int>(c->slot_levels[s])) return false;
  *cost_ms = c->pointCost(s, level);
  *benefit = c->pointBenefit(s, level);
  return true;
}

bool SelectionJob::validate() const {
  if (!context || !camera || !cameraValid(*camera)) return false;
  const size_t n = centers.count;
  if (n > context->max_objects) return false;
  if (levels.cell_width.count > context->max_rows) return false;
  if (radii.count != n || max_scales.count != n || chains.count != n || levels_out.count != n) return false;
  if ((n > 0 && (!centers.data || !radii.data || !max_scales.data || !chains.data || !levels_out.data))) return false;
  auto optional = [n](size_t count, const void* data) { return count == 0 || (count == n && data); };
  if (!optional(importance.count, importance.data) || !optional(must_draw.count, must_draw.data) ||
      !optional(visible_fraction.count, visible_fraction.data) || !optional(focus.count, focus.data) ||
      !optional(motion.count, motion.data) || !optional(cost_ms_out.count, cost_ms_out.data))
    return false;
  if (!(params.pixels_per_cell > 0.0f) || !std::isfinite(params.pixels_per_cell)) return false;
  if (!(params.hysteresis >= 0.0f) || !std::isfinite(params.hysteresis)) return false;
  if (params.mode == SelectionMode::kBudget && !(params.budget_ms > 0.0f)) return false;
  // level table
  const size_t rows = levels.cell_width.count;
  if (levels.chain_level_offset.count < 1 || !levels.chain_level_offset.data) return false;
  if (levels.triangle_count.count != rows || levels.vertex_count.count != rows || levels.line_point_count.count != rows)
    return false;
  if (rows > 0 && (!levels.cell_width.data || !levels.triangle_count.data || !levels.vertex_count.data ||
                   !levels.line_point_count.data))
    return false;
  const size_t chain_count = levels.chainCount();
  if (levels.chain_level_offset[0] != 0 || levels.chain_level_offset[chain_count] != rows) return false;
  for (size_t c = 0; c < chain_count; ++c) {
    const uint32_t b = levels.chain_level_offset[c], e = levels.chain_level_offset[c + 1];
    if (e < b || e - b > context->hull_stride - 1) return false;
    for (uint32_t r = b; r < e; ++r) {
      const float w = levels.cell_width[r];
      if (!(w >= 0.0f) || !std::isfinite(w)) return false;
      if (r > b && w < levels.cell_width[r - 1]) return false;
    }
  }
  // no early exit: an OR over the whole column vectorises (the valid case reads it all anyway)
  if (n > 0 && chain_count == 0) return false;
  const uint32_t last_chain = static_cast<uint32_t>(chain_count - 1);
  return (context->use_avx2 ? chainsAboveAvx2 : chainsAboveSse2)(chains.data, n, last_chain) == 0;
}

PassResult SelectorContext::pass(size_t slot_count, double lambda, double lo, double hi) const {
  // pointCost / pointBenefit spelled out over locals, and the sums in locals: the compiler keeps
  // them in registers instead of reloading the context's arrays for every hull point
  const uint8_t* const hull_levels = hull;
  const uint8_t* const counts = hull_count;
  const float* const sa = slot_a;
  const float* const sb = slot_b;
  const float* const sq = slot_q;
  const float* const rc = row_cost;
  const float* const riw = row_inv_w;
  const uint32_t* const r0 = slot_row0;
  const int8_t* const sp = slot_prev;
  const float hh = h1;
  const size_t stride = hull_stride;
  double cost = 0.0;
  size_t above = 0, below = 0;
  for (size_t s = 0; s < slot_count; ++s) {
    const size_t n = counts[s];
    const uint8_t* const h = hull_levels + s * stride;
    const float a = sa[s], b = sb[s], q = sq[s];
    const uint32_t row0 = r0[s];
    const int prev = sp[s];
    auto cost_of = [&](int l) { return l < 0 ? 0.0f : a + rc[row0 + static_cast<uint32_t>(l)]; };
    auto benefit_of = [&](int l) {
      if (l < 0) return 0.0f;
      float acc = std::min(1.0f, q * riw[row0 + static_cast<uint32_t>(l)]);
      if (l == prev) acc *= hh;
      return b * acc;
    };
    size_t k = 0;
    int l0 = h[0] == kNotDrawn ? -1 : static_cast<int>(h[0]);
    float c0 = cost_of(l0), b0 = benefit_of(l0);
    double chosen_cost = c0;
    bool taking = true;
    while (k + 1 < n) {
      const int l1 = h[k + 1] == kNotDrawn ? -1 : static_cast<int>(h[k + 1]);
      const float c1 = cost_of(l1), b1 = benefit_of(l1);
      const double r = ratio(c0, b0, c1, b1);
      if (r <= lo) break;
      if (taking && r > lambda) {
        chosen_cost = c1;
        if (r <= hi) ++above;
      } else {
        taking = false;
        ++below;
      }
      ++k;
      c0 = c1;
      b0 = b1;
    }
    cost += chosen_cost;
  }
  PassResult result;
  result.cost = cost;
  result.above = above;
  result.below = below;
  return result;
}

void SelectorContext::greedy(size_t slot_count, double total, double cap, bool stop, int64_t* split_slot,
                             uint32_t* split_step) const {
  size_t heap_size = 0;
  for (size_t s = 0; s < slot_count; ++s) {
    chosen[s] = 0;
    if (hull_count[s] < 2) continue;
    const int l0 = hullLevel(s, 0), l1 = hullLevel(s, 1);
    heap[heap_size++] = {ratio(pointCost(s, l0), pointBenefit(s, l0), pointCost(s, l1), pointBenefit(s, l1)),
                         static_cast<uint32_t>(s)};
  }
  std::make_heap(heap, heap + heap_size, HeapLess());
  while (heap_size > 0) {
    std::pop_heap(heap, heap + heap_size, HeapLess());
    const HeapEntry e = heap[--heap_size];
    const size_t s = e.slot, k = chosen[s];
    const int l0 = hullLevel(s, k), l1 = hullLevel(s, k + 1);
    const float c0 = pointCost(s, l0), c1 = pointCost(s, l1);
    const double delta = static_cast<double>(c1) - static_cast<double>(c0);
    if (total + delta <= cap) {
      total += delta;
      chosen[s] = static_cast<uint8_t>(k + 1);
      if (k + 2 < hull_count[s]) {
        const int l2 = hullLevel(s, k + 2);
        heap[heap_size++] = {ratio(c1, pointBenefit(s, l1), pointCost(s, l2), pointBenefit(s, l2)), e.slot};
        std::push_heap(heap, heap + heap_size, HeapLess());
      }
    } else {
      if (*split_slot < 0) {
        *split_slot = static_cast<int64_t>(s);
        *split_step = static_cast<uint32_t>(k);
      }
      if (stop) return;
    }
  }
}

bool SelectionJob::run() {
  if (!validate()) return false;
  SelectorContext& ctx = *context;
  const Camera& cam = *camera;
  const size_t n = centers.count;
  const bool budget = params.mode == SelectionMode::kBudget;

  // calibration: the last reported frame time, if it belongs to a frame we still know
  const uint64_t word = ctx.mailbox.exchange(0, std::memory_order_acquire);
  if (word != 0 && params.calibrate) {
    const uint64_t tag = word >> 32;
    const uint32_t bits = static_cast<uint32_t>(word & 0xffffffffu);
    float ms;
    std::memcpy(&ms, &bits, sizeof(ms));
    const uint64_t f = tag - 1;
    const size_t slot = static_cast<size_t>(f % kRingSize);
    if ((ctx.ring_frame[slot] & 0xffffffffu) == f) ctx.calibrator.update(ctx.ring_features[slot], ms);
  }
  const CostCoefficients coef = ctx.calibrator.coefficients();
  {
    const float c_tri = static_cast<float>(coef.per_triangle_ms), c_vert = static_cast<float>(coef.per_vertex_ms),
                c_lp = static_cast<float>(coef.per_line_point_ms);
    for (size_t r = 0; r < levels.cell_width.count; ++r) {
      ctx.row_cost[r] = c_tri * static_cast<float>(levels.triangle_count[r]) +
                        c_vert * static_cast<float>(levels.vertex_count[r]) +
                        c_lp * static_cast<float>(levels.line_point_count[r]);
      const float w = levels.cell_width[r];
      ctx.row_inv_w[r] = w > 0.0f ? 1.0f / w : std::numeric_limits<float>::infinity();
    }
    // a chain's kLanes rows are read side by side, past the last row too
    for (size_t r = levels.cell_width.count; r < levels.cell_width.count + kLanes; ++r) {
      ctx.row_cost[r] = 0.0f;
      ctx.row_inv_w[r] = 0.0f;
    }
  }
  const float c_obj = static_cast<float>(coef.per_object_ms), c_px = static_cast<float>(coef.per_pixel_ms);
  ctx.h1 = 1.0f + params.hysteresis;
  const float pixel_factor = pixelSizeFactor(cam);
  const float ortho_pixel = pixelSize(cam, 0.0f);
  const bool ortho = cam.projection == Projection::kOrthographic;

  const Frustum frustum = computeFrustum(cam);
  const float viewport_px = static_cast<float>(cam.viewport_width_px) * static_cast<float>(cam.viewport_height_px);
  const float x_cells = params.pixels_per_cell;

  // Passes 1a-1c fused over blocks of kSlotBlock objects held in local columns: the frustum test,
  // the compaction of the objects in view (and with levels) into slots, and per slot the
  // level-independent terms and the finest candidate level, so that each object's inputs are read
  // once (the compaction queues the centres and radii it has loaded for the frustum test beside
  // the slots' object indices). Budget mode stores the slots' terms in the slot columns for the
  // hull passes; distance mode needs no column but the queue: it chooses the level and adds the
  // slot to the frame's sums in the same block
  // (slot order as in writeOut, so the same sums). The float terms run as plain loops over the local
  // columns that the compiler vectorises (sqrt and divisions 4 or 8 wide; the same IEEE operations
  // as one object at a time, so the same bits).
  // (locals for every array below: the byte stores would otherwise make the compiler reload the
  // pointers from the job and the context on every iteration)
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "centers are read as packed floats");
  const float* const xyz = n ? &centers[0].x : nullptr;
  const auto frustum_outside = ctx.use_avx2 ? frustumOutsideAvx2 : frustumOutsideSse2;
  const auto frustum_compact = ctx.use_avx2 ? frustumCompactAvx2 : frustumCompactSse2;
  const bool use_avx2 = ctx.use_avx2;
  const uint32_t* const chain_offset = levels.chain_level_offset.data;
  const uint32_t* const chain_of = chains.data;
  int8_t* const level_of = levels_out.data;
  uint32_t* const slot_object = ctx.slot_object;
  double mandatory = coef.per_frame_ms;
  uint32_t prev_dropped = 0;  // budget mode: slots last frame "not drawn" with a benefit > 0 (settleKeys)
  const float* const radius_of = radii.data;
  const float* const scale_of = max_scales.data;
  const float* const row_inv_w = ctx.row_inv_w;
  int8_t* const prev_level = ctx.prev_level;
  float* const slot_a = ctx.slot_a;
  float* const slot_b = ctx.slot_b;
  float* const slot_q = ctx.slot_q;
  float* const slot_px = ctx.slot_px;
  uint8_t* const slot_finest = ctx.slot_finest;
  uint8_t* const slot_must = ctx.slot_must;
  uint32_t* const slot_row0 = ctx.slot_row0;
  int8_t* const slot_prev = ctx.slot_prev;
  uint8_t* const slot_levels = ctx.slot_levels;
  uint16_t* const slot_key = ctx.slot_key;
  // the spheres in view queue up in slot order: object index, centre and radius (these three in
  // the columns that pass 1c overwrites for the same slots once it has read them)
  float* const queue_x = slot_a;
  float* const queue_y = slot_b;
  float* const queue_z = slot_q;
  float* const queue_r = slot_px;
  const glm::vec3 eye = cam.eye;
  const float* const importance_of = importance.count ? importance.data : nullptr;
  const float* const focus_of = focus.count ? focus.data : nullptr;
  const float* const motion_of = motion.count ? motion.data : nullptr;
  const float* const visible_of = visible_fraction.count ? visible_fraction.data : nullptr;
  const uint8_t* const must_of = must_draw.count ? must_draw.data : nullptr;
  float* const cost_out = cost_ms_out.count ? cost_ms_out.data : nullptr;
  const float near_plane = cam.near_plane;
  const float* const row_cost = ctx.row_cost;
  const uint32_t* const tri = levels.triangle_count.data;
  const uint32_t* const vert = levels.vertex_count.data;
  const uint32_t* const lines = levels.line_point_count.data;
  const float h_mult[2] = {1.0f, ctx.h1};
  const float h1 = ctx.h1;

  // the frame's sums (writeOut in budget mode, the fused blocks in distance mode)
  CostFeatures f;
  // the integer features summed exactly in 64 bits (n < 2^31 terms below 2^32): the same value as
  // the double sum in slot order while the total stays below 2^53 (every partial sum is then an
  // exact double); f.objects is `drawn`
  uint64_t tri_sum = 0, vert_sum = 0, line_sum = 0;
  double predicted = coef.per_frame_ms, benefit = 0.0;
  uint32_t dropped = 0, drawn = 0, switches = 0;
  // one slot's share of them at level byte `level`, without branches: in budget mode about half of
  // the slots are drawn, in no predictable order, and GCC turns selects into branches; a slot not
  // drawn reads its level-0 row and adds its terms masked to +0 (x + 0.0 == x, so the sums are the
  // same); returns the slot's cost at that level
  auto addSlot = [&](uint8_t level, float a, float b, float q, float px, uint32_t row0, int8_t prev) {
    const uint32_t keep = 0u - static_cast<uint32_t>(level != kNotDrawn);  // all ones if drawn
    dropped += (keep ^ 1u) & (b > 0.0f ? 1u : 0u);
    drawn += keep & 1u;
    const uint32_t row = row0 + (level & keep);
    // ctx.pointCost / ctx.pointBenefit at a drawn level
    const float cost = a + row_cost[row];
    const bool current = level == static_cast<uint8_t>(prev);
    const float acc = std::min(1.0f, q * row_inv_w[row]) * h_mult[current];
    predicted += maskFloat(cost, keep);
    benefit += maskFloat(b * acc, keep);
    tri_sum += tri[row] & keep;
    vert_sum += vert[row] & keep;
    line_sum += lines[row] & keep;
    f.pixels += maskFloat(px, keep);
    return cost;
  };

  constexpr size_t kSlotBlock = 64;
  alignas(32) uint8_t gout[kSlotBlock];
  alignas(32) float gx[kSlotBlock], gy[kSlotBlock], gz[kSlotBlock], gr[kSlotBlock], gs[kSlotBlock];
  alignas(32) float gi[kSlotBlock], gf[kSlotBlock], gm[kSlotBlock], gv[kSlotBlock];
  // the block's slot terms: in budget mode the slot columns themselves, in distance mode locals
  alignas(32) uint32_t lrow0[kSlotBlock];
  alignas(32) float lq[kSlotBlock], la[kSlotBlock], lb[kSlotBlock], lpx[kSlotBlock];
  alignas(32) uint8_t lfinest[kSlotBlock], llevels[kSlotBlock];
  alignas(32) int8_t lprev[kSlotBlock];
  // per slot, over the block of the m slots from s0 (m <= kSlotBlock): the terms and the finest
  // level, then in budget mode the must-draw part, in distance mode the level and the sums
  auto slotBlock = [&](size_t s0, size_t m) __attribute__((always_inline)) {
    uint32_t* const gobj = slot_object + s0;
    uint32_t* const grow0 = budget ? slot_row0 + s0 : lrow0;
    float* const gq = budget ? slot_q + s0 : lq;
    float* const ga = budget ? slot_a + s0 : la;
    float* const gb = budget ? slot_b + s0 : lb;
    float* const gpx = budget ? slot_px + s0 : lpx;
    uint8_t* const gfinest = budget ? slot_finest + s0 : lfinest;
    uint8_t* const glevels = budget ? slot_levels + s0 : llevels;
    int8_t* const gprev = budget ? slot_prev + s0 : lprev;
    // the centres and radii from the compaction's queue (in the columns of a, b, q and pixels, read
    // here before this block's terms overwrite them)
    for (size_t j = 0; j < m; ++j) {
      gx[j] = queue_x[s0 + j];
      gy[j] = queue_y[s0 + j];
      gz[j] = queue_z[s0 + j];
      gr[j] = queue_r[s0 + j];
    }
    for (size_t j = 0; j < m; ++j) gs[j] = scale_of[gobj[j]];
    // missing factors are 1 (b * 1.0f == b)
    for (size_t j = 0; j < m; ++j) gi[j] = importance_of ? importance_of[gobj[j]] : 1.0f;
    for (size_t j = 0; j < m; ++j) gf[j] = focus_of ? focus_of[gobj[j]] : 1.0f;
    for (size_t j = 0; j < m; ++j) gm[j] = motion_of ? motion_of[gobj[j]] : 1.0f;
    for (size_t j = 0; j < m; ++j) gv[j] = visible_of ? visible_of[gobj[j]] : 1.0f;
    // gx becomes the pixel size R
    if (ortho) {
      for (size_t j = 0; j < m; ++j) gx[j] = ortho_pixel;
    } else {
      for (size_t j = 0; j < m; ++j) {
        const float dx = gx[j] - eye.x, dy = gy[j] - eye.y, dz = gz[j] - eye.z;
        const float dist = std::sqrt(dx * dx + dy * dy + dz * dz);
        gx[j] = std::max(dist - gr[j], near_plane) * pixel_factor;  // = pixelSize(cam, dist - r)
      }
    }
    for (size_t j = 0; j < m; ++j) {
      const float pixel = gx[j];
      const float r_px = gr[j] / pixel;
      const float px = std::min(kPi * r_px * r_px, viewport_px);
      gq[j] = x_cells * pixel / gs[j];
      ga[j] = c_obj + c_px * px;
      gb[j] = (((px * gi[j]) * gf[j]) * gm[j]) * gv[j];
      gpx[j] = px;
    }
    if (use_avx2) {
      chainTermsAvx2(gobj, gq, m, chain_of, chain_offset, row_inv_w, prev_level, gfinest, grow0, gprev, glevels,
                     level_of);
    } else {
      for (size_t j = 0; j < m; ++j) {
        const size_t i = gobj[j];
        const uint32_t chain = chain_of[i];
        const uint32_t row0 = chain_offset[chain];
        const uint32_t level_count = chain_offset[chain + 1] - row0;
        const float q = gq[j];
        // the coarsest level of accuracy 1 (level 0, w = 0, always is): widths do not fall with the
        // level, so the accurate-enough levels 1.. are a prefix (q * (1 / w) >= 1 falls with w, NaN
        // included) and its length is their count: for a chain of up to kLanes levels, counted over
        // the chain's lanes at once without a branch (the binary search it replaces had a loop of
        // varying length per object, which mispredicted)
        uint32_t finest;
        if (level_count <= kLanes) {
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
    if (budget && use_avx2)
      prev_dropped += settleKeysAvx2(ga, gb, glevels, gfinest, gprev, m, slot_key + s0);
    else if (budget)
      prev_dropped += settleKeys(ga, gb, glevels, gfinest, gprev, m, slot_key + s0);
    if (budget && !must_of) {
      std::memset(slot_must + s0, 0, m);
    } else if (budget) {
      for (size_t j = 0; j < m; ++j) {
        const size_t s = s0 + j;
        const bool must = must_of[gobj[j]] != 0;
        slot_must[s] = must ? 1 : 0;
        if (must) {
          slot_key[s] = kSettleIneligible;
          float cheapest = std::numeric_limits<float>::infinity();
          for (int l = gfinest[j]; l < static_cast<int>(glevels[j]); ++l)
            cheapest = std::min(cheapest, ga[j] + row_cost[grow0[j] + static_cast<uint32_t>(l)]);  // ctx.pointCost
          mandatory += cheapest;
        }
      }
    } else {
      for (size_t j = 0; j < m; ++j) {
        const uint32_t row0 = grow0[j];
        int level = gfinest[j];
        const int p = gprev[j];
        // hysteresis: a coarser current level stays while it is within the margin (ctx.accuracy)
        if (p > level && p < static_cast<int>(glevels[j]) &&
            std::min(1.0f, gq[j] * row_inv_w[row0 + static_cast<uint32_t>(p)]) * h1 >= 1.0f)
          level = p;
        const float cost = addSlot(static_cast<uint8_t>(level), ga[j], gb[j], gq[j], gpx[j], row0, gprev[j]);
        level_of[gobj[j]] = static_cast<int8_t>(level);
        if (cost_out) cost_out[gobj[j]] = cost;
      }
    }
  };
  // chains without levels (their objects are never slots): the compaction reads the chain table
  // per object only when there are any
  bool any_empty_chain = false;
  for (size_t c = 0, chain_count = levels.chainCount(); c < chain_count; ++c)
    any_empty_chain |= chain_offset[c + 1] == chain_offset[c];
  // slots are compacted a block of objects at a time and handed on in full blocks of kSlotBlock
  // (loops of a constant trip count, which predict) while their objects' inputs are still in cache
  size_t slots = 0, done = 0;
  for (size_t i0 = 0; i0 < n; i0 += kSlotBlock) {
    const size_t mo = std::min(kSlotBlock, n - i0);
    // every object's level starts at -1 (culled: stays) and the slots' levels are written later
    if (any_empty_chain) {
      frustum_outside(frustum, xyz + 3 * i0, radius_of + i0, mo, gout);
      // branch-free compaction of the block's objects in view and with levels
      for (size_t j = 0; j < mo; ++j) {
        const uint32_t chain = chain_of[i0 + j];
        const uint32_t out = static_cast<uint32_t>(gout[j]) | static_cast<uint32_t>(chain_offset[chain + 1] == chain_offset[chain]);
        level_of[i0 + j] = -1;
        slot_object[slots] = static_cast<uint32_t>(i0 + j);
        queue_x[slots] = xyz[3 * (i0 + j)];
        queue_y[slots] = xyz[3 * (i0 + j) + 1];
        queue_z[slots] = xyz[3 * (i0 + j) + 2];
        queue_r[slots] = radius_of[i0 + j];
        slots += 1u - out;
      }
    } else {
      if (mo == kSlotBlock) {
        // a full block by four 16-byte stores (the byte loop was about 56 instructions a block)
        const uint64_t ones[2] = {~uint64_t(0), ~uint64_t(0)};
        for (size_t k = 0; k < kSlotBlock; k += 16) std::memcpy(level_of + i0 + k, ones, sizeof(ones));
      } else {
        for (size_t j = 0; j < mo; ++j) level_of[i0 + j] = -1;
      }
      const SphereQueue queue{slot_object + slots, queue_x + slots, queue_y + slots, queue_z + slots, queue_r + slots};
      slots += frustum_compact(frustum, xyz + 3 * i0, radius_of + i0, mo, static_cast<uint32_t>(i0), queue);
    }
    if (cost_out && !budget)
      for (size_t j = 0; j < mo; ++j) cost_out[i0 + j] = 0.0f;
    if (slots - done >= kSlotBlock) {
      slotBlock(done, kSlotBlock);
      done += kSlotBlock;
    }
  }
  for (; done < slots; done += kSlotBlock) slotBlock(done, std::min(kSlotBlock, slots - done));
  const uint32_t culled = static_cast<uint32_t>(n - slots);

  SelectionStats st;
  st.frame = ctx.frame;
  st.culled_count = culled;
  st.mandatory_ms = budget ? mandatory : 0.0;
  const double cap = static_cast<double>(params.budget_ms);
  // the last settling pass's fused write-out (HullSums)
  bool fused = false;
  size_t unsettled_count = 0;
  SettleSums settled_sums{};
  int64_t half_slot = -1;  // the 1/2 guarantee's alternative: this slot at hull step half_step,
  uint32_t half_step = 0;  // every other slot at its base, with this benefit
  double half_alt_benefit = 0.0;

  if (budget) {
    // pass 2: each slot's upper convex hull over the points that fit alone
    const double avail = cap - mandatory;
    const double obj_cap = cap - coef.per_frame_ms;  // objects' share of the budget
    const bool use_greedy = params.algorithm == BudgetAlgorithm::kGreedy || !params.stop_at_first_non_fitting;
    // Lagrangian form: every hull segment's ratio goes into a histogram over its float bits (a
    // positive float's bits are monotone in its value), bucket = exponent and top mantissa bits, over
    // a window of kHistBinades binades around last frame's price (or a sampled guess). A hull's ratios
    // fall strictly, so at any price an object takes exactly the segments above it and C(lambda) at a
    // bucket edge is a suffix sum of the histogram: the bucket holding the budget's edge is found
    // without a pass over the objects.
    const int sub_bits = std::min(kHistMaxSubBits, std::max(4, static_cast<int>(std::log2(static_cast<double>(slots + 1))) - 5));
    const int key_shift = 23 - sub_bits;
    const int64_t inner_buckets = int64_t(kHistBinades) << sub_bits;  // buckets 1..inner; 0 below, inner + 1 above
    int64_t key_base = 0;
    double* const hist_cost = ctx.hist_cost;
    uint32_t* const hist_count = ctx.hist_count;
    if (!use_greedy) {
      double centre = ctx.has_history && ctx.last_lambda > 0.0 ? ctx.last_lambda : 0.0;
      if (!(centre > 0.0) && slots > 0) {
        // benefit per ms of the finest candidates of about 256 sampled slots
        double b = 0.0, c = 0.0;
        const size_t step = std::max<size_t>(1, slots / 256);
        for (size_t s = 0; s < slots; s += step) {
          b += slot_b[s];
          c += static_cast<double>(slot_a[s]) + ctx.row_cost[slot_row0[s] + slot_finest[s]];
        }
        centre = c > 0.0 && b > 0.0 ? b / c : 1.0;
      }
      const float centre_f = static_cast<float>(std::min(centre, 1e30));
      uint32_t centre_bits;
      std::memcpy(&centre_bits, &centre_f, sizeof(centre_bits));
      const int e0 = std::min(255 - kHistBinades, std::max(1, static_cast<int>((centre_bits >> 23) & 0xff) - kHistBinades / 2));
      key_base = int64_t(e0) << sub_bits;
    }
    struct Pt { float c, b; int l; };
    double top_cost = 0.0;   // every upgrade taken: what the pass at lambda = 0 would sum
    double base_total = 0.0; // no upgrade taken
    double base_benefit = 0.0;  // benefit with no upgrade taken (the 1/2 guarantee's alternative)
    size_t segments = 0;
    uint8_t* const hull = ctx.hull;
    uint8_t* const hull_count = ctx.hull_count;
    const size_t hull_stride = ctx.hull_stride;
    // Incremental case (Lagrangian, last frame's price known): first settleSlots* finds the objects
    // whose choice cannot change inside a predicted bracket (plo, phi] around last frame's price
    // (on a smooth camera about 97 % of them); only the others get their hull, take their upgrades
    // above phi and put those inside into the bracket array. When the budget's edge falls inside
    // (checked exactly below), no other pass over the objects is needed; otherwise every hull is
    // built (with the price histogram) and the search runs as in the cold case.
    const bool predict = !use_greedy && ctx.has_history && ctx.last_lambda > 0.0 && std::isfinite(ctx.last_lambda);
    double plo = predict ? ctx.last_lambda / (1.0 + ctx.predict_width) : 0.0;
    double phi = predict ? ctx.last_lambda * (1.0 + ctx.predict_width) : 0.0;
    size_t pcount = 0, pwanted = 0;
    bool poverflow = false;
    double ptotal = 0.0;
    uint8_t* const chosen_step = ctx.chosen;
    BracketEntry* const pbracket = ctx.bracket;
    const size_t pcapacity = ctx.bracket_capacity;
    // every row's geometry cost >= 0 (not NaN), which settleSlots* relies on
    bool rows_nonnegative = true;
    for (size_t r = 0; r < levels.cell_width.count; ++r) rows_nonnegative &= row_cost[r] >= 0.0f;
    // the sums in locals (shadowing the outer ones until the end): through the captured references
    // every += would be a store and a reload
    auto buildHulls = [&](bool settle) {
      // local copies: the byte stores below may alias anything reached through the closure, so
      // captured values would be reloaded after each of them
      const auto slot_levels_ = slot_levels;
      const auto slot_key_ = slot_key;
      const auto slot_a_ = slot_a;
      const auto slot_b_ = slot_b;
      const auto slot_q_ = slot_q;
      const auto slot_row0_ = slot_row0;
      const auto slot_prev_ = slot_prev;
      const auto slot_must_ = slot_must;
      const auto slot_finest_ = slot_finest;
      const auto row_cost_ = row_cost;
      const auto row_inv_w_ = row_inv_w;
      const auto hull_ = hull;
      const auto hull_count_ = hull_count;
      const auto hull_stride_ = hull_stride;
      const auto avail_ = avail;
      const auto hist_cost_ = hist_cost;
      const auto hist_count_ = hist_count;
      const auto key_shift_ = key_shift;
      const auto key_base_ = key_base;
      const auto inner_buckets_ = inner_buckets;
      const auto use_greedy_ = use_greedy;
      const auto phi_ = phi;
      const auto plo_ = plo;
      const auto pbracket_ = pbracket;
      const auto pcapacity_ = pcapacity;
      const auto chosen_step_ = chosen_step;
      const float h_mult_[2] = {h_mult[0], h_mult[1]};
      const auto h1_ = h1;
      const auto rows_nonnegative_ = rows_nonnegative;
      const size_t slots_ = slots;
      const float* const slot_px_ = slot_px;
      uint32_t* const row_drawn_ = ctx.row_drawn;
      const size_t rows_ = levels.cell_width.count;
      uint32_t* const unsettled_list_ = reinterpret_cast<uint32_t*>(ctx.heap);
      Pt pts[65];
      double top_cost = 0.0, base_total = 0.0, base_benefit = 0.0, ptotal = 0.0;
      size_t segments = 0, pcount = 0, pwanted = 0;
      bool poverflow = false;
      if (!settle && !use_greedy_) {
        std::memset(hist_cost_, 0, static_cast<size_t>(inner_buckets_ + 2) * sizeof(double));
        std::memset(hist_count_, 0, static_cast<size_t>(inner_buckets_ + 2) * sizeof(uint32_t));
      }
      // settled slots first, then the hulls of the others (all slots when not settling)
      uint32_t* const unsettled = unsettled_list_;  // the heap is free until the greedy
      size_t build_count = slots_;
      SettleSums settled{};
      bool fused = false;
      if (settle) {
        const SettleInput in{slot_key_, slot_row0_, slot_a_, slot_b_, slot_q_,
                             row_cost_, row_inv_w_, h1_, 1.0f, floatAtMost(avail_),
                             static_cast<float>(plo_ / (1.0 + kSettleMargin)),
                             static_cast<float>(phi_ * (1.0 + kSettleMargin)),
                             slot_px_, row_drawn_, rows_};
        if (rows_nonnegative_) {
          // the write-out's sums fused in when it counts per row (fewer rows than slots)
          fused = rows_ <= slots_;
          build_count = (ctx.use_avx2 ? (fused ? settleSlotsAvx2<true> : settleSlotsAvx2<false>)
                                      : (fused ? settleSlotsSse2<true> : settleSlotsSse2<false>))(
              in, slots_, chosen_step_, unsettled, &settled);
          ptotal = settled.cost;
        } else {
          for (size_t s = 0; s < slots_; ++s) unsettled[s] = static_cast<uint32_t>(s);
        }
      }
      for (size_t u = 0; u < build_count; ++u) {
        const size_t s = settle ? unsettled[u] : u;
        const int level_count = static_cast<int>(slot_levels_[s]);
        // pointCost / pointBenefit with the slot's terms in registers
        const float sa = slot_a_[s], sb = slot_b_[s], sq = slot_q_[s];
        const uint32_t row0 = slot_row0_[s];
        const int prev = slot_prev_[s];
        uint8_t* h = hull_ + s * hull_stride_;
        Pt hp[65];
        float hr[65];  // hr[k] = ratio(hp[k - 1], hp[k]), kept so each test divides once
        size_t hn = 0;
        // one step of the upper hull_ over points in sorted order (Andrew's monotone chain)
        auto addPoint = [&](const Pt& p) {
          if (hn > 0 && !(p.b > hp[hn - 1].b)) return;
          float r_new = 0.0f;
          while (hn >= 1) {
            r_new = SelectorContext::ratio(hp[hn - 1].c, hp[hn - 1].b, p.c, p.b);
            if (hn < 2 || hr[hn - 1] > r_new) break;
            --hn;
          }
          hr[hn] = r_new;
          h[hn] = static_cast<uint8_t>(p.l);  // -1 becomes kNotDrawn
          hp[hn++] = p;
        };
        auto pointAt = [&](int l) {
          const uint32_t row = row0 + static_cast<uint32_t>(l);
          // hysteresis by a table lookup, not a branch (x * 1.0f == x, so the values are the same)
          const float acc = std::min(1.0f, sq * row_inv_w_[row]) * h_mult_[l == prev];
          return Pt{sa + row_cost_[row], sb * acc, l};
        };
        const bool must = slot_must_[s] != 0;
        const int finest = slot_finest_[s];
        // common case: the points arrive (not drawn, then coarsest to finest level) in strictly rising
        // cost, which is the sorted order, and all fit alone; then the hull_ is built as they arrive
        bool general = false;
        {
          float last_c = -std::numeric_limits<float>::infinity(), base_cost = 0.0f;
          if (!must) {
            addPoint(Pt{0.0f, 0.0f, -1});
            last_c = 0.0f;
          }
          for (int l = level_count - 1; l >= finest; --l) {
            const Pt p = pointAt(l);
            if (hn == 0) base_cost = p.c;
            if (!(p.c > last_c) || static_cast<double>(p.c) - base_cost > avail_) {
              general = true;
              break;
            }
            last_c = p.c;
            addPoint(p);
          }
        }
        if (general) {
          size_t m = 0;
          if (!must) pts[m++] = {0.0f, 0.0f, -1};
          for (int l = level_count - 1; l >= finest; --l) pts[m++] = pointAt(l);
          // insertion sort: cost ascending, benefit descending, coarser level first (a total order, so
          // the sorted result does not depend on the arrival order)
          for (size_t a = 1; a < m; ++a) {
            const Pt p = pts[a];
            size_t j = a;
            auto before = [](const Pt& x, const Pt& y) {
              if (x.c != y.c) return x.c < y.c;
              if (x.b != y.b) return x.b > y.b;
              return x.l > y.l;
            };
            while (j > 0 && before(p, pts[j - 1])) {
              pts[j] = pts[j - 1];
              --j;
            }
            pts[j] = p;
          }
          const float base_cost = pts[0].c;
          hn = 0;
          for (size_t a = 0; a < m; ++a) {
            if (hn > 0 && static_cast<double>(pts[a].c) - base_cost > avail_) break;  // cannot fit even alone
            addPoint(pts[a]);
          }
        }
        hull_count_[s] = static_cast<uint8_t>(hn);
        top_cost += hp[hn - 1].c;
        base_total += hp[0].c;
        base_benefit += hp[0].b;
        segments += hn - 1;
        if (settle) {
          uint32_t above = 0, inside = 0;  // segments with ratio > phi_, > plo_ (a prefix: ratios fall)
          for (size_t k = 1; k < hn; ++k) {
            above += static_cast<double>(hr[k]) > phi_ ? 1u : 0u;
            inside += static_cast<double>(hr[k]) > plo_ ? 1u : 0u;
          }
          // what the collection below does at (plo_, phi_], on the same float ratios
          chosen_step_[s] = static_cast<uint8_t>(above);
          ptotal += hp[above].c;
          pwanted += inside - above;
          for (size_t k = above + 1; k <= inside; ++k) {
            if (pcount == pcapacity_) {
              poverflow = true;
              break;
            }
            pbracket_[pcount++] = {hr[k], static_cast<uint32_t>(s), static_cast<uint32_t>(k - 1)};
          }
        } else if (!use_greedy_) {
          for (size_t k = 1; k < hn; ++k) {
            uint32_t bits;
            std::memcpy(&bits, &hr[k], sizeof(bits));
            // negative or NaN ratios (bad inputs) land above the window; the collection checks its bound
            int64_t key = static_cast<int64_t>(bits >> key_shift_) - key_base_ + 1;
            key = key < 0 ? 0 : (key > inner_buckets_ + 1 ? inner_buckets_ + 1 : key);
            hist_cost_[key] += static_cast<double>(hp[k].c) - static_cast<double>(hp[k - 1].c);
            hist_count_[key] += 1;
          }
        }
      }
      return HullSums{top_cost, base_total, base_benefit, ptotal, segments, pcount, pwanted, poverflow,
                      fused, build_count, settled};
    };
    auto storeSums = [&](const HullSums& h) {
      fused = h.fused;
      unsettled_count = h.unsettled_count;
      settled_sums = h.settled;
      top_cost = h.top_cost;
      base_total = h.base_total;
      base_benefit = h.base_benefit;
      ptotal = h.ptotal;
      segments = h.segments;
      pcount = h.pcount;
      pwanted = h.pwanted;
      poverflow = h.poverflow;
    };
    storeSums(buildHulls(predict));

    int64_t split_slot = -1;
    uint32_t split_step = 0;
    uint32_t passes = 0;
    double lambda = 0.0;
    if (use_greedy) {
      double base_total = 0.0;
      for (size_t s = 0; s < slots; ++s) base_total += ctx.pointCost(s, ctx.hullLevel(s, 0));
      ctx.greedy(slots, base_total, obj_cap, params.stop_at_first_non_fitting, &split_slot, &split_step);
    } else {
      const double inf = std::numeric_limits<double>::infinity();
      auto float_below = [](int64_t bits) {  // the largest float whose bits are below `bits` (0 for none)
        if (bits <= 0) return 0.0;
        const uint32_t b = static_cast<uint32_t>(bits - 1);
        float f;
        std::memcpy(&f, &b, sizeof(f));
        return static_cast<double>(f);
      };
      // The price search: a bracket (lo, hi] of the price with C(hi) <= cap < C(lo) holding at most
      // bracket_capacity upgrades. `from_histogram` starts from the histogram's bucket, otherwise from
      // last frame's price (the fallback when the histogram's rounded sums disagree with the exact ones).
      auto search = [&](bool from_histogram, double* lo_out, double* hi_out, bool* separated) {
        // the pass at lambda = 0 (every upgrade taken) was summed while building the hulls
        size_t in_bracket = segments;
        double lo = 0.0, hi = inf;
        if (top_cost <= obj_cap) {
          *lo_out = 0.0;
          *hi_out = 0.0;  // everything fits
          *separated = true;
          return;
        }
        double cost_lo = top_cost, cost_hi = 0.0, lam = 0.0, step = 1.1;
        bool have_lam = false;
        if (from_histogram) {
          // C at the lower edge of bucket j = base_total + the steps of buckets j and above
          int64_t j = inner_buckets + 1;
          double t = base_total;
          bool found = t > obj_cap;
          if (!found) {
            for (;; --j) {
              const double t_next = t + hist_cost[j];
              if (t_next > obj_cap) {
                found = true;
                cost_hi = t;
                cost_lo = t_next;
                break;
              }
              t = t_next;
              if (j == 0) break;
            }
          }
          if (found) {
            lo = j == 0 ? 0.0 : float_below((j - 1 + key_base) << key_shift);
            hi = j == inner_buckets + 1 ? inf : float_below((j + key_base) << key_shift);
            in_bracket = hist_count[j];
            if (hi == inf) {
              lam = lo > 0.0 ? lo * step : 0.0;
              step *= step;
            } else {
              double tt = cost_lo > cost_hi ? (cost_lo - obj_cap) / (cost_lo - cost_hi) : 0.5;
              lam = lo + std::min(0.9, std::max(0.1, tt)) * (hi - lo);
            }
            have_lam = lam > lo && lam < hi;
          }
        }
        if (!have_lam && in_bracket > ctx.bracket_capacity) {
          lam = ctx.has_history && ctx.last_lambda > 0.0 ? ctx.last_lambda : 0.0;
          if (!(lam > 0.0)) {
            // a first guess: the mean benefit per ms of the finest fitting points
            double b = 0.0, c = 0.0;
            for (size_t s = 0; s < slots; ++s) {
              const int l = ctx.hullLevel(s, ctx.hull_count[s] - 1u);
              b += ctx.pointBenefit(s, l);
              c += ctx.pointCost(s, l);
            }
            lam = c > 0.0 && b > 0.0 ? b / c : 1.0;
          }
          if (!(lam > lo && lam < hi)) in_bracket = ctx.bracket_capacity + 1;  // forces the greedy below
        }
        // C(lambda) falls from C(0) = top_cost; find hi with C(hi) <= cap by growing steps from the
        // guess (last frame's price when the camera moves smoothly), then interpolate C linearly
        // between lo and hi, kept off the ends, until few upgrades remain in (lo, hi]
        while (in_bracket > ctx.bracket_capacity && passes < 64 && lam > lo && lam < hi) {
          const PassResult pr = ctx.pass(slots, lam, lo, hi);
          ++passes;
          if (pr.cost <= obj_cap) {
            hi = lam;
            cost_hi = pr.cost;
            in_bracket = pr.below;
          } else {
            lo = lam;
            cost_lo = pr.cost;
            in_bracket = pr.above;
          }
          if (in_bracket <= ctx.bracket_capacity) break;
          double next;
          if (hi == inf) {
            next = lo * step;
            step *= step;
          } else {
            double t = cost_lo > cost_hi ? (cost_lo - obj_cap) / (cost_lo - cost_hi) : 0.5;
            t = std::min(0.9, std::max(0.1, t));
            next = lo + t * (hi - lo);
          }
          if (!(next > lo && next < hi)) break;  // no double strictly inside: all ties
          lam = next;
        }
        *lo_out = lo;
        *hi_out = hi;
        *separated = in_bracket <= ctx.bracket_capacity;
      };
      // take every upgrade above hi, collect those in (lo, hi], then greedy on the bracket
      enum class Collected { kDone, kOverflow, kEdgeOutside };
      // greedy over the `count` upgrades in the bracket, every upgrade above it taken (cost `total`)
      auto bracketGreedy = [&](double lo, double hi, size_t count, double total) {
        lambda = hi;
        split_slot = -1;
        // the bracket must hold the budget's edge: the upgrades above it fit, all of them together not
        if (hi != inf && total > obj_cap) return Collected::kEdgeOutside;
        sortBracket(ctx.bracket, ctx.bracket_scratch, count);
        for (size_t e = 0; e < count; ++e) {
          const BracketEntry& be = ctx.bracket[e];
          if (ctx.chosen[be.slot] != be.step) continue;  // an earlier step of this slot did not fit
          const int l0 = ctx.hullLevel(be.slot, be.step), l1 = ctx.hullLevel(be.slot, be.step + 1);
          const double delta = static_cast<double>(ctx.pointCost(be.slot, l1)) - ctx.pointCost(be.slot, l0);
          if (total + delta <= obj_cap) {
            total += delta;
            ctx.chosen[be.slot] = static_cast<uint8_t>(be.step + 1);
            lambda = be.ratio;
          } else {
            split_slot = be.slot;
            split_step = be.step;
            lambda = be.ratio;
            break;
          }
        }
        return split_slot >= 0 || lo == 0.0 ? Collected::kDone : Collected::kEdgeOutside;
      };
      auto collect = [&](double lo, double hi) {
        lambda = hi;
        split_slot = -1;
        double total = 0.0;
        size_t count = 0;
        uint8_t* const chosen = ctx.chosen;
        BracketEntry* const bracket = ctx.bracket;
        const size_t capacity = ctx.bracket_capacity;
        for (size_t s = 0; s < slots; ++s) {
          const size_t hn = hull_count[s];
          const uint8_t* const h = hull + s * hull_stride;
          const float sa = slot_a[s], sb = slot_b[s], sq = slot_q[s];
          const uint32_t row0 = slot_row0[s];
          const int prev = slot_prev[s];
          // ctx.pointCost / ctx.pointBenefit over the slot's terms in registers
          auto cost_of = [&](int l) { return l < 0 ? 0.0f : sa + row_cost[row0 + static_cast<uint32_t>(l)]; };
          auto benefit_of = [&](int l) {
            if (l < 0) return 0.0f;
            float acc = std::min(1.0f, sq * row_inv_w[row0 + static_cast<uint32_t>(l)]);
            if (l == prev) acc *= h1;
            return sb * acc;
          };
          size_t k = 0;
          int l0 = h[0] == kNotDrawn ? -1 : static_cast<int>(h[0]);
          float c0 = cost_of(l0), b0 = benefit_of(l0);
          float chosen_cost = c0;
          bool taking = true;
          uint8_t pick = 0;
          while (k + 1 < hn) {
            const int l1 = h[k + 1] == kNotDrawn ? -1 : static_cast<int>(h[k + 1]);
            const float c1 = cost_of(l1), b1 = benefit_of(l1);
            const float q = SelectorContext::ratio(c0, b0, c1, b1);
            if (static_cast<double>(q) <= lo) break;
            if (taking && static_cast<double>(q) > hi) {
              chosen_cost = c1;
              pick = static_cast<uint8_t>(k + 1);
            } else {
              if (taking) pick = static_cast<uint8_t>(k);
              taking = false;
              if (count == capacity) return Collected::kOverflow;
              bracket[count++] = {q, static_cast<uint32_t>(s), static_cast<uint32_t>(k)};
            }
            ++k;
            c0 = c1;
            b0 = b1;
          }
          if (taking) pick = static_cast<uint8_t>(k);
          chosen[s] = pick;
          total += chosen_cost;
        }
        return bracketGreedy(lo, hi, count, total);
      };
      auto heapGreedy = [&]() {
        // ties the bracket cannot separate: the heap greedy gives the same order
        double base = 0.0;
        for (size_t s = 0; s < slots; ++s) base += ctx.pointCost(s, ctx.hullLevel(s, 0));
        split_slot = -1;
        ctx.greedy(slots, base, obj_cap, true, &split_slot, &split_step);
      };
      // first from the histogram; if its rounded sums put the edge outside the bucket that the exact
      // sums find (the budget within rounding of a bucket edge), again by passes from last frame's price
      bool from_prediction = false;
      if (predict) {
        // (no top_cost > obj_cap test: settled objects do not sum it, and when everything fits the
        // bracket's greedy finds no split, which is a miss for a bracket above 0)
        // a miss (the edge outside the bracket) is retried at twice the width, an overflow at half
        // of it or less (the width that would hold about 3/4 of the capacity, from the count of
        // the upgrades inside, stored or not), and between a miss and an overflow of the same
        // frame at their geometric mean; each retry costs one more settling pass instead of every
        // hull, the histogram and a collection pass
        double overflow_width = 0.0, miss_width = 0.0;  // this frame's tries that overflowed / missed
        for (int retry = 0;; ++retry) {
          if (!poverflow && bracketGreedy(plo, phi, pcount, ptotal) == Collected::kDone) {
            from_prediction = true;
            break;
          }
          // missed: widen the window; overflowed: narrow it (now and next frame)
          const double width = ctx.predict_width;
          double next;
          if (poverflow) {
            overflow_width = width;
            next = std::min(width * 0.5, width * 0.75 * static_cast<double>(pcapacity) / static_cast<double>(pwanted));
            if (miss_width > 0.0) next = std::max(next, std::sqrt(miss_width * width));
          } else {
            miss_width = width;
            next = width * 2.0;
            if (overflow_width > 0.0) next = std::min(next, std::sqrt(overflow_width * width));
          }
          ctx.predict_width = std::min(kPredictWidthMax, std::max(kPredictWidthMin, next));
          if (retry == kPredictRetries || ctx.predict_width == width) {
            // settled objects have no full hull, and the search needs the histogram
            storeSums(buildHulls(false));
            break;
          }
          plo = ctx.last_lambda / (1.0 + ctx.predict_width);
          phi = ctx.last_lambda * (1.0 + ctx.predict_width);
          storeSums(buildHulls(true));
        }
      }
      for (int attempt = 0; attempt < 2 && !from_prediction; ++attempt) {
        double lo = 0.0, hi = 0.0;
        bool separated = false;
        search(attempt == 0, &lo, &hi, &separated);
        if (!separated) {
          lambda = hi;
          heapGreedy();
          break;
        }
        const Collected result = collect(lo, hi);
        if (result == Collected::kOverflow) {
          lambda = hi;
          heapGreedy();
          break;
        }
        if (result == Collected::kDone || attempt == 1) break;
      }
    }
    // the 1/2 guarantee (the first upgrade that did not fit, alone with every other object at its
    // base) is checked after the write-out below, which sums the greedy's benefit in the same order
    if (params.half_approximation && split_slot >= 0) {
      const size_t js = static_cast<size_t>(split_slot);
      half_alt_benefit = base_benefit + ctx.pointBenefit(js, ctx.hullLevel(js, split_step + 1)) -
                         ctx.pointBenefit(js, ctx.hullLevel(js, 0));
      half_slot = split_slot;
      half_step = split_step + 1;
    }
    ctx.last_lambda = lambda;
    st.lambda = lambda;
    st.search_passes = passes;
    if (mandatory > cap) st.flags |= kFlagOverBudget;
  }

  if (budget) {
    // write levels, statistics, features; chosen[] holds steps along the hulls, whose entries are
    // level bytes (kNotDrawn = -1), read here rather than in a pass of their own, or
    // kSettledAtPrev / kSettledAtBase for a settled slot
    const uint8_t* const hull = ctx.hull;
    const size_t hull_stride = ctx.hull_stride;
    auto writeOut = [&]() {
      f = CostFeatures();
      tri_sum = vert_sum = line_sum = 0;
      predicted = coef.per_frame_ms;
      benefit = 0.0;
      dropped = 0;
      drawn = 0;
      // counting per row pays when there are fewer rows than slots
      const size_t rows = levels.cell_width.count;
      const bool count_rows = rows <= slots;
      const WriteOutInput in{ctx.chosen, hull, hull_stride, slot_object, slot_a, slot_b, slot_q, slot_px,
                             slot_row0, slot_prev, row_cost, row_inv_w, tri, vert, lines, h1,
                             count_rows ? ctx.row_drawn : nullptr, rows};
      const SlotSums sums =
          ctx.use_avx2 ? (count_rows ? writeOutSlotsAvx2<true>(in, slots, predicted, level_of)
                                     : writeOutSlotsAvx2<false>(in, slots, predicted, level_of))
                       : (count_rows ? writeOutSlotsSse2<true>(in, slots, predicted, level_of)
                                     : writeOutSlotsSse2<false>(in, slots, predicted, level_of));
      predicted = sums.predicted;
      benefit = sums.benefit;
      f.pixels = sums.pixels;
      tri_sum = sums.tri;
      vert_sum = sums.vert;
      line_sum = sums.lines;
      dropped = sums.dropped;
      drawn = sums.drawn;
    };
    // the fused form: the settled slots' levels and sums are in (pass 1c and the settling pass),
    // the unsettled slots' are added after them in slot order (addSlot's operations), and the
    // features summed per row. The float sums are then in another order than writeOut's (settled
    // slots first): the same values whenever every partial double sum is exact (no more than
    // 53 significant bits), as on every scene checked (docs/bench/selection.md)
    auto writeOutUnsettled = [&]() {
      f = CostFeatures();
      predicted = coef.per_frame_ms + settled_sums.cost;
      benefit = settled_sums.benefit;
      double pixels = settled_sums.pixels;
      // settleKeys counted the slots last frame "not drawn" with a benefit: the settled ones are
      // dropped again, the unsettled ones are counted by their level here instead
      uint32_t dropped_ = prev_dropped;
      const uint32_t* const list = reinterpret_cast<const uint32_t*>(ctx.heap);
      const uint8_t* const chosen = ctx.chosen;
      uint32_t* const row_drawn = ctx.row_drawn;
      for (size_t u = 0; u < unsettled_count; ++u) {
        const size_t s = list[u];
        const uint8_t level = hull[s * hull_stride + chosen[s]];
        level_of[slot_object[s]] = static_cast<int8_t>(level);
        const uint32_t keep = 0u - static_cast<uint32_t>(level != kNotDrawn);  // all ones if drawn
        const float b = slot_b[s];
        dropped_ += (keep ^ 1u) & (b > 0.0f ? 1u : 0u);
        dropped_ -= slot_prev[s] < 0 && b > 0.0f ? 1u : 0u;
        const uint32_t row = slot_row0[s] + (level & keep);
        row_drawn[row] -= keep;
        const float cost = slot_a[s] + row_cost[row];
        const bool current = level == static_cast<uint8_t>(slot_prev[s]);
        const float acc = std::min(1.0f, slot_q[s] * row_inv_w[row]) * h_mult[current];
        predicted += maskFloat(cost, keep);
        benefit += maskFloat(b * acc, keep);
        pixels += maskFloat(slot_px[s], keep);
      }
      f.pixels = pixels;
      tri_sum = vert_sum = line_sum = 0;
      drawn = 0;
      for (size_t r = 0, rows = levels.cell_width.count; r < rows; ++r) {
        const uint64_t k = row_drawn[r];
        drawn += static_cast<uint32_t>(k);
        tri_sum += k * tri[r];
        vert_sum += k * vert[r];
        line_sum += k * lines[r];
      }
      dropped = dropped_;
    };
    if (fused)
      writeOutUnsettled();
    else
      writeOut();
    // the sum of benefits over slots in slot order is what the greedy's choice scores
    if (half_slot >= 0 && half_alt_benefit > benefit) {
      const size_t js = static_cast<size_t>(half_slot);
      for (size_t s = 0; s < slots; ++s)  // every slot at its base
        ctx.chosen[s] = ctx.chosen[s] == kSettledAtPrev ? kSettledAtBase : 0;
      ctx.chosen[js] = static_cast<uint8_t>(half_step);
      st.flags |= kFlagSplitFallback;
      writeOut();
    }
    if (cost_out) {
      for (size_t i = 0; i < n; ++i) cost_out[i] = 0.0f;
      for (size_t s = 0; s < slots; ++s) {
        const size_t i = ctx.slot_object[s];
        if (levels_out[i] >= 0) cost_out[i] = ctx.pointCost(s, levels_out[i]);
      }
    }
  }
  {
    // the switches counted 16 objects at a time in byte lanes (-1 per differing lane, at most 127
    // vectors per count before it is widened), last frame's levels overwritten in the same loop
    typedef int8_t V16b __attribute__((vector_size(16)));
    size_t i = 0;
    while (i + 16 <= n) {
      V16b count = {};
      for (const size_t end = std::min(n, i + 16 * 127); i + 16 <= end; i += 16) {
        V16b now, before;
        std::memcpy(&now, level_of + i, sizeof(now));
        std::memcpy(&before, prev_level + i, sizeof(before));
        count += now != before;
        std::memcpy(prev_level + i, &now, sizeof(now));
      }
      for (int l = 0; l < 16; ++l) switches += static_cast<uint32_t>(-count[l]);
    }
    for (; i < n; ++i) {
      switches += level_of[i] != prev_level[i] ? 1u : 0u;
      prev_level[i] = level_of[i];
    }
  }
  st.dropped_count = dropped;
  st.drawn_count = drawn;
  if (st.dropped_count > 0) st.flags |= kFlagObjectsDropped;
  st.switch_count = switches;
  st.predicted_ms = predicted;
  st.total_benefit = benefit;
  f.objects = static_cast<double>(drawn);
  {
    // above 2^53 the double sums in slot order rounded: sum them so again (drawn objects in object
    // order are the slots in slot order, and a slot not drawn added +0)
    constexpr uint64_t kExact = uint64_t(1) << 53;
    const uint32_t* const feature[3] = {tri, vert, lines};
    const uint64_t sums[3] = {tri_sum, vert_sum, line_sum};
    double* const out[3] = {&f.triangles, &f.vertices, &f.line_points};
    for (int k = 0; k < 3; ++k) {
      if (sums[k] < kExact) {
        *out[k] = static_cast<double>(sums[k]);
        continue;
      }
      double t = 0.0;
      for (size_t i = 0; i < n; ++i)
        if (level_of[i] >= 0) t += feature[k][chain_offset[chain_of[i]] + static_cast<uint32_t>(level_of[i])];
      *out[k] = t;
    }
  }
  st.features = f;

  const size_t ring = static_cast<size_t>(ctx.frame % kRingSize);
  ctx.ring_features[ring] = f;
  ctx.ring_frame[ring] = ctx.frame;
  ctx.has_history = true;
  ctx.last_was_budget = budget;
  ctx.last_slot_count = slots;
  ++ctx.frame;
  if (stats) *stats = st;
  return true;
}

}  // namespace scenelod::selection
