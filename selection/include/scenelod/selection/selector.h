#pragma once
// Per-frame level-of-detail selection: one level per object (or "not drawn") from the camera, in
// distance mode (the coarsest accurate-enough level, Low & Tan 1997 §4) or under a frame-time budget
// (Funkhouser & Sequin 1993, with Mason & Blake 1997's convex-hull greedy and its Lagrangian twin).
//
// Shape (the per-frame job of ../shared/STYLE.md §3, the style guide beside the repository): a
// SelectionJob holds const spans over caller-owned per-object arrays (SoA), a flat per-chain level
// table, spans for the outputs, and a pointer to a SelectorContext created once for the largest
// object count. run() allocates nothing, locks nothing, throws nothing, and the same inputs on a
// context in the same state give bit-identical outputs.
//
// Threads: one thread calls run() on a context at a time. reportFrameTime() may be called from any
// one other thread at the same time (the engine's render thread reporting the frame it just
// finished); it hands the time over through a lock-free single-slot mailbox that the next run()
// reads. See docs/SELECTION.md.
#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/span.h"
#include "scenelod/selection/camera.h"
#include "scenelod/selection/cost_model.h"

namespace scenelod::selection {

// Memory for a context: allocate(user, bytes, alignment) returns memory or null; free(user, p).
// Per context, so two engines in one process stay independent.
struct Allocator {
  void* (*allocate)(void* user, size_t bytes, size_t alignment) = nullptr;
  void (*free)(void* user, void* pointer) = nullptr;
  void* user = nullptr;
};

// The C library's aligned allocation.
Allocator defaultAllocator();

// Levels of every chain, flattened: chain c owns rows [chain_level_offset[c], chain_level_offset[c+1]).
// Row order within a chain is level order: level 0 (the original, cell width 0) first, cell widths
// non-decreasing. All spans but chain_level_offset have one entry per row.
struct LevelTable {
  Span<const uint32_t> chain_level_offset;  // chain_count + 1 entries, starting at 0, non-decreasing
  Span<const float> cell_width;             // object space, >= 0, finite
  Span<const uint32_t> triangle_count;
  Span<const uint32_t> vertex_count;
  Span<const uint32_t> line_point_count;    // edges + points
  // empty = no level has geomorph data (transitions fade instead of morphing), else one per row:
  // nonzero = the level's vertices carry their targets in the next coarser level of the chain
  Span<const uint8_t> has_morph;

