// Pass 2 of budget mode: each object's upper convex hull of (cost, benefit) over its levels that
// fit the budget alone, plus "not drawn" unless it must be drawn (Mason & Blake 1997: the greedy
// and the Lagrangian price only ever take a hull's points, in the order of its falling ratios).
// The hull is Andrew's monotone chain over the points sorted by cost; in the common case the
// points arrive sorted (not drawn, then coarsest to finest level) and the hull is built as they
// arrive. What the price search needs is summed on the way: every upgrade taken (the pass at
// lambda = 0), none taken, and per segment either the price histogram (Lagrangian form, cold) or,
// with a predicted bracket, the upgrades above it taken and those inside it listed; slots that
// the settling pass (selector_simd.cpp) settles inside the bracket get no hull at all.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

// a settled object's choice is the unique maximiser of benefit - lambda cost on the predicted bracket
// widened by this factor at both ends; far above the float ratios' rounding (about 2^-22 relative)
constexpr double kSettleMargin = 1.0 / 4096.0;

// the largest float at most v
float floatAtMost(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

struct Pt {
  float c, b;
  int l;
};

// One slot's upper hull: points hp and ratios hr[k] = ratio(hp[k - 1], hp[k]) (kept so each test
// divides once); its level bytes go to the context's hull row (-1 becomes kNotDrawn).
struct Hull {
  Pt hp[65];
  float hr[65];
};

// One step of the upper hull over points in sorted order (Andrew's monotone chain): adds p to the
// hn points of `hull` (levels h) and returns their new count.
inline __attribute__((always_inline)) size_t addPoint(Hull* hull, uint8_t* h, size_t hn, const Pt& p) {
  Pt* const hp = hull->hp;
  float* const hr = hull->hr;
  if (hn > 0 && !(p.b > hp[hn - 1].b)) return hn;
  float r_new = 0.0f;
  while (hn >= 1) {
    r_new = SelectorContext::ratio(hp[hn - 1].c, hp[hn - 1].b, p.c, p.b);
    if (hn < 2 || hr[hn - 1] > r_new) break;
    --hn;
  }
  hr[hn] = r_new;
  h[hn] = static_cast<uint8_t>(p.l);
  hp[hn++] = p;
  return hn;
}

// One slot's terms and the frame's row terms: its points as ctx.pointCost / ctx.pointBenefit give them.
struct SlotPoints {
  float sa, sb, sq;
  uint32_t row0;
  int prev;
  const float* row_cost;
  const float* row_inv_w;
  const float* h_mult;  // {1, 1 + hysteresis}

  Pt at(int l) const {
    const uint32_t row = row0 + static_cast<uint32_t>(l);
    // hysteresis by a table lookup, not a branch (x * 1.0f == x, so the values are the same)
    const float acc = std::min(1.0f, sq * row_inv_w[row]) * h_mult[l == prev];
    return Pt{sa + row_cost[row], sb * acc, l};
  }
};

// The hull of points that arrive out of cost order or do not all fit alone: sorted first (cost
// ascending, benefit descending, coarser level first: a total order, so the result does not
// depend on the arrival order), then cut at the first point that cannot fit even alone.
inline __attribute__((always_inline)) size_t sortedHull(const SlotPoints& sp, bool must, int finest,
                                                       int level_count, double avail, uint8_t* h, Hull* hull) {
  Pt pts[65];
  size_t m = 0;
  if (!must) pts[m++] = {0.0f, 0.0f, -1};
  for (int l = level_count - 1; l >= finest; --l) pts[m++] = sp.at(l);
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
  size_t hn = 0;
  for (size_t a = 0; a < m; ++a) {
    if (hn > 0 && static_cast<double>(pts[a].c) - base_cost > avail) break;  // cannot fit even alone
    hn = addPoint(hull, h, hn, pts[a]);
  }
  return hn;
}

// The slot's hull (levels h), as the points arrive when they rise strictly in cost and all fit
// alone (the common case), else sortedHull. Returns its point count.
inline __attribute__((always_inline)) size_t slotHull(const SlotPoints& sp, bool must, int finest, int level_count,
                                                     double avail, uint8_t* h, Hull* hull) {
  size_t hn = 0;
  float last_c = -std::numeric_limits<float>::infinity(), base_cost = 0.0f;
  if (!must) {
    hn = addPoint(hull, h, hn, Pt{0.0f, 0.0f, -1});
    last_c = 0.0f;
  }
  for (int l = level_count - 1; l >= finest; --l) {
    const Pt p = sp.at(l);
    if (hn == 0) base_cost = p.c;
    if (!(p.c > last_c) || static_cast<double>(p.c) - base_cost > avail)
      return sortedHull(sp, must, finest, level_count, avail, h, hull);
    last_c = p.c;
    hn = addPoint(hull, h, hn, p);
  }
  return hn;
}

// The settling pass before the hulls: returns the count of unsettled slots, listed in `unsettled`
// (every slot when a row's cost is negative or NaN, which the settling test cannot take).
size_t settle(const SelectorContext& ctx, const BudgetFrame& frame, const PriceBracket& predicted,
              uint32_t* unsettled, HullSums* sums) {
  if (!frame.rows_nonnegative) {
    for (size_t s = 0; s < frame.slots; ++s) unsettled[s] = static_cast<uint32_t>(s);
    return frame.slots;
  }
  const SettleInput in{ctx.slot_key, ctx.slot_row0, ctx.slot_a, ctx.slot_b, ctx.slot_q,
                       ctx.row_cost, ctx.row_inv_w, ctx.h1, 1.0f, floatAtMost(frame.avail),
                       floatAtMost(frame.avail * (1.0 - 1.0 / 4096.0)), ctx.row_spread, frame.keep,
                       static_cast<float>(predicted.lo / (1.0 + kSettleMargin)),
                       static_cast<float>(predicted.hi * (1.0 + kSettleMargin)),
                       ctx.slot_px, ctx.row_drawn, frame.rows};
  // the write-out's sums fused in when it counts per row (fewer rows than slots)
  sums->fused = frame.rows <= frame.slots;
  const size_t count = settleSlots(ctx.use_avx2, sums->fused, in, frame.slots, ctx.chosen, unsettled, &sums->settled);
  sums->ptotal = sums->settled.cost;
  return count;
}

}  // namespace

