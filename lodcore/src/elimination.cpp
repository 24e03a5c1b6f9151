// Elimination (Low & Tan 1997 §2 step 5, Rossignac & Borrel 1993): each input triangle is mapped to
// the clusters of its corners; three distinct clusters keep a triangle, two make an edge, one a
// point. Duplicate triangles of the same orientation are removed; a pair of opposite orientation is
// a two-sided sheet and both stay (each is visible from its own side with back-face culling).
// Edges covered by a kept triangle, and points covered by a kept edge or triangle, are removed.
// Input edges and points are mapped the same way.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "cluster_internal.h"
#include "test_hooks.h"

namespace scenelod::detail {

// x86: AVX2 with POPCNT (cpuHasAvx2 checks both), for the lists' counts
#if defined(__x86_64__) || defined(__i386__)
#define SCENELOD_ELIMINATION_AVX2_TARGET __attribute__((target("avx2,popcnt")))
#else
#define SCENELOD_ELIMINATION_AVX2_TARGET
#endif

namespace {
inline uint32_t branchlessMin(uint32_t a, uint32_t b) { return b ^ ((a ^ b) & (0u - uint32_t(a < b))); }

// Candidate edges listed under their lower cluster id, chained through flat arrays under a 4-byte
// head per cluster (a walk of a node or two that a nearby input triangle wrote recently: the input
// order is spatially coherent, the cluster ids are not).
class EdgeLists {
 public:
  explicit EdgeLists(size_t clusters) : head_(clusters, kNoNode) {
    node_hi_.reset(new uint32_t[1]);
    node_next_.reset(new uint32_t[1]);
    node_hi_[0] = kNone;  // node 0: the end of every list (its hi matches no cluster)
    node_next_[0] = kNoNode;
  }
  // the id of edge (lo, hi), lo < hi, or kNone (kNoNode - 1)
  SCENELOD_ALWAYS_INLINE uint32_t find(uint32_t lo, uint32_t hi) const { return walkNodes(lo, hi) - 1; }
  // The id of edge (lo, hi), lo < hi; an edge not listed yet is listed as `id` (the count of edges
  // so far), which is returned. Without a branch on which: the new node is written whatever and
  // linked only for a new edge (a branch on it mispredicted: 1 M sphere 10 %, 135 k times, a quarter
  // of the collapsed triangles' lookups making an edge).
  SCENELOD_ALWAYS_INLINE uint32_t findOrAdd(uint32_t lo, uint32_t hi, uint32_t id) {
    const uint32_t node = id + 1;
    if (node >= node_room_) growNodes();
    const uint32_t found = walkNodes(lo, hi);
    const uint32_t head = head_[lo];
    node_hi_[node] = hi;
    node_next_[node] = head;
    // (masks: as selects, the compiler made the first one a branch)
    const uint32_t made = 0u - uint32_t(found == kNoNode);
    head_[lo] = head ^ ((node ^ head) & made);
    return (found ^ ((node ^ found) & made)) - 1;
  }

