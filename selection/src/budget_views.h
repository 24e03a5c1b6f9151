#pragma once
// What selector_views.cpp (frames with views) and budget_views.cpp (their tuple hulls and greedy)
// share: the frame's views grouped, one object's terms per group, and the tuple hull of one object.
// Private to selection/src; built with the selector's flags.
#include <cstddef>
#include <cstdint>
#include <limits>

#include "selector_internal.h"

namespace scenelod::selection {

// The frame's views as the per-object pass reads them, grouped (groups in order of first appearance).
struct ViewFrame {
  size_t views = 0, groups = 0;
  int group_of[kMaxViews];
  ViewKind kind_of_group[kMaxViews];
  int primary = -1;  // the group shadows follow: the first primary group, else eye, else secondary; -1 = none
  int output = 0;    // the group written to levels_out: the primary group, else the first
  Frustum frustum[kMaxViews];
  glm::vec3 eye[kMaxViews];
  float near_plane[kMaxViews], pixel_factor[kMaxViews], ortho_pixel[kMaxViews], viewport_px[kMaxViews];
  float x[kMaxViews];  // X * bias
  bool ortho[kMaxViews];
  const float* visible[kMaxViews];
  ViewKindWeights weights[kMaxViews];       // the job's view_kinds (the features' scales)
  ViewKindWeights cost_weights[kMaxViews];  // ... times the learnt shadow factors (the costs' scales)
  float geometry_factor[kMaxViews];         // per group: the learnt geometry factor of its kind (1 but shadows)
  float c_obj = 0.0f, c_px = 0.0f;
};

struct ObjectTerms {
  uint32_t in_mask = 0;  // bit g: some view of group g sees the object
  GroupTerms group[kMaxViews];
};

// One object's tuple hull input.
struct TupleHullInput {
  const SelectorContext* ctx;
  const ViewFrame* frame;
  const ObjectTerms* terms;
  const int8_t* prev;  // last frame's level per group
  uint32_t row0;
  int levels;
  int forced;          // -1 = free
  bool must;
  TuplePoint* pool;    // kTuplePoolCap points of scratch
};

// The coarsest level of accuracy 1 for accuracy term q (level 0, of width 0, always is).
int finestLevel(const SelectorContext& ctx, uint32_t row0, int levels, float q);

// The object's upper hull of (cost, benefit) over the level tuples that obey the rules (a shadow
// group no finer than the primary group where that sees it; must-draw: drawn in every group that
// sees it; forced: that level there): its first point to *base, then at most max_steps steps
// (ViewStep, order = slot << 8 | step) to `steps`. Returns the step count.
size_t tupleHull(const TupleHullInput& in, uint32_t slot, size_t max_steps, TuplePoint* base, ViewStep* steps);

}  // namespace scenelod::selection
