// Per-frame LOD selection: SelectionJob::run as a list of phases.
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
// The phases: validate; the rows' costs under this frame's cost model; the slot pass (frustum test,
// compaction of the objects in view into slots, their level-independent terms, and in distance
// mode their levels, block by block while the inputs are in cache); in budget mode the hulls
// (budget_hulls.cpp), the price search and the greedy on its bracket (budget_lagrangian.cpp) or the
// heap greedy (budget_greedy.cpp), the write-out and the 1/2 guarantee; the switches; the statistics.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

constexpr float kPi = 3.14159265358979f;

// The frame's inputs as the phases read them: the job's spans as plain pointers (null for an
// absent optional column), the camera's terms and the cost model's.
struct FrameInput {
  size_t n = 0;
  const float* xyz = nullptr;  // packed centres
  const float* radius = nullptr;
  const float* scale = nullptr;
  const uint32_t* chain_of = nullptr;
  const uint32_t* chain_offset = nullptr;
  size_t chain_count = 0;
  const float* importance = nullptr;
  const float* focus = nullptr;
  const float* motion = nullptr;
  const float* visible = nullptr;
  const uint8_t* must = nullptr;
  size_t rows = 0;
  const uint32_t* tri = nullptr;
  const uint32_t* vert = nullptr;
  const uint32_t* lines = nullptr;
  int8_t* level_of = nullptr;
  float* cost_out = nullptr;
  Frustum frustum;
  glm::vec3 eye{0.0f};
  float near_plane = 0.0f;
  float pixel_factor = 0.0f;
  float ortho_pixel = 0.0f;
  bool ortho = false;
  float viewport_px = 0.0f;
  float x_cells = 0.0f;
  float c_obj = 0.0f, c_px = 0.0f;  // the cost model's per object and per pixel
  double per_frame_ms = 0.0;
  bool budget = false;
  float keep_px = 0.0f;          // budget mode: slots with at least these projected pixels are kept
                                 // (the drop policy; +inf: none)
  bool keep_slot_terms = false;  // distance mode: keep a and pixels in the slot columns (transitions)
  float* morph_out = nullptr;    // distance mode, morph transitions: the morph factors, per block
};

FrameInput frameInput(const SelectionJob& job, const CostCoefficients& coef) {
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "centers are read as packed floats");
  const Camera& cam = *job.camera;
  FrameInput in;
  in.n = job.centers.count;
  in.xyz = in.n ? &job.centers[0].x : nullptr;
  in.radius = job.radii.data;
  in.scale = job.max_scales.data;
  in.chain_of = job.chains.data;
  in.chain_offset = job.levels.chain_level_offset.data;
  in.chain_count = job.levels.chainCount();
  in.importance = job.importance.count ? job.importance.data : nullptr;
  in.focus = job.focus.count ? job.focus.data : nullptr;
  in.motion = job.motion.count ? job.motion.data : nullptr;
  in.visible = job.visible_fraction.count ? job.visible_fraction.data : nullptr;
  in.must = job.must_draw.count ? job.must_draw.data : nullptr;
  in.rows = job.levels.cell_width.count;
  in.tri = job.levels.triangle_count.data;
  in.vert = job.levels.vertex_count.data;
  in.lines = job.levels.line_point_count.data;
  in.level_of = job.levels_out.data;
  in.cost_out = job.cost_ms_out.count ? job.cost_ms_out.data : nullptr;
  in.frustum = computeFrustum(cam);
  in.eye = cam.eye;
  in.near_plane = cam.near_plane;
  in.pixel_factor = pixelSizeFactor(cam);
  in.ortho_pixel = pixelSize(cam, 0.0f);
  in.ortho = cam.projection == Projection::kOrthographic;
  in.viewport_px = static_cast<float>(cam.viewport_width_px) * static_cast<float>(cam.viewport_height_px);
  in.x_cells = job.params.pixels_per_cell;
  in.c_obj = static_cast<float>(coef.per_object_ms);
  in.c_px = static_cast<float>(coef.per_pixel_ms);
  in.per_frame_ms = coef.per_frame_ms;
  in.budget = job.params.mode == SelectionMode::kBudget;
  in.keep_slot_terms = job.params.transitions != Transitions::kNone;
  const float min_drop = job.params.min_drop_px;
  in.keep_px = min_drop > 0.0f ? std::min(kPi * min_drop * min_drop, in.viewport_px)
                               : std::numeric_limits<float>::infinity();
  if (!in.budget && job.params.transitions == Transitions::kMorph && job.morph_out.count) in.morph_out = job.morph_out.data;
  return in;
}

