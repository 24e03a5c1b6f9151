#pragma once
// What the selector's files share (private to selection/src): the context's layout, the constants
// of its byte encodings, the SIMD passes (selector_simd.cpp) and the budget phases
// (budget_hulls.cpp, budget_lagrangian.cpp, budget_greedy.cpp) that SelectionJob::run
// (selector.cpp) calls in order. Every file that includes this one is built with selector.cpp's
// flags (-fno-math-errno -ffp-contract=off -fno-trapping-math, selection/CMakeLists.txt): the
// bits of a selection do not depend on the file a step lives in.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "scenelod/selection/camera.h"
#include "scenelod/selection/selector.h"

namespace scenelod::selection {

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
// the predicted bracket's starting relative half-width (budget_lagrangian.cpp adapts it)
constexpr double kPredictWidthStart = 1.0 / 16.0;
// levels of one chain side by side: kLanes floats, two SSE2 vectors or one AVX2 vector
constexpr int kLanes = 8;
// slots per block of the slot pass: full blocks run loops of a constant trip count, which predict
constexpr size_t kSlotBlock = 64;
// A slot's settling key (settleKeys*): kSettleIneligible, or the lane-mask row
// finest * (kLanes + 1) + level count in bits 4.. and the candidate (last frame's level) + 1 in bits 0..3.
constexpr uint16_t kSettleIneligible = 0x8000;
// A visible fraction at or below this reads as hidden: the drop policy may drop the object.
constexpr float kHiddenFraction = 0.05f;
// Set in an eligible key: the slot is kept by the drop policy (its hull has no "not drawn" point).
constexpr uint16_t kSettleKeep = 0x4000;

// GCC vector extensions: only IEEE adds, multiplies, compares and selects, so the bits do not depend
// on how the compiler lowers them
typedef float V4f __attribute__((vector_size(16)));
typedef int32_t V4i __attribute__((vector_size(16)));

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

struct HeapEntry {
  float ratio;
  uint32_t slot;
};

struct BracketEntry {
  float ratio;
  uint32_t slot;
  uint32_t step;  // upgrade from hull point `step` to `step + 1`
};

// A step along one object's hull of level tuples in a frame with views (budget_views.cpp): the
// upgrade to the hull point of cost `cost` and benefit `benefit` whose levels are `tuple` (byte g =
// the level in group g + 1, 0 = not drawn there). `order` = slot << 8 | step index: the tie-break
// after the ratio (a total order, so the selection is deterministic).
struct ViewStep {
  float ratio;
  float dcost;  // cost - the previous hull point's cost
  float cost;
  float benefit;
  uint64_t order;
  uint64_t tuple;
};
// One object in one group: its level-independent cost a (the views that see it, kind-weighted),
// the geometry multiplier m (a level costs a + m * row cost), its benefit b at accuracy 1, the
// accuracy term q (X R / scale of the view needing the finest level), and the kind-weighted object
// and pixel features it adds when drawn.
struct GroupTerms {
  float a = 0.0f, m = 0.0f, b = 0.0f;
  float q = std::numeric_limits<float>::infinity();
  float feature_objects = 0.0f, feature_pixels = 0.0f;
  int finest = 0;  // the coarsest level of accuracy 1 (finestLevel)
};
// A point of a tuple hull: cost, benefit, levels (byte g = level in group g + 1, 0 = not drawn).
// No member initialisers: the hull code's arrays of them are scratch, not to be zeroed per object.
struct TuplePoint {
  float c, b;
  uint64_t t;
};
// The points one object's joint hull may gather: per level of the primary group (and not drawn),
// a chain summed over the groups of at most levels + 2 points each.
constexpr size_t kTuplePoolCap = (kMaxViewLevels + 1) * kMaxViews * (kMaxViewLevels + 2);
// Steps kept per group of an object's tuple hull (its cheaper end; docs/SELECTION.md, "Views").
constexpr size_t kViewStepsPerGroup = 8;

// The memory of frames with views (SelectorConfig::max_view_groups > 0): one allocation of its own.
struct ViewScratch {
  size_t max_groups = 0;
  int8_t* prev = nullptr;          // max_objects * max_groups: last frame's level per object and group
  uint32_t* slot_object = nullptr; // per slot (object in some view), in object order
  uint8_t* slot_groups = nullptr;  // per slot: bit g = some view of group g sees the object
  GroupTerms* slot_terms = nullptr; // per slot, max_groups: its terms in each group (the write-out's)
  float* base_cost = nullptr;      // per slot: the hull's first point (not drawn, or the cheapest
  float* base_benefit = nullptr;   // tuple of a must-draw or forced object)
  uint64_t* base_tuple = nullptr;
  uint32_t* best = nullptr;        // per slot: 1 + index of the chosen step, 0 = the base
  uint8_t* best_step = nullptr;
  ViewStep* steps = nullptr;
  size_t step_capacity = 0;
  TuplePoint* pool = nullptr;      // kTuplePoolCap: one object's joint hull's points
  void* block = nullptr;
};

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
  // per row, this frame: the smallest geometry cost from this row to its chain's end (a kept
  // slot's cheapest level is a + row_suffix_min[row0 + finest]); and at a chain's first row, the
  // spread of its rows' costs (largest - smallest) when they fall strictly from level to level,
  // else +inf (a kept slot may settle only where every level fits alone: spread <= the budget left)
  float* row_suffix_min = nullptr;
  float* row_spread = nullptr;
  uint32_t* row_drawn = nullptr;  // per row: the drawn slots at it (the budget write-out's counters)
  size_t max_rows = 0;
  uint8_t* hull = nullptr;       // hull_stride bytes per slot: levels along the hull, kNotDrawn = -1
  uint8_t* hull_count = nullptr;
  uint8_t* chosen = nullptr;     // index into the slot's hull
  HeapEntry* heap = nullptr;     // the heap greedy's; before it, the settling pass's unsettled slots
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

