// The AVX2 variants of the floating-cell assignment's flat grids (floating_cell_cluster.cpp has the
// baseline ones and picks these at run time, where the CPU has AVX2): the 27 heads of a vertex's
// cubes gathered as 9 rows of 4 loads with one compaction per pair of rows, and the cells tested 8
// at a time. The lanes use testCellLanes' operations (no FMA: "avx2" alone never contracts
// a * b + c) and keep the same order on (d^2, id), so the cell chosen, and every bit after it, is
// the same (tests/lodcore/floating_cell_test.cpp, floating_cache_test.cpp).
#include <atomic>
#include <utility>

#include "floating_cell_internal.h"
#include "test_hooks.h"

#if defined(SCENELOD_FLOATING_AVX2)

namespace scenelod::detail {

using namespace floating;

namespace {

// The packing of the non-empty heads among 8 lanes (two rows: lanes 0-2 and 4-6 of a pair of
// 4-head loads) takes kLaneCompaction's row of their mask.

// the non-zero heads of rows r0 and r1 (three each) appended to found[count ..); writes 8 entries
SCENELOD_FLOATING_AVX2_TARGET inline uint32_t packRows(const uint32_t* r0, const uint32_t* r1, uint32_t valid,
                                                       uint32_t* found, uint32_t count) {
  const __m256i v = _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r0))),
                                            _mm_loadu_si128(reinterpret_cast<const __m128i*>(r1)), 1);
  const uint32_t zero = uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(v, _mm256_setzero_si256()))));
  const uint32_t m = ~zero & valid;
  const __m256i perm = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[m])));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(found + count), _mm256_permutevar8x32_epi32(v, perm));
  return count + uint32_t(_mm_popcnt_u32(m));
}

// the non-empty heads of the 3 x 3 x 3 cubes from base (rows at base + row_offset[0 .. 9)) into
// found; their count. Each load takes a fourth head (inside the grid: a row spans dims[0] >= 7 cubes
// and lo + 3 is at most dims[0] - 1), masked off; the rows go in pairs, the last alone.
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t gatherRows27(const uint32_t* base, const size_t row_offset[9], uint32_t* found) {
  const size_t* r = row_offset;
  uint32_t count = packRows(base + r[0], base + r[1], 0x77u, found, 0);
  count = packRows(base + r[2], base + r[3], 0x77u, found, count);
  count = packRows(base + r[4], base + r[5], 0x77u, found, count);
  count = packRows(base + r[6], base + r[7], 0x77u, found, count);
  return packRows(base + r[8], base + r[8], 0x07u, found, count);
}

// floorToInt per lane
SCENELOD_FLOATING_AVX2_TARGET inline __m128i floorToInt4(__m128 x) {
  const __m128i t = _mm_cvttps_epi32(x);
  return _mm_add_epi32(t, _mm_castps_si128(_mm_cmplt_ps(x, _mm_cvtepi32_ps(t))));
}

// a vertex's position in grid units and its searched range of cubes (lo, hi), x, y, z in lanes 0-2
struct Located {
  __m128 q4;
  __m128i lo4, hi4;
};

// The flat grids' per-level constants in lanes: at(pv) is a vertex's range of cubes along the three
// axes at once, with the scalar path's operations per lane ((q - reach) - slack and floorToInt's
// truncation and correction); row_offset, the offsets of the 9 rows of 3 x 3 x 3 cubes from the first.
struct Locator {
  Locator(const DenseGrid& grid, float cube_width, float reach, const int32_t lo_cube[3])
      : inv4(_mm_set1_ps(1.0f / cube_width)), reach4(_mm_set1_ps(reach)),
        slack4(_mm_set1_ps(kSearchSlack * 2.0f * reach)), lo_cube4(_mm_setr_epi32(lo_cube[0], lo_cube[1], lo_cube[2], 0)) {
    for (int z = 0; z < 3; ++z)
      for (int y = 0; y < 3; ++y) row_offset[3 * z + y] = size_t(z) * grid.sz + size_t(y) * grid.sy;
  }
  SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE Located at(const glm::vec3& pv) const {
    Located l;
    l.q4 = _mm_mul_ps(_mm_setr_ps(pv.x, pv.y, pv.z, 0.0f), inv4);
    l.lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(l.q4, reach4), slack4)), lo_cube4);
    l.hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(l.q4, reach4), slack4)), lo_cube4);
    return l;
  }
  // the cube holding a position in grid units (q4), x, y, z
  SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE void cubeOf(__m128 q4, int32_t c[3]) const {
    const __m128i c4 = _mm_sub_epi32(floorToInt4(q4), lo_cube4);
    c[0] = _mm_cvtsi128_si32(c4), c[1] = _mm_extract_epi32(c4, 1), c[2] = _mm_extract_epi32(c4, 2);
  }
  __m128 inv4, reach4, slack4;
  __m128i lo_cube4;
  size_t row_offset[9];
};

// a new cluster for vertex v, whose cell at pv (q4 in grid units) is listed in the cube holding it
// (its coordinates into c); returns the cluster's id
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t addCell(DenseGrid& grid, const Locator& loc, __m128 q4,
                                                                      const glm::vec3& pv, uint32_t v, Assignment& out,
                                                                      int32_t c[3]) {
  const uint32_t id = out.cluster_count++;
  out.heaviest.push_back(v);
  loc.cubeOf(q4, c);
  grid.list(c[0], c[1], c[2], pv, id);
  return id;
}

// testCell's containment in 8 lanes (the same operations): the lanes of the cells centred at (cx, cy,
// cz) that hold the point (px, py, pz), and its d^2 to each
template <bool kCube>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE __m256 inside8(__m256 px, __m256 py, __m256 pz, __m256 cx, __m256 cy,
                                                                    __m256 cz, const JoinRule& rule, __m256& d2) {
  const __m256 dx = _mm256_sub_ps(px, cx), dy = _mm256_sub_ps(py, cy), dz = _mm256_sub_ps(pz, cz);
  d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
  if (!kCube) return _mm256_cmp_ps(d2, _mm256_set1_ps(rule.half2), _CMP_LE_OQ);
  const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  return _mm256_cmp_ps(_mm256_max_ps(_mm256_max_ps(_mm256_and_ps(dx, absmask), _mm256_and_ps(dy, absmask)),
                                     _mm256_and_ps(dz, absmask)),
                       _mm256_set1_ps(rule.half), _CMP_LE_OQ);
}