 private:
  // The node of edge (lo, hi) in lo's list, or kNoNode. The first kWalkDepth nodes are read whatever
  // the list's length (node 0 ends a list and links to itself) and the match picked without a
  // branch; a branch only where the list goes on past them. (The loop's exits mispredicted: 1 M
  // sphere 10 %, 535 k of the elimination's 591 k mispredicts. Three nodes: there 96 % of the walks
  // end within them; four were no faster.)
  SCENELOD_ALWAYS_INLINE uint32_t walkNodes(uint32_t lo, uint32_t hi) const {
    const uint32_t* next = node_next_.get();
    const uint32_t* his = node_hi_.get();
    uint32_t n[kWalkDepth];
    n[0] = head_[lo];
    for (int k = 1; k < kWalkDepth; ++k) n[k] = next[n[k - 1]];
    uint32_t found = kNoNode;
    for (int k = kWalkDepth - 1; k >= 0; --k) found = his[n[k]] == hi ? n[k] : found;
    // one test (as two, the first, not found, mispredicted: 1 M sphere 10 %, 207 k times)
    if (n[kWalkDepth - 1] & (0u - uint32_t(found == kNoNode))) {
      for (uint32_t e = next[n[kWalkDepth - 1]]; e != kNoNode; e = next[e])
        if (his[e] == hi) {
          found = e;
          break;
        }
    }
    return found;
  }
  static constexpr int kWalkDepth = 3;
  static constexpr uint32_t kNoNode = 0;
  // the node arrays' size, doubled when full (as a vector's capacity; without the vector's zeroing of
  // what findOrAdd writes anyway: 1 M sphere 10 %, 1 MB)
  uint32_t node_room_ = 1;
  std::vector<uint32_t> head_;  // per cluster: its first node, kNoNode for none
  // per node: the other cluster id (the edge's id is the node's index - 1), the next node of its list
  std::unique_ptr<uint32_t[]> node_hi_, node_next_;
  void growNodes() {
    const uint32_t n = node_room_;
    node_room_ = 2 * n;
    auto grow = [&](std::unique_ptr<uint32_t[]>& a) {
      std::unique_ptr<uint32_t[]> b(new uint32_t[node_room_]);
      std::copy(a.get(), a.get() + n, b.get());
      a = std::move(b);
    };
    grow(node_hi_);
    grow(node_next_);
  }
};

constexpr size_t kBlock = 512;             // triangles classified at once
constexpr size_t kPrefetchTriangles = 16;  // how far ahead the cluster ids are prefetched (large meshes)

// One block's triangles by class, each list in input order; columns, so that the AVX2 classification
// stores eight lanes of each at once (a store starts at most at kBlock - 8, since a list holds at
// most the triangles before the group; the 8 entries past kBlock are a margin)
struct BlockLists {
  // the corners' clusters of kept triangles, rotated (keeping the orientation) so that the smallest
  // id comes first where `rotated`, else rotated when added
  uint32_t kept[3][kBlock + 8];
  uint32_t edge[3][kBlock + 8];  // collapsed to an edge: first corner's cluster, the other, the triangle
  uint32_t point[kBlock + 8];    // collapsed to a point: its cluster
  size_t kept_count, edge_count, point_count;
  bool rotated;
};

// rotation (keeping orientation) that puts the smallest id first, by index rather than by selects
// (which the compiler turned into branches); for a kept triangle (three distinct ids)
SCENELOD_ALWAYS_INLINE void rotateSmallestFirst(uint32_t& c0, uint32_t& c1, uint32_t& c2) {
  const uint32_t c[5] = {c0, c1, c2, c0, c1};
  const uint32_t lo = branchlessMin(branchlessMin(c0, c1), c2);
  const uint32_t r = uint32_t(c1 == lo) + 2u * uint32_t(c2 == lo);  // 0, 1 or 2
  c0 = lo;
  c1 = c[r + 1];
  c2 = c[r + 2];
}

// Classifies triangles [t, t1) onto the lists' ends. Compiled for each set of constants (a test of
// a flag in memory per triangle otherwise); kRotate: kept triangles rotated (rotateSmallestFirst),
// for the tail of the AVX2 classification.
template <bool kPrefetch, bool kPointsFirst, bool kRotate = false>
SCENELOD_ALWAYS_INLINE void classifyScalar(const uint32_t* tri, const uint32_t* co, size_t t, size_t t1, BlockLists& l) {
  size_t nk = l.kept_count, ne = l.edge_count, np = l.point_count;
  for (const uint32_t* v = tri + 3 * t; t < t1; ++t, v += 3) {
    if (kPrefetch) {
      __builtin_prefetch(co + v[3 * kPrefetchTriangles]);
      __builtin_prefetch(co + v[3 * kPrefetchTriangles + 1]);
      __builtin_prefetch(co + v[3 * kPrefetchTriangles + 2]);
    }
    const uint32_t c0 = co[v[0]], c1 = co[v[1]], c2 = co[v[2]];
    if (kPointsFirst && (c0 == c1) & (c1 == c2)) {  // predictable there, and cheaper than the full body
      l.point[np++] = c0;
      continue;
    }
    const bool e01 = c0 == c1, e12 = c1 == c2, e02 = c0 == c2;
    const bool kept = !(e01 | e12 | e02), point = e01 & e12;
    if (kRotate && kept) {
      uint32_t r0 = c0, r1 = c1, r2 = c2;
      rotateSmallestFirst(r0, r1, r2);
      l.kept[0][nk] = r0;
      l.kept[1][nk] = r1;
      l.kept[2][nk] = r2;
    } else {
      l.kept[0][nk] = c0;
      l.kept[1][nk] = c1;
      l.kept[2][nk] = c2;
    }
    nk += kept;
    l.edge[0][ne] = c0;
    l.edge[1][ne] = c1 ^ ((c1 ^ c2) & (0u - uint32_t(e01)));
    l.edge[2][ne] = static_cast<uint32_t>(t);
    ne += !kept & !point;
    l.point[np] = c0;
    np += point;
  }
  l.kept_count = nk;
  l.edge_count = ne;
  l.point_count = np;
}

// Whether the triangles come in a spatially coherent order, judged from the first kOrderSample:
// most of them have their first corner within kNearIds ids of the previous triangle's (a
// generator's rings or a scanned mesh: 1 apart; shuffled: a random distance, near 0.4 % of the time
// on the 1 M sphere)
bool coherentOrder(const uint32_t* tri, size_t tn) {
  constexpr size_t kOrderSample = 1024;
  constexpr uint32_t kNearIds = 1024;  // 4 KB of cluster ids
  const size_t n = std::min(tn, kOrderSample);
  size_t near = 0;
  for (size_t t = 1; t < n; ++t) {
    const uint32_t x = tri[3 * t], y = tri[3 * t - 3];
    near += (x > y ? x - y : y - x) < kNearIds;
  }
  return 2 * near > n;
}

#if defined(__x86_64__) || defined(__i386__)
// stores the lanes of `v` that `perm` (a row of kLaneCompaction) selects at dst[0, its count), in lane
// order; all 8 lanes are written
SCENELOD_ELIMINATION_AVX2_TARGET inline void storeCompacted(uint32_t* dst, __m256i v, __m256i perm) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), _mm256_permutevar8x32_epi32(v, perm));
}

