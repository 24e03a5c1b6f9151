// Level transitions (docs/SELECTION.md, "Transitions"): geomorph factors and time-based cross-fades
// on top of a frame's chosen levels.
//   Morph factor: level k of a chain is drawn unambiguously (whatever the history) for accuracy
//   terms q = X R / scale in [w_k, w_{k+1} / (1 + h)): from the finer switch (q = w_k) to where the
//   hysteresis zone toward level k + 1 begins. Over the last morph_band of that interval in log q
//   the factor rises from 0 to 1 by a smoothstep, and it stays 1 through the hysteresis zone, up to
//   the switch to k + 1 at q = w_{k+1}. So at either switch between k and k + 1 the finer level is at
//   factor 1 and the coarser at 0: level k at factor 1 is drawn where level k + 1 is, and no switch
//   moves a vertex (exactly so for nested chains). Level 0 (w = 0) takes one octave below its end as
//   its interval.
//   Fades: a switch that is not a morph (a jump of several levels, a level without morph data, a
//   switch the distance rule would not make, an object dropped or drawn again while in view) starts
//   a fade of fade_ms: both levels are drawn, the new one with weight elapsed / fade_ms. Objects
//   entering or leaving the frustum switch at once (they were or become off-screen).
#include <cmath>
#include <cstring>
#include <limits>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The morph factor of a level whose band is [start, end) with inv = 1 / ln(end / start).
inline float morphFactor(float q, float start, float end, float inv) {
  if (!(q > start)) return 0.0f;  // below the band, or a row that never morphs (start = +inf)
  if (q >= end) return 1.0f;
  float t = std::log(q / start) * inv;
  t = std::min(1.0f, std::max(0.0f, t));
  return t * t * (3.0f - 2.0f * t);
}

// The level the distance rule keeps for accuracy term q with last frame's level p (the finest
// candidate, or p while its accuracy times 1 + h stays >= 1).
inline int distanceRule(const SelectorContext& ctx, float q, int finest, int p, int count, uint32_t row0) {
  if (p > finest && p < count && std::min(1.0f, q * ctx.row_inv_w[row0 + static_cast<uint32_t>(p)]) * ctx.h1 >= 1.0f)
    return p;
  return finest;
}

// The tag marking objects in view this frame; renumbers the tags when they run out.
uint8_t nextViewTag(SelectorContext& ctx, size_t n) {
  if (!ctx.transitions_valid) {
    // no object was seen by a frame with transitions: tags 0, last frame's 1
    std::memset(ctx.view_tag, 0, ctx.max_objects);
    ctx.last_view_tag = 1;
  } else if (ctx.last_view_tag == 255) {
    for (size_t i = 0; i < n; ++i) ctx.view_tag[i] = ctx.view_tag[i] == 255 ? 1 : 0;
    for (size_t i = n; i < ctx.max_objects; ++i) ctx.view_tag[i] = 0;
    ctx.last_view_tag = 1;
  }
  return static_cast<uint8_t>(ctx.last_view_tag + 1);
}

}  // namespace

const char* transitionsError(const SelectionJob& job) {
  const SelectionParams& p = job.params;
  if (!(p.dt_ms >= 0.0f) || !std::isfinite(p.dt_ms)) return "dt_ms must be >= 0 and finite";
  if (!(p.fade_ms >= 0.0f) || !std::isfinite(p.fade_ms)) return "fade_ms must be >= 0 and finite";
  if (!(p.morph_band > 0.0f && p.morph_band <= 1.0f)) return "morph_band must be in (0, 1]";
  if (!(p.fade_budget_share >= 0.0f && p.fade_budget_share <= 1.0f)) return "fade_budget_share must be in [0, 1]";
  if (p.transitions != Transitions::kNone && p.transitions != Transitions::kFade && p.transitions != Transitions::kMorph)
    return "transitions is not a Transitions value";
  if (p.transitions != Transitions::kNone && (job.views.count || job.forced_levels.count))
    return "transitions need a job without views or forced levels";
  if (job.levels.has_morph.count != 0 &&
      (job.levels.has_morph.count != job.levels.cell_width.count || !job.levels.has_morph.data))
    return "has_morph must be empty or one per level-table row";
  const size_t n = job.centers.count;
  auto optional = [n](size_t count, const void* data) { return count == 0 || (count == n && data); };
  if (!optional(job.morph_out.count, job.morph_out.data) ||
      !optional(job.previous_levels_out.count, job.previous_levels_out.data) ||
      !optional(job.fade_out.count, job.fade_out.data))
    return "morph_out, previous_levels_out and fade_out must each be empty or one per object";
  return nullptr;
}