  ViewScratch views;  // frames with views (selector_views.cpp)

  // transitions (selector_transitions.cpp): per object whether a fade runs (1) or not (0), the
  // level fading out and the fade's elapsed time (read only while it runs), and the tag of the
  // last budget frame with transitions that had it in view (a slot)
  uint8_t* fading = nullptr;
  int8_t* fade_from = nullptr;
  float* fade_elapsed = nullptr;
  uint8_t* view_tag = nullptr;
  uint8_t last_view_tag = 1;
  bool transitions_valid = false;  // last frame ran with transitions (its fades hold)
  bool transitions_budget = false; // ... in budget mode (its view tags hold)
  // per level-table row, frames in morph mode: the morph factor's band [start, end) of the
  // accuracy term q as 1 / start, end and 1 / L(end / start) (L: selector_transitions.cpp's log);
  // 1 / start = 0 and end = +inf: the row never morphs
  float* row_morph_inv_start = nullptr;
  float* row_morph_end = nullptr;
  float* row_morph_inv = nullptr;
  // ... and the largest q whose factor is exactly 0 on the row: every q in [0, this] has factor +0
  // (-1: none), so most slots are told by one compare
  float* row_morph_zero_to = nullptr;

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
};

// ---- context (selector_context.cpp)

// Feeds the last reported frame time to the calibration (when `calibrate` and it belongs to a frame
// still in the ring) and returns the cost model for this frame.
CostCoefficients takeReportedFrameTime(SelectorContext& ctx, bool calibrate);
// Keeps this frame's features for a later time report and advances the context's history.
void recordFrame(SelectorContext& ctx, const CostFeatures& features, bool budget, size_t slot_count);

// ---- transitions (selector_transitions.cpp)

// Null when the job's transition parameters and outputs are usable, else what is wrong.
const char* transitionsError(const SelectionJob& job);
// The rows' morph bands for this frame's hysteresis and morph_band (morph mode).
void prepareMorphRows(SelectorContext& ctx, const LevelTable& levels, const SelectionParams& params);
// The morph factors of m slots (objects, first rows and accuracy terms of their chains, levels by
// object) into morph_out by object; 0 for a slot not drawn.
void morphFactors(const SelectorContext& ctx, const uint32_t* object, const uint32_t* row0, const float* q,
                  const int8_t* level_of, size_t m, float* morph_out);
// The same for m drawn slots at the given rows (distance mode: their levels' rows, no lookup by object).
void morphFactorsAtRows(const SelectorContext& ctx, const uint32_t* object, const uint32_t* row, const float* q,
                        size_t m, float* morph_out);
// Budget mode, before the choice: the predicted cost of the levels still fading out this frame
// from fades started in earlier frames (slot columns a of the slot pass), in slot order while it
// stays within `cap`; the fades beyond it end now.
double fadeReserve(SelectorContext& ctx, const SelectionJob& job, size_t slots, double cap);
// The outgoing levels drawn this frame beside the chosen ones: their count, cost and features.
struct TransitionSums {
  uint32_t count = 0;
  double cost = 0.0, pixels = 0.0;
  uint64_t tri = 0, vert = 0, lines = 0;
};
// After the choice (levels_out final, ctx.prev_level still last frame's): advances and starts the
// fades, computes the morph factors (budget mode; distance mode's came with the slot pass), writes
// the job's transition outputs. Needs the slot columns object, a and px (and row0, q, finest in
// budget mode) of this frame's `slots` slots.
// `new_fade_cap`: the cost the fades started in this frame may add (+inf in distance mode); a switch
// whose fade would exceed it is a hard switch.
TransitionSums transitionPass(SelectorContext& ctx, const SelectionJob& job, size_t slots, double new_fade_cap);
// A frame without transitions: the outputs (when given) say "no fade, no morph"; the fade state is
// forgotten.
void noTransitions(SelectorContext& ctx, const SelectionJob& job);