// cells a and b as the two halves of a vector
template <typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET inline __m256 load2Cells(const CellRecord* cells, uint32_t a, uint32_t b) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&cells[a].x)), _mm_loadu_ps(&cells[b].x), 1);
}

// testCellLanes, 8 lanes: lane k holds list[j + k] (records k and k + 4 share a 128-bit half, so the
// in-half transpose leaves the lanes in list order). Needs 8 spare entries after the list.
template <bool kCube, bool kNearest, typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET inline __m256i testCellLanes8(const CellRecord* cells, uint32_t* list, uint32_t count, __m256 px,
                                                   __m256 py, __m256 pz, const JoinRule& rule, __m256& bd2,
                                                   __m256i& bid) {
  static_assert(sizeof(CellRecord) == 16, "a cell is read as one 16-byte lane");
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(list + count), _mm256_setzero_si256());  // pad with the sentinel
  __m256i chained = _mm256_setzero_si256();
  for (uint32_t j = 0; j < count; j += 8) {
    const __m256 a0 = load2Cells(cells, list[j], list[j + 4]), a1 = load2Cells(cells, list[j + 1], list[j + 5]);
    const __m256 a2 = load2Cells(cells, list[j + 2], list[j + 6]), a3 = load2Cells(cells, list[j + 3], list[j + 7]);
    const __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpacklo_ps(a2, a3);
    const __m256 t2 = _mm256_unpackhi_ps(a0, a1), t3 = _mm256_unpackhi_ps(a2, a3);
    const __m256 cx = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 cy = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 cz = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 cw = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
    __m256 d2;
    const __m256 inside = inside8<kCube>(px, py, pz, cx, cy, cz, rule, d2);
    const __m256i id =
        _mm256_sub_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(list + j)), _mm256_set1_epi32(1));
    const __m256 id_less = _mm256_castsi256_ps(_mm256_cmpgt_epi32(bid, id));
    const __m256 better =
        kNearest ? _mm256_or_ps(_mm256_cmp_ps(d2, bd2, _CMP_LT_OQ),
                                _mm256_and_ps(_mm256_cmp_ps(d2, bd2, _CMP_EQ_OQ), id_less))
                 : id_less;
    const __m256 take = _mm256_and_ps(inside, better);
    bd2 = _mm256_blendv_ps(bd2, d2, take);
    bid = _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(bid), _mm256_castsi256_ps(id), take));
    chained = _mm256_or_si256(chained, _mm256_castps_si256(cw));
  }
  return chained;
}

// laneBest over 8 lanes: the least d2, then the least id among the lanes holding it
template <bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET inline uint32_t laneBest8(__m256 bd2, __m256i bid) {
  __m256i sel = bid;
  if (kNearest) {
    __m256 m = _mm256_min_ps(bd2, _mm256_permute2f128_ps(bd2, bd2, 1));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    sel = _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)),
                                               _mm256_castsi256_ps(bid), _mm256_cmp_ps(bd2, m, _CMP_EQ_OQ)));
  }
  __m128i s = _mm_min_epi32(_mm256_castsi256_si128(sel), _mm256_extracti128_si256(sel, 1));
  s = _mm_min_epi32(s, _mm_shuffle_epi32(s, _MM_SHUFFLE(1, 0, 3, 2)));
  s = _mm_min_epi32(s, _mm_shuffle_epi32(s, _MM_SHUFFLE(2, 3, 0, 1)));
  const int32_t id0 = _mm_cvtsi128_si32(s);
  return id0 == 0x7fffffff ? kNone : uint32_t(id0);
}

// The AVX2 flat-grid loops' shared steps (inlined into each). The non-empty heads of the cubes
// lo..hi along each axis, any span (the uncommon case: a vertex within the slack of a cube face),
// appended to `found` without a branch per head.
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t gatherHeadsAnySpan(const uint32_t* head, size_t sy, size_t sz,
                                                                                 const int32_t lo[3], const int32_t hi[3],
                                                                                 uint32_t* found, uint32_t found_count) {
  for (int32_t z = lo[2]; z <= hi[2]; ++z)
    for (int32_t y = lo[1]; y <= hi[1]; ++y) {
      const uint32_t* row = head + size_t(z) * sz + size_t(y) * sy;
      for (int32_t x = lo[0]; x <= hi[0]; ++x) {
        found[found_count] = row[x];
        found_count += row[x] != 0;
      }
    }
  return found_count;
}

// The cell a vertex at pv joins among the listed cells `found` (padded as testCellLanes8 reads it;
// 64 + 8 entries) and their successors along the lists, one round of 8 lanes per step, or kNone.
template <bool kCube, bool kNearest, typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t bestListedCell8(const CellRecord* cells, uint32_t* found,
                                                                              uint32_t found_count, const glm::vec3& pv,
                                                                              const JoinRule& rule) {
  const __m256 px = _mm256_set1_ps(pv.x), py = _mm256_set1_ps(pv.y), pz = _mm256_set1_ps(pv.z);
  __m256 bd2 = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  __m256i bid = _mm256_set1_epi32(0x7fffffff);
  uint32_t* list = found;
  uint32_t list_count = found_count;
  uint32_t successors[64 + 8];
  for (;;) {
    const __m256i chained = testCellLanes8<kCube, kNearest>(cells, list, list_count, px, py, pz, rule, bd2, bid);
    if (_mm256_testz_si256(chained, chained)) break;
    uint32_t* next_list = list == found ? successors : found;
    list_count = listSuccessors(cells, list, list_count, next_list);
    list = next_list;
  }
  return laneBest8<kNearest>(bd2, bid);
}


// testCellLanes8 and laneBest8 on 8 cells whose indices c ascend along the lanes (0, the sentinel,
// in free lanes), given with their centres (cx, cy, cz: NaN in free lanes): the same cell, found with
// one reduction of d^2 and the first lane holding it, the least id on a tie (for the heaviest rule
// the first inside lane); kNone if none
// the centres of the 8 cells c[0 .. 8) into cx, cy, cz (lane k: c[k]; records k and k + 4 share a
// 128-bit half, so the in-half transpose leaves the lanes in order)
template <typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE void loadCentres8(const CellRecord* cells, const uint16_t* c, __m256& cx,
                                                                       __m256& cy, __m256& cz) {
  const __m256 a0 = load2Cells(cells, c[0], c[4]), a1 = load2Cells(cells, c[1], c[5]);
  const __m256 a2 = load2Cells(cells, c[2], c[6]), a3 = load2Cells(cells, c[3], c[7]);
  const __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpacklo_ps(a2, a3);
  const __m256 t2 = _mm256_unpackhi_ps(a0, a1), t3 = _mm256_unpackhi_ps(a2, a3);
  cx = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  cy = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  cz = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
}