// The classification eight triangles at a time (the tail of a block scalar): the three corners'
// vertex ids split into columns, their clusters gathered, the classes compared per lane and each
// list's lanes compacted through a permutation table; the same lists as classifyScalar, with kRotate
// the kept triangles rotated in lanes (rotateSmallestFirst, about 25 instructions a kept triangle
// where it is added, against 8 per eight triangles here).
template <bool kPrefetch, bool kRotate>
SCENELOD_ELIMINATION_AVX2_TARGET void classifyAvx2(const uint32_t* tri, const uint32_t* co, size_t t, size_t t1,
                                                   BlockLists& l) {
  size_t nk = l.kept_count, ne = l.edge_count, np = l.point_count;
  const int* ids = reinterpret_cast<const int*>(co);
  // the triangles whose corner k the blends below put in lanes 0-7 are 0 3 6 1 4 7 2 5 (k = 0),
  // 5 0 3 6 1 4 7 2 (k = 1), 2 5 0 3 6 1 4 7 (k = 2); these permutations put triangle j in lane j
  const __m256i order0 = _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5);
  const __m256i order1 = _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6);
  const __m256i order2 = _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (; t + 8 <= t1; t += 8) {
    const uint32_t* v = tri + 3 * t;
    if (kPrefetch) {
      // (unrolled: as a loop, 15.8 M of the 1 M sphere 10 % level's 87 M instructions)
#pragma GCC unroll 24
      for (int k = 0; k < 24; ++k) __builtin_prefetch(co + v[3 * kPrefetchTriangles + k]);
    }
    // a = v0 v1 v2 | v0 v1 v2 | v0 v1, b = v2 | v0 v1 v2 | v0 v1 v2 | v0, c = v1 v2 | v0 v1 v2 | v0 v1 v2
    const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(v));
    const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(v + 8));
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(v + 16));
    // corner k of triangle j sits in a at 3j + k, in b at 3j + k - 8, in c at 3j + k - 16
    const __m256i x0 = _mm256_blend_epi32(_mm256_blend_epi32(a, b, 0x92), c, 0x24);  // lanes 1 4 7 of b, 2 5 of c
    const __m256i x1 = _mm256_blend_epi32(_mm256_blend_epi32(a, b, 0x24), c, 0x49);  // lanes 2 5 of b, 0 3 6 of c
    const __m256i x2 = _mm256_blend_epi32(_mm256_blend_epi32(a, b, 0x49), c, 0x92);  // lanes 0 3 6 of b, 1 4 7 of c
    const __m256i c0 = _mm256_i32gather_epi32(ids, _mm256_permutevar8x32_epi32(x0, order0), 4);
    const __m256i c1 = _mm256_i32gather_epi32(ids, _mm256_permutevar8x32_epi32(x1, order1), 4);
    const __m256i c2 = _mm256_i32gather_epi32(ids, _mm256_permutevar8x32_epi32(x2, order2), 4);
    const __m256i e01 = _mm256_cmpeq_epi32(c0, c1), e12 = _mm256_cmpeq_epi32(c1, c2), e02 = _mm256_cmpeq_epi32(c0, c2);
    const uint32_t any = uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_or_si256(_mm256_or_si256(e01, e12), e02))));
    const uint32_t point = uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_and_si256(e01, e12))));
    const uint32_t kept = ~any & 0xFFu, edge = any & ~point;
    const __m256i pk = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[kept])));
    const __m256i pe = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[edge])));
    const __m256i pp = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[point])));
    if (kRotate) {
      // as rotateSmallestFirst: exactly one corner of a kept triangle holds the smallest id
      const __m256i lo = _mm256_min_epu32(_mm256_min_epu32(c0, c1), c2);
      const __m256i at1 = _mm256_cmpeq_epi32(c1, lo), at2 = _mm256_cmpeq_epi32(c2, lo);
      storeCompacted(l.kept[0] + nk, lo, pk);
      storeCompacted(l.kept[1] + nk, _mm256_blendv_epi8(_mm256_blendv_epi8(c1, c2, at1), c0, at2), pk);
      storeCompacted(l.kept[2] + nk, _mm256_blendv_epi8(_mm256_blendv_epi8(c2, c0, at1), c1, at2), pk);
    } else {
      storeCompacted(l.kept[0] + nk, c0, pk);
      storeCompacted(l.kept[1] + nk, c1, pk);
      storeCompacted(l.kept[2] + nk, c2, pk);
    }
    nk += size_t(__builtin_popcount(kept));
    storeCompacted(l.edge[0] + ne, c0, pe);
    storeCompacted(l.edge[1] + ne, _mm256_blendv_epi8(c1, c2, e01), pe);  // the corner not in c0's cluster
    storeCompacted(l.edge[2] + ne, _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(t)), lane), pe);
    ne += size_t(__builtin_popcount(edge));
    storeCompacted(l.point + np, c0, pp);
    np += size_t(__builtin_popcount(point));
  }
  l.kept_count = nk;
  l.edge_count = ne;
  l.point_count = np;
  classifyScalar<false, false, kRotate>(tri, co, t, t1, l);
}
#else
template <bool kPrefetch, bool kRotate>
void classifyAvx2(const uint32_t* tri, const uint32_t* co, size_t t, size_t t1, BlockLists& l) {
  classifyScalar<false, false, kRotate>(tri, co, t, t1, l);
}
#endif

// Drops the entries of a block's edge list (x[j], y[j]) that are the same cluster pair as the
// entry before them, in place, and leaves each kept pair as (lower id, higher id); returns the count
// kept. A dropped entry equals the last kept one, so comparing with that is comparing with the
// entry before. The lookup of a repeated pair finds the edge its predecessor found or made and
// changes nothing (findOrAdd writes a spare node), so only the lookups made differ.
// (The 1 M sphere's 10 % level in its generator's ring order: 268.9 k of its 522.5 k collapsed
// triangles repeat the pair before, about 90 instructions a lookup on the chained lists; the
// bunny's 50 % level 4.2 k of 34.0 k, chain level 2 6.8 k of 35.8 k.)
size_t dropRepeatedEdgesScalar(uint32_t* x, uint32_t* y, size_t j, size_t n, size_t kept) {
  uint32_t last_lo = kept ? x[kept - 1] : kNone, last_hi = kept ? y[kept - 1] : kNone;
  for (; j < n; ++j) {
    const uint32_t lo = branchlessMin(x[j], y[j]), hi = x[j] ^ y[j] ^ lo;
    x[kept] = lo;  // (kept <= j: an entry already read)
    y[kept] = hi;
    kept += uint32_t(lo != last_lo) | uint32_t(hi != last_hi);
    last_lo = lo;
    last_hi = hi;
  }
  return kept;
}

