// The Lagrangian form of the budget's greedy (docs/SELECTION.md): at a price lambda every object
// takes the upgrades of its convex hull whose marginal ratio is above lambda, and the total cost
// C(lambda) falls with lambda. A few linear passes (or the price histogram built with the hulls)
// bracket the price at the budget's edge, (lo, hi] with C(hi) <= budget < C(lo) and at most
// bracket_capacity upgrades inside; every upgrade above the bracket is taken and those inside are
// sorted and taken greedily, which chooses what Mason & Blake's heap greedy (budget_greedy.cpp)
// chooses, the Lagrangian relaxation of the multiple-choice knapsack (Sinha & Zoltners 1979) giving
// the price. On a smooth camera last frame's price predicts the bracket: slots settled inside it
// need no hull (budget_hulls.cpp), and a miss or an overflow retries a wider or narrower bracket.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

// predicted bracket (lambda_prev / (1 + w), lambda_prev * (1 + w)]: the bounds of w
constexpr double kPredictWidthMin = 1.0 / 4096.0;
constexpr double kPredictWidthMax = 4.0;
constexpr int kPredictRetries = 2;  // wider (after a miss) or narrower (after an overflow) brackets
                                    // tried before the full search
constexpr double kInf = std::numeric_limits<double>::infinity();

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

struct PassResult {
  double cost = 0.0;        // total object cost with every upgrade of ratio > lambda taken
  size_t below = 0;         // upgrades with ratio in (lo, lambda]
  size_t above = 0;         // upgrades with ratio in (lambda, hi]
};

// The hulls' points as ctx.pointCost / ctx.pointBenefit give them, every array in a local: the
// compiler keeps them in registers instead of reloading the context's arrays for every point.
struct HullPoints {
  const uint8_t* hull;
  const uint8_t* count;
  size_t stride;
  const float* a;
  const float* b;
  const float* q;
  const uint32_t* row0;
  const int8_t* prev;
  const float* row_cost;
  const float* row_inv_w;
  float h1;
};
HullPoints hullPoints(const SelectorContext& ctx) {
  return HullPoints{ctx.hull,   ctx.hull_count, ctx.hull_stride, ctx.slot_a,   ctx.slot_b,    ctx.slot_q,
                    ctx.slot_row0, ctx.slot_prev, ctx.row_cost, ctx.row_inv_w, ctx.h1};
}

// Where a slot's hull walk ended: the point it took (step along the hull) and that point's cost,
// in double like the sums it goes into; stopped when `inside` ended the walk.
struct WalkEnd {
  double cost;
  uint8_t step;
  bool stopped;
};

// Walks slot s's hull from its first point, upgrade by upgrade while the ratio is above lo: the
// upgrades above `take` (a prefix: a hull's ratios fall) are taken, each reported to taken(ratio);
// every later one goes to inside(step, ratio), which returns false to stop the walk. The ratios
// are the floats the hull was built with, compared in double with the price's bounds.
template <typename Taken, typename Inside>
inline __attribute__((always_inline)) WalkEnd walkHull(const HullPoints& pts, size_t s, double lo, double take,
                                                       Taken&& taken, Inside&& inside) {
  const size_t n = pts.count[s];
  const uint8_t* const h = pts.hull + s * pts.stride;
  const float a = pts.a[s], b = pts.b[s], q = pts.q[s];
  const uint32_t row0 = pts.row0[s];
  const int prev = pts.prev[s];
  const float* const rc = pts.row_cost;
  const float* const riw = pts.row_inv_w;
  const float hh = pts.h1;
  auto cost_of = [&](int l) { return l < 0 ? 0.0f : a + rc[row0 + static_cast<uint32_t>(l)]; };
  auto benefit_of = [&](int l) {
    if (l < 0) return 0.0f;
    float acc = std::min(1.0f, q * riw[row0 + static_cast<uint32_t>(l)]);
    if (l == prev) acc *= hh;
    return b * acc;
  };
  size_t k = 0;
  const int l0 = h[0] == kNotDrawn ? -1 : static_cast<int>(h[0]);
  float c0 = cost_of(l0), b0 = benefit_of(l0);
  WalkEnd end{c0, 0, false};
  bool taking = true;
  while (k + 1 < n) {
    const int l1 = h[k + 1] == kNotDrawn ? -1 : static_cast<int>(h[k + 1]);
    const float c1 = cost_of(l1), b1 = benefit_of(l1);
    const float r = SelectorContext::ratio(c0, b0, c1, b1);
    if (static_cast<double>(r) <= lo) break;
    if (taking && static_cast<double>(r) > take) {
      end.cost = c1;
      end.step = static_cast<uint8_t>(k + 1);
      taken(r);
    } else {
      taking = false;
      if (!inside(k, r)) {
        end.stopped = true;
        return end;
      }
    }
    ++k;
    c0 = c1;
    b0 = b1;
  }
  return end;
}

