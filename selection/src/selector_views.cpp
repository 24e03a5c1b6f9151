// Frames with several views (shadow cascades, stereo eyes, split screens) or forced levels: one
// level per object and view group (docs/SELECTION.md, "Views").
//   Per object and group: in view when its sphere meets one of the group's frusta; the accuracy
//   term from the view needing the finest level (min over its views of X * bias * R / scale); the
//   level-independent cost summed over the views that see it, each scaled by its kind's weights
//   (a shadow view's times the calibration's learnt factors);
//   the benefit the largest of its views' (pixels * visible fraction of that view), times the kind's
//   benefit weight and the object's importance, focus and motion.
//   Distance mode: per group the coarsest accurate-enough level (with hysteresis), then a shadow
//   group is made no finer than the primary group where the primary group sees the object.
//   Budget mode: each object is one choice among tuples of levels (one per group) that obey the
//   same rule; its upper hull of (cost, benefit) over those tuples (budget_views.cpp builds it)
//   gives steps, which the greedy takes by falling ratio until one does not fit, with the 1/2
//   guarantee of the single-view path.
// Scalar code over the objects: the single-view path (selector.cpp) is not touched by it.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "budget_views.h"
#include "selector_internal.h"

namespace scenelod::selection {

namespace {

constexpr float kPi = 3.14159265358979f;

ViewKindWeights kindWeights(const SelectionParams& params, ViewKind kind) {
  return params.view_kinds[static_cast<size_t>(kind)];
}

// The views of the frame: the job's, or its camera as the one primary view.
Span<const View> frameViews(const SelectionJob& job, View* single) {
  if (job.views.count) return job.views;
  single->camera = *job.camera;
  single->pixels_per_cell = job.params.pixels_per_cell;
  single->visible_fraction = job.visible_fraction;
  return Span<const View>(single, 1);
}

// The group index of view v: its group value's rank in order of first appearance.
int groupIndexOf(Span<const View> views, size_t v) {
  int g = 0;
  for (size_t u = 0; u < v; ++u) {
    bool first = true;
    for (size_t w = 0; w < u; ++w) first &= views[w].group != views[u].group;
    if (views[u].group == views[v].group) return g;
    g += first ? 1 : 0;
  }
  return g;
}

}  // namespace

const char* viewsError(const SelectionJob& job) {
  const size_t n = job.centers.count;
  const SelectorContext& ctx = *job.context;
  if (job.views.count > kMaxViews) return "more than 8 views";
  if (job.views.count && !job.views.data) return "views has a count but no data";
  if (job.views.count && job.visible_fraction.count)
    return "visible_fraction must be empty with views (each view has its own)";
  ViewKind group_kind[kMaxViews];
  size_t groups = 0;
  for (size_t v = 0; v < job.views.count; ++v) {
    const View& view = job.views[v];
    if (view.camera.viewport_width_px == 0 || view.camera.viewport_height_px == 0) return "a view with a zero viewport";
    if (!cameraValid(view.camera)) return "a view whose camera is not finite or degenerate (cameraValid)";
    if (static_cast<size_t>(view.kind) >= kViewKindCount) return "a view of an unknown kind";
    if (!(view.pixels_per_cell > 0.0f) || !std::isfinite(view.pixels_per_cell))
      return "a view's pixels_per_cell must be positive and finite";
    if (!(view.lod_bias > 0.0f) || !std::isfinite(view.lod_bias)) return "a view's lod_bias must be positive and finite";
    if (view.visible_fraction.count != 0 && (view.visible_fraction.count != n || !view.visible_fraction.data))
      return "a view's visible_fraction is neither empty nor one per object";
    const size_t g = static_cast<size_t>(groupIndexOf(job.views, v));
    if (g == groups) group_kind[groups++] = view.kind;
    if (group_kind[g] != view.kind) return "a view group mixing kinds";
  }
  if (groups == 0) groups = 1;  // forced levels only: the camera's one group
  if (groups > ctx.views.max_groups) return "more view groups than the context's max_view_groups";
  if (job.group_levels_out.count != 0 && (job.group_levels_out.count != groups * n || !job.group_levels_out.data))
    return "group_levels_out is neither empty nor group count * objects";
  const uint32_t* offset = job.levels.chain_level_offset.data;
  for (size_t c = 0; c < job.levels.chainCount(); ++c)
    if (offset[c + 1] - offset[c] > kMaxViewLevels) return "a chain of more than 16 levels in a job with views";
  for (size_t i = 0; i < job.forced_levels.count; ++i) {
    const int f = job.forced_levels[i];
    const uint32_t c = job.chains[i];
    if (f < -1 || (f >= 0 && static_cast<uint32_t>(f) >= offset[c + 1] - offset[c]))
      return "a forced level out of its chain's range";
  }
  return nullptr;
}

namespace {

ViewFrame viewFrame(const SelectionJob& job, Span<const View> views, const CostCoefficients& coef) {
  ViewFrame f;
  f.views = views.count;
  f.c_obj = static_cast<float>(coef.per_object_ms);
  f.c_px = static_cast<float>(coef.per_pixel_ms);
  for (size_t v = 0; v < views.count; ++v) {
    const View& view = views[v];
    const Camera& cam = view.camera;
    const int g = groupIndexOf(views, v);
    f.group_of[v] = g;
    f.groups = std::max(f.groups, static_cast<size_t>(g) + 1);
    f.kind_of_group[g] = view.kind;
    f.frustum[v] = computeFrustum(cam);
    f.eye[v] = cam.eye;
    f.near_plane[v] = cam.near_plane;
    f.pixel_factor[v] = pixelSizeFactor(cam);
    f.ortho_pixel[v] = pixelSize(cam, 0.0f);
    f.ortho[v] = cam.projection == Projection::kOrthographic;
    f.viewport_px[v] = static_cast<float>(cam.viewport_width_px) * static_cast<float>(cam.viewport_height_px);
    f.x[v] = view.pixels_per_cell * view.lod_bias;
    f.visible[v] = view.visible_fraction.count ? view.visible_fraction.data : nullptr;
    f.weights[v] = kindWeights(job.params, view.kind);
    f.cost_weights[v] = f.weights[v];
    f.geometry_factor[g] = 1.0f;
    if (view.kind == ViewKind::kShadow) {  // the calibration's factors (1 until it learns them)
      f.cost_weights[v].object_cost *= static_cast<float>(coef.shadow_object_factor);
      f.cost_weights[v].pixel_cost *= static_cast<float>(coef.shadow_pixel_factor);
      f.cost_weights[v].geometry_cost *= static_cast<float>(coef.shadow_geometry_factor);
      f.geometry_factor[g] = static_cast<float>(coef.shadow_geometry_factor);
    }
  }
  for (ViewKind k : {ViewKind::kPrimary, ViewKind::kEye, ViewKind::kSecondary}) {
    for (size_t g = 0; g < f.groups && f.primary < 0; ++g)
      if (f.kind_of_group[g] == k) f.primary = static_cast<int>(g);
  }
  f.output = std::max(f.primary, 0);
  return f;
}

// Per object: its chain's rows, its forced level and must-draw.
struct ObjectChoice {
  uint32_t row0 = 0;
  int levels = 0;
  int forced = -1;
  bool must = false;
};

ObjectChoice objectChoice(const SelectionJob& job, size_t i) {
  ObjectChoice o;
  const uint32_t c = job.chains[i];
  o.row0 = job.levels.chain_level_offset[c];
  o.levels = static_cast<int>(job.levels.chain_level_offset[c + 1] - o.row0);
  o.forced = job.forced_levels.count ? job.forced_levels[i] : -1;
  o.must = job.must_draw.count && job.must_draw[i] != 0;
  return o;
}

// Bit v of mask[j] = view v sees object i0 + j, for a block of m <= kSlotBlock objects (the
// single-view path's SIMD frustum test, once per view).
void viewMasks(const SelectorContext& ctx, const ViewFrame& f, const SelectionJob& job, size_t i0, size_t m,
               uint8_t* mask) {
  alignas(32) uint8_t outside[kSlotBlock];
  std::memset(mask, 0, m);
  const float* const xyz = &job.centers[0].x + 3 * i0;
  for (size_t v = 0; v < f.views; ++v) {
    (ctx.use_avx2 ? frustumOutsideAvx2 : frustumOutsideSse2)(f.frustum[v], xyz, job.radii.data + i0, m, outside);
    for (size_t j = 0; j < m; ++j) mask[j] |= static_cast<uint8_t>((outside[j] ? 0u : 1u) << v);
  }
}

// One object's terms in every group of the frame (ObjectTerms, budget_views.h) from the views that
// see it (views: bit v for view v).
void objectTerms(const SelectorContext& ctx, const ViewFrame& f, const SelectionJob& job, size_t i, uint32_t views,
                 const ObjectChoice& o, ObjectTerms* t) {
  const glm::vec3 c = job.centers[i];
  const float r = job.radii[i], scale = job.max_scales[i];
  const float factor = (job.importance.count ? job.importance[i] : 1.0f) * (job.focus.count ? job.focus[i] : 1.0f) *
                       (job.motion.count ? job.motion[i] : 1.0f);
  t->in_mask = 0;
  for (size_t g = 0; g < f.groups; ++g) t->group[g] = GroupTerms{};
  for (size_t v = 0; v < f.views; ++v) {
    if (!(views >> v & 1u)) continue;
    float pixel = f.ortho_pixel[v];
    if (!f.ortho[v]) {
      const glm::vec3 d = c - f.eye[v];
      pixel = std::max(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z) - r, f.near_plane[v]) * f.pixel_factor[v];
    }
    const float r_px = r / pixel;
    const float px = std::min(kPi * r_px * r_px, f.viewport_px[v]);
    const ViewKindWeights &w = f.weights[v], &cw = f.cost_weights[v];
    GroupTerms& gt = t->group[f.group_of[v]];
    t->in_mask |= 1u << f.group_of[v];
    gt.feature_objects += w.object_cost;
    gt.feature_pixels += w.pixel_cost * px;
    gt.a += cw.object_cost * f.c_obj + cw.pixel_cost * f.c_px * px;
    gt.m += cw.geometry_cost;
    gt.b = std::max(gt.b, w.benefit * px * (f.visible[v] ? f.visible[v][i] : 1.0f) * factor);
    gt.q = std::min(gt.q, f.x[v] * pixel / scale);
  }
  for (size_t g = 0; g < f.groups; ++g)
    if (t->in_mask >> g & 1u) t->group[g].finest = finestLevel(ctx, o.row0, o.levels, t->group[g].q);
}

// Distance mode's levels of one object (-1 where a group does not see it).
void distanceTuple(const ViewFrame& f, const ObjectTerms& t, const ObjectChoice& o, const int8_t* prev,
                   const SelectorContext& ctx, int* level) {
  for (size_t g = 0; g < f.groups; ++g) {
    level[g] = -1;
    if (!(t.in_mask >> g & 1u) || o.levels == 0) continue;
    if (o.forced >= 0) {
      level[g] = o.forced;
      continue;
    }
    const float q = t.group[g].q;
    int l = t.group[g].finest;
    const int p = prev[g];
    if (p > l && p < o.levels && std::min(1.0f, q * ctx.row_inv_w[o.row0 + static_cast<uint32_t>(p)]) * ctx.h1 >= 1.0f)
      l = p;
    level[g] = l;
  }
  const int pg = f.primary;
  if (pg < 0 || level[pg] < 0) return;
  for (size_t g = 0; g < f.groups; ++g)
    if (f.kind_of_group[g] == ViewKind::kShadow && level[g] >= 0) level[g] = std::max(level[g], level[pg]);
}

// The frame's sums over the objects (the statistics and the calibration's features).
struct ViewSums {
  double predicted = 0.0, benefit = 0.0;
  CostFeatures features;
  uint32_t drawn = 0, culled = 0, dropped = 0, switches = 0;
};

// Writes object i's levels (tuple: byte g = level + 1) to the outputs, adds its cost, benefit and
// features to the sums and moves its history on.
void writeObject(const SelectionJob& job, SelectorContext& ctx, const ViewFrame& f, size_t i, uint32_t in_mask,
                 const GroupTerms* terms, const ObjectChoice& o, uint64_t tuple, ViewSums* sums) {
  int8_t* const prev = ctx.views.prev + i * ctx.views.max_groups;
  float cost = 0.0f;
  bool drawn = false, changed = false;
  for (size_t g = 0; g < f.groups; ++g) {
    const int level = static_cast<int>(tuple >> (8 * g) & 0xFFu) - 1;
    if (job.group_levels_out.count) job.group_levels_out[g * job.centers.count + i] = static_cast<int8_t>(level);
    changed |= prev[g] != level;
    if (level >= 0) {
      const GroupTerms& gt = terms[g];
      const uint32_t row = o.row0 + static_cast<uint32_t>(level);
      const float group_cost = gt.a + gt.m * ctx.row_cost[row];
      const float acc = std::min(1.0f, gt.q * ctx.row_inv_w[row]) * (level == prev[g] ? ctx.h1 : 1.0f);
      cost += group_cost;
      sums->benefit += gt.b * acc;
      if (f.kind_of_group[g] == ViewKind::kShadow) {  // at the kind's scales, before the learnt factors
        const double m = static_cast<double>(gt.m) / f.geometry_factor[g];
        sums->features.shadow_objects += gt.feature_objects;
        sums->features.shadow_pixels += gt.feature_pixels;
        sums->features.shadow_triangles += m * job.levels.triangle_count[row];
        sums->features.shadow_vertices += m * job.levels.vertex_count[row];
        sums->features.shadow_line_points += m * job.levels.line_point_count[row];
      } else {
        sums->features.objects += gt.feature_objects;
        sums->features.pixels += gt.feature_pixels;
        sums->features.triangles += gt.m * job.levels.triangle_count[row];
        sums->features.vertices += gt.m * job.levels.vertex_count[row];
        sums->features.line_points += gt.m * job.levels.line_point_count[row];
      }
      drawn = true;
    }
    prev[g] = static_cast<int8_t>(level);
  }
  const int8_t out = static_cast<int8_t>(static_cast<int>(tuple >> (8 * f.output) & 0xFFu) - 1);
  job.levels_out[i] = out;
  ctx.prev_level[i] = out;
  if (job.cost_ms_out.count) job.cost_ms_out[i] = cost;
  sums->predicted += cost;
  sums->drawn += drawn ? 1u : 0u;
  sums->culled += in_mask == 0 ? 1u : 0u;
  sums->dropped += in_mask != 0 && !drawn ? 1u : 0u;
  sums->switches += changed ? 1u : 0u;
}

void distanceFrame(const SelectionJob& job, SelectorContext& ctx, const ViewFrame& f, ViewSums* sums) {
  ObjectTerms t;
  int level[kMaxViews];
  alignas(32) uint8_t mask[kSlotBlock];
  for (size_t i0 = 0; i0 < job.centers.count; i0 += kSlotBlock) {
    const size_t m = std::min(kSlotBlock, job.centers.count - i0);
    viewMasks(ctx, f, job, i0, m, mask);
    for (size_t i = i0; i < i0 + m; ++i) {
      const ObjectChoice o = mask[i - i0] ? objectChoice(job, i) : ObjectChoice{};
      if (o.levels == 0) {
        writeObject(job, ctx, f, i, 0, nullptr, o, 0, sums);  // seen by no view, or no level
        continue;
      }
      objectTerms(ctx, f, job, i, mask[i - i0], o, &t);
      distanceTuple(f, t, o, ctx.views.prev + i * ctx.views.max_groups, ctx, level);
      uint64_t tuple = 0;
      for (size_t g = 0; g < f.groups; ++g) tuple |= static_cast<uint64_t>(level[g] + 1) << (8 * g);
      writeObject(job, ctx, f, i, t.in_mask, t.group, o, tuple, sums);
    }
  }
}

// Budget mode's first pass: every object in view becomes a slot with its tuple hull's base and
// steps (in slot order). Returns the mandatory part: per-frame constant + the slots' bases.
double tupleHulls(const SelectionJob& job, SelectorContext& ctx, const ViewFrame& f, double per_frame_ms,
                  size_t* slot_count, size_t* step_count) {
  ViewScratch& vs = ctx.views;
  ObjectTerms t;
  double mandatory = per_frame_ms;
  size_t slots = 0, count = 0;
  alignas(32) uint8_t mask[kSlotBlock];
  for (size_t i = 0; i < job.centers.count; ++i) {
    if (i % kSlotBlock == 0) viewMasks(ctx, f, job, i, std::min(kSlotBlock, job.centers.count - i), mask);
    if (!mask[i % kSlotBlock]) continue;
    const ObjectChoice o = objectChoice(job, i);
    if (o.levels == 0) continue;
    objectTerms(ctx, f, job, i, mask[i % kSlotBlock], o, &t);
    vs.slot_groups[slots] = static_cast<uint8_t>(t.in_mask);
    std::copy(t.group, t.group + f.groups, vs.slot_terms + slots * vs.max_groups);
    const TupleHullInput hin{&ctx, &f, &t, vs.prev + i * vs.max_groups, o.row0, o.levels, o.forced, o.must,
                               vs.pool};
    TuplePoint base;
    count += tupleHull(hin, static_cast<uint32_t>(slots), f.groups * kViewStepsPerGroup, &base, vs.steps + count);
    vs.slot_object[slots] = static_cast<uint32_t>(i);
    vs.base_cost[slots] = base.c;
    vs.base_benefit[slots] = base.b;
    vs.base_tuple[slots] = base.t;
    vs.best[slots] = 0;
    vs.best_step[slots] = 0;
    mandatory += base.c;
    ++slots;
  }
  *slot_count = slots;
  *step_count = count;
  return mandatory;
}

// The steps that fit alone (cost above their slot's base within `avail`), kept in order; a
// hull's costs rise, so each slot keeps a prefix. Returns their count.
size_t stepsThatFit(ViewScratch& vs, size_t count, double avail) {
  size_t kept = 0;
  for (size_t k = 0; k < count; ++k) {
    const ViewStep& e = vs.steps[k];
    if (static_cast<double>(e.cost) - vs.base_cost[e.order >> 8] <= avail) vs.steps[kept++] = e;
  }
  return kept;
}

// Budget mode: the tuple hulls, the greedy on their steps, the 1/2 guarantee, the write-out.
// Returns the price at the budget's edge.
double budgetFrame(const SelectionJob& job, SelectorContext& ctx, const ViewFrame& f, double per_frame_ms,
                   ViewSums* sums, SelectionStats* st) {
  ViewScratch& vs = ctx.views;
  const double cap = static_cast<double>(job.params.budget_ms);
  size_t slots = 0, count = 0;
  const double mandatory = tupleHulls(job, ctx, f, per_frame_ms, &slots, &count);
  if (mandatory > cap) st->flags |= kFlagOverBudget;
  st->mandatory_ms = mandatory;
  const double avail = cap - mandatory;
  count = stepsThatFit(vs, count, avail);
  size_t split = count;
  const size_t taken = viewGreedy(vs.steps, count, avail, &split);
  double base_benefit = 0.0;
  for (size_t s = 0; s < slots; ++s) base_benefit += vs.base_benefit[s];
  for (size_t k = 0; k < taken; ++k) {
    const size_t s = static_cast<size_t>(vs.steps[k].order >> 8);
    const uint8_t step = static_cast<uint8_t>(vs.steps[k].order & 0xFFu);
    if (step > vs.best_step[s]) {
      vs.best_step[s] = step;
      vs.best[s] = static_cast<uint32_t>(k + 1);
    }
  }
  double greedy_benefit = base_benefit;
  for (size_t s = 0; s < slots; ++s)
    if (vs.best[s]) greedy_benefit += vs.steps[vs.best[s] - 1].benefit - vs.base_benefit[s];
  // the 1/2 guarantee: the first step that did not fit, alone with every other slot at its base
  if (split < count && job.params.half_approximation) {
    const ViewStep& e = vs.steps[split];
    const size_t js = static_cast<size_t>(e.order >> 8);
    if (base_benefit - vs.base_benefit[js] + e.benefit > greedy_benefit) {
      for (size_t s = 0; s < slots; ++s) vs.best[s] = 0;
      vs.best[js] = static_cast<uint32_t>(split + 1);
      st->flags |= kFlagSplitFallback;
    }
  }
  // the write-out in object order (the slots' order)
  size_t s = 0;
  for (size_t i = 0; i < job.centers.count; ++i) {
    if (s == slots || vs.slot_object[s] != i) {
      writeObject(job, ctx, f, i, 0, nullptr, ObjectChoice{}, 0, sums);
      continue;
    }
    writeObject(job, ctx, f, i, vs.slot_groups[s], vs.slot_terms + s * vs.max_groups, objectChoice(job, i),
                vs.best[s] ? vs.steps[vs.best[s] - 1].tuple : vs.base_tuple[s], sums);
    ++s;
  }
  return split < count ? static_cast<double>(vs.steps[split].ratio) : 0.0;
}

}  // namespace