// ---- frames with views or forced levels (selector_views.cpp)

// Null when the job's views, groups and forced levels are usable, else what is wrong.
const char* viewsError(const SelectionJob& job);
// Selects one level per object and group (job.views, or the job's camera as one primary view when
// only forced levels are given) and writes the outputs and statistics.
void runViews(const SelectionJob& job, const CostCoefficients& coef);
// Allocates / frees the context's ViewScratch for max_view_groups groups. False when the allocator fails.
bool allocateViewScratch(SelectorContext& ctx, size_t max_view_groups);
void freeViewScratch(SelectorContext& ctx);

// ---- SIMD passes (selector_simd.cpp): each in an SSE2 and an AVX2 form giving the same bits

bool cpuHasAvx2();

// Nonzero when one of the n chain indices is above last_chain.
uint32_t chainsAboveSse2(const uint32_t* chain_of, size_t n, uint32_t last_chain);
uint32_t chainsAboveAvx2(const uint32_t* chain_of, size_t n, uint32_t last_chain);

// outside[i] = 1 when sphere i (centre xyz[3 i..], radius rad[i]) is outside one of the frustum's planes.
void frustumOutsideSse2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint8_t* outside);
void frustumOutsideAvx2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint8_t* outside);
// Where the frustum compaction queues the spheres in view (room for n more entries each): their
// object indices, and their centres and radii, which the slot terms then read in order instead of
// gathering them again by object.
struct SphereQueue {
  uint32_t* object;
  float* x;
  float* y;
  float* z;
  float* r;
};
// The frustum test and the compaction of one block of n <= 64 objects (no chain empty): the indices
// base + j of the spheres in view, in order, and their centres and radii to q; returns their count.
size_t frustumCompactSse2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint32_t base,
                          const SphereQueue& q);
size_t frustumCompactAvx2(const Frustum& frustum, const float* xyz, const float* rad, size_t n, uint32_t base,
                          const SphereQueue& q);

// Per-slot chain terms of m slots (objects gobj, accuracy terms gq): first row, level count, last
// frame's level and the finest candidate (the coarsest level of accuracy 1); level_of[object] =
// last frame's level (a settled slot keeps it; every other path writes its level again).
void chainTermsSse2(const uint32_t* gobj, const float* gq, size_t m, const uint32_t* chain_of,
                    const uint32_t* chain_offset, const float* row_inv_w, const int8_t* prev_level,
                    uint8_t* gfinest, uint32_t* grow0, int8_t* gprev, uint8_t* glevels, int8_t* level_of);
void chainTermsAvx2(const uint32_t* gobj, const float* gq, size_t m, const uint32_t* chain_of,
                    const uint32_t* chain_offset, const float* row_inv_w, const int8_t* prev_level,
                    uint8_t* gfinest, uint32_t* grow0, int8_t* gprev, uint8_t* glevels, int8_t* level_of);

// The settling keys (kSettleIneligible or lane masks and candidate) of m slots. Eligible: a chain of
// at most kLanes levels, a level-independent cost > 0, not must-draw (the caller marks those), and
// the candidate "not drawn" or a level in [finest, level count). Returns the count of slots with last
// frame's level "not drawn" and a benefit > 0 (the settled slots' part of the dropped count).
uint32_t settleKeysSse2(const float* ga, const float* gb, const uint8_t* glevels, const uint8_t* gfinest,
                        const int8_t* gprev, size_t m, uint16_t* gkey);
uint32_t settleKeysAvx2(const float* ga, const float* gb, const uint8_t* glevels, const uint8_t* gfinest,
                        const int8_t* gprev, size_t m, uint16_t* gkey);