// Each level-table row's geometry cost under this frame's cost model, and 1 / its cell width.
void priceRows(SelectorContext& ctx, const LevelTable& levels, const CostCoefficients& coef) {
  const float c_tri = static_cast<float>(coef.per_triangle_ms), c_vert = static_cast<float>(coef.per_vertex_ms),
              c_lp = static_cast<float>(coef.per_line_point_ms);
  for (size_t r = 0; r < levels.cell_width.count; ++r) {
    ctx.row_cost[r] = c_tri * static_cast<float>(levels.triangle_count[r]) +
                      c_vert * static_cast<float>(levels.vertex_count[r]) +
                      c_lp * static_cast<float>(levels.line_point_count[r]);
    const float w = levels.cell_width[r];
    ctx.row_inv_w[r] = w > 0.0f ? 1.0f / w : std::numeric_limits<float>::infinity();
  }
  // per chain: the smallest cost from each row to the chain's end, and the spread of its costs
  // when they fall strictly from level to level (the drop policy's settling, budget_hulls.cpp)
  for (size_t c = 0; c < levels.chainCount(); ++c) {
    const uint32_t b = levels.chain_level_offset[c], e = levels.chain_level_offset[c + 1];
    float least = std::numeric_limits<float>::infinity();
    bool falling = true;
    for (uint32_t r = e; r-- > b;) {
      least = std::min(least, ctx.row_cost[r]);
      ctx.row_suffix_min[r] = least;
      if (r + 1 < e) falling &= ctx.row_cost[r] > ctx.row_cost[r + 1];
    }
    if (e > b) ctx.row_spread[b] = falling ? ctx.row_cost[b] - ctx.row_cost[e - 1] : std::numeric_limits<float>::infinity();
  }
  // a chain's kLanes rows are read side by side, past the last row too
  for (size_t r = levels.cell_width.count; r < levels.cell_width.count + kLanes; ++r) {
    ctx.row_cost[r] = 0.0f;
    ctx.row_inv_w[r] = 0.0f;
  }
}

// One block's slot columns: in budget mode the context's from the block's first slot on, in
// distance mode locals (the block's levels are chosen before the next block overwrites them).
struct SlotColumns {
  uint32_t* object;
  uint32_t* row0;
  float* q;
  float* a;
  float* b;
  float* px;
  uint8_t* finest;
  uint8_t* levels;
  int8_t* prev;
};

// What the slot pass hands to budget mode.
struct SlotPass {
  size_t slots = 0;
  double mandatory = 0.0;     // per-frame constant + must-draw objects at their cheapest level
  uint32_t prev_dropped = 0;  // slots last frame "not drawn" with a benefit > 0 (settleKeys)
};

// The m slots from s0: their level-independent terms (cost a, benefit b, accuracy term q, pixels)
// from the centres and radii the compaction queued (in the columns of a, b, q and pixels, read here
// before this block's terms overwrite them), then the chain terms and the finest candidate. The float
// terms run as plain loops over local columns that the compiler vectorises (sqrt and divisions 4 or
// 8 wide; the same IEEE operations as one object at a time, so the same bits).
inline __attribute__((always_inline)) void slotTerms(const FrameInput& in, const SelectorContext& ctx, size_t s0,
                                                     size_t m, const SlotColumns& g) {
  alignas(32) float gx[kSlotBlock], gy[kSlotBlock], gz[kSlotBlock], gr[kSlotBlock], gs[kSlotBlock];
  alignas(32) float gi[kSlotBlock], gf[kSlotBlock], gm[kSlotBlock], gv[kSlotBlock];
  // locals for every array: the stores would otherwise make the compiler reload them
  const float* const queue_x = ctx.slot_a + s0;
  const float* const queue_y = ctx.slot_b + s0;
  const float* const queue_z = ctx.slot_q + s0;
  const float* const queue_r = ctx.slot_px + s0;
  const uint32_t* const gobj = g.object;
  const float* const scale_of = in.scale;
  const float* const importance_of = in.importance;
  const float* const focus_of = in.focus;
  const float* const motion_of = in.motion;
  const float* const visible_of = in.visible;
  for (size_t j = 0; j < m; ++j) {
    gx[j] = queue_x[j];
    gy[j] = queue_y[j];
    gz[j] = queue_z[j];
    gr[j] = queue_r[j];
  }
  for (size_t j = 0; j < m; ++j) gs[j] = scale_of[gobj[j]];
  // missing factors are 1 (b * 1.0f == b)
  for (size_t j = 0; j < m; ++j) gi[j] = importance_of ? importance_of[gobj[j]] : 1.0f;
  for (size_t j = 0; j < m; ++j) gf[j] = focus_of ? focus_of[gobj[j]] : 1.0f;
  for (size_t j = 0; j < m; ++j) gm[j] = motion_of ? motion_of[gobj[j]] : 1.0f;
  for (size_t j = 0; j < m; ++j) gv[j] = visible_of ? visible_of[gobj[j]] : 1.0f;
  // gx becomes the pixel size R
  if (in.ortho) {
    const float ortho_pixel = in.ortho_pixel;
    for (size_t j = 0; j < m; ++j) gx[j] = ortho_pixel;
  } else {
    const glm::vec3 eye = in.eye;
    const float near_plane = in.near_plane, pixel_factor = in.pixel_factor;
    for (size_t j = 0; j < m; ++j) {
      const float dx = gx[j] - eye.x, dy = gy[j] - eye.y, dz = gz[j] - eye.z;
      const float dist = std::sqrt(dx * dx + dy * dy + dz * dz);
      gx[j] = std::max(dist - gr[j], near_plane) * pixel_factor;  // = pixelSize(cam, dist - r)
    }
  }
  float* const gq = g.q;
  float* const ga = g.a;
  float* const gb = g.b;
  float* const gpx = g.px;
  const float viewport_px = in.viewport_px, x_cells = in.x_cells, c_obj = in.c_obj, c_px = in.c_px;
  for (size_t j = 0; j < m; ++j) {
    const float pixel = gx[j];
    const float r_px = gr[j] / pixel;
    const float px = std::min(kPi * r_px * r_px, viewport_px);
    gq[j] = x_cells * pixel / gs[j];
    ga[j] = c_obj + c_px * px;
    gb[j] = (((px * gi[j]) * gf[j]) * gm[j]) * gv[j];
    gpx[j] = px;
  }
  (ctx.use_avx2 ? chainTermsAvx2 : chainTermsSse2)(gobj, gq, m, in.chain_of, in.chain_offset, ctx.row_inv_w,
                                                   ctx.prev_level, g.finest, g.row0, g.prev, g.levels, in.level_of);
}