void prepareMorphRows(SelectorContext& ctx, const LevelTable& levels, const SelectionParams& params) {
  const size_t chains = levels.chainCount();
  const double band = params.morph_band;
  for (size_t c = 0; c < chains; ++c) {
    const uint32_t r0 = levels.chain_level_offset[c], r1 = levels.chain_level_offset[c + 1];
    for (uint32_t r = r0; r < r1; ++r) {
      float start = kInf, end = kInf, inv = 0.0f;
      const bool morph = r + 1 < r1 && levels.has_morph.count && levels.has_morph[r] != 0;
      if (morph) {
        const double hi = static_cast<double>(levels.cell_width[r + 1]) / static_cast<double>(ctx.h1);
        const double w = levels.cell_width[r];
        const double lo = w > 0.0 ? w : 0.5 * hi;
        end = static_cast<float>(hi);
        start = end;  // a step at `end` when the interval is empty
        if (hi > lo && lo > 0.0) {
          const double s = hi * std::exp(band * (std::log(lo) - std::log(hi)));
          const float sf = static_cast<float>(s);
          const double len = std::log(static_cast<double>(end) / static_cast<double>(sf));
          if (sf < end && len > 0.0 && std::isfinite(1.0 / len)) {
            start = sf;
            inv = static_cast<float>(1.0 / len);
          }
        }
      }
      ctx.row_morph_start[r] = start;
      ctx.row_morph_end[r] = end;
      ctx.row_morph_inv[r] = inv;
    }
  }
}

double fadeReserve(SelectorContext& ctx, const SelectionJob& job, size_t slots, double cap) {
  const SelectionParams& p = job.params;
  if (!ctx.transitions_valid || p.transitions == Transitions::kNone) return 0.0;
  const uint32_t* const chain_of = job.chains.data;
  const uint32_t* const offset = job.levels.chain_level_offset.data;
  const uint8_t last = ctx.last_view_tag;
  double reserve = 0.0;
  for (size_t s = 0; s < slots; ++s) {
    const uint32_t i = ctx.slot_object[s];
    if (ctx.view_tag[i] != last) continue;
    const int from = ctx.fade_from[i];
    if (from < 0 || !(ctx.fade_elapsed[i] + p.dt_ms < p.fade_ms)) continue;
    const uint32_t r0 = offset[chain_of[i]], count = offset[chain_of[i] + 1] - r0;
    if (static_cast<uint32_t>(from) >= count) continue;
    const double cost = ctx.slot_a[s] + ctx.row_cost[r0 + static_cast<uint32_t>(from)];
    if (reserve + cost <= cap)
      reserve += cost;
    else
      ctx.fade_elapsed[i] = kInf;  // ends now: the budget has no room for both levels
  }
  return reserve;
}

void noTransitions(SelectorContext& ctx, const SelectionJob& job) {
  ctx.transitions_valid = false;
  const size_t n = job.centers.count;
  if (job.morph_out.count) std::fill(job.morph_out.data, job.morph_out.data + n, 0.0f);
  if (job.previous_levels_out.count) std::memcpy(job.previous_levels_out.data, job.levels_out.data, n);
  if (job.fade_out.count) std::fill(job.fade_out.data, job.fade_out.data + n, 1.0f);
}