// What the settling pass reads: the slot columns, this frame's row terms and the widened bracket ends.
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
  float keep_avail;        // a kept slot settles only when its chain's spread is <= this (below avail)
  const float* spread;     // row_spread
  bool keep;               // some key may carry kSettleKeep (the drop policy is on)
  float lo, hi;            // the predicted bracket's ends, widened by kSettleMargin
  // the fused write-out's (fuse only): pixels per slot and the per-row counters of drawn slots
  // (zeroed here)
  const float* px;
  uint32_t* row_drawn;
  size_t rows;
};
// The settled slots' share of the frame's sums, in slot order (fused; else only cost).
struct SettleSums {
  double cost, benefit, pixels;
};
// Settles the slots whose choice cannot change inside the bracket [in.lo, in.hi] (their chosen
// step becomes kSettledAtPrev), lists the others in slot order in `unsettled` and returns their
// count. fuse: also sums the settled slots' write-out terms and counts them per row.
size_t settleSlots(bool avx2, bool fuse, const SettleInput& in, size_t slot_count, uint8_t* chosen_step,
                   uint32_t* unsettled, SettleSums* settled_sums);

// What the budget write-out reads: the slot columns, the hulls' level bytes and the row tables.
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
// The frame's sums over the slots in slot order: cost (per-frame constant included), benefit,
// pixels and the integer features of the drawn levels, the slots dropped and drawn.
struct SlotSums {
  double predicted, benefit, pixels;
  uint64_t tri, vert, lines;
  uint32_t dropped, drawn;
};
// Each slot's level into level_of and its share of the frame's sums, from predicted0 on.
// count_rows: in.row_drawn is set (fewer rows than slots).
SlotSums writeOutSlots(bool avx2, bool count_rows, const WriteOutInput& in, size_t slot_count, double predicted0,
                       int8_t* level_of);

// ---- budget mode

// The price histogram's window: a segment's bucket is (its ratio's float bits >> key_shift) -
// key_base + 1, clamped to [0, inner_buckets + 1].
struct HistWindow {
  int key_shift = 0;
  int64_t key_base = 0;
  int64_t inner_buckets = 0;
};
// What the budget phases share about this frame (the slot columns are in the context).
struct BudgetFrame {
  size_t slots = 0;
  size_t rows = 0;              // level-table rows
  double avail = 0.0;           // the budget left after the mandatory part
  double obj_cap = 0.0;         // the objects' share of the budget
  bool use_greedy = false;      // the heap greedy instead of the Lagrangian form
  bool rows_nonnegative = true; // every row's geometry cost >= 0 (not NaN): the settling pass may run
  bool keep = false;            // the drop policy is on: some slots may be kept (kSettleKeep)
  HistWindow hist;
};
// A price bracket (lo, hi].
struct PriceBracket {
  double lo, hi;
};
// What building the hulls summed.
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
// Where the greedy stopped and at which price: the first upgrade that did not fit (slot -1: none).
struct BudgetChoice {
  double lambda = 0.0;
  int64_t split_slot = -1;
  uint32_t split_step = 0;
  uint32_t passes = 0;  // linear passes of the price search
};

// Pass 2 (budget_hulls.cpp): each slot's upper convex hull over its points that fit alone. With a
// predicted bracket, the slots settled inside it get none, and the others' upgrades inside it go
// to ctx.bracket; without, every slot gets its hull and (Lagrangian form) the price histogram.
HullSums buildHulls(const SelectorContext& ctx, const BudgetFrame& frame, const PriceBracket* predicted);

// The Lagrangian form (budget_lagrangian.cpp).
// The price histogram's window for this frame: around last frame's price, else a sampled guess.
HistWindow histogramWindow(const SelectorContext& ctx, size_t slots, bool use_greedy);
// Whether last frame's price can predict this frame's bracket, and that bracket.
bool pricePredictable(const SelectorContext& ctx);
PriceBracket predictedBracket(const SelectorContext& ctx);
// Chooses every slot's hull step (ctx.chosen) by the price search and the greedy on the bracket.
// hulls holds what buildHulls summed (with `predicted`, when not null); a failed prediction
// rebuilds them.
BudgetChoice lagrangianChoice(SelectorContext& ctx, const BudgetFrame& frame, const PriceBracket* predicted,
                              HullSums* hulls);

// Frames with views (budget_views.cpp): the greedy on the tuple hulls' steps[0, count) by falling
// ratio (ViewStep::order on ties) while they fit `avail`, stopping at the first that does not:
// reorders the steps so that the taken ones come first and returns their count; *split = the
// index of the first that did not fit, or count when all fit.
size_t viewGreedy(ViewStep* steps, size_t count, double avail, size_t* split);

// The heap greedy (budget_greedy.cpp): upgrades by decreasing marginal ratio until one does not
// fit (stop) or all were tried; returns the first that did not fit.
BudgetChoice heapGreedy(const SelectorContext& ctx, size_t slots, double cap, bool stop);

}  // namespace scenelod::selection