#if defined(__x86_64__) || defined(__i386__)
// dropRepeatedEdgesScalar eight entries at a time (the tail scalar): each lane compared with the
// lane before (lane 0 with the last of the previous eight), the kept lanes compacted through
// kLaneCompaction. In place: a store at `kept` <= j reaches at most the eight entries just read.
SCENELOD_ELIMINATION_AVX2_TARGET size_t dropRepeatedEdgesAvx2(uint32_t* x, uint32_t* y, size_t n) {
  const __m256i before = _mm256_setr_epi32(7, 0, 1, 2, 3, 4, 5, 6);
  __m256i prev_lo = _mm256_set1_epi32(-1), prev_hi = prev_lo;  // (kNone: no pair's lower id)
  size_t j = 0, kept = 0;
  for (; j + 8 <= n; j += 8) {
    const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(x + j));
    const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(y + j));
    const __m256i lo = _mm256_min_epu32(a, b), hi = _mm256_max_epu32(a, b);
    const __m256i lo1 = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(lo, before),
                                           _mm256_permutevar8x32_epi32(prev_lo, before), 0x01);
    const __m256i hi1 = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(hi, before),
                                           _mm256_permutevar8x32_epi32(prev_hi, before), 0x01);
    const __m256i same = _mm256_and_si256(_mm256_cmpeq_epi32(lo, lo1), _mm256_cmpeq_epi32(hi, hi1));
    const uint32_t keep = ~uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(same))) & 0xFFu;
    const __m256i perm = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[keep])));
    storeCompacted(x + kept, lo, perm);
    storeCompacted(y + kept, hi, perm);
    kept += size_t(__builtin_popcount(keep));
    prev_lo = lo;
    prev_hi = hi;
  }
  return dropRepeatedEdgesScalar(x, y, j, n, kept);
}
#else
size_t dropRepeatedEdgesAvx2(uint32_t* x, uint32_t* y, size_t n) { return dropRepeatedEdgesScalar(x, y, 0, n, 0); }
#endif

// Drops the entries of a block's point list that repeat the entry before them, in place; returns
// the count kept (addPoint of a repeat finds its cluster listed and does nothing). (The 1 M
// sphere's 1 % level: 798 k of its 1.04 M triangles collapse to a point, about 10 instructions
// each in addPoint.)
size_t dropRepeatedPointsScalar(uint32_t* c, size_t j, size_t n, size_t kept) {
  uint32_t last = kept ? c[kept - 1] : kNone;
  for (; j < n; ++j) {
    const uint32_t x = c[j];
    c[kept] = x;
    kept += x != last;
    last = x;
  }
  return kept;
}

#if defined(__x86_64__) || defined(__i386__)
// dropRepeatedPointsScalar eight entries at a time, as dropRepeatedEdgesAvx2
SCENELOD_ELIMINATION_AVX2_TARGET size_t dropRepeatedPointsAvx2(uint32_t* c, size_t n) {
  const __m256i before = _mm256_setr_epi32(7, 0, 1, 2, 3, 4, 5, 6);
  __m256i prev = _mm256_set1_epi32(-1);  // (kNone: no cluster id)
  size_t j = 0, kept = 0;
  for (; j + 8 <= n; j += 8) {
    const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c + j));
    const __m256i x1 = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(x, before),
                                          _mm256_permutevar8x32_epi32(prev, before), 0x01);
    const uint32_t keep = ~uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(x, x1)))) & 0xFFu;
    const __m256i perm = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[keep])));
    storeCompacted(c + kept, x, perm);
    kept += size_t(__builtin_popcount(keep));
    prev = x;
  }
  return dropRepeatedPointsScalar(c, j, n, kept);
}
#else
size_t dropRepeatedPointsAvx2(uint32_t* c, size_t n) { return dropRepeatedPointsScalar(c, 0, n, 0); }
#endif

// false: every collapsed triangle's pair and point looked up (useRepeatedEdgeDrop, a test hook)
bool g_drop_repeated_edges = true;
// how far ahead, in kept triangles, a large table's home slots are prefetched (eliminate), and the
// table size from which they are (the bunny's 50 % level: 256 KB)
constexpr size_t kPrefetchKept = 32;
constexpr size_t kPrefetchTableBytes = size_t(1) << 19;
}  // namespace

// (test_hooks.h)
bool useRepeatedEdgeDrop(bool on) { return std::exchange(g_drop_repeated_edges, on); }

namespace {

// a cluster's point state (Candidates::point_state): 1 once listed as a point, 2 once a corner of an
// output triangle or edge, which covers its point
constexpr uint8_t kListed = 1, kUsed = 2;

// The kept triangles, each once: a table of output triangle indices keyed by the rotation starting
// at the smallest id, sized for the expected output (a closed surface has about 2 triangles per
// cluster, capped by the input count) rather than the input, so that it stays in cache; grows at 2/3
// load (a power of two at least 1.5 x expected, so about half full at the end: at 1/2 the power of
// two was about 4 x the output, the largest array of the main pass at fine levels). A slot holds the
// triangle's index in its low log2(cap) bits and, above them, bits of its hash that do not pick its
// home: an occupant whose bits differ is passed over without reading its triangle, a random read of
// the output (bunny 50 %: 19 k of its 255 k D1 read misses; 1 M sphere 10 %: 36 k). An index is
// below 2/3 cap, so no slot is kNone. A new triangle marks its corners' clusters kUsed.
class TriangleTable {
 public:
  TriangleTable(size_t expected, std::vector<uint32_t>& triangles, uint8_t* point_state)
      : triangles_(triangles), point_state_(point_state) {
    while (cap_ * 2 < expected * 3) cap_ <<= 1;
    mask_ = cap_ - 1;
    index_bits_ = size_t(__builtin_ctzll(cap_));
    table_.assign(cap_, kNone);
  }
  static size_t hash(uint32_t c0, uint32_t c1, uint32_t c2) {
    const uint64_t h = (uint64_t(c0) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(c1) * 0xC2B2AE3D27D4EB4Full) ^
                       (uint64_t(c2) * 0x165667B19E3779F9ull);
    return static_cast<size_t>(h ^ (h >> 31));
  }
  size_t bytes() const { return cap_ * sizeof(uint32_t); }
  void prefetch(uint32_t c0, uint32_t c1, uint32_t c2) const { __builtin_prefetch(table_.data() + home(hash(c0, c1, c2))); }
  // the triangle (c0, c1, c2), rotated smallest first, unless it is listed already
  SCENELOD_ALWAYS_INLINE void add(uint32_t c0, uint32_t c1, uint32_t c2) {
    const size_t h = hash(c0, c1, c2);
    const uint32_t* slots = table_.data();
    for (size_t i = home(h);; i = nextSlot(i)) {
      const uint32_t o = slots[i];
      if (o == kNone) {
        insert(i, h, c0, c1, c2);
        return;
      }
      if ((o ^ slotOf(h, 0)) >> index_bits_) continue;  // another triangle's bits
      const uint32_t* occupant = triangles_.data() + 3 * size_t(o & mask_);
      if (occupant[0] == c0 && occupant[1] == c1 && occupant[2] == c2) return;
    }
  }
  void release() { std::vector<uint32_t>().swap(table_); }