template <bool kCube, bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t testEntry8(const uint16_t* c, __m256 cx, __m256 cy, __m256 cz,
                                                                         __m256 px, __m256 py, __m256 pz,
                                                                         const JoinRule& rule) {
  __m256 d2;
  const __m256 inside = inside8<kCube>(px, py, pz, cx, cy, cz, rule, d2);
  uint32_t lanes = uint32_t(_mm256_movemask_ps(inside));
  if (kNearest) {
    // an inside cell's d^2 is finite (at most 3 (w/2)^2), so +inf elsewhere never ties with it
    const __m256 v = _mm256_blendv_ps(_mm256_set1_ps(std::numeric_limits<float>::infinity()), d2, inside);
    __m256 m = _mm256_min_ps(v, _mm256_permute2f128_ps(v, v, 1));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    lanes &= uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(v, m, _CMP_EQ_OQ)));
  }
  return lanes == 0 ? kNone : uint32_t(c[__builtin_ctz(lanes)]) - 1;
}

// The cells that the vertices of one grid cube of side w/2 test, cached per cube: those listed in
// the 3 x 3 x 3 cubes around it, up to 8, as their indices into the cells (16 bits, ascending, 0 for
// a free place: the sentinel), so that a vertex reads one entry instead of gathering 27 heads and
// walking their lists. An entry is made at its cube's first vertex and kept current by adding each
// new cell to the built entries of the 27 cubes it is near; a cube near more than 8 cells is marked
// (kOverflow) and takes the general path, as does one near a cell whose index needs more than 16
// bits (32-bit heads). Worth it where cells are rare among the vertices (at the bunny's 2 % level
// 700 cells among 35 k vertices: 1,721 entries made, each then read ~20 times; the 1 M sphere's 1 %
// level 5 k cells among 519 k vertices).
// Small, for the chain's memory peak (reached in its width search's coarse probes): entries of
// 16 bytes, and the cubes' entry numbers in bricks of 4 x 4 x 4 cubes allocated where a cube has
// an entry: about 55 KB at the 2 % level. (Entries that kept their cells' centres, and the entry
// numbers in one flat array, were no faster here: tried and not kept.)
class CandidateCache {
 public:
  static constexpr uint16_t kOverflow = 0xffff;
  struct Entry {
    uint16_t cell[8];  // the cells' indices (cluster + 1), ascending, 0 (the sentinel) in free places
  };
  // `reserve_entries`: about the cubes the vertices fall in (0: no cache, nothing allocated)
  CandidateCache(const size_t dims[3], size_t reserve_entries) : bx_((dims[0] + 3) / 4), by_((dims[1] + 3) / 4) {
    if (reserve_entries == 0) return;
    top_.assign(bx_ * by_ * ((dims[2] + 3) / 4), 0);
    slots_.reserve((reserve_entries / 16 + 16) * 64);  // 15.6 to 16 entries per brick used (bunny 2-5 %)
    slots_.assign(64, 0);  // brick 0: no entries
    entries_.reserve(reserve_entries + 1);
    entries_.push_back(Entry{});
  }
  const Entry& entry(uint16_t e) const { return entries_[e]; }
  const Entry* entries() const { return entries_.data(); }  // moves when make adds an entry
  // for the caller's SIMD loop: the strides of the bricks' y and z, the bricks (which never move) and
  // the slots (which move when make allocates a brick)
  size_t brickStrideY() const { return bx_; }
  size_t brickStrideZ() const { return bx_ * by_; }
  const uint32_t* bricks() const { return top_.data(); }
  const uint16_t* slots() const { return slots_.data(); }
  // a new entry for cube (x, y, z) holding the cells list[0 .. count), ascending: its number, or
  // kOverflow (the cube marked so) where they are more than 8 or the entry numbers are used up
  uint16_t make(int32_t x, int32_t y, int32_t z, const uint32_t* list, uint32_t count) {
    uint16_t& slot = slotFor(x, y, z);
    if (count > 8 || entries_.size() >= kOverflow || (count > 0 && list[count - 1] > 0xffff)) {
      slot = kOverflow;
      return kOverflow;
    }
    const uint16_t number = uint16_t(entries_.size());
    slot = number;
    Entry e{};
    for (uint32_t k = 0; k < count; ++k) e.cell[k] = uint16_t(list[k]);
    entries_.push_back(e);
    return number;
  }
  // cell index c (the newest: entries stay ascending) in cube (cx, cy, cz), into the built entries of
  // the 27 cubes whose 3 x 3 x 3 hold that cube
  void add(int32_t cx, int32_t cy, int32_t cz, uint32_t c) {
    // the brick and in-brick parts of the three coordinates on each axis once
    size_t xb[3], xi[3], yb[3], yi[3], zb[3], zi[3];
    for (int k = 0; k < 3; ++k) {
      xb[k] = size_t((cx - 2 + k) >> 2), xi[k] = size_t((cx - 2 + k) & 3);
      yb[k] = size_t((cy - 2 + k) >> 2) * bx_, yi[k] = size_t((cy - 2 + k) & 3) << 2;
      zb[k] = size_t((cz - 2 + k) >> 2) * bx_ * by_, zi[k] = size_t((cz - 2 + k) & 3) << 4;
    }
    // the slots holding a built entry first, without a branch per slot (which of the 27 do is
    // random: the test per slot mispredicted about twice per new cell, 8.5 k times at the bunny's
    // chain level 3, with 1,681 cells), then those entries
    uint16_t* built[27];
    uint32_t built_count = 0;
    for (int z = 0; z < 3; ++z)
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 3; ++x) {
          // brick 0's slots are all 0 (none built): one test for no brick, no entry or overflow
          uint16_t* slot = &slots_[size_t(top_[zb[z] + yb[y] + xb[x]]) << 6 | zi[z] | yi[y] | xi[x]];
          built[built_count] = slot;
          built_count += uint16_t(*slot - 1) < kOverflow - 1;
        }
    for (uint32_t b = 0; b < built_count; ++b) {
      uint16_t& slot = *built[b];
      Entry& e = entries_[slot];
      // the free places (a full entry has none), without a loop whose exit would mispredict
      const uint32_t free_places = uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi16(
                                       _mm_loadu_si128(reinterpret_cast<const __m128i*>(e.cell)), _mm_setzero_si128()))) &
                                   0x5555u;
      if (free_places == 0 || c > 0xffff) {  // full, or a cell index past 16 bits (32-bit heads)
        slot = kOverflow;
        continue;
      }
      const int k = __builtin_ctz(free_places) >> 1;
      e.cell[k] = uint16_t(c);
    }
  }

 private:
  size_t brick(int32_t x, int32_t y, int32_t z) const {
    return (size_t(z >> 2) * by_ + size_t(y >> 2)) * bx_ + size_t(x >> 2);
  }
  static size_t inBrick(int32_t x, int32_t y, int32_t z) { return size_t((z & 3) << 4 | (y & 3) << 2 | (x & 3)); }
  uint16_t& slotFor(int32_t x, int32_t y, int32_t z) {
    uint32_t& b = top_[brick(x, y, z)];
    if (b == 0) {
      b = uint32_t(slots_.size() >> 6);
      slots_.resize(slots_.size() + 64, 0);
    }
    return slots_[size_t(b) << 6 | inBrick(x, y, z)];
  }
  size_t bx_, by_;                 // bricks along x and y
  std::vector<uint32_t> top_;      // per brick position: its brick, 0 for the shared empty one
  std::vector<uint16_t> slots_;    // 64 per brick: the cubes' entry numbers
  std::vector<Entry> entries_;     // entries_[0] unused
};