// Budget mode's part of a block of slots (in the context's columns from s0): the settling keys,
// and the slots kept in view at any price (must-draw objects, never settled, and objects the drop
// policy keeps, which settle like the others but without a "not drawn" point) with their cheapest
// level's cost to the mandatory part.
inline __attribute__((always_inline)) void budgetSlotTerms(const FrameInput& in, SelectorContext& ctx, size_t s0,
                                                           size_t m, const SlotColumns& g, SlotPass* pass) {
  uint16_t* const key = ctx.slot_key + s0;
  uint8_t* const must = ctx.slot_must + s0;
  pass->prev_dropped += (ctx.use_avx2 ? settleKeysAvx2 : settleKeysSse2)(g.a, g.b, g.levels, g.finest, g.prev, m, key);
  const uint8_t* const must_of = in.must;
  const float keep_px = in.keep_px;
  if (!must_of && !(keep_px < std::numeric_limits<float>::infinity())) {
    std::memset(must, 0, m);
    return;
  }
  const float* const suffix_min = ctx.row_suffix_min;
  const float* const visible_of = in.visible;
  double mandatory = pass->mandatory;
  for (size_t j = 0; j < m; ++j) {
    const uint32_t i = g.object[j];
    const bool must_draw = must_of && must_of[i] != 0;
    // the drop policy: large enough on screen and not hidden
    const bool large = g.px[j] >= keep_px && (!visible_of || visible_of[i] > kHiddenFraction);
    const bool kept = must_draw || large;
    must[j] = kept ? 1 : 0;
    if (kept) {
      // a kept object settles at a drawn level only (its hull has no "not drawn" point)
      const uint16_t k = key[j];
      key[j] = must_draw || k >= kSettleIneligible || (k & 15u) == 0 ? kSettleIneligible
                                                                    : static_cast<uint16_t>(k | kSettleKeep);
      // the cheapest of its levels [finest, count): min over l of a + row cost (ctx.pointCost)
      mandatory += g.a[j] + suffix_min[g.row0[j] + g.finest[j]];
    }
  }
  pass->mandatory = mandatory;
}

// Distance mode's levels of a block of m slots: the finest candidate, or a coarser current level
// while it is within the hysteresis margin; each slot's cost and benefit at it added to the
// frame's sums in slot order (the slot is drawn: ctx.pointCost / ctx.pointBenefit at its level); each
// slot's row to row_of.
inline __attribute__((always_inline)) void distanceLevels(const FrameInput& in, const SelectorContext& ctx, size_t m,
                                                          const SlotColumns& g, SlotSums* sums, uint32_t* row_of) {
  const float* const row_cost = ctx.row_cost;
  const float* const row_inv_w = ctx.row_inv_w;
  const uint32_t* const tri = in.tri;
  const uint32_t* const vert = in.vert;
  const uint32_t* const lines = in.lines;
  int8_t* const level_of = in.level_of;
  float* const cost_out = in.cost_out;
  const float h_mult[2] = {1.0f, ctx.h1};
  const float h1 = ctx.h1;
  SlotSums s = *sums;
  for (size_t j = 0; j < m; ++j) {
    const uint32_t row0 = g.row0[j];
    int level = g.finest[j];
    const int p = g.prev[j];
    // hysteresis: a coarser current level stays while it is within the margin (ctx.accuracy)
    if (p > level && p < static_cast<int>(g.levels[j]) &&
        std::min(1.0f, g.q[j] * row_inv_w[row0 + static_cast<uint32_t>(p)]) * h1 >= 1.0f)
      level = p;
    const uint32_t row = row0 + static_cast<uint32_t>(level);
    row_of[j] = row;
    const float cost = g.a[j] + row_cost[row];
    const float acc = std::min(1.0f, g.q[j] * row_inv_w[row]) * h_mult[level == p];
    s.predicted += cost;
    s.benefit += g.b[j] * acc;
    s.tri += tri[row];
    s.vert += vert[row];
    s.lines += lines[row];
    s.pixels += g.px[j];
    s.drawn += 1;
    level_of[g.object[j]] = static_cast<int8_t>(level);
    if (cost_out) cost_out[g.object[j]] = cost;
  }
  *sums = s;
}