// One linear pass of the price search at lambda: the total cost with every upgrade above lambda
// taken, and the upgrades in (lo, hi] counted on either side of lambda.
PassResult pricePass(const SelectorContext& ctx, size_t slot_count, double lambda, double lo, double hi) {
  const HullPoints pts = hullPoints(ctx);
  double cost = 0.0;
  size_t above = 0, below = 0;
  for (size_t s = 0; s < slot_count; ++s) {
    const WalkEnd end = walkHull(
        pts, s, lo, lambda,
        [&](float r) {
          if (static_cast<double>(r) <= hi) ++above;
        },
        [&](size_t, float) {
          ++below;
          return true;
        });
    cost += end.cost;
  }
  PassResult result;
  result.cost = cost;
  result.above = above;
  result.below = below;
  return result;
}

// the largest float whose bits are below `bits` (0 for none)
double floatBelow(int64_t bits) {
  if (bits <= 0) return 0.0;
  const uint32_t b = static_cast<uint32_t>(bits - 1);
  float f;
  std::memcpy(&f, &b, sizeof(f));
  return static_cast<double>(f);
}

// The price search's state: the bracket (lo, hi] with the total costs at its ends, the price to
// try next, the growth factor while hi is unbounded, and how many upgrades the bracket holds.
struct Search {
  double lo = 0.0, hi = kInf;
  double cost_lo = 0.0, cost_hi = 0.0;
  double lam = 0.0, step = 1.1;
  size_t in_bracket = 0;
};

// The next price to try: growing steps while the bracket is unbounded above, else C interpolated
// linearly between lo and hi, kept off the ends.
double nextPrice(Search* s, double obj_cap) {
  if (s->hi == kInf) {
    const double next = s->lo * s->step;
    s->step *= s->step;
    return next;
  }
  double t = s->cost_lo > s->cost_hi ? (s->cost_lo - obj_cap) / (s->cost_lo - s->cost_hi) : 0.5;
  t = std::min(0.9, std::max(0.1, t));
  return s->lo + t * (s->hi - s->lo);
}

// The bracket from the price histogram: the bucket holding the budget's edge (C at the lower edge
// of bucket j = base_total + the steps of buckets j and above) and a price inside it. Returns
// whether that price lies strictly inside.
bool histogramBracket(const SelectorContext& ctx, const BudgetFrame& frame, const HullSums& hulls, Search* s) {
  const HistWindow& w = frame.hist;
  int64_t j = w.inner_buckets + 1;
  double t = hulls.base_total;
  bool found = t > frame.obj_cap;
  if (!found) {
    for (;; --j) {
      const double t_next = t + ctx.hist_cost[j];
      if (t_next > frame.obj_cap) {
        found = true;
        s->cost_hi = t;
        s->cost_lo = t_next;
        break;
      }
      t = t_next;
      if (j == 0) break;
    }
  }
  if (!found) return false;
  s->lo = j == 0 ? 0.0 : floatBelow((j - 1 + w.key_base) << w.key_shift);
  s->hi = j == w.inner_buckets + 1 ? kInf : floatBelow((j + w.key_base) << w.key_shift);
  s->in_bracket = ctx.hist_count[j];
  s->lam = nextPrice(s, frame.obj_cap);
  return s->lam > s->lo && s->lam < s->hi;
}