// The coarsest level of accuracy 1 for accuracy term q (level 0, of width 0, always is).
int finestLevel(const SelectorContext& ctx, uint32_t row0, int levels, float q) {
  // widths rise along a chain, so q / width falls: a binary search for the last level of accuracy 1
  int lo = 0, hi = levels - 1;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (std::min(1.0f, q * ctx.row_inv_w[row0 + static_cast<uint32_t>(mid)]) >= 1.0f)
      lo = mid;
    else
      hi = mid - 1;
  }
  return lo;
}

void runViews(const SelectionJob& job, const CostCoefficients& coef) {
  SelectorContext& ctx = *job.context;
  View single;
  const Span<const View> views = frameViews(job, &single);
  const ViewFrame f = viewFrame(job, views, coef);
  SelectionStats st;
  st.frame = ctx.frame;
  st.group_count = static_cast<uint32_t>(f.groups);
  ViewSums sums;
  const bool budget = job.params.mode == SelectionMode::kBudget;
  if (budget)
    st.lambda = budgetFrame(job, ctx, f, coef.per_frame_ms, &sums, &st);
  else
    distanceFrame(job, ctx, f, &sums);
  st.predicted_ms = coef.per_frame_ms + sums.predicted;
  st.total_benefit = sums.benefit;
  st.features = sums.features;
  st.drawn_count = sums.drawn;
  st.culled_count = sums.culled;
  st.dropped_count = sums.dropped;
  st.switch_count = sums.switches;
  if (sums.dropped > 0) st.flags |= kFlagObjectsDropped;
  // the single-view path's history is not this frame's: its next frame starts cold on the price
  ctx.last_lambda = 0.0;
  recordFrame(ctx, st.features, false, 0);
  if (job.stats) *job.stats = st;
}