// The frustum test and compaction of one block of mo objects from i0 when some chain has no level
// (its objects are never slots): branch-free, each object queued and kept when in view and with
// levels. Returns the new slot count.
size_t compactWithEmptyChains(const FrameInput& in, SelectorContext& ctx, size_t i0, size_t mo, size_t slots) {
  alignas(32) uint8_t gout[kSlotBlock];
  (ctx.use_avx2 ? frustumOutsideAvx2 : frustumOutsideSse2)(in.frustum, in.xyz + 3 * i0, in.radius + i0, mo, gout);
  const uint32_t* const chain_of = in.chain_of;
  const uint32_t* const chain_offset = in.chain_offset;
  const float* const xyz = in.xyz;
  const float* const radius_of = in.radius;
  int8_t* const level_of = in.level_of;
  uint32_t* const slot_object = ctx.slot_object;
  float* const queue_x = ctx.slot_a;
  float* const queue_y = ctx.slot_b;
  float* const queue_z = ctx.slot_q;
  float* const queue_r = ctx.slot_px;
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
  return slots;
}

// The frustum test and compaction of one block of mo objects from i0 when every chain has levels.
// Returns the new slot count.
size_t compactBlock(const FrameInput& in, SelectorContext& ctx, size_t i0, size_t mo, size_t slots) {
  int8_t* const level_of = in.level_of;
  if (mo == kSlotBlock) {
    // a full block by four 16-byte stores (the byte loop was about 56 instructions a block)
    const uint64_t ones[2] = {~uint64_t(0), ~uint64_t(0)};
    for (size_t k = 0; k < kSlotBlock; k += 16) std::memcpy(level_of + i0 + k, ones, sizeof(ones));
  } else {
    for (size_t j = 0; j < mo; ++j) level_of[i0 + j] = -1;
  }
  const SphereQueue queue{ctx.slot_object + slots, ctx.slot_a + slots, ctx.slot_b + slots, ctx.slot_q + slots,
                          ctx.slot_px + slots};
  return slots + (ctx.use_avx2 ? frustumCompactAvx2 : frustumCompactSse2)(in.frustum, in.xyz + 3 * i0, in.radius + i0,
                                                                          mo, static_cast<uint32_t>(i0), queue);
}

// The slot pass: the frustum test and the compaction of the objects in view (and with levels) into
// slots, a block of objects at a time, and per block of kSlotBlock slots their terms and finest
// candidate, so that each object's inputs are read once (the compaction queues the centres and
// radii it has loaded for the frustum test beside the slots' object indices). Budget mode stores
// the slots' terms in the slot columns for the hull passes; distance mode needs no column but the
// queue: it chooses the level and adds the slot to the frame's sums in the same block (slot order
// as in the budget write-out). Every object's level starts at -1 (culled: stays).
SlotPass slotPass(const FrameInput& in, SelectorContext& ctx, SlotSums* distance_sums) {
  SlotPass pass;
  pass.mandatory = in.per_frame_ms;
  bool any_empty_chain = false;
  for (size_t c = 0; c < in.chain_count; ++c) any_empty_chain |= in.chain_offset[c + 1] == in.chain_offset[c];
  // distance mode's block columns
  alignas(32) uint32_t lrow0[kSlotBlock], lrow[kSlotBlock];  // first rows, chosen rows
  alignas(32) float lq[kSlotBlock], la[kSlotBlock], lb[kSlotBlock], lpx[kSlotBlock];
  alignas(32) uint8_t lfinest[kSlotBlock], llevels[kSlotBlock];
  alignas(32) int8_t lprev[kSlotBlock];
  // inlined at both calls: a full block's loops get their constant trip count
  auto slotBlock = [&](size_t s0, size_t m) __attribute__((always_inline)) {
    const SlotColumns g =
        in.budget ? SlotColumns{ctx.slot_object + s0, ctx.slot_row0 + s0,  ctx.slot_q + s0,
                                ctx.slot_a + s0,      ctx.slot_b + s0,     ctx.slot_px + s0,
                                ctx.slot_finest + s0, ctx.slot_levels + s0, ctx.slot_prev + s0}
                  : SlotColumns{ctx.slot_object + s0, lrow0, lq, la, lb, lpx, lfinest, llevels, lprev};
    slotTerms(in, ctx, s0, m, g);
    if (in.budget) {
      budgetSlotTerms(in, ctx, s0, m, g, &pass);
    } else {
      distanceLevels(in, ctx, m, g, distance_sums, lrow);
      if (in.keep_slot_terms) {  // the block's queue entries are consumed: their columns are free
        std::memcpy(ctx.slot_a + s0, la, m * sizeof(float));
        std::memcpy(ctx.slot_px + s0, lpx, m * sizeof(float));
      }
      if (in.morph_out) morphFactorsAtRows(ctx, g.object, lrow, g.q, m, in.morph_out);
    }
  };
  // slots are handed on in full blocks while their objects' inputs are still in cache
  size_t slots = 0, done = 0;
  for (size_t i0 = 0; i0 < in.n; i0 += kSlotBlock) {
    const size_t mo = std::min(kSlotBlock, in.n - i0);
    slots = any_empty_chain ? compactWithEmptyChains(in, ctx, i0, mo, slots) : compactBlock(in, ctx, i0, mo, slots);
    if (in.cost_out && !in.budget)
      for (size_t j = 0; j < mo; ++j) in.cost_out[i0 + j] = 0.0f;
    if (slots - done >= kSlotBlock) {
      slotBlock(done, kSlotBlock);
      done += kSlotBlock;
    }
  }
  for (; done < slots; done += kSlotBlock) slotBlock(done, std::min(kSlotBlock, slots - done));
  pass.slots = slots;
  return pass;
}