// A first price without the histogram: last frame's, else the mean benefit per ms of the finest
// fitting points.
double firstPrice(const SelectorContext& ctx, size_t slots) {
  if (ctx.has_history && ctx.last_lambda > 0.0) return ctx.last_lambda;
  double b = 0.0, c = 0.0;
  for (size_t s = 0; s < slots; ++s) {
    const int l = ctx.hullLevel(s, ctx.hull_count[s] - 1u);
    b += ctx.pointBenefit(s, l);
    c += ctx.pointCost(s, l);
  }
  return c > 0.0 && b > 0.0 ? b / c : 1.0;
}

// The price search: a bracket (lo, hi] of the price with C(hi) <= cap < C(lo) holding at most
// bracket_capacity upgrades. `from_histogram` starts from the histogram's bucket, otherwise from
// last frame's price (the fallback when the histogram's rounded sums disagree with the exact ones).
// Returns false when no bracket separates few enough upgrades (ties).
bool searchPrice(const SelectorContext& ctx, const BudgetFrame& frame, const HullSums& hulls, bool from_histogram,
                 PriceBracket* bracket, uint32_t* passes) {
  const double obj_cap = frame.obj_cap;
  const size_t capacity = ctx.bracket_capacity;
  if (hulls.top_cost <= obj_cap) {
    *bracket = PriceBracket{0.0, 0.0};  // everything fits
    return true;
  }
  // the pass at lambda = 0 (every upgrade taken) was summed while building the hulls
  Search s;
  s.in_bracket = hulls.segments;
  s.cost_lo = hulls.top_cost;
  const bool have_lam = from_histogram && histogramBracket(ctx, frame, hulls, &s);
  if (!have_lam && s.in_bracket > capacity) {
    s.lam = firstPrice(ctx, frame.slots);
    if (!(s.lam > s.lo && s.lam < s.hi)) s.in_bracket = capacity + 1;  // forces the greedy below
  }
  // C(lambda) falls from C(0) = top_cost; find hi with C(hi) <= cap by growing steps from the
  // guess (last frame's price when the camera moves smoothly), then interpolate C linearly
  // between lo and hi, kept off the ends, until few upgrades remain in (lo, hi]
  while (s.in_bracket > capacity && *passes < 64 && s.lam > s.lo && s.lam < s.hi) {
    const PassResult pr = pricePass(ctx, frame.slots, s.lam, s.lo, s.hi);
    ++*passes;
    if (pr.cost <= obj_cap) {
      s.hi = s.lam;
      s.cost_hi = pr.cost;
      s.in_bracket = pr.below;
    } else {
      s.lo = s.lam;
      s.cost_lo = pr.cost;
      s.in_bracket = pr.above;
    }
    if (s.in_bracket <= capacity) break;
    const double next = nextPrice(&s, obj_cap);
    if (!(next > s.lo && next < s.hi)) break;  // no double strictly inside: all ties
    s.lam = next;
  }
  *bracket = PriceBracket{s.lo, s.hi};
  return s.in_bracket <= capacity;
}

enum class Collected { kDone, kOverflow, kEdgeOutside };

