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

// ---- settling (docs/SELECTION.md, "Views"): an object whose last tuple is the unique best at
// every price in the predicted bracket needs no hull

// the settling test's slack on b - lambda c: far above the rounding of the hull's float sums over
// at most 8 groups and of the test's own float values (about 2^-20 of the summed magnitudes)
constexpr float kSettleSlack = 1.0f / 65536.0f;

}  // namespace

bool tupleSettles(const TupleHullInput& in, size_t max_steps, double lo_d, double hi_d, double avail, TuplePoint* point,
                  double* need) {
  const ViewFrame& f = *in.frame;
  const SelectorContext& ctx = *in.ctx;
  if (in.must || in.forced >= 0) return false;
  // costs that rise with detail (row costs falling strictly along the chain, >= 0): the hull's
  // steps then make each group's level finer, never coarser (Topkis), so the candidate's step
  // index is at most the count of coarser options summed over the groups
  if (!(ctx.row_spread[in.row0] < std::numeric_limits<float>::infinity()) || !(ctx.row_suffix_min[in.row0] >= 0.0f))
    return false;
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  const float lo = static_cast<float>(lo_d), hi = static_cast<float>(hi_d);
  const uint32_t mask = in.terms->in_mask;
  const bool joint = f.primary >= 0 && (mask >> f.primary & 1u);
  const int pg = f.primary;
  const int levels = in.levels;
  const int pp = joint ? in.prev[pg] : -1;
  if (pp >= levels) return false;
  const float* const row_cost = ctx.row_cost + in.row0;
  const float* const row_inv_w = ctx.row_inv_w + in.row0;
  const float h1 = ctx.h1;
  float bsum = 0.0f, csum = 0.0f, cost = 0.0f;
  float cand[kMaxViews][2];  // per group: the candidate's cost and benefit
  size_t coarser = 0;
  // at lo ([0]) and hi ([1]): the joint part's value at the candidate, and per primary option lp
  // (at [lp + 1]) with the constrained groups at their best; per group the candidate's margin over
  // the best other offered option (free groups; constrained ones from the primary's candidate on)
  float vp[2] = {0.0f, 0.0f};
  float joint_at[kMaxViewLevels + 1][2];
  if (joint)
    for (int l = 0; l <= levels; ++l) joint_at[l][0] = joint_at[l][1] = 0.0f;
  float margin[2] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()};
  for (size_t g = 0; g < f.groups; ++g) {
    if (!(mask >> g & 1u)) continue;
    const GroupTerms& gt = in.terms->group[g];
    if (!(gt.a > 0.0f) || !(gt.m >= 0.0f)) return false;
    const int p = in.prev[g];
    if (p >= levels) return false;
    const bool primary = joint && static_cast<int>(g) == pg;
    const bool c = joint && !primary && constrained(in, g);
    if (c && (pp < 0 ? p >= 0 : p < pp)) return false;  // the candidate breaks the rule
    const int first = p >= 0 && p < gt.finest ? p : gt.finest;
    const int from = c ? pp : 0;
    // from the coarsest level to the finest offered: values, the suffix best, the best other
    float best0 = kNone, best1 = kNone, other0 = p < 0 ? kNone : 0.0f, other1 = other0;
    float v0p = 0.0f, v1p = 0.0f, cp = 0.0f, bp = 0.0f, cmax = 0.0f, bmax = 0.0f;
    for (int l = levels - 1; l >= first; --l) {
      if (l >= gt.finest || l == p) {
        const float acc = std::min(1.0f, gt.q * row_inv_w[l]) * (l == p ? h1 : 1.0f);
        const float cl = gt.a + gt.m * row_cost[l], bl = gt.b * acc;
        const float v0 = bl - lo * cl, v1 = bl - hi * cl;
        cmax = std::max(cmax, cl);
        bmax = std::max(bmax, bl);
        best0 = std::max(best0, v0);
        best1 = std::max(best1, v1);
        if (l == p) {
          v0p = v0;
          v1p = v1;
          cp = cl;
          bp = bl;
        } else if (l >= from) {
          other0 = std::max(other0, v0);
          other1 = std::max(other1, v1);
        }
        if (primary) {
          joint_at[l + 1][0] += v0;
          joint_at[l + 1][1] += v1;
        }
      } else if (primary) {
        joint_at[l + 1][0] = joint_at[l + 1][1] = kNone;  // not offered
      }
      if (c) {
        joint_at[l + 1][0] += std::max(0.0f, best0);
        joint_at[l + 1][1] += std::max(0.0f, best1);
      }
    }
    if (joint && first > 0) {
      // the levels finer than any offered one
      for (int l = 0; l < first; ++l) {
        if (primary) joint_at[l + 1][0] = joint_at[l + 1][1] = kNone;
        if (c) {
          joint_at[l + 1][0] += std::max(0.0f, best0);
          joint_at[l + 1][1] += std::max(0.0f, best1);
        }
      }
    }
    bsum += bmax;
    csum += cmax;
    cand[g][0] = cp;
    cand[g][1] = bp;
    if (p >= 0) {
      cost += cp;
      coarser += static_cast<size_t>(levels - p);  // not drawn and the levels past p
    }
    if (primary || c) {
      vp[0] += v0p;
      vp[1] += v1p;
    }
    // the candidate's level beats every other offered one (a constrained group whose primary
    // candidate is "not drawn" has no other option)
    if (!primary && !(c && pp < 0)) {
      margin[0] = std::min(margin[0], v0p - other0);
      margin[1] = std::min(margin[1], v1p - other1);
    }
  }
  if (coarser > max_steps) return false;
  *need = static_cast<double>(cost) + static_cast<double>(kSettleSlack) * csum;
  if (*need > avail) return false;  // the candidate must fit alone (its hull point within rounding)
  const float slack[2] = {kSettleSlack * (bsum + lo * csum), kSettleSlack * (bsum + hi * csum)};
  if (!(margin[0] > slack[0] && margin[1] > slack[1])) return false;
  if (joint) {
    for (int lp = -1; lp < levels; ++lp)
      if (lp != pp && !(vp[0] - joint_at[lp + 1][0] > slack[0] && vp[1] - joint_at[lp + 1][1] > slack[1]))
        return false;  // (a level not offered is at -inf: it passes)
  }
  // the candidate's point, summed in the hull's order (the joint part, then the other groups)
  TuplePoint pt{0.0f, 0.0f, 0};
  bool first_add = true;
  auto add = [&](size_t g) {
    const int l = in.prev[g];
    const float c = l < 0 ? 0.0f : cand[g][0], b = l < 0 ? 0.0f : cand[g][1];
    pt.c = first_add ? c : pt.c + c;
    pt.b = first_add ? b : pt.b + b;
    pt.t |= static_cast<uint64_t>(l + 1) << (8 * g);
    first_add = false;
  };
  if (joint) {
    add(static_cast<size_t>(pg));
    for (size_t g = 0; g < f.groups; ++g)
      if ((mask >> g & 1u) && constrained(in, g)) add(g);
  }
  for (size_t g = 0; g < f.groups; ++g)
    if ((mask >> g & 1u) && !(joint && (static_cast<int>(g) == pg || constrained(in, g)))) add(g);
  *point = pt;
  return true;
}

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