// The budget write-out of every slot: levels, sums and features (selector_simd.cpp). chosen[]
// holds steps along the hulls, whose entries are level bytes (kNotDrawn = -1), or kSettledAtPrev /
// kSettledAtBase for a settled slot.
SlotSums writeOutAll(const FrameInput& in, const SelectorContext& ctx, size_t slots) {
  // counting per row pays when there are fewer rows than slots
  const bool count_rows = in.rows <= slots;
  const WriteOutInput wo{ctx.chosen, ctx.hull, ctx.hull_stride, ctx.slot_object, ctx.slot_a, ctx.slot_b,
                         ctx.slot_q, ctx.slot_px, ctx.slot_row0, ctx.slot_prev, ctx.row_cost, ctx.row_inv_w,
                         in.tri, in.vert, in.lines, ctx.h1, count_rows ? ctx.row_drawn : nullptr, in.rows};
  return writeOutSlots(ctx.use_avx2, count_rows, wo, slots, in.per_frame_ms, in.level_of);
}

// The fused form: the settled slots' levels and sums are in (the slot pass and the settling pass),
// the unsettled slots' are added after them in slot order (the write-out's operations), and the
// features summed per row. The float sums are then in another order than writeOutAll's (settled
// slots first): the same values whenever every partial double sum is exact (no more than
// 53 significant bits), as on every scene checked (docs/bench/selection.md)
SlotSums writeOutUnsettled(const FrameInput& in, const SelectorContext& ctx, const HullSums& hulls,
                           uint32_t prev_dropped) {
  const uint8_t* const hull = ctx.hull;
  const size_t hull_stride = ctx.hull_stride;
  const uint32_t* const slot_object = ctx.slot_object;
  const float* const slot_a = ctx.slot_a;
  const float* const slot_b = ctx.slot_b;
  const float* const slot_q = ctx.slot_q;
  const float* const slot_px = ctx.slot_px;
  const uint32_t* const slot_row0 = ctx.slot_row0;
  const int8_t* const slot_prev = ctx.slot_prev;
  const float* const row_cost = ctx.row_cost;
  const float* const row_inv_w = ctx.row_inv_w;
  int8_t* const level_of = in.level_of;
  const float h_mult[2] = {1.0f, ctx.h1};
  SlotSums sums{};
  sums.predicted = in.per_frame_ms + hulls.settled.cost;
  sums.benefit = hulls.settled.benefit;
  sums.pixels = hulls.settled.pixels;
  // settleKeys counted the slots last frame "not drawn" with a benefit: the settled ones are
  // dropped again, the unsettled ones are counted by their level here instead
  uint32_t dropped = prev_dropped;
  const uint32_t* const list = reinterpret_cast<const uint32_t*>(ctx.heap);
  const uint8_t* const chosen = ctx.chosen;
  uint32_t* const row_drawn = ctx.row_drawn;
  for (size_t u = 0; u < hulls.unsettled_count; ++u) {
    const size_t s = list[u];
    const uint8_t level = hull[s * hull_stride + chosen[s]];
    level_of[slot_object[s]] = static_cast<int8_t>(level);
    const uint32_t keep = 0u - static_cast<uint32_t>(level != kNotDrawn);  // all ones if drawn
    const float b = slot_b[s];
    dropped += (keep ^ 1u) & (b > 0.0f ? 1u : 0u);
    dropped -= slot_prev[s] < 0 && b > 0.0f ? 1u : 0u;
    const uint32_t row = slot_row0[s] + (level & keep);
    row_drawn[row] -= keep;
    const float cost = slot_a[s] + row_cost[row];
    const bool current = level == static_cast<uint8_t>(slot_prev[s]);
    const float acc = std::min(1.0f, slot_q[s] * row_inv_w[row]) * h_mult[current];
    sums.predicted += maskFloat(cost, keep);
    sums.benefit += maskFloat(b * acc, keep);
    sums.pixels += maskFloat(slot_px[s], keep);
  }
  for (size_t r = 0; r < in.rows; ++r) {
    const uint64_t k = row_drawn[r];
    sums.drawn += static_cast<uint32_t>(k);
    sums.tri += k * in.tri[r];
    sums.vert += k * in.vert[r];
    sums.lines += k * in.lines[r];
  }
  sums.dropped = dropped;
  return sums;
}