// The greedy over the `count` upgrades in ctx.bracket, every upgrade above the bracket taken (cost
// `total`): sorted by ratio, taken while they fit. kEdgeOutside when the bracket does not hold the
// budget's edge (the upgrades above it do not fit, or all of them together do).
Collected bracketGreedy(const SelectorContext& ctx, double obj_cap, const PriceBracket& bracket, size_t count,
                        double total, BudgetChoice* choice) {
  choice->lambda = bracket.hi;
  choice->split_slot = -1;
  if (bracket.hi != kInf && total > obj_cap) return Collected::kEdgeOutside;
  sortBracket(ctx.bracket, ctx.bracket_scratch, count);
  for (size_t e = 0; e < count; ++e) {
    const BracketEntry& be = ctx.bracket[e];
    if (ctx.chosen[be.slot] != be.step) continue;  // an earlier step of this slot did not fit
    const int l0 = ctx.hullLevel(be.slot, be.step), l1 = ctx.hullLevel(be.slot, be.step + 1);
    const double delta = static_cast<double>(ctx.pointCost(be.slot, l1)) - ctx.pointCost(be.slot, l0);
    if (total + delta <= obj_cap) {
      total += delta;
      ctx.chosen[be.slot] = static_cast<uint8_t>(be.step + 1);
      choice->lambda = be.ratio;
    } else {
      choice->split_slot = be.slot;
      choice->split_step = be.step;
      choice->lambda = be.ratio;
      break;
    }
  }
  return choice->split_slot >= 0 || bracket.lo == 0.0 ? Collected::kDone : Collected::kEdgeOutside;
}

// Takes every upgrade above the bracket (lo, hi], collects those inside into ctx.bracket, then
// runs the greedy on them. kOverflow when more than bracket_capacity are inside.
Collected collect(const SelectorContext& ctx, const BudgetFrame& frame, const PriceBracket& range,
                  BudgetChoice* choice) {
  choice->lambda = range.hi;
  choice->split_slot = -1;
  const HullPoints pts = hullPoints(ctx);
  uint8_t* const chosen = ctx.chosen;
  BracketEntry* const bracket = ctx.bracket;
  const size_t capacity = ctx.bracket_capacity;
  double total = 0.0;
  size_t count = 0;
  for (size_t s = 0; s < frame.slots; ++s) {
    const WalkEnd end = walkHull(
        pts, s, range.lo, range.hi, [](float) {},
        [&](size_t k, float r) {
          if (count == capacity) return false;
          bracket[count++] = {r, static_cast<uint32_t>(s), static_cast<uint32_t>(k)};
          return true;
        });
    if (end.stopped) return Collected::kOverflow;
    chosen[s] = end.step;
    total += end.cost;
  }
  return bracketGreedy(ctx, frame.obj_cap, range, count, total, choice);
}

// Ties the bracket cannot separate: the heap greedy gives the same order.
void heapFallback(const SelectorContext& ctx, const BudgetFrame& frame, double hi, BudgetChoice* choice) {
  const uint32_t passes = choice->passes;
  *choice = heapGreedy(ctx, frame.slots, frame.obj_cap, true);
  choice->lambda = hi;
  choice->passes = passes;
}

// The incremental case: the greedy on the bracket predicted from last frame's price. A miss (the
// edge outside the bracket) is retried at twice the width, an overflow at half of it or less (the
// width that would hold about 3/4 of the capacity, from the count of the upgrades inside, stored
// or not), and between a miss and an overflow of the same frame at their geometric mean; each retry
// costs one more settling pass instead of every hull, the histogram and a collection pass. Returns
// false after the last retry, with every hull (and the histogram) built for the full search.
// (no top_cost > obj_cap test: settled objects do not sum it, and when everything fits the
// bracket's greedy finds no split, which is a miss for a bracket above 0)
bool predictedChoice(SelectorContext& ctx, const BudgetFrame& frame, PriceBracket predicted, HullSums* hulls,
                     BudgetChoice* choice) {
  double overflow_width = 0.0, miss_width = 0.0;  // this frame's tries that overflowed / missed
  for (int retry = 0;; ++retry) {
    if (!hulls->poverflow &&
        bracketGreedy(ctx, frame.obj_cap, predicted, hulls->pcount, hulls->ptotal, choice) == Collected::kDone)
      return true;
    // missed: widen the window; overflowed: narrow it (now and next frame)
    const double width = ctx.predict_width;
    double next;
    if (hulls->poverflow) {
      overflow_width = width;
      next = std::min(width * 0.5, width * 0.75 * static_cast<double>(ctx.bracket_capacity) /
                                       static_cast<double>(hulls->pwanted));
      if (miss_width > 0.0) next = std::max(next, std::sqrt(miss_width * width));
    } else {
      miss_width = width;
      next = width * 2.0;
      if (overflow_width > 0.0) next = std::min(next, std::sqrt(overflow_width * width));
    }
    ctx.predict_width = std::min(kPredictWidthMax, std::max(kPredictWidthMin, next));
    if (retry == kPredictRetries || ctx.predict_width == width) {
      // settled objects have no full hull, and the search needs the histogram
      *hulls = buildHulls(ctx, frame, nullptr);
      return false;
    }
    predicted = predictedBracket(ctx);
    *hulls = buildHulls(ctx, frame, &predicted);
  }
}

}  // namespace