 private:
  size_t home(size_t h) const { return h & mask_; }
  size_t nextSlot(size_t i) const { return (i + 1) & mask_; }
  uint32_t slotOf(size_t h, size_t index) const {
    return static_cast<uint32_t>(index) | (static_cast<uint32_t>(uint64_t(h) >> 32) << index_bits_);
  }
  // the new triangle (c0, c1, c2) with hash h into empty slot i
  void insert(size_t i, size_t h, uint32_t c0, uint32_t c1, uint32_t c2) {
    table_[i] = slotOf(h, triangles_.size() / 3);
    if ((triangles_.size() / 3 + 1) * 3 > cap_ * 2) {  // keep the load at most 2/3
      cap_ <<= 1;
      mask_ = cap_ - 1;
      ++index_bits_;
      table_.assign(cap_, kNone);
      for (size_t k = 0; k < triangles_.size(); k += 3) {
        const size_t hk = hash(triangles_[k], triangles_[k + 1], triangles_[k + 2]);
        size_t j = home(hk);
        while (table_[j] != kNone) j = nextSlot(j);
        table_[j] = slotOf(hk, k / 3);
      }
      size_t j = home(h);
      while (table_[j] != kNone) j = nextSlot(j);
      table_[j] = slotOf(h, triangles_.size() / 3);
    }
    triangles_.push_back(c0);
    triangles_.push_back(c1);
    triangles_.push_back(c2);
    point_state_[c0] = point_state_[c1] = point_state_[c2] = kUsed;
  }
  std::vector<uint32_t>& triangles_;
  uint8_t* point_state_;
  size_t cap_ = 64, mask_ = 63, index_bits_ = 6;
  std::vector<uint32_t> table_;
};

// The candidate edges and points of one level and what the thickness needs of them.
struct Candidates {
  Candidates(size_t clusters, size_t listed, bool input_edges)
      : input_edges(input_edges), lists(listed), point_state(clusters, 0) {}
  // the entry of edge e: its cluster pair, low id first, then the block of the last triangle
  // collapsed onto it (kNone for none)
  uint32_t* entry(size_t e) { return edges[e / kEdgeChunk].get() + 3 * (e % kEdgeChunk); }
  // the entry of the next edge (allocated whole, uninitialised, when the first edge could go in it)
  uint32_t* nextEntry() {
    if (edge_total == edge_room) {
      edges.emplace_back(new uint32_t[3 * kEdgeChunk]);
      edge_room += kEdgeChunk;
    }
    return edges.back().get() + 3 * (edge_total % kEdgeChunk);
  }
  // The id of candidate edge (x, y), listed if new: the new edge's entry is written whatever (past
  // the last edge) and counted only when made. (inlined: called out of line, its saves and restores
  // were about a quarter of its cost)
  SCENELOD_ALWAYS_INLINE uint32_t edge(uint32_t x, uint32_t y) {
    const uint32_t lo = branchlessMin(x, y), hi = x ^ y ^ lo;
    uint32_t* e_entry = nextEntry();
    const uint32_t id = static_cast<uint32_t>(edge_total);
    const uint32_t e = lists.findOrAdd(lo, hi, id);
    e_entry[0] = lo;
    e_entry[1] = hi;
    e_entry[2] = kNone;
    edge_total += e == edge_total;
    if (input_edges) input_thickness.resize(edge_total, 0.0f);
    return e;
  }
  void addPoint(uint32_t c) {
    if (point_state[c]) return;
    point_state[c] = kListed;
    point_candidates.push_back(c);
  }