// The 1/2 guarantee: the first upgrade that did not fit, alone with every other object at its base,
// replaces the greedy's choice when its benefit is higher (the write-out's benefit, summed in slot
// order, is what the greedy's choice scores). Returns whether it did (ctx.chosen rewritten).
bool halfGuarantee(SelectorContext& ctx, const HullSums& hulls, const BudgetChoice& choice, size_t slots,
                   double greedy_benefit) {
  const size_t js = static_cast<size_t>(choice.split_slot);
  // settled kept slots have no hull: their base is their coarsest level (they settle only on
  // chains whose costs fall from level to level, so it is their cheapest)
  // (16 slots at a time: without the drop policy no slot is one, and most blocks have none)
  typedef uint8_t V16u __attribute__((vector_size(16)));
  const uint8_t* const chosen = ctx.chosen;
  const uint8_t* const must = ctx.slot_must;
  double kept_settled_benefit = 0.0;
  auto add = [&](size_t s) {
    if (chosen[s] == kSettledAtPrev && must[s])
      kept_settled_benefit += ctx.pointBenefit(s, static_cast<int>(ctx.slot_levels[s]) - 1);
  };
  size_t s0 = 0;
  for (; s0 + 16 <= slots; s0 += 16) {
    V16u c, k;
    std::memcpy(&c, chosen + s0, sizeof(c));
    std::memcpy(&k, must + s0, sizeof(k));
    const auto hit = (c == kSettledAtPrev) & (k != 0);
    uint64_t w[2];
    std::memcpy(w, &hit, sizeof(w));
    if ((w[0] | w[1]) == 0) continue;
    for (size_t s = s0; s < s0 + 16; ++s) add(s);
  }
  for (; s0 < slots; ++s0) add(s0);
  const double alt_benefit = hulls.base_benefit + kept_settled_benefit +
                             ctx.pointBenefit(js, ctx.hullLevel(js, choice.split_step + 1)) -
                             ctx.pointBenefit(js, ctx.hullLevel(js, 0));
  if (!(alt_benefit > greedy_benefit)) return false;
  for (size_t s = 0; s < slots; ++s) {  // every slot at its base
    if (ctx.chosen[s] == kSettledAtPrev && ctx.slot_must[s]) {
      ctx.hull[s * ctx.hull_stride] = static_cast<uint8_t>(ctx.slot_levels[s] - 1);
      ctx.chosen[s] = 0;
    } else {
      ctx.chosen[s] = ctx.chosen[s] == kSettledAtPrev ? kSettledAtBase : 0;
    }
  }
  ctx.chosen[js] = static_cast<uint8_t>(choice.split_step + 1);
  return true;
}

