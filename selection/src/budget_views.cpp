// Budget mode with views: one object's upper hull over its level tuples, and the greedy over every
// hull's steps (Mason & Blake 1997's greedy on the hulls, extended from levels to tuples).
//   The tuples obey the rules, so the hull is not the plain Minkowski sum of the groups' hulls: for
//   each level of the primary group (not drawn included) the constrained shadow groups' hulls over
//   their allowed levels (no finer than it; not drawn when it is not drawn) are summed onto it, the
//   union of those chains gives the joint hull, and the other groups' hulls are summed onto that
//   (Minkowski sums of concave chains: a merge by falling ratio). Every chain here is the upper
//   hull from the cheapest point to the most beneficial, with strictly rising cost and benefit.
//   The greedy takes steps by falling ratio while they fit and stops at the first that does not:
//   a weighted selection (nth_element halving the undecided range, O(steps) expected) instead of a
//   sort, since only the cut matters.
#include <algorithm>
#include <cmath>

#include "budget_views.h"

namespace scenelod::selection {

namespace {

constexpr size_t kGroupCap = kMaxViewLevels + 2;           // levels, last frame's level, not drawn
constexpr size_t kChainCap = kMaxViews * kGroupCap;        // a sum of one chain per group

// The upper hull of pts[0, n) (reordered) into out: sorted by cost (more benefit first on ties),
// each point kept when its benefit rises and the turn stays concave. Returns its size.
size_t upperHull(TuplePoint* pts, size_t n, TuplePoint* out) {
  auto before = [](const TuplePoint& x, const TuplePoint& y) {
    return x.c < y.c || (x.c == y.c && (x.b > y.b || (x.b == y.b && x.t < y.t)));
  };
  if (n > 32) {
    std::sort(pts, pts + n, before);
  } else {
    // few points, mostly in order already (not drawn, then coarse to fine): insertion
    for (size_t k = 1; k < n; ++k)
      for (size_t j = k; j > 0 && before(pts[j], pts[j - 1]); --j) std::swap(pts[j], pts[j - 1]);
  }
  size_t h = 0;
  for (size_t k = 0; k < n; ++k) {
    const TuplePoint& p = pts[k];
    if (h > 0 && !(p.b > out[h - 1].b)) continue;
    while (h >= 2 && SelectorContext::ratio(out[h - 2].c, out[h - 2].b, out[h - 1].c, out[h - 1].b) <=
                         SelectorContext::ratio(out[h - 1].c, out[h - 1].b, p.c, p.b))
      --h;
    out[h++] = p;
  }
  return h;
}

// The Minkowski sum of two upper hulls (groups disjoint, so their tuples combine by OR).
size_t minkowski(const TuplePoint* a, size_t na, const TuplePoint* b, size_t nb, TuplePoint* out) {
  size_t i = 0, j = 0, h = 0;
  for (;;) {
    out[h++] = TuplePoint{a[i].c + b[j].c, a[i].b + b[j].b, a[i].t | b[j].t};
    const bool more_a = i + 1 < na, more_b = j + 1 < nb;
    if (!more_a && !more_b) return h;
    bool take_a = more_a;
    if (more_a && more_b)
      take_a = SelectorContext::ratio(a[i].c, a[i].b, a[i + 1].c, a[i + 1].b) >=
               SelectorContext::ratio(b[j].c, b[j].b, b[j + 1].c, b[j + 1].b);
    (take_a ? i : j) += 1;
  }
}

// Group g's allowed levels as points: the forced level alone, else the accurate-enough levels from
// min_level on, last frame's level if finer and allowed, and "not drawn" unless the object must
// be drawn (or `none_only`: "not drawn" alone). Returns their count.
size_t groupPoints(const TupleHullInput& in, size_t g, int min_level, bool none_only, TuplePoint* out) {
  if (none_only) {
    out[0] = TuplePoint{0.0f, 0.0f, 0};
    return 1;
  }
  const SelectorContext& ctx = *in.ctx;
  const GroupTerms& gt = in.terms->group[g];
  const int shift = static_cast<int>(8 * g);
  auto point = [&](int l) {
    const uint32_t row = in.row0 + static_cast<uint32_t>(l);
    const float acc = std::min(1.0f, gt.q * ctx.row_inv_w[row]) * (l == in.prev[g] ? ctx.h1 : 1.0f);
    return TuplePoint{gt.a + gt.m * ctx.row_cost[row], gt.b * acc, static_cast<uint64_t>(l + 1) << shift};
  };
  size_t n = 0;
  if (in.forced >= 0) {
    out[n++] = point(in.forced);
    return n;
  }
  if (!in.must) out[n++] = TuplePoint{0.0f, 0.0f, 0};
  const int finest = std::max(gt.finest, min_level);
  for (int l = in.levels - 1; l >= finest; --l) out[n++] = point(l);
  const int p = in.prev[g];
  if (p >= min_level && p < finest) out[n++] = point(p);
  return n;
}

// The hull of group g's allowed levels (groupPoints) into out; returns its size.
size_t groupHull(const TupleHullInput& in, size_t g, int min_level, bool none_only, TuplePoint* out) {
  TuplePoint pts[kGroupCap];
  return upperHull(pts, groupPoints(in, g, min_level, none_only, pts), out);
}

bool constrained(const TupleHullInput& in, size_t g) {
  const ViewFrame& f = *in.frame;
  return f.primary >= 0 && (in.terms->in_mask >> f.primary & 1u) && static_cast<int>(g) != f.primary &&
         f.kind_of_group[g] == ViewKind::kShadow;
}

// The joint hull of the primary group and the shadow groups it constrains into out; its size.
size_t jointHull(const TupleHullInput& in, TuplePoint* out) {
  const ViewFrame& f = *in.frame;
  const size_t pg = static_cast<size_t>(f.primary);
  TuplePoint primary[kGroupCap], hull[kGroupCap], chain[2][kChainCap];
  TuplePoint* const pool = in.pool;
  bool any_constrained = false;
  for (size_t g = 0; g < f.groups; ++g) any_constrained |= (in.terms->in_mask >> g & 1u) && constrained(in, g);
  if (!any_constrained) return groupHull(in, pg, 0, false, out);
  const size_t np = groupPoints(in, pg, 0, false, primary);
  size_t pooled = 0;
  for (size_t k = 0; k < np; ++k) {
    const int lp = static_cast<int>(primary[k].t >> (8 * pg) & 0xFFu) - 1;
    size_t nc = 1, cur = 0;
    chain[0][0] = primary[k];
    for (size_t g = 0; g < f.groups; ++g) {
      if (!(in.terms->in_mask >> g & 1u) || !constrained(in, g)) continue;
      const size_t nh = groupHull(in, g, lp, lp < 0, hull);
      nc = minkowski(chain[cur], nc, hull, nh, chain[cur ^ 1]);
      cur ^= 1;
    }
    std::copy(chain[cur], chain[cur] + nc, pool + pooled);
    pooled += nc;
  }
  return upperHull(pool, pooled, out);
}

}  // namespace

size_t tupleHull(const TupleHullInput& in, uint32_t slot, size_t max_steps, TuplePoint* base, ViewStep* steps) {
  const ViewFrame& f = *in.frame;
  TuplePoint chain[2][kChainCap], hull[kChainCap];
  size_t nc = 1, cur = 0;
  chain[0][0] = TuplePoint{0.0f, 0.0f, 0};
  const bool joint = f.primary >= 0 && (in.terms->in_mask >> f.primary & 1u);
  if (joint) nc = jointHull(in, chain[0]);
  bool origin = !joint;  // the chain is still the one point "nothing drawn": a sum onto it is a copy
  for (size_t g = 0; g < f.groups; ++g) {
    if (!(in.terms->in_mask >> g & 1u) || (joint && (static_cast<int>(g) == f.primary || constrained(in, g)))) continue;
    if (origin) {
      nc = groupHull(in, g, 0, false, chain[cur]);
      origin = false;
      continue;
    }
    const size_t nh = groupHull(in, g, 0, false, hull);
    nc = minkowski(chain[cur], nc, hull, nh, chain[cur ^ 1]);
    cur ^= 1;
  }
  const TuplePoint* h = chain[cur];
  *base = h[0];
  const size_t count = std::min(nc - 1, max_steps);
  float last_ratio = std::numeric_limits<float>::infinity();
  for (size_t k = 1; k <= count; ++k) {
    // rounding may make a ratio exceed the one before it: clamped, so each slot's steps fall
    const float r = std::min(last_ratio, SelectorContext::ratio(h[k - 1].c, h[k - 1].b, h[k].c, h[k].b));
    last_ratio = r;
    steps[k - 1] = ViewStep{r, h[k].c - h[k - 1].c, h[k].c, h[k].b, static_cast<uint64_t>(slot) << 8 | k, h[k].t};
  }
  return count;
}

size_t viewGreedy(ViewStep* steps, size_t count, double avail, size_t* split) {
  auto precedes = [](const ViewStep& x, const ViewStep& y) {
    return x.ratio > y.ratio || (x.ratio == y.ratio && x.order < y.order);
  };
  // [0, lo) taken, [lo, hi) undecided, [hi, count) after the first that does not fit
  size_t lo = 0, hi = count;
  double left = avail;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    std::nth_element(steps + lo, steps + mid, steps + hi, precedes);
    double sum = 0.0;
    for (size_t k = lo; k <= mid; ++k) sum += steps[k].dcost;
    if (sum <= left) {
      left -= sum;
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  *split = lo;
  return lo;
}

}  // namespace scenelod::selection