bool allocateViewScratch(SelectorContext& ctx, size_t max_groups) {
  ViewScratch& vs = ctx.views;
  const size_t n = ctx.max_objects;
  const size_t steps = n * max_groups * kViewStepsPerGroup;
  const size_t sizes[11] = {steps * sizeof(ViewStep),
                            n * max_groups * sizeof(GroupTerms),
                            n * sizeof(uint64_t),
                            n * sizeof(uint32_t),
                            n * sizeof(float),
                            n * sizeof(float),
                            n * sizeof(uint32_t),
                            n * max_groups,
                            n,
                            n,
                            kTuplePoolCap * sizeof(TuplePoint)};
  size_t at[11], total = 0;
  for (size_t k = 0; k < 11; ++k) {
    at[k] = total;
    total += (sizes[k] + 63) / 64 * 64;
  }
  void* block = ctx.allocator.allocate(ctx.allocator.user, total, 64);
  if (!block) return false;
  auto* base = static_cast<unsigned char*>(block);
  vs.block = block;
  vs.max_groups = max_groups;
  vs.step_capacity = steps;
  vs.steps = reinterpret_cast<ViewStep*>(base + at[0]);
  vs.slot_terms = reinterpret_cast<GroupTerms*>(base + at[1]);
  vs.base_tuple = reinterpret_cast<uint64_t*>(base + at[2]);
  vs.slot_object = reinterpret_cast<uint32_t*>(base + at[3]);
  vs.base_cost = reinterpret_cast<float*>(base + at[4]);
  vs.base_benefit = reinterpret_cast<float*>(base + at[5]);
  vs.best = reinterpret_cast<uint32_t*>(base + at[6]);
  vs.prev = reinterpret_cast<int8_t*>(base + at[7]);
  vs.best_step = base + at[8];
  vs.slot_groups = base + at[9];
  vs.pool = reinterpret_cast<TuplePoint*>(base + at[10]);
  ctx.total_bytes += total;
  ctx.per_object_bytes += at[10];  // all but the pool scale with the objects
  return true;
}

void freeViewScratch(SelectorContext& ctx) {
  if (ctx.views.block) ctx.allocator.free(ctx.allocator.user, ctx.views.block);
  ctx.views = ViewScratch{};
}

}  // namespace scenelod::selection