// assignDenseT on AVX2 (see there): the same grid, cells and order of creation; the gather of the
// 3 x 3 x 3 heads packs pairs of rows (packRows) instead of 27 scalar steps, and the cells found
// are tested 8 at a time
template <bool kCube, bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET void assignDenseAvx2T(const PreparedMesh& p, float cube_width, float reach,
                                                    const int32_t lo_cube[3], const size_t dims[3], JoinRule rule,
                                                    size_t expected, Assignment& out) {
  DenseGrid grid(dims, expected);  // as in assignDenseT
  auto& cells = grid.cells;
  auto& head = grid.head;
  const size_t sy = grid.sy, sz = grid.sz;
  const Locator loc(grid, cube_width, reach, lo_cube);
  const size_t* row_offset = loc.row_offset;
  const size_t n = p.order.size();
  const PositionsByWeight sorted(p);  // (as in assignDenseT)
  // the next vertex's range and the offset of its first cube in the flat array, a vertex ahead
  Located ahead{};
  size_t ahead_offset = 0;
  glm::vec3 ahead_pv{0.0f};
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    ahead_pv = sorted[k];
    ahead = loc.at(ahead_pv);
    // lo >= 0: lo_cube is 3 cubes below the box
    ahead_offset = size_t(uint32_t(_mm_extract_epi32(ahead.lo4, 2))) * sz +
                   size_t(uint32_t(_mm_extract_epi32(ahead.lo4, 1))) * sy + size_t(uint32_t(_mm_cvtsi128_si32(ahead.lo4)));
  };
  // the order and cluster_of as plain pointers (through the vectors, each vertex reloaded their data
  // pointers: heaviest's push_back may, for the compiler, change them)
  const uint32_t* const order = p.order.data();
  uint32_t* const cluster_of = out.cluster_of.data();
  if (n > 0) plan(0);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 pv = ahead_pv;
    const Located here = ahead;
    const size_t offset = ahead_offset;
    if (i + 1 < n) plan(i + 1);
    const __m128 q4 = here.q4;
    const __m128i lo4 = here.lo4, hi4 = here.hi4;
    const __m128i span = _mm_sub_epi32(hi4, lo4);
    uint32_t found[64 + 8];  // 8 spare: packRows and testCellLanes8 write 8 entries
    uint32_t found_count = 0;
    const int32_t lo[3] = {_mm_cvtsi128_si32(lo4), _mm_extract_epi32(lo4, 1), _mm_extract_epi32(lo4, 2)};
    if ((_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(span, _mm_set1_epi32(2)))) & 7) == 7) {
      // 9 rows of 3 heads; each load takes a fourth head (inside the grid: a row spans dims[0] >= 7
      // cubes and lo + 3 is at most dims[0] - 1), masked off. The rows go in pairs, the last alone.
      const uint32_t* base = head.data() + offset;
      const size_t* r = row_offset;
      found_count = packRows(base + r[0], base + r[1], 0x77u, found, found_count);
      found_count = packRows(base + r[2], base + r[3], 0x77u, found, found_count);
      found_count = packRows(base + r[4], base + r[5], 0x77u, found, found_count);
      found_count = packRows(base + r[6], base + r[7], 0x77u, found, found_count);
      found_count = packRows(base + r[8], base + r[8], 0x07u, found, found_count);
    } else if ((_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(span, _mm_set1_epi32(1)))) & 7) == 7) {
      // 2 x 2 x 2 cubes (the grid of side w): 4 rows of 2 heads, in two pairs
      const uint32_t* base = head.data() + offset;
      const size_t* r = row_offset;
      found_count = packRows(base + r[0], base + r[1], 0x33u, found, found_count);
      found_count = packRows(base + r[3], base + r[4], 0x33u, found, found_count);
    } else {
      const int32_t hi[3] = {_mm_cvtsi128_si32(hi4), _mm_extract_epi32(hi4, 1), _mm_extract_epi32(hi4, 2)};
      found_count = gatherHeadsAnySpan(head.data(), sy, sz, lo, hi, found, found_count);
    }
    uint32_t best = bestListedCell8<kCube, kNearest>(cells.data(), found, found_count, pv, rule);
    if (best == kNone) {
      int32_t c[3];
      best = addCell(grid, loc, q4, pv, order[i], out, c);
    }
    cluster_of[order[i]] = best;
  }
}


// setFloatingCacheRunsForTest's choice: -1 the default (runs where the bricks' strides allow them),
// 0 no runs, 1 runs
std::atomic<int> g_cache_runs{-1};