  // candidate edges in chunks of kEdgeChunk: a growing vector's copy (old and new buffers at once)
  // came at the peak of a level (1024: the unused part of the last chunk, 6 KB on average, was part
  // of the bunny chain's peak)
  static constexpr size_t kEdgeChunk = 1024;
  std::vector<std::unique_ptr<uint32_t[]>> edges;
  size_t edge_total = 0;
  size_t edge_room = 0;  // edges the chunks hold
  const bool input_edges;
  std::vector<float> input_thickness;  // per candidate edge: its input edges' largest thickness
  // Candidate edges are found again through per-cluster lists (EdgeLists). The hash this replaces
  // (16-byte slots, two per cluster) was larger than the cache at fine levels, where the coverage
  // pass's lookups went to random slots of it.
  EdgeLists lists;
  // Triangles collapsed onto a candidate edge (for the thickness of the edges left uncovered): listed
  // while they are at most kCollapsedList; past that the list is dropped and, if some edge stays
  // uncovered, the blocks of triangles that can hold its triangles are read again at the end.
  // On closed surfaces nearly every candidate edge is covered, while most triangles of a coarse level
  // collapse: the list (8 bytes per collapsed triangle, about 4.5 MB at the 1 M sphere's level 2) was
  // the largest transient of a coarse level's elimination. Each candidate edge keeps the block of its
  // last triangle for this, beside its cluster pair (its first block follows from its id).
  static constexpr size_t kCollapsedList = 4096;
  std::vector<CollapsedTriangle> collapsed_list;
  bool collapsed_dropped = false;
  std::vector<uint32_t> block_first_edge;  // per block: the id of the first edge it created
  // clusters of collapsed primitives, each listed once in order of first appearance (the order
  // points are output in); coarse levels collapse most triangles onto a few clusters. Per cluster:
  // 1 once listed, 2 once a corner of an output triangle or edge, which covers its point (it is then
  // not listed, or dropped at the end: a separate pass over the output triangles did that before)
  std::vector<uint32_t> point_candidates;
  std::vector<uint8_t> point_state;
};

// The triangles collapsed onto uncovered edges (remap[e] != kNone) in the blocks that `rescan`
// opens (+1 at an edge's first block, -1 past its last), with the edges' output ids, appended to
// `collapsed`, where the list of collapsed triangles was dropped.
void rescanCollapsed(const Mesh& m, const uint32_t* co, const std::vector<int32_t>& rescan, const std::vector<uint32_t>& remap,
                     const std::vector<uint32_t>& out_edges, Candidates& c, std::vector<CollapsedTriangle>& collapsed) {
  const uint32_t* tri = m.triangles.data();
  const size_t tn = m.triangleCount();
  std::vector<uint8_t>& point_state = c.point_state;
  const EdgeLists& edge_lists = c.lists;
  // A triangle collapsed onto an uncovered edge has its corners in the edge's two clusters: with
  // those marked (the point states are no longer read), a triangle whose first corner is not is
  // passed over after one test that is rarely taken (at 2 % of the bunny, one uncovered edge of
  // four triangles spread over most blocks: the full classification of them cost 0.9 M
  // instructions, 11 % of the level's elimination).
  constexpr uint8_t kEdgeEnd = 4;
  for (uint32_t k : out_edges) point_state[k] = kEdgeEnd;
  // A block's triangles whose first corner is at an edge's end (counted): where they were over
  // 1/32 of the last block read, the next one tests the class and the corner in one test (at the
  // bunny chain's level 6, w = 0.856, the ends' clusters hold much of the blocks, and the test of
  // the corner first mispredicted 9.7 k times of the elimination's 16.6 k: 0.31-0.34 -> 0.26-0.28
  // ms, 2.96 -> 4.13 M instructions); else the corner first, a branch rarely taken (at 2 %, where
  // the one test cost 0.2 M instructions more and no time back; at 1/8 level 6 kept 9.3 k
  // mispredicts, 0.28-0.29 ms).
  auto rescanBlock = [&](size_t t0, size_t t1, bool one_test) __attribute__((always_inline)) {
    size_t ends = 0;
    for (size_t t = t0; t < t1; ++t) {
      const uint32_t* v = tri + 3 * t;
      const uint32_t c0 = co[v[0]];
      const bool end = point_state[c0] == kEdgeEnd;
      if (!one_test && !end) continue;
      const uint32_t c1 = co[v[1]], c2 = co[v[2]];
      const bool e01 = c0 == c1, e12 = c1 == c2, e02 = c0 == c2;
      ends += end;
      // collapsed to an edge: not kept, not a point
      if (!(uint32_t(e01 | e12 | e02) & ~uint32_t(e01 & e12) & uint32_t(end))) continue;
      const uint32_t y = e01 ? c2 : c1, lo = branchlessMin(c0, y);
      const uint32_t r = remap[edge_lists.find(lo, c0 ^ y ^ lo)];
      if (r != kNone) collapsed.push_back({static_cast<uint32_t>(t), r});
    }
    return ends;
  };
  int32_t open = 0;
  bool one_test = false;
  for (size_t b = 0; b + 1 < rescan.size(); ++b) {
    open += rescan[b];
    if (open == 0) continue;
    const size_t t0 = b * kBlock, t1 = std::min(tn, (b + 1) * kBlock);
    const size_t ends = one_test ? rescanBlock(t0, t1, true) : rescanBlock(t0, t1, false);
    one_test = ends * 32 > t1 - t0;
  }
}

// After the main pass: the candidate edges no kept triangle covers go out (edges of kept triangles
// remove candidate edges, used clusters remove points), then the points, then the thickness.
void finishEdges(const PreparedMesh& p, const Assignment& a, bool compute_thickness, Candidates& c, Eliminated& out) {
  const size_t en = c.edge_total;
  std::vector<uint8_t> covered(en + 1, 0);  // the last entry takes the edges of kept triangles that are not candidates
  if (en > 0)
    for (size_t t = 0; t < out.triangles.size(); t += 3) {
      const uint32_t c0 = out.triangles[t], c1 = out.triangles[t + 1], c2 = out.triangles[t + 2];
      const uint32_t x = branchlessMin(c0, c1), y = branchlessMin(c1, c2), z = branchlessMin(c2, c0);
      covered[branchlessMin(c.lists.find(x, c0 ^ c1 ^ x), uint32_t(en))] = 1;
      covered[branchlessMin(c.lists.find(y, c1 ^ c2 ^ y), uint32_t(en))] = 1;
      covered[branchlessMin(c.lists.find(z, c2 ^ c0 ^ z), uint32_t(en))] = 1;
    }
  // where the list of collapsed triangles was dropped: the blocks from the first to the last of each
  // uncovered edge's triangles (+1 at its first block, -1 past its last) are read again below
  std::vector<int32_t> rescan;
  if (c.collapsed_dropped)
    for (size_t e = 0; e < en; ++e) {
      const uint32_t last = c.entry(e)[2];
      if (covered[e] || last == kNone) continue;
      if (rescan.empty()) rescan.assign(c.block_first_edge.size() + 1, 0);
      // the block whose triangle created the edge (edges from triangles come first, in block order)
      const size_t first = static_cast<size_t>(
          std::upper_bound(c.block_first_edge.begin(), c.block_first_edge.end(), uint32_t(e)) - c.block_first_edge.begin() - 1);
      ++rescan[first];
      --rescan[last + 1];
    }
  if (rescan.empty()) { EdgeLists released(0); std::swap(released, c.lists); }
  std::vector<uint32_t> remap(en, kNone);
  for (size_t e = 0; e < en; ++e) {
    if (covered[e]) continue;
    const uint32_t* pair = c.entry(e);
    remap[e] = static_cast<uint32_t>(out.edges.size() / 2);
    out.edges.push_back(pair[0]);
    out.edges.push_back(pair[1]);
    c.point_state[pair[0]] = c.point_state[pair[1]] = kUsed;
  }
  std::vector<std::unique_ptr<uint32_t[]>>().swap(c.edges);
  for (uint32_t k : c.point_candidates)
    if (c.point_state[k] == kListed) out.points.push_back(k);

  if (!compute_thickness) return;
  out.edge_thickness.assign(out.edges.size() / 2, 0.0f);
  // the triangles collapsed onto uncovered edges, in input order, with the edges' output ids
  std::vector<CollapsedTriangle> collapsed;
  if (!c.collapsed_dropped) {
    size_t kept = 0;
    for (const CollapsedTriangle& ct : c.collapsed_list) kept += remap[ct.edge] != kNone;
    collapsed.reserve(kept);
    for (const CollapsedTriangle& ct : c.collapsed_list)
      if (remap[ct.edge] != kNone) collapsed.push_back({ct.triangle, remap[ct.edge]});
    std::vector<CollapsedTriangle>().swap(c.collapsed_list);
  } else if (!rescan.empty()) {
    rescanCollapsed(*p.mesh, a.cluster_of.data(), rescan, remap, out.edges, c, collapsed);
    EdgeLists released(0);
    std::swap(released, c.lists);
  }
  computeThickness(p, a, collapsed, out);
  if (c.input_edges)
    for (size_t e = 0; e < en; ++e)
      if (remap[e] != kNone) out.edge_thickness[remap[e]] = std::max(out.edge_thickness[remap[e]], c.input_thickness[e]);
}

}  // namespace