// Budget mode after the slot pass: the hulls, the price search and the greedy on its bracket (or
// the heap greedy), the write-out and the 1/2 guarantee. Returns the frame's sums.
SlotSums budgetLevels(const FrameInput& in, SelectorContext& ctx, const SelectionParams& params, const SlotPass& pass,
                      double reserve, SelectionStats* st) {
  // the fades running since an earlier frame (`reserve`, transitions) come off the budget first
  const double cap = static_cast<double>(params.budget_ms) - reserve;
  BudgetFrame frame;
  frame.slots = pass.slots;
  frame.rows = in.rows;
  frame.avail = cap - pass.mandatory;
  frame.obj_cap = cap - in.per_frame_ms;
  frame.keep = in.keep_px < std::numeric_limits<float>::infinity();
  frame.use_greedy = params.algorithm == BudgetAlgorithm::kGreedy || !params.stop_at_first_non_fitting;
  frame.hist = histogramWindow(ctx, frame.slots, frame.use_greedy);
  for (size_t r = 0; r < in.rows; ++r) frame.rows_nonnegative &= ctx.row_cost[r] >= 0.0f;
  // the incremental case: last frame's price predicts the bracket
  const bool predict = !frame.use_greedy && pricePredictable(ctx);
  const PriceBracket predicted = predict ? predictedBracket(ctx) : PriceBracket{0.0, 0.0};
  HullSums hulls = buildHulls(ctx, frame, predict ? &predicted : nullptr);
  const BudgetChoice choice =
      frame.use_greedy ? heapGreedy(ctx, frame.slots, frame.obj_cap, params.stop_at_first_non_fitting)
                       : lagrangianChoice(ctx, frame, predict ? &predicted : nullptr, &hulls);
  ctx.last_lambda = choice.lambda;
  st->lambda = choice.lambda;
  st->search_passes = choice.passes;
  if (pass.mandatory > cap) st->flags |= kFlagOverBudget;
  SlotSums sums =
      hulls.fused ? writeOutUnsettled(in, ctx, hulls, pass.prev_dropped) : writeOutAll(in, ctx, frame.slots);
  if (params.half_approximation && choice.split_slot >= 0 &&
      halfGuarantee(ctx, hulls, choice, frame.slots, sums.benefit)) {
    st->flags |= kFlagSplitFallback;
    sums = writeOutAll(in, ctx, frame.slots);
  }
  if (in.cost_out) {
    for (size_t i = 0; i < in.n; ++i) in.cost_out[i] = 0.0f;
    for (size_t s = 0; s < frame.slots; ++s) {
      const size_t i = ctx.slot_object[s];
      if (in.level_of[i] >= 0) in.cost_out[i] = ctx.pointCost(s, in.level_of[i]);
    }
  }
  return sums;
}

// The objects whose level changed since last frame, last frame's levels overwritten in the same
// loop: 16 objects at a time in byte lanes (-1 per differing lane, at most 127 vectors per count
// before it is widened).
uint32_t countSwitches(const int8_t* level_of, int8_t* prev_level, size_t n) {
  typedef int8_t V16b __attribute__((vector_size(16)));
  uint32_t switches = 0;
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
  return switches;
}

// The features of the chosen levels. The integer features were summed exactly in 64 bits (n < 2^31
// terms below 2^32): the same value as the double sum in slot order while the total stays below
// 2^53 (every partial sum is then an exact double); above, that double sum rounded: it is summed
// so again (drawn objects in object order are the slots in slot order, and a slot not drawn added +0).
CostFeatures frameFeatures(const FrameInput& in, const SlotSums& sums) {
  CostFeatures f;
  f.pixels = sums.pixels;
  f.objects = static_cast<double>(sums.drawn);
  constexpr uint64_t kExact = uint64_t(1) << 53;
  const uint32_t* const feature[3] = {in.tri, in.vert, in.lines};
  const uint64_t totals[3] = {sums.tri, sums.vert, sums.lines};
  double* const out[3] = {&f.triangles, &f.vertices, &f.line_points};
  for (int k = 0; k < 3; ++k) {
    if (totals[k] < kExact) {
      *out[k] = static_cast<double>(totals[k]);
      continue;
    }
    double t = 0.0;
    for (size_t i = 0; i < in.n; ++i)
      if (in.level_of[i] >= 0)
        t += feature[k][in.chain_offset[in.chain_of[i]] + static_cast<uint32_t>(in.level_of[i])];
    *out[k] = t;
  }
  return f;
}

}  // namespace