// An entry's cells where at most 8 heads were found and each lists one cell (cube cells: a cube of
// side w/2 lists at most one): found[0 .. count) sorted into listed[0 .. count), each placed at its
// rank (the number of smaller ones), without a branch per cell; false (nothing sorted) where a list
// is longer. found must have 8 places; listed, 9. The walk along the lists with an insertion sort
// mispredicted about 2.3 times per entry made (9.6 k at the bunny's chain level 3, 4,265 entries).
template <typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE bool sortLoneHeads8(const CellRecord* cells, uint32_t* found,
                                                                         uint32_t count, uint32_t* listed) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i used = _mm256_cmpgt_epi32(_mm256_set1_epi32(int32_t(count)), lane);
  // the free lanes at 0 (the sentinel, whose next is 0)
  const __m256i v = _mm256_and_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(found)), used);
  alignas(32) uint32_t c[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(c), v);
  uint32_t chained = 0;
  for (int k = 0; k < 8; ++k) chained |= cells[c[k]].next;
  if (chained != 0) return false;
  // the indices (below 2^31) ranked with the free lanes past them all
  const __m256i key = _mm256_blendv_epi8(_mm256_set1_epi32(0x7fffffff), v, used);
  alignas(32) int32_t keys[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(keys), key);
  for (int k = 0; k < 8; ++k) {
    const uint32_t rank = uint32_t(
        _mm_popcnt_u32(uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(keys[k]), key))))));
    listed[rank] = c[k];  // a free lane writes listed[count], past the cells
  }
  return true;
}

// What cachedRun reads: plain pointers and constants, copied into registers. The cache's pointers
// are taken at each call (make moves them, and make is never called inside a run).
template <typename CellRecord>
struct CachedRunInputs {
  const CellRecord* cells;
  const CandidateCache::Entry* entries;
  const uint32_t* cache_bricks;
  const uint16_t* slots;
  const glm::vec3* positions;  // sorted (kSorted) or indexed by the order
  const uint32_t* order;
  uint32_t* cluster_of;
  __m128 inv4, reach4, slack4;
  __m128i lo_cube4, brick_stride4;
  JoinRule rule;
};

// assignDenseCachedAvx2T's common vertex, in a loop of its own that calls nothing, so that its state
// stays in registers (inside the whole loop, with the rare paths' calls and the cache's vectors, the
// compiler kept the counter, the pointers and the position on the stack: ~199 instructions a vertex
// at the bunny's chain level 4, of which ~40 loads and stores of these): a vertex whose 3 x 3 x 3
// cubes have an entry and which is inside one of its cells. From vertex i on, it joins such vertices
// and returns the first one that is not (it or one of the last two: the caller takes that one).
// Each vertex's entry is found two vertices ahead: the loop is bound by the latency from a position
// to its cell (~100 cycles: the range, the brick, the slot, the centres, d^2, the reduction) over
// the reorder window, not by its ~100 instructions; one vertex ahead, levels 4, 6 and 8 took
// 0.51, 0.39 and 0.34 ms instead of 0.42-0.47, 0.32-0.34 and 0.28-0.29 (three ahead: no better).
template <bool kCube, bool kNearest, bool kSorted, typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET __attribute__((noinline)) size_t cachedRun(const CachedRunInputs<CellRecord>& in, size_t i,
                                                                          size_t n) {
  const CellRecord* const cells = in.cells;
  const CandidateCache::Entry* const entries = in.entries;
  const uint32_t* const cache_bricks = in.cache_bricks;
  const uint16_t* const slots = in.slots;
  const glm::vec3* const positions = in.positions;
  const uint32_t* const order = in.order;
  uint32_t* const cluster_of = in.cluster_of;
  const __m128 inv4 = in.inv4, reach4 = in.reach4, slack4 = in.slack4;
  const __m128i lo_cube4 = in.lo_cube4, brick_stride4 = in.brick_stride4;
  const JoinRule rule = in.rule;
  // vertex k's position, its vertex index and its entry (0 where it has none or its cubes are not
  // 3 x 3 x 3)
  struct Planned {
    const float* pv;
    uint32_t v;
    uint32_t e;
  };
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    Planned pl;
    pl.v = order[k];
    pl.pv = &positions[kSorted ? k : pl.v].x;
    // x, y from one 8-byte load (movq, unaligned-safe: _mm_load_sd would dereference a double* at a
    // float's alignment), z inserted (a 16-byte load could read past the positions)
    const __m128 pk = _mm_insert_ps(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(pl.pv))),
                                    _mm_load_ss(pl.pv + 2), 0x20);
    // the caller's operations per lane ((q - reach) - slack and floorToInt's truncation and correction)
    const __m128 q4 = _mm_mul_ps(pk, inv4);
    const __m128i lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(q4, reach4), slack4)), lo_cube4);
    const __m128i hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(q4, reach4), slack4)), lo_cube4);
    const bool span2 =
        (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_sub_epi32(hi4, lo4), _mm_set1_epi32(2)))) & 7) == 7;
    // the brick (lanes' sum) and in-brick place (lanes' or, the same as their sum: disjoint bits) of
    // cube lo, both summed by two horizontal additions; lane 3 is 0 in both (a stride of 0, a shift of 32)
    // the products by 16-bit halves (vpmaddwd, 5 cycles of latency on the way to the entry, against
    // vpmulld's 10): the bricks' coordinates and strides fit 15 bits (assignDenseCachedAvx2T)
    // lo is inside the grid even where the span is not 2 (lo_cube is 3 cubes below the box)
    const __m128i bm = _mm_madd_epi16(_mm_srai_epi32(lo4, 2), brick_stride4);
    const __m128i im = _mm_sllv_epi32(_mm_and_si128(lo4, _mm_set1_epi32(3)), _mm_setr_epi32(0, 2, 4, 32));
    const __m128i sums = _mm_hadd_epi32(_mm_hadd_epi32(bm, im), _mm_setzero_si128());
    const uint32_t e =
        slots[size_t(cache_bricks[uint32_t(_mm_cvtsi128_si32(sums))]) << 6 | uint32_t(_mm_extract_epi32(sums, 1))];
    pl.e = span2 ? e : 0;
    return pl;
  };
  if (i + 2 >= n) return i;
  Planned here = plan(i), next = plan(i + 1);
  for (; i + 2 < n; ++i) {
    const Planned after = plan(i + 2);
    // 0 (no entry) and kOverflow: the caller's paths
    if (uint16_t(here.e - 1) >= CandidateCache::kOverflow - 1) break;
    __m256 cx, cy, cz;
    loadCentres8(cells, entries[here.e].cell, cx, cy, cz);
    const uint32_t best =
        testEntry8<kCube, kNearest>(entries[here.e].cell, cx, cy, cz, _mm256_broadcast_ss(here.pv),
                                    _mm256_broadcast_ss(here.pv + 1), _mm256_broadcast_ss(here.pv + 2), rule);
    if (best == kNone) break;
    cluster_of[here.v] = best;
    here = next;
    next = after;
  }
  return i;
}