void eliminate(const PreparedMesh& p, const Assignment& a, bool keep_edges, bool keep_points, bool compute_thickness,
               Eliminated& out) {
  const Mesh& m = *p.mesh;
  const uint32_t* co = a.cluster_of.data();
  out.triangles.clear();
  out.edges.clear();
  out.edge_thickness.clear();
  out.points.clear();
  out.collapsed_triangles = 0;

  const size_t tn = m.triangleCount();
  const size_t nc = a.cluster_count;
  // (a little over 2 triangles per cluster, so that a closed surface's 2C - 4 + a few never regrows
  // the output: the extra is about constant, not proportional: the 1 M sphere's chain keeps 2C + 1.9 k
  // / 2.9 k / 2.8 k / 1.7 k triangles at levels 1-4, the bunny's 2C + 6 / 191 / 377 / 112; a regrowth,
  // old and new arrays at once, at the sphere's level 3 was part of its chain's peak with 2C + C/16 + 64)
  const size_t expected = std::min(tn, size_t(2) * nc + nc / 32 + std::min<size_t>(4096, nc / 8));
  out.triangles.reserve(3 * expected);
  const bool input_edges = m.edgeCount() > 0;
  Candidates c(nc, keep_edges || input_edges ? nc : 0, input_edges);
  TriangleTable table(expected, out.triangles, c.point_state.data());
  const bool track_collapsed = compute_thickness && keep_edges;
  if (track_collapsed) {
    c.collapsed_list.reserve(std::min(c.kCollapsedList, tn));
    c.block_first_edge.reserve((tn + kBlock - 1) / kBlock);
  }

  // The triangles are classified in blocks without a branch (kept, collapsed to an edge, collapsed
  // to a point: at coarse levels the three are mixed at random, so a branch on the class
  // mispredicted about once per triangle), each class into its own small list; the lists are then
  // processed in input order, so ids and output order are those of a single pass.
  BlockLists lists;
  const uint32_t* tri = m.triangles.data();
  // where over 3/4 of the triangles of the last block collapsed to a point, the next block tests for that
  // first (a branch that is then predicted) and skips the rest of the classification (the scalar
  // classification only: the AVX2 one costs the same for every class)
  bool points_dominate = false;
  // where over 1/16 of the last block's triangles were kept, the next block's are rotated in lanes
  // (the AVX2 classification only; at the 1 M sphere's 1 % level, 1 % kept, the lanes took 1.0 M
  // instructions more than they saved, 22.22 -> 23.19 M)
  bool rotate_in_lanes = true;
  // Where the cluster ids (4 bytes per vertex) outgrow the cache and the input order is not
  // spatially coherent, the ids of the triangles a little ahead are prefetched: the loop's three
  // random reads are then no longer misses (the 1 M sphere with shuffled vertices and triangles:
  // scalar, 10 % level, eliminate about 42 -> 36 ms; AVX2, 1 % level, 12.2-12.9 -> 10.1-11.6 ms,
  // 10 % within noise). In a coherent order, where nearby triangles share cache lines of the ids,
  // the 24 prefetches per 8 triangles only cost: the 1 M sphere in its generator's ring order, AVX2,
  // 1 % level 6.6-7.2 -> 4.9-5.1 ms without them, 10 % 14.6-15.5 -> 14.1-15.3; scalar, 10 %
  // 16.2-19.2 -> 15.0-15.3, 1 % within noise. Smaller meshes skip them (a test per block,
  // unswitched out of the loop).
  const bool prefetch = a.cluster_of.size() > (size_t(1) << 18) && !coherentOrder(tri, tn);
  // (the gathers take the vertex ids as signed 32-bit offsets)
  const bool avx2 = avx2Paths() && a.cluster_of.size() <= size_t(INT32_MAX);
  // the classification of one block [t0, t1)
  auto classifyBlock = [&](size_t t0, size_t t1, bool prefetch_block) {
    lists.kept_count = lists.edge_count = lists.point_count = 0;
    lists.rotated = avx2 && rotate_in_lanes;
    if (avx2) {
      if (prefetch_block) {
        if (rotate_in_lanes) classifyAvx2<true, true>(tri, co, t0, t1, lists);
        else classifyAvx2<true, false>(tri, co, t0, t1, lists);
      } else {
        if (rotate_in_lanes) classifyAvx2<false, true>(tri, co, t0, t1, lists);
        else classifyAvx2<false, false>(tri, co, t0, t1, lists);
      }
    } else if (prefetch_block) {
      if (points_dominate) classifyScalar<true, true>(tri, co, t0, t1, lists);
      else classifyScalar<true, false>(tri, co, t0, t1, lists);
    } else {
      if (points_dominate) classifyScalar<false, true>(tri, co, t0, t1, lists);
      else classifyScalar<false, false>(tri, co, t0, t1, lists);
    }
  };
  for (size_t t0 = 0; t0 < tn; t0 += kBlock) {
    const size_t t1 = std::min(tn, t0 + kBlock);
    const bool prefetch_block = prefetch && t1 + kPrefetchTriangles <= tn;  // (not the last block)
    classifyBlock(t0, t1, prefetch_block);
    const size_t kept_count = lists.kept_count;
    out.collapsed_triangles += (t1 - t0) - kept_count;
    // for the next block: fine meshes at coarse widths. At 3/4 rather than 7/8: 1 M sphere 1 %, 77 %
    // of the triangles points, eliminate 82.3 -> 70.5 M instructions, 7.2 -> 5.9 ms, mispredicts 59 k ->
    // 120 k; at 2/3 the bunny 2 % level (69 % points) mispredicted 3 x as often, 0.38 -> 0.46 ms
    points_dominate = lists.point_count * 4 > (t1 - t0) * 3;
    rotate_in_lanes = kept_count * 16 > t1 - t0;
    // where the table is past the cache (kPrefetchTableBytes), the home slots of the kept
    // triangles kPrefetchKept ahead are prefetched: each kept triangle's first probe was otherwise
    // a miss, one at a time (the 1 M sphere's 50 % level, a table of 4 MB: 43 % of its elimination's
    // samples on that load)
    const bool prefetch_slots = table.bytes() > kPrefetchTableBytes;
    auto prefetchKept = [&](size_t j) __attribute__((always_inline)) {
      uint32_t c0 = lists.kept[0][j], c1 = lists.kept[1][j], c2 = lists.kept[2][j];
      if (!lists.rotated) rotateSmallestFirst(c0, c1, c2);
      table.prefetch(c0, c1, c2);
    };
    if (prefetch_slots)
      for (size_t j = 0; j < std::min(kept_count, kPrefetchKept); ++j) prefetchKept(j);
    if (lists.rotated)
      for (size_t j = 0; j < kept_count; ++j) {
        if (prefetch_slots && j + kPrefetchKept < kept_count) prefetchKept(j + kPrefetchKept);
        table.add(lists.kept[0][j], lists.kept[1][j], lists.kept[2][j]);
      }
    else
      for (size_t j = 0; j < kept_count; ++j) {
        if (prefetch_slots && j + kPrefetchKept < kept_count) prefetchKept(j + kPrefetchKept);
        uint32_t c0 = lists.kept[0][j], c1 = lists.kept[1][j], c2 = lists.kept[2][j];
        rotateSmallestFirst(c0, c1, c2);
        table.add(c0, c1, c2);
      }
    if (keep_points) {
      size_t point_count = lists.point_count;
      if (g_drop_repeated_edges)
        point_count = avx2 ? dropRepeatedPointsAvx2(lists.point, point_count)
                           : dropRepeatedPointsScalar(lists.point, 0, point_count, 0);
      for (size_t j = 0; j < point_count; ++j) c.addPoint(lists.point[j]);
    }
    if (!keep_edges) continue;
    if (track_collapsed && !c.collapsed_dropped && c.collapsed_list.size() + lists.edge_count > c.kCollapsedList) {
      c.collapsed_dropped = true;
      std::vector<CollapsedTriangle>().swap(c.collapsed_list);
    }
    // the collapsed triangles whose pair repeats the one before are not looked up where nothing
    // lists them one by one (the list of collapsed triangles)
    size_t edge_count = lists.edge_count;
    if (g_drop_repeated_edges && (!track_collapsed || c.collapsed_dropped))
      edge_count = avx2 ? dropRepeatedEdgesAvx2(lists.edge[0], lists.edge[1], edge_count)
                        : dropRepeatedEdgesScalar(lists.edge[0], lists.edge[1], 0, edge_count, 0);
    if (!track_collapsed) {
      for (size_t j = 0; j < edge_count; ++j) c.edge(lists.edge[0][j], lists.edge[1][j]);
    } else {
      const uint32_t block = static_cast<uint32_t>(t0 / kBlock);
      c.block_first_edge.push_back(static_cast<uint32_t>(c.edge_total));
      for (size_t j = 0; j < edge_count; ++j) {
        const uint32_t e = c.edge(lists.edge[0][j], lists.edge[1][j]);
        c.entry(e)[2] = block;
        if (!c.collapsed_dropped) c.collapsed_list.push_back({lists.edge[2][j], e});
      }
    }
  }
  for (size_t e = 0; e < m.edgeCount(); ++e) {
    const uint32_t x = co[m.edges[2 * e]], y = co[m.edges[2 * e + 1]];
    if (x == y) {
      c.addPoint(x);
      continue;
    }
    const uint32_t s = c.edge(x, y);
    c.input_thickness[s] = std::max(c.input_thickness[s], m.edgeThickness(e));
  }
  for (uint32_t v : m.points) c.addPoint(co[v]);
  table.release();
  finishEdges(p, a, compute_thickness, c, out);
}

}  // namespace scenelod::detail
