// The budget's greedy on convex hulls: Funkhouser & Sequin 1993 ("Adaptive display algorithm for
// interactive frame rates during visualization of complex virtual environments") choose one level
// per object as a multiple-choice knapsack of cost (predicted ms) and benefit; Mason & Blake 1997
// ("Adaptive visualization of multiresolution models") solve it on each object's upper convex hull
// of (cost, benefit) by taking upgrades in decreasing marginal ratio, here from a max-heap. It is
// the algorithm kGreedy, the one that skips upgrades that do not fit
// (stop_at_first_non_fitting = false), and the Lagrangian form's fallback when its bracket cannot
// separate ties (budget_lagrangian.cpp takes the same upgrades in the same order).
#include <algorithm>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

// max-heap on ratio, then the lower slot first (a total order: deterministic)
struct HeapLess {
  bool operator()(const HeapEntry& x, const HeapEntry& y) const {
    if (x.ratio != y.ratio) return x.ratio < y.ratio;
    return x.slot > y.slot;
  }
};

}  // namespace

BudgetChoice heapGreedy(const SelectorContext& ctx, size_t slots, double cap, bool stop) {
  BudgetChoice choice;
  // every slot at its hull's first point
  double total = 0.0;
  for (size_t s = 0; s < slots; ++s) total += ctx.pointCost(s, ctx.hullLevel(s, 0));
  uint8_t* const chosen = ctx.chosen;
  HeapEntry* const heap = ctx.heap;
  size_t heap_size = 0;
  for (size_t s = 0; s < slots; ++s) {
    chosen[s] = 0;
    if (ctx.hull_count[s] < 2) continue;
    const int l0 = ctx.hullLevel(s, 0), l1 = ctx.hullLevel(s, 1);
    heap[heap_size++] = {SelectorContext::ratio(ctx.pointCost(s, l0), ctx.pointBenefit(s, l0), ctx.pointCost(s, l1),
                                                ctx.pointBenefit(s, l1)),
                         static_cast<uint32_t>(s)};
  }
  std::make_heap(heap, heap + heap_size, HeapLess());
  while (heap_size > 0) {
    std::pop_heap(heap, heap + heap_size, HeapLess());
    const HeapEntry e = heap[--heap_size];
    const size_t s = e.slot, k = chosen[s];
    const int l0 = ctx.hullLevel(s, k), l1 = ctx.hullLevel(s, k + 1);
    const float c0 = ctx.pointCost(s, l0), c1 = ctx.pointCost(s, l1);
    const double delta = static_cast<double>(c1) - static_cast<double>(c0);
    if (total + delta <= cap) {
      total += delta;
      chosen[s] = static_cast<uint8_t>(k + 1);
      if (k + 2 < ctx.hull_count[s]) {
        const int l2 = ctx.hullLevel(s, k + 2);
        heap[heap_size++] = {SelectorContext::ratio(c1, ctx.pointBenefit(s, l1), ctx.pointCost(s, l2),
                                                    ctx.pointBenefit(s, l2)),
                             e.slot};
        std::push_heap(heap, heap + heap_size, HeapLess());
      }
    } else {
      if (choice.split_slot < 0) {
        choice.split_slot = static_cast<int64_t>(s);
        choice.split_step = static_cast<uint32_t>(k);
      }
      if (stop) return choice;
    }
  }
  return choice;
}

}  // namespace scenelod::selection