// assignDenseAvx2T with a CandidateCache (see there): the vertices whose 3 x 3 x 3 cubes' cells are
// in an entry test those; the others (wide ranges, overflowing entries) take assignDenseAvx2T's path.
// kRuns: the common vertices go through cachedRun (see there)
template <bool kCube, bool kNearest, bool kRuns>
SCENELOD_FLOATING_AVX2_TARGET void assignDenseCachedAvx2Impl(const PreparedMesh& p, float cube_width, float reach,
                                                             const int32_t lo_cube[3], const size_t dims[3], JoinRule rule,
                                                             size_t expected, Assignment& out) {
  const size_t n = p.order.size();
  DenseGrid grid(dims, expected);  // as in assignDenseT
  auto& cells = grid.cells;
  auto& head = grid.head;
  const size_t sy = grid.sy, sz = grid.sz;
  const Locator loc(grid, cube_width, reach, lo_cube);
  const __m128 inv4 = loc.inv4, reach4 = loc.reach4, slack4 = loc.slack4;
  const __m128i lo_cube4 = loc.lo_cube4;
  const size_t* row_offset = loc.row_offset;
  // entries for the cubes the vertices fall in: 2.6 and 2.4 per expected cell at the bunny's 2 % and
  // 10 % levels
  CandidateCache cache(dims, expected * 3);
  const uint32_t* const cache_bricks = cache.bricks();
  const uint16_t* slots = cache.slots();
  // lane 3 of lo4 is not a coordinate: a stride of 0, a shift of 32 (0)
  const __m128i brick_stride4 = _mm_setr_epi32(1, int32_t(cache.brickStrideY()), int32_t(cache.brickStrideZ()), 0);
  const __m128i in_brick_shift4 = _mm_setr_epi32(0, 2, 4, 32);
  const PositionsByWeight sorted(p);  // (as in assignDenseT)
  // vertex k's range and the place of its cube in the cache (cache.find with the three axes at once:
  // the scalar form took 30 instructions a vertex), a vertex ahead (as in assignDenseAvx2T; the
  // bricks themselves may be allocated meanwhile), or for the vertices cachedRun leaves. The first
  // head's offset, needed by the few vertices that gather, is not (ahead, it cost 9 instructions a vertex)
  Located ahead{};
  uint32_t ahead_brick = 0, ahead_in_brick = 0;
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    ahead = loc.at(sorted[k]);
    const __m128i lo4 = ahead.lo4;
    const __m128i bm = _mm_mullo_epi32(_mm_srai_epi32(lo4, 2), brick_stride4);
    const __m128i im = _mm_sllv_epi32(_mm_and_si128(lo4, _mm_set1_epi32(3)), in_brick_shift4);
    __m128i bs = _mm_add_epi32(bm, _mm_shuffle_epi32(bm, _MM_SHUFFLE(1, 0, 3, 2)));
    __m128i is = _mm_or_si128(im, _mm_shuffle_epi32(im, _MM_SHUFFLE(1, 0, 3, 2)));
    bs = _mm_add_epi32(bs, _mm_shuffle_epi32(bs, _MM_SHUFFLE(2, 3, 0, 1)));
    is = _mm_or_si128(is, _mm_shuffle_epi32(is, _MM_SHUFFLE(2, 3, 0, 1)));
    ahead_brick = uint32_t(_mm_cvtsi128_si32(bs));
    ahead_in_brick = uint32_t(_mm_cvtsi128_si32(is));
  };
  // the order and cluster_of as plain pointers: through the vectors, each vertex reloaded both data
  // pointers from the stack and from p and out (the rare paths' calls may, for the compiler, change
  // them), 6 of the ~190 instructions a vertex at the 1 M sphere's 1 % level
  const uint32_t* const order = p.order.data();
  uint32_t* const cluster_of = out.cluster_of.data();
  const bool by_order = sorted.sorted == nullptr;
  CachedRunInputs<DenseGrid::Cell> run_in{nullptr, nullptr, cache_bricks, nullptr,
                                          by_order ? sorted.positions : sorted.sorted, order, cluster_of,
                                          inv4, reach4, slack4, lo_cube4, brick_stride4, rule};
  // the vertices from k on that their entries settle; the first that needs more
  auto runFrom = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    run_in.entries = cache.entries();
    run_in.cells = cells.data();
    run_in.slots = cache.slots();
    return by_order ? cachedRun<kCube, kNearest, false>(run_in, k, n) : cachedRun<kCube, kNearest, true>(run_in, k, n);
  };
  // without runs (grids whose bricks' strides pass 15 bits, and a test's choice) as before them
  if (n > 0 && !kRuns) plan(0);
  for (size_t i = 0; i < n; ++i) {
    // after a run, vertex i: its cubes not 3 x 3 x 3, no entry yet or an overflowing one, inside
    // none of its entry's cells (a new cell), or the last vertex
    if constexpr (kRuns) {
      i = runFrom(i);
      plan(i);
    }
    const glm::vec3 pv = sorted[i];
    const __m128 q4 = ahead.q4;
    const __m128i lo4 = ahead.lo4, hi4 = ahead.hi4;
    const uint32_t brick_at = ahead_brick, in_brick = ahead_in_brick;
    if (!kRuns && i + 1 < n) plan(i + 1);
    const __m128i span = _mm_sub_epi32(hi4, lo4);
    const bool span2 = (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(span, _mm_set1_epi32(2)))) & 7) == 7;
    uint32_t found[64 + 8];  // 8 spare: packRows and testCellLanes8 write 8 entries
    uint32_t found_count = 0;
    const int32_t lo[3] = {_mm_cvtsi128_si32(lo4), _mm_extract_epi32(lo4, 1), _mm_extract_epi32(lo4, 2)};
    uint32_t best = kNone;
    bool tested = false;
    if (span2) {
      uint16_t e = slots[size_t(cache_bricks[brick_at]) << 6 | in_brick];
      if (e == 0) {  // the cube's first vertex: its cells from the heads and lists, by index
        const uint32_t heads =
            gatherRows27(head.data() + size_t(lo[2]) * sz + size_t(lo[1]) * sy + size_t(lo[0]), row_offset, found);
        uint32_t listed[27 * 8];
        uint32_t count = 0;
        if (heads > 8 || !sortLoneHeads8(cells.data(), found, heads, listed)) {
          for (uint32_t j = 0; j < heads; ++j)
            for (uint32_t c = found[j]; c != 0; c = cells[c].next) {
              uint32_t k = count++;
              for (; k > 0 && listed[k - 1] > c; --k) listed[k] = listed[k - 1];
              listed[k] = c;
            }
        } else {
          count = heads;
        }
        e = cache.make(lo[0], lo[1], lo[2], listed, count);
        slots = cache.slots();
      }
      if (e != CandidateCache::kOverflow) {
        const CandidateCache::Entry& entry = cache.entry(e);
        __m256 cx, cy, cz;
        loadCentres8(cells.data(), entry.cell, cx, cy, cz);
        best = testEntry8<kCube, kNearest>(entry.cell, cx, cy, cz, _mm256_set1_ps(pv.x), _mm256_set1_ps(pv.y),
                                           _mm256_set1_ps(pv.z), rule);
        tested = true;
      }
    }
    if (!tested) {  // the general path (reach 1: 3 or 4 cubes per axis)
      if (span2) {
        found_count = gatherRows27(head.data() + size_t(lo[2]) * sz + size_t(lo[1]) * sy + size_t(lo[0]), row_offset, found);
      } else {
        const int32_t hi[3] = {_mm_cvtsi128_si32(hi4), _mm_extract_epi32(hi4, 1), _mm_extract_epi32(hi4, 2)};
        found_count = gatherHeadsAnySpan(head.data(), sy, sz, lo, hi, found, found_count);
      }
      best = bestListedCell8<kCube, kNearest>(cells.data(), found, found_count, pv, rule);
    }
    if (best == kNone) {
      int32_t c[3];
      best = addCell(grid, loc, q4, pv, order[i], out, c);
      cache.add(c[0], c[1], c[2], best + 1);
    }
    cluster_of[order[i]] = best;
  }
}