TransitionSums transitionPass(SelectorContext& ctx, const SelectionJob& job, size_t slots, double new_fade_cap) {
  const SelectionParams& p = job.params;
  const size_t n = job.centers.count;
  const bool morph_mode = p.transitions == Transitions::kMorph;
  const bool budget = p.mode == SelectionMode::kBudget;
  const float dt = p.dt_ms, fade_ms = p.fade_ms;
  const float inv_fade = fade_ms > 0.0f ? 1.0f / fade_ms : 0.0f;
  const uint8_t tag = nextViewTag(ctx, n);
  const uint8_t last = ctx.last_view_tag;
  const uint32_t* const chain_of = job.chains.data;
  const uint32_t* const offset = job.levels.chain_level_offset.data;
  const uint8_t* const has_morph = job.levels.has_morph.count ? job.levels.has_morph.data : nullptr;
  const int8_t* const level_of = job.levels_out.data;
  float* const morph_out = job.morph_out.count ? job.morph_out.data : nullptr;
  int8_t* const prev_out = job.previous_levels_out.count ? job.previous_levels_out.data : nullptr;
  float* const fade_out = job.fade_out.count ? job.fade_out.data : nullptr;
  // objects out of view: no fade, no morph (overwritten below for the slots)
  if (morph_out) std::fill(morph_out, morph_out + n, 0.0f);
  if (prev_out) std::memcpy(prev_out, level_of, n);
  if (fade_out) std::fill(fade_out, fade_out + n, 1.0f);

  TransitionSums sums;
  double new_fades = 0.0;  // the outgoing levels' cost of the fades started in this frame
  for (size_t s = 0; s < slots; ++s) {
    const uint32_t i = ctx.slot_object[s];
    const int l = level_of[i];
    const int prev = ctx.prev_level[i];
    const bool was_in_view = ctx.view_tag[i] == last;
    ctx.view_tag[i] = tag;
    const uint32_t chain = chain_of[i];
    const uint32_t r0 = offset[chain];
    const int count = static_cast<int>(offset[chain + 1] - r0);
    const float q = ctx.slot_q[s];
    int from = ctx.fade_from[i];
    float elapsed = ctx.fade_elapsed[i] + dt;
    bool active = was_in_view && elapsed < fade_ms && from < count;
    if (l != prev) {
      const int finer = std::min(l, prev);
      const bool morph = morph_mode && l >= 0 && prev >= 0 && (l - prev == 1 || prev - l == 1) && has_morph &&
                         has_morph[r0 + static_cast<uint32_t>(finer)] != 0 &&
                         (!budget || l == distanceRule(ctx, q, ctx.slot_finest[s], prev, count, r0));
      if (prev < 0 && !was_in_view) {
        active = false;  // entering the view: it was off-screen
      } else if (morph) {
        if (active && from == l) active = false;  // the morph reached the level that was fading out
      } else if (fade_ms > 0.0f) {
        // a fade back to the level fading out continues from the same mix
        elapsed = active && from == l ? fade_ms - elapsed : 0.0f;
        from = prev;
        active = true;
        if (prev >= 0) {  // the outgoing level's cost must fit what the budget leaves to fades
          const double cost = ctx.slot_a[s] + ctx.row_cost[r0 + static_cast<uint32_t>(prev)];
          if (new_fades + cost <= new_fade_cap)
            new_fades += cost;
          else
            active = false;
        }
      } else {
        active = false;
      }
    }
    ctx.fade_from[i] = static_cast<int8_t>(active ? from : l);
    ctx.fade_elapsed[i] = active ? elapsed : kInf;
    if (prev_out) prev_out[i] = static_cast<int8_t>(active ? from : l);
    if (fade_out) fade_out[i] = active ? std::min(1.0f, elapsed * inv_fade) : 1.0f;
    if (active && from >= 0) {
      const uint32_t row = r0 + static_cast<uint32_t>(from);
      sums.count += 1;
      sums.cost += ctx.slot_a[s] + ctx.row_cost[row];
      sums.pixels += ctx.slot_px[s];
      sums.tri += job.levels.triangle_count[row];
      sums.vert += job.levels.vertex_count[row];
      sums.lines += job.levels.line_point_count[row];
    }
    if (morph_mode && morph_out && l >= 0) {
      const uint32_t row = r0 + static_cast<uint32_t>(l);
      morph_out[i] = morphFactor(q, ctx.row_morph_start[row], ctx.row_morph_end[row], ctx.row_morph_inv[row]);
    }
  }
  ctx.last_view_tag = tag;
  ctx.transitions_valid = true;
  return sums;
}

}  // namespace scenelod::selection