HistWindow histogramWindow(const SelectorContext& ctx, size_t slots, bool use_greedy) {
  HistWindow w;
  const int sub_bits = std::min(kHistMaxSubBits, std::max(4, static_cast<int>(std::log2(static_cast<double>(slots + 1))) - 5));
  w.key_shift = 23 - sub_bits;
  w.inner_buckets = int64_t(kHistBinades) << sub_bits;  // buckets 1..inner; 0 below, inner + 1 above
  if (use_greedy) return w;
  // centred on last frame's price, else on the benefit per ms of the finest candidates of about
  // 256 sampled slots
  double centre = ctx.has_history && ctx.last_lambda > 0.0 ? ctx.last_lambda : 0.0;
  if (!(centre > 0.0) && slots > 0) {
    double b = 0.0, c = 0.0;
    const size_t step = std::max<size_t>(1, slots / 256);
    for (size_t s = 0; s < slots; s += step) {
      b += ctx.slot_b[s];
      c += static_cast<double>(ctx.slot_a[s]) + ctx.row_cost[ctx.slot_row0[s] + ctx.slot_finest[s]];
    }
    centre = c > 0.0 && b > 0.0 ? b / c : 1.0;
  }
  const float centre_f = static_cast<float>(std::min(centre, 1e30));
  uint32_t centre_bits;
  std::memcpy(&centre_bits, &centre_f, sizeof(centre_bits));
  const int e0 = std::min(255 - kHistBinades, std::max(1, static_cast<int>((centre_bits >> 23) & 0xff) - kHistBinades / 2));
  w.key_base = int64_t(e0) << sub_bits;
  return w;
}

bool pricePredictable(const SelectorContext& ctx) {
  return ctx.has_history && ctx.last_lambda > 0.0 && std::isfinite(ctx.last_lambda);
}

PriceBracket predictedBracket(const SelectorContext& ctx) {
  return PriceBracket{ctx.last_lambda / (1.0 + ctx.predict_width), ctx.last_lambda * (1.0 + ctx.predict_width)};
}

BudgetChoice lagrangianChoice(SelectorContext& ctx, const BudgetFrame& frame, const PriceBracket* predicted,
                              HullSums* hulls) {
  BudgetChoice choice;
  if (predicted && predictedChoice(ctx, frame, *predicted, hulls, &choice)) return choice;
  // first from the histogram; if its rounded sums put the edge outside the bucket that the exact
  // sums find (the budget within rounding of a bucket edge), again by passes from last frame's price
  for (int attempt = 0; attempt < 2; ++attempt) {
    PriceBracket range{0.0, 0.0};
    if (!searchPrice(ctx, frame, *hulls, attempt == 0, &range, &choice.passes)) {
      heapFallback(ctx, frame, range.hi, &choice);
      break;
    }
    const Collected result = collect(ctx, frame, range, &choice);
    if (result == Collected::kOverflow) {
      heapFallback(ctx, frame, range.hi, &choice);
      break;
    }
    if (result == Collected::kDone) break;
  }
  return choice;
}

}  // namespace scenelod::selection