// the runs wherever the bricks' strides fit 15 bits (on entries of indices, the cells' centres
// gathered and transposed: at the bunny's chain level 3 and 2 % level, where 1 vertex in 6-8 leaves
// a run, 0.84-0.89 -> 0.79-0.86 ms and 0.64 -> 0.54)
template <bool kCube, bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET void assignDenseCachedAvx2T(const PreparedMesh& p, float cube_width, float reach,
                                                          const int32_t lo_cube[3], const size_t dims[3], JoinRule rule,
                                                          size_t expected, Assignment& out) {
  const int forced = g_cache_runs.load(std::memory_order_relaxed);
  // cachedRun's brick places as products of 16-bit halves: the strides of the bricks below 2^15
  const size_t bx = (dims[0] + 3) / 4, by = (dims[1] + 3) / 4, bz = (dims[2] + 3) / 4;
  const bool small_bricks = bx * by < 32768 && bz < 32768;
  if (small_bricks && forced != 0)
    assignDenseCachedAvx2Impl<kCube, kNearest, true>(p, cube_width, reach, lo_cube, dims, rule, expected, out);
  else
    assignDenseCachedAvx2Impl<kCube, kNearest, false>(p, cube_width, reach, lo_cube, dims, rule, expected, out);
}

// assignBlocksT on AVX2: the searched range on the three axes at once, the same copies of the
// first blocks, the cells tested 8 at a time (testCellLanes8, laneBest8)
template <bool kCube, bool kNearest, bool kBricked>
SCENELOD_FLOATING_AVX2_TARGET void assignBlocksAvx2T(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3],
                                                     const size_t dims[3], JoinRule rule, size_t expected,
                                                     size_t brick_count, Assignment& out) {
  struct Cell {
    float x, y, z;
    uint32_t zero;
  };
  std::vector<Cell> cells;
  cells.reserve(CellBlocks<kBricked>::reservedCells(expected, p.order.size()));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cells.push_back({nan, nan, nan, 0});
  CellBlocks<kBricked> grid(dims, expected, brick_count);
  const size_t sy = grid.sy, sz = grid.sz;
  std::vector<uint32_t> scratch;
  const float inv = 1.0f / cube_width;
  const __m128 inv4 = _mm_set1_ps(inv), half4 = _mm_set1_ps(0.5f), slack4 = _mm_set1_ps(kSearchSlack);
  const __m128i lo_cube4 = _mm_setr_epi32(lo_cube[0], lo_cube[1], lo_cube[2], 0);
  const size_t n = p.order.size();
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
  // each vertex's range and (flat) the offset of its first head, planned kBlocksAhead vertices
  // ahead, when its heads' cache lines and its cluster id's slot are prefetched (see kBlocksAhead;
  // bricked, the lines of the bricks the table names then, re-read when the vertex is reached)
  struct Planned {
    Located at;
    size_t offset;
  };
  Planned ring[kBlocksAhead];
  const uint32_t* order = p.order.data();
  uint32_t* cluster_of = out.cluster_of.data();
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    Planned& a = ring[k % kBlocksAhead];
    const glm::vec3 pk = sorted[k];
    a.at.q4 = _mm_mul_ps(_mm_setr_ps(pk.x, pk.y, pk.z, 0.0f), inv4);
    a.at.lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(a.at.q4, half4), slack4)), lo_cube4);
    a.at.hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(a.at.q4, half4), slack4)), lo_cube4);
    // lo >= 0: lo_cube is 3 cubes below the box
    const size_t x = size_t(uint32_t(_mm_cvtsi128_si32(a.at.lo4))), y = size_t(uint32_t(_mm_extract_epi32(a.at.lo4, 1))),
                 z = size_t(uint32_t(_mm_extract_epi32(a.at.lo4, 2)));
    if constexpr (kBricked) {
      a.offset = 0;  // (unused: the bricks are looked up again when the vertex is reached)
      // the z-slices of lo's cubes and of lo + (1, 1, 1)'s (the other cubes' lines but where a
      // row crosses a brick along x or y)
      const uint32_t* top = grid.top.data();
      const size_t in0 = (z & 3) << 4 | (y & 3) << 2, in1 = ((z + 1) & 3) << 4 | ((y + 1) & 3) << 2;
      const size_t b0 = top[(z >> 2) * sz + (y >> 2) * sy + (x >> 2)];
      const size_t b1 = top[((z + 1) >> 2) * sz + ((y + 1) >> 2) * sy + ((x + 1) >> 2)];
      const size_t b2 = top[((z + 1) >> 2) * sz + (y >> 2) * sy + (x >> 2)];
      const size_t b3 = top[(z >> 2) * sz + ((y + 1) >> 2) * sy + ((x + 1) >> 2)];
      const auto* bricks = grid.bricks.data();
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b0].h + in0), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b1].h + in1), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b2].h + (((z + 1) & 3) << 4 | (y & 3) << 2)), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b3].h + ((z & 3) << 4 | ((y + 1) & 3) << 2)), _MM_HINT_T0);
    } else {
      a.offset = z * sz + y * sy + x;
      const uint32_t* h = grid.head.data() + a.offset;
      _mm_prefetch(reinterpret_cast<const char*>(h), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(h + sy), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(h + sz), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(h + sz + sy), _MM_HINT_T0);
    }
    _mm_prefetch(reinterpret_cast<const char*>(cluster_of + order[k]), _MM_HINT_T0);
  };
  for (size_t k = 0; k < std::min(n, kBlocksAhead); ++k) plan(k);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 pv = sorted[i];
    const Planned& planned = ring[i % kBlocksAhead];
    const __m128 q4 = planned.at.q4;
    const __m128i lo4 = planned.at.lo4, hi4 = planned.at.hi4;
    const size_t first = planned.offset;
    if (i + kBlocksAhead < n) plan(i + kBlocksAhead);
    const int32_t lo[3] = {_mm_cvtsi128_si32(lo4), _mm_extract_epi32(lo4, 1), _mm_extract_epi32(lo4, 2)};
    uint32_t found[8 * 5 + 8];  // 8 blocks at counts up to 5, then 8 sentinels of padding
    uint32_t* list = found;
    uint32_t count = 0;
    uint32_t chained = 0;
    const bool narrow =
        (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_sub_epi32(hi4, lo4), _mm_set1_epi32(1)))) & 7) == 7;
    if (narrow) {
      uint32_t h[8];
      grid.heads8(lo, first, h);
      count = grid.copyBlocks8(h, found, chained);
    }
    if (!narrow || (chained & 8u)) {
      const int32_t hi[3] = {_mm_cvtsi128_si32(hi4), _mm_extract_epi32(hi4, 1), _mm_extract_epi32(hi4, 2)};
      count = grid.gatherAll(lo, hi, scratch, 8);
      list = scratch.data();
    }
    __m256 bd2 = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    __m256i bid = _mm256_set1_epi32(0x7fffffff);
    testCellLanes8<kCube, kNearest>(cells.data(), list, count, _mm256_set1_ps(pv.x), _mm256_set1_ps(pv.y),
                                    _mm256_set1_ps(pv.z), rule, bd2, bid);
    uint32_t best = laneBest8<kNearest>(bd2, bid);
    if (best == kNone) {
      best = out.cluster_count;
      const __m128i c4 = _mm_sub_epi32(floorToInt4(q4), lo_cube4);
      grid.add(_mm_cvtsi128_si32(c4), _mm_extract_epi32(c4, 1), _mm_extract_epi32(c4, 2), best + 1);
      ++out.cluster_count;
      out.heaviest.push_back(p.order[i]);
      cells.push_back({pv.x, pv.y, pv.z, 0});
    }
    cluster_of[order[i]] = best;
  }
}

}  // namespace