const char* SelectionJob::error() const {
  if (!context) return "no selector context";
  const bool with_views = views.count > 0;
  if (!with_views && (!camera || !cameraValid(*camera))) return "no camera, or an invalid one";
  const size_t n = centers.count;
  if (n > context->max_objects) return "more objects than the context holds";
  if (levels.cell_width.count > context->max_rows) return "more level rows than the context holds";
  if (radii.count != n || max_scales.count != n || chains.count != n || levels_out.count != n)
    return "radii, max_scales, chains and levels_out need one entry per object";
  if ((n > 0 && (!centers.data || !radii.data || !max_scales.data || !chains.data || !levels_out.data)))
    return "a null per-object column";
  auto optional = [n](size_t count, const void* data) { return count == 0 || (count == n && data); };
  if (!optional(importance.count, importance.data) || !optional(must_draw.count, must_draw.data) ||
      !optional(visible_fraction.count, visible_fraction.data) || !optional(focus.count, focus.data) ||
      !optional(motion.count, motion.data) || !optional(cost_ms_out.count, cost_ms_out.data) ||
      !optional(forced_levels.count, forced_levels.data))
    return "an optional per-object column is neither empty nor one per object";
  if (!with_views && (!(params.pixels_per_cell > 0.0f) || !std::isfinite(params.pixels_per_cell)))
    return "pixels_per_cell must be positive and finite";
  if (!(params.hysteresis >= 0.0f) || !std::isfinite(params.hysteresis)) return "hysteresis must be >= 0 and finite";
  if (!(params.min_drop_px >= 0.0f) || !std::isfinite(params.min_drop_px)) return "min_drop_px must be >= 0 and finite";
  if (params.mode == SelectionMode::kBudget && !(params.budget_ms > 0.0f)) return "budget_ms must be positive";
  // level table
  const size_t rows = levels.cell_width.count;
  if (levels.chain_level_offset.count < 1 || !levels.chain_level_offset.data) return "no chain_level_offset";
  if (levels.triangle_count.count != rows || levels.vertex_count.count != rows || levels.line_point_count.count != rows)
    return "level table columns of different lengths";
  if (rows > 0 && (!levels.cell_width.data || !levels.triangle_count.data || !levels.vertex_count.data ||
                   !levels.line_point_count.data))
    return "a null level table column";
  const size_t chain_count = levels.chainCount();
  if (levels.chain_level_offset[0] != 0 || levels.chain_level_offset[chain_count] != rows)
    return "chain_level_offset must start at 0 and end at the row count";
  for (size_t c = 0; c < chain_count; ++c) {
    const uint32_t b = levels.chain_level_offset[c], e = levels.chain_level_offset[c + 1];
    if (e < b || e - b > context->hull_stride - 1) return "a chain with decreasing offsets or more levels than max_levels_per_chain";
    for (uint32_t r = b; r < e; ++r) {
      const float w = levels.cell_width[r];
      if (!(w >= 0.0f) || !std::isfinite(w)) return "a cell width negative or not finite";
      if (r > b && w < levels.cell_width[r - 1]) return "cell widths decreasing within a chain";
    }
  }
  // no early exit: an OR over the whole column vectorises (the valid case reads it all anyway)
  if (n > 0 && chain_count == 0) return "objects but no chain";
  const uint32_t last_chain = static_cast<uint32_t>(chain_count - 1);
  if ((context->use_avx2 ? chainsAboveAvx2 : chainsAboveSse2)(chains.data, n, last_chain) != 0)
    return "a chain index out of range";
  if (const char* e = transitionsError(*this)) return e;
  if (with_views || forced_levels.count) return viewsError(*this);
  return nullptr;
}

bool SelectionJob::validate() const { return error() == nullptr; }

bool SelectionJob::run() {
  if (!validate()) return false;
  SelectorContext& ctx = *context;
  const CostCoefficients coef = takeReportedFrameTime(ctx, params.calibrate);
  priceRows(ctx, levels, coef);
  ctx.h1 = 1.0f + params.hysteresis;
  if (views.count || forced_levels.count) {
    runViews(*this, coef);  // selector_views.cpp
    noTransitions(ctx, *this);
    return true;
  }
  const bool transitions = params.transitions != Transitions::kNone;
  if (params.transitions == Transitions::kMorph) prepareMorphRows(ctx, levels, params);
  if (params.transitions == Transitions::kMorph && morph_out.count)  // fade mode: transitionPass
    std::fill(morph_out.data, morph_out.data + centers.count, 0.0f);
  const FrameInput in = frameInput(*this, coef);

  SlotSums sums{};
  sums.predicted = coef.per_frame_ms;
  const SlotPass pass = slotPass(in, ctx, &sums);
  SelectionStats st;
  st.frame = ctx.frame;
  st.culled_count = static_cast<uint32_t>(in.n - pass.slots);
  // fades running since an earlier frame draw their outgoing level too: budget mode reserves it,
  // within the share of the objects' budget that fades may take
  double new_fade_cap = std::numeric_limits<double>::infinity(), reserve = 0.0;
  if (in.budget && transitions) {
    const double share = params.fade_budget_share * std::max(0.0, static_cast<double>(params.budget_ms) - pass.mandatory);
    reserve = fadeReserve(ctx, *this, pass.slots, share);
    new_fade_cap = share - reserve;
  }
  st.mandatory_ms = in.budget ? pass.mandatory + reserve : 0.0;
  if (in.budget) sums = budgetLevels(in, ctx, params, pass, reserve, &st);
  TransitionSums fades;
  if (transitions)
    fades = transitionPass(ctx, *this, pass.slots, new_fade_cap);
  else
    noTransitions(ctx, *this);

  st.switch_count = countSwitches(in.level_of, ctx.prev_level, in.n);
  st.dropped_count = sums.dropped;
  st.drawn_count = sums.drawn;
  if (st.dropped_count > 0) st.flags |= kFlagObjectsDropped;
  st.predicted_ms = sums.predicted + fades.cost;
  st.total_benefit = sums.benefit;
  st.features = frameFeatures(in, sums);
  st.fading_count = fades.count;
  st.fade_cost_ms = fades.cost;
  if (fades.count) {
    st.features.objects += fades.count;
    st.features.pixels += fades.pixels;
    st.features.triangles += static_cast<double>(fades.tri);
    st.features.vertices += static_cast<double>(fades.vert);
    st.features.line_points += static_cast<double>(fades.lines);
  }
  recordFrame(ctx, st.features, in.budget, pass.slots);
  if (stats) *stats = st;
  return true;
}

}  // namespace scenelod::selection