  size_t chainCount() const { return chain_level_offset.count ? chain_level_offset.count - 1 : 0; }
  size_t rowCount() const { return cell_width.count; }
};

enum class SelectionMode : uint8_t {
  kDistance,  // the coarsest accurate-enough level (w_k * scale <= X * R), no budget
  kBudget,    // maximise total benefit with predicted cost <= budget_ms
};

enum class BudgetAlgorithm : uint8_t {
  kLagrangian,  // price search warm-started from last frame, exact greedy on the bracket (default)
  kGreedy,      // upgrades by decreasing marginal ratio from a heap (Mason & Blake)
};

// What a view draws (SelectionParams::view_kinds weighs each kind; docs/SELECTION.md, "Views").
enum class ViewKind : uint8_t {
  kPrimary,    // the main camera
  kShadow,     // a shadow map (cascade): an orthographic light camera, viewport in texels
  kEye,        // one eye of a stereo pair (both eyes in one group)
  kSecondary,  // a mirror, a split screen, a picture in picture
};
constexpr size_t kViewKindCount = 4;
constexpr size_t kMaxViews = 8;
// Chains longer than this are refused by a job with views or forced levels.
constexpr size_t kMaxViewLevels = 16;

// One view of a frame. Views with the same group value form one group: they get one level per
// object, chosen for the union of their frusta, with the pixel size of the view that needs the
// finest level (the nearest one when the views share X). A group's views share one kind.
struct View {
  Camera camera;                        // perspective or orthographic (cameraValid)
  ViewKind kind = ViewKind::kPrimary;
  uint32_t group = 0;                   // any value; groups are numbered in order of first appearance
  float pixels_per_cell = 1.0f;         // X of this view (> 0); shadows may be coarser, e.g. 4
  float lod_bias = 1.0f;                // > 0, multiplies X: 2 = twice as coarse (Unity's lodBias inverted)
  Span<const float> visible_fraction;   // empty = 1, else one per object in [0, 1]: occlusion
                                        // estimated for this view's camera, and only applied to it
};

// How a kind of view is priced and valued: the cost model's per-object, per-pixel and geometry
// (triangles, vertices, line points) coefficients are multiplied by the first three when an object
// is drawn in a view of that kind; its benefit there by `benefit`. The cost model's coefficients
// stay shared. For the shadow kind the three cost scales are also multiplied by the factors the
// calibration learns from the frame times (CostCoefficients::shadow_*_factor, 1 = as given; they
// are the prior's scales); the other kinds' scales are not learnt.
struct ViewKindWeights {
  float object_cost = 1.0f;
  float pixel_cost = 1.0f;
  float geometry_cost = 1.0f;
  float benefit = 1.0f;
};

enum SelectionFlag : uint32_t {
  kFlagOverBudget = 1u << 0,       // even the mandatory levels (must-draw and kept objects at their
                                   // cheapest) exceed the budget
  kFlagObjectsDropped = 1u << 1,   // some objects in view were not drawn to fit the budget
  kFlagSplitFallback = 1u << 2,    // the half-approximation fallback beat the greedy this frame
};

// How level switches are shown (docs/SELECTION.md, "Transitions"). The selector cannot know whether
// the renderer draws two levels at once, so the default is none: hard switches, as before.
enum class Transitions : uint8_t {
  kNone,   // hard switches; the transition outputs say "no fade, no morph"
  kFade,   // every switch in view (and every drop or return of an object in view) cross-fades over fade_ms
  kMorph,  // geomorphs where a level has morph data and the switch is to the next level at the
           // distance rule's point; cross-fades for every other switch
};

struct SelectionParams {
  SelectionMode mode = SelectionMode::kBudget;
  float budget_ms = 16.0f;          // budget mode: total predicted frame time allowed, > 0
  float pixels_per_cell = 1.0f;     // X: a level is accurate enough when one cell projects to <= X pixels
  float hysteresis = 0.1f;          // >= 0: the current level's benefit counts (1 + h) times, so a
                                    // switch to a finer level happens at X*R/(1+h) of the cell width
                                    // where a switch to coarser happens; also in distance mode
  bool stop_at_first_non_fitting = true;  // false: skip an upgrade that does not fit and keep trying
                                          // cheaper ones (always uses the greedy algorithm)
  bool half_approximation = true;   // compare with the first non-fitting upgrade alone (1/2 bound)
  BudgetAlgorithm algorithm = BudgetAlgorithm::kLagrangian;
  bool calibrate = true;            // fit the cost model from reported frame times
  // per ViewKind (primary, shadow, eye, secondary), for jobs with views: a shadow pass draws depth
  // only (cheaper pixels, position-only vertices) and is worth less than what the camera shows
  ViewKindWeights view_kinds[kViewKindCount] = {
      {1.0f, 1.0f, 1.0f, 1.0f}, {1.0f, 0.25f, 0.5f, 0.25f}, {1.0f, 1.0f, 1.0f, 1.0f}, {1.0f, 1.0f, 1.0f, 1.0f}};
  // drop policy (budget mode, jobs without views): an object in view whose projected radius is at
  // least min_drop_px pixels and whose visible fraction is above 0.05 is never dropped: at worst
  // it is drawn at its cheapest level, counted in the mandatory part like a must-draw object (and
  // the frame flagged over budget when even that does not fit). 0: any object may be dropped.
  float min_drop_px = 4.0f;         // >= 0, finite
  // transitions (jobs without views or forced levels)
  Transitions transitions = Transitions::kNone;
  float dt_ms = 1000.0f / 60.0f;    // >= 0, finite: time since the last run() (fades advance by it)
  float fade_ms = 250.0f;           // >= 0, finite: duration of a cross-fade (0 = hard switches)
  float morph_band = 0.3f;          // (0, 1]: the share of a level's log pixel-size interval, before
                                    // its switch to the next coarser level, over which the morph
                                    // factor rises from 0 to 1 (smoothstep)
  float fade_budget_share = 0.1f;   // [0, 1], budget mode: the share of the objects' budget (budget_ms
                                    // less the mandatory part) that fading-out levels may take; fades
                                    // beyond it end at once (hard switches)
};

struct SelectionStats {
  uint64_t frame = 0;              // index of this selection on the context, from 0; pass it to
                                   // reportFrameTime when the frame has been rendered
  double predicted_ms = 0.0;       // predicted cost of the chosen levels, per-frame constant included
  double mandatory_ms = 0.0;       // per-frame constant + must-draw objects and objects kept by the
                                   // drop policy (min_drop_px) at their cheapest level
  double total_benefit = 0.0;      // sum of benefits of the chosen levels (hysteresis included)
  double lambda = 0.0;             // benefit per ms at the budget's edge (budget mode)
  CostFeatures features;           // what the chosen levels draw (the calibration's regressors;
                                   // with views, the shadow views' part in its shadow_* fields)
  uint32_t drawn_count = 0;
  uint32_t culled_count = 0;       // outside the view frustum (never drawn)
  uint32_t dropped_count = 0;      // in view but not drawn to fit the budget
  uint32_t switch_count = 0;       // objects whose level changed since last frame (to/from -1 included)
  uint32_t search_passes = 0;      // linear passes of the price search
  uint32_t flags = 0;              // SelectionFlag bits
  uint32_t group_count = 0;        // view groups of the frame (1 without views)
  // transitions: objects in view that draw a fading-out level beside their level this frame, and
  // that level's predicted cost (included in predicted_ms and features). Budget mode reserves the
  // fades running since an earlier frame before the choice (counted in mandatory_ms) and keeps all
  // fades within fade_budget_share of the objects' budget, so predicted_ms exceeds budget_ms by at
  // most the fades started in this frame, themselves within that share
  uint32_t fading_count = 0;
  double fade_cost_ms = 0.0;
};

class SelectorContext;

struct SelectorConfig {
  size_t max_object_count = 0;       // > 0
  size_t max_levels_per_chain = 16;  // 1..64
  size_t max_level_rows = 65536;     // rows of the level table (all chains' levels together)
  size_t bracket_capacity = 2048;    // upgrades sorted at the budget's edge by the Lagrangian form
  CostCoefficients initial_cost;
  CalibrationParams calibration;
  Allocator allocator;               // null functions = defaultAllocator()
  bool sse2_only = false;            // true: the SSE2 code paths even where the CPU has AVX2 (both
                                     // give the same bits; tests compare them)
  size_t max_view_groups = 0;        // 0..8: view groups a job may use (views, forced levels); 0 keeps
                                     // no memory for them. Each costs 285 bytes per object, plus 26
                                     // per object and 39 KB for any (docs/SELECTION.md, "Views").
};

// Creates a context: all memory for max_object_count objects in one allocation. Returns null on a bad
// config or when the allocator fails. Cost: one allocation, O(max_object_count).
SelectorContext* createSelectorContext(const SelectorConfig& config);
// Frees the context through its allocator. Null is ignored.
void destroySelectorContext(SelectorContext* context);
// Forgets last frame's levels and price (a cold start); the cost model is kept.
void resetSelectorHistory(SelectorContext* context);
// Bytes the context holds, and the part of it that scales per object, divided by max_object_count.
size_t selectorMemoryBytes(const SelectorContext* context);
double selectorBytesPerObject(const SelectorContext* context);

// The current cost model (the prior, or the calibrated one), the learnt shadow factors included.
CostCoefficients selectorCostModel(const SelectorContext* context);
// Replaces the cost model and restarts its calibration from it.
void setSelectorCostModel(SelectorContext* context, const CostCoefficients& coefficients);

// Hands the measured time of frame `frame` (SelectionStats::frame) to the context. Lock-free,
// wait-free; may run concurrently with run() from one other thread. The next run() feeds it to the
// calibration if it refers to one of the last 16 frames; a newer report overwrites an unread one.
void reportFrameTime(SelectorContext* context, uint64_t frame, float measured_ms);

// Predicted cost and benefit (hysteresis included) the last run() gave `object` at `level` (-1 = not
// drawn) in budget mode. Returns false when the object was culled, the level is out of range, or
// the last run was not a single-view budget frame (no views, no forced levels). Needs nothing of the last run's inputs. For tests and tools.
bool selectorLastPoint(const SelectorContext* context, size_t object, int level, double* cost_ms,
                       double* benefit);

struct SelectionJob {
  // inputs
  const Camera* camera = nullptr;
  SelectionParams params;
  LevelTable levels;
  Span<const glm::vec3> centers;        // world bounding-sphere centres, one per object
  Span<const float> radii;              // world bounding-sphere radii, >= 0
  Span<const float> max_scales;         // largest scale of the instance (cell widths are object space)
  Span<const uint32_t> chains;          // chain of each object, < levels.chainCount()
  Span<const float> importance;         // empty = 1 for all, else one per object, >= 0
  Span<const uint8_t> must_draw;        // empty = none, else one per object (nonzero = must draw)
  Span<const float> visible_fraction;   // empty = 1 (visibility helper), else in [0, 1]
  Span<const float> focus;              // empty = 1, else >= 0
  Span<const float> motion;             // empty = 1, else in [0, 1] (lower for fast-moving objects)
  // Several views (up to kMaxViews): empty = the one view of `camera` with params.pixels_per_cell.
  // With views, `camera` and params.pixels_per_cell are not read, visible_fraction must be empty
  // (each view has its own) and the context needs max_view_groups >= the groups used.
  // Rules: a shadow group never gets an object finer than the primary group (the first group of
  // kind primary, else of kind eye, else of kind secondary) unless the object is outside the
  // primary group's views; an object outside every view of a group is -1 there and costs nothing.
  Span<const View> views;
  Span<const int8_t> forced_levels;     // empty = all free, else one per object: -1 free, or the level
                                        // drawn in every group that sees the object (must be < its
                                        // chain's level count); needs max_view_groups >= 1
  // outputs
  Span<int8_t> levels_out;              // one per object: chosen level, -1 = not drawn; with views,
                                        // the primary group's (else the first group's)
  Span<int8_t> group_levels_out;        // empty, or with views group_count * objects: the level of
                                        // object i in group g (order of first appearance) at g * n + i
  Span<float> cost_ms_out;              // empty or one per object: predicted cost of its level(s)
  // transition outputs (each empty or one per object; docs/SELECTION.md, "Transitions"):
  Span<float> morph_out;                // geomorph factor of levels_out's level toward the next
                                        // coarser level, in [0, 1]; 0 without morphs
  Span<int8_t> previous_levels_out;     // the level fading out (-1: fading in from nothing); equal to
                                        // levels_out when no fade runs
  Span<float> fade_out;                 // weight of levels_out's level in [0, 1] (1 - fade for the
                                        // previous level); 1 when no fade runs
  SelectionStats* stats = nullptr;      // may be null
  SelectorContext* context = nullptr;

  // Null when the job can run, else what is wrong with it (a static string): a null context or
  // camera, an invalid camera, spans of the wrong size, more objects or level rows than the context
  // holds, a malformed level table (offsets, more levels than max_levels_per_chain, decreasing or
  // non-finite widths), a chain id out of range, non-positive budget in budget mode or non-positive
  // pixels_per_cell; with views: more than kMaxViews, a group mixing kinds, a view with a zero
  // viewport or an invalid camera, X or bias not positive, more groups than max_view_groups, a
  // wrong-sized output; a forced level out of its chain's range; dt_ms negative or not finite,
  // fade_ms negative or not finite, morph_band outside (0, 1], fade_budget_share outside [0, 1], transitions with views or forced
  // levels, a has_morph column of the wrong length; min_drop_px negative or not finite.
  // Cost: O(objects + rows).
  const char* error() const;
  // error() == nullptr.
  bool validate() const;
  // validate(), then selects. Returns false (outputs untouched) when validation fails.
  // Cost: O(objects * levels) per frame plus a few linear passes; no allocation.
  bool run();
};

}  // namespace scenelod::selection