namespace floating {

void assignDenseAvx2(const PreparedMesh& p, float cube_width, float reach, const int32_t lo_cube[3],
                     const size_t dims[3], JoinRule rule, size_t expected, bool cached, Assignment& out) {
  using Fn = void (*)(const PreparedMesh&, float, float, const int32_t*, const size_t*, JoinRule, size_t,
                      Assignment&);
  static constexpr Fn kFns[2][2][2] = {
      {{assignDenseAvx2T<false, false>, assignDenseAvx2T<false, true>},
       {assignDenseAvx2T<true, false>, assignDenseAvx2T<true, true>}},
      {{assignDenseCachedAvx2T<false, false>, assignDenseCachedAvx2T<false, true>},
       {assignDenseCachedAvx2T<true, false>, assignDenseCachedAvx2T<true, true>}}};
  kFns[cached][rule.cube][rule.nearest](p, cube_width, reach, lo_cube, dims, rule, expected, out);
}

void assignBlocksAvx2(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3], const size_t dims[3],
                      JoinRule rule, size_t expected, bool bricked, size_t brick_count, Assignment& out) {
  using Fn = void (*)(const PreparedMesh&, float, const int32_t*, const size_t*, JoinRule, size_t, size_t,
                      Assignment&);
  static constexpr Fn kFns[2][2][2] = {
      {{assignBlocksAvx2T<false, false, false>, assignBlocksAvx2T<false, true, false>},
       {assignBlocksAvx2T<true, false, false>, assignBlocksAvx2T<true, true, false>}},
      {{assignBlocksAvx2T<false, false, true>, assignBlocksAvx2T<false, true, true>},
       {assignBlocksAvx2T<true, false, true>, assignBlocksAvx2T<true, true, true>}}};
  kFns[bricked][rule.cube][rule.nearest](p, cube_width, lo_cube, dims, rule, expected, brick_count, out);
}

}  // namespace floating

// (test_hooks.h)
int setFloatingCacheRunsForTest(int runs) { return g_cache_runs.exchange(runs < 0 ? -1 : runs > 0 ? 1 : 0); }

}  // namespace scenelod::detail

#else

namespace scenelod::detail {
// without the AVX2 variants the cache and its runs are never taken (test_hooks.h)
int setFloatingCacheRunsForTest(int runs) { return runs; }
}  // namespace scenelod::detail

#endif