HullSums buildHulls(const SelectorContext& ctx, const BudgetFrame& frame, const PriceBracket* predicted) {
  // locals for every array and term: the byte stores below may alias anything reached through a
  // pointer, so values read through ctx or frame would be reloaded after each of them
  const uint8_t* const slot_levels = ctx.slot_levels;
  const float* const slot_a = ctx.slot_a;
  const float* const slot_b = ctx.slot_b;
  const float* const slot_q = ctx.slot_q;
  const uint32_t* const slot_row0 = ctx.slot_row0;
  const int8_t* const slot_prev = ctx.slot_prev;
  const uint8_t* const slot_must = ctx.slot_must;
  const uint8_t* const slot_finest = ctx.slot_finest;
  const float* const row_cost = ctx.row_cost;
  const float* const row_inv_w = ctx.row_inv_w;
  uint8_t* const hull_levels = ctx.hull;
  uint8_t* const hull_count = ctx.hull_count;
  const size_t hull_stride = ctx.hull_stride;
  const double avail = frame.avail;
  double* const hist_cost = ctx.hist_cost;
  uint32_t* const hist_count = ctx.hist_count;
  const int key_shift = frame.hist.key_shift;
  const int64_t key_base = frame.hist.key_base;
  const int64_t inner_buckets = frame.hist.inner_buckets;
  const bool histogram = !predicted && !frame.use_greedy;
  const double plo = predicted ? predicted->lo : 0.0;
  const double phi = predicted ? predicted->hi : 0.0;
  BracketEntry* const bracket = ctx.bracket;
  const size_t capacity = ctx.bracket_capacity;
  uint8_t* const chosen_step = ctx.chosen;
  const float h_mult[2] = {1.0f, ctx.h1};
  HullSums sums{};
  if (histogram) {
    std::memset(hist_cost, 0, static_cast<size_t>(inner_buckets + 2) * sizeof(double));
    std::memset(hist_count, 0, static_cast<size_t>(inner_buckets + 2) * sizeof(uint32_t));
  }
  // settled slots first, then the hulls of the others (all slots when not settling)
  uint32_t* const unsettled = reinterpret_cast<uint32_t*>(ctx.heap);  // the heap is free until the greedy
  const size_t build_count = predicted ? settle(ctx, frame, *predicted, unsettled, &sums) : frame.slots;
  double top_cost = 0.0, base_total = 0.0, base_benefit = 0.0, ptotal = sums.ptotal;
  size_t segments = 0, pcount = 0, pwanted = 0;
  bool poverflow = false;
  Hull hull;
  for (size_t u = 0; u < build_count; ++u) {
    const size_t s = predicted ? unsettled[u] : u;
    const SlotPoints sp{slot_a[s], slot_b[s], slot_q[s], slot_row0[s], slot_prev[s], row_cost, row_inv_w, h_mult};
    const size_t hn = slotHull(sp, slot_must[s] != 0, slot_finest[s], static_cast<int>(slot_levels[s]), avail,
                               hull_levels + s * hull_stride, &hull);
    const Pt* const hp = hull.hp;
    const float* const hr = hull.hr;
    hull_count[s] = static_cast<uint8_t>(hn);
    top_cost += hp[hn - 1].c;
    base_total += hp[0].c;
    base_benefit += hp[0].b;
    segments += hn - 1;
    if (predicted) {
      uint32_t above = 0, inside = 0;  // segments with ratio > phi, > plo (a prefix: ratios fall)
      for (size_t k = 1; k < hn; ++k) {
        above += static_cast<double>(hr[k]) > phi ? 1u : 0u;
        inside += static_cast<double>(hr[k]) > plo ? 1u : 0u;
      }
      // what the collection (budget_lagrangian.cpp) does at (plo, phi], on the same float ratios
      chosen_step[s] = static_cast<uint8_t>(above);
      ptotal += hp[above].c;
      pwanted += inside - above;
      for (size_t k = above + 1; k <= inside; ++k) {
        if (pcount == capacity) {
          poverflow = true;
          break;
        }
        bracket[pcount++] = {hr[k], static_cast<uint32_t>(s), static_cast<uint32_t>(k - 1)};
      }
    } else if (histogram) {
      for (size_t k = 1; k < hn; ++k) {
        uint32_t bits;
        std::memcpy(&bits, &hr[k], sizeof(bits));
        // negative or NaN ratios (bad inputs) land above the window; the collection checks its bound
        int64_t key = static_cast<int64_t>(bits >> key_shift) - key_base + 1;
        key = key < 0 ? 0 : (key > inner_buckets + 1 ? inner_buckets + 1 : key);
        hist_cost[key] += static_cast<double>(hp[k].c) - static_cast<double>(hp[k - 1].c);
        hist_count[key] += 1;
      }
    }
  }
  sums.top_cost = top_cost;
  sums.base_total = base_total;
  sums.base_benefit = base_benefit;
  sums.ptotal = ptotal;
  sums.segments = segments;
  sums.pcount = pcount;
  sums.pwanted = pwanted;
  sums.poverflow = poverflow;
  sums.unsettled_count = build_count;
  return sums;
}

}  // namespace scenelod::selection
