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

#include <emmintrin.h>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// ln(x) for x > 0 by its series in s = (x - 1) / (x + 1): 2 (s + s^3/3 + s^5/5). Continuous and
// increasing; relative error below 1e-3 for x in [1/2.6, 2.6], the ratios a morph band spans
// (end / start = (w_{k+1} / (w_k (1 + h)))^morph_band). No branch, no call: it vectorises.
inline float bandLog(float x) {
  const float s = (x - 1.0f) / (x + 1.0f);
  const float s2 = s * s;
  return s * (2.0f + s2 * (2.0f / 3.0f + s2 * 0.4f));
}

// The morph factor of accuracy term q on a row with band [1 / inv_start, end) and inv = 1 / bandLog
// of the band's ratio: 0 below the band (or on a row that never morphs, inv_start = 0), a smoothstep
// of the log position inside it, exactly 1 from its end on.
inline float morphFactor(float q, float inv_start, float end, float inv) {
  const float x = std::max(q * inv_start, 1.0f);
  float t = std::min(bandLog(x) * inv, 1.0f);
  t = std::max(t, 0.0f);
  const float m = t * t * (3.0f - 2.0f * t);
  return q >= end ? 1.0f : m;
}

// The level the distance rule keeps for accuracy term q with last frame's level p (the finest
// candidate, or p while its accuracy times 1 + h stays >= 1).
inline int distanceRule(const SelectorContext& ctx, float q, int finest, int p, int count, uint32_t row0) {
  if (p > finest && p < count && std::min(1.0f, q * ctx.row_inv_w[row0 + static_cast<uint32_t>(p)]) * ctx.h1 >= 1.0f)
    return p;
  return finest;
}

// The tag marking objects in view in this budget frame; renumbers the tags when they run out.
uint8_t nextViewTag(SelectorContext& ctx, size_t n) {
  if (!ctx.transitions_valid) {
    // no tag is last frame's: tags 0, last frame's 1
    std::memset(ctx.view_tag, 0, ctx.max_objects);
    ctx.last_view_tag = 1;
  } else if (ctx.last_view_tag == 255) {
    for (size_t i = 0; i < n; ++i) ctx.view_tag[i] = ctx.view_tag[i] == 255 ? 1 : 0;
    for (size_t i = n; i < ctx.max_objects; ++i) ctx.view_tag[i] = 0;
    ctx.last_view_tag = 1;
  }
  return static_cast<uint8_t>(ctx.last_view_tag + 1);
}

// Calls block(i0, count) for every run of 16 objects (the last one shorter), then f(i) for each
// object i in it with c[i] != 0 (a fade runs) or a[i] != b[i] (a switch), in increasing order; with
// `skip_none` not for a switch from or to -1: 16 objects at a time (byte compares and a mask; most
// blocks have none).
template <class B, class F>
inline void forEachMarked(const int8_t* a, const int8_t* b, const uint8_t* c, size_t n, bool skip_none, B&& block,
                          F&& f) {
  const __m128i none = _mm_set1_epi8(-1);
  const __m128i skip = skip_none ? none : _mm_setzero_si128();
  const __m128i zero = _mm_setzero_si128();
  size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    block(i, size_t(16));
    const __m128i va = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i));
    const __m128i vb = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + i));
    const __m128i vc = _mm_loadu_si128(reinterpret_cast<const __m128i*>(c + i));
    // unmarked: no fade, and the same level or (skip_none) either level -1
    const __m128i either_none = _mm_or_si128(_mm_cmpeq_epi8(va, none), _mm_cmpeq_epi8(vb, none));
    const __m128i quiet = _mm_or_si128(_mm_cmpeq_epi8(va, vb), _mm_and_si128(skip, either_none));
    const __m128i same = _mm_and_si128(quiet, _mm_cmpeq_epi8(vc, zero));
    uint32_t bits = ~static_cast<uint32_t>(_mm_movemask_epi8(same)) & 0xffffu;
    while (bits) {
      f(i + static_cast<size_t>(__builtin_ctz(bits)));
      bits &= bits - 1;
    }
  }
  if (i < n) block(i, n - i);
  for (; i < n; ++i)
    if (c[i] != 0 || (a[i] != b[i] && !(skip_none && (a[i] < 0 || b[i] < 0)))) f(i);
}

// The slot of object i, searching forward from *s (objects are visited in increasing order, slots
// hold increasing objects) by doubling steps, then halving; false when the object is not in view.
inline bool slotOf(const uint32_t* slot_object, size_t slots, uint32_t i, size_t* s) {
  size_t lo = *s;  // slot_object[k] < i for every k < lo
  if (lo >= slots || slot_object[lo] >= i) return lo < slots && slot_object[lo] == i;
  // slot_object[lo] < i: find hi with slot_object[hi] >= i (or the end)
  size_t step = 1, hi = lo + 1;
  while (hi < slots && slot_object[hi] < i) {
    lo = hi;
    step *= 2;
    hi = lo + step;
  }
  hi = std::min(hi, slots);
  // slot_object[lo] < i, and slot_object[hi] >= i or hi = slots
  while (hi - lo > 1) {
    const size_t mid = lo + (hi - lo) / 2;
    (slot_object[mid] < i ? lo : hi) = mid;
  }
  *s = hi;
  return hi < slots && slot_object[hi] == i;
}

// The largest float q >= 0 with q * inv_start <= 1 (the float product, as the frame computes it)
// and q < end: on [0, it] the morph factor is +0 (morphFactor: x = 1, bandLog(1) = +0, t = +0,
// m = +0; q < end). Each condition holds up to a point and fails beyond it (the rounded product
// grows with q): the first's point is 1 / inv_start within an ulp or two, the second's the float
// below end. -1 when q = 0 fails already (inv_start = +inf: 0 * inf is NaN; end = 0).
float zeroTo(float inv_start, float end) {
  if (!(0.0f * inv_start <= 1.0f) || !(0.0f < end)) return -1.0f;
  constexpr float kMax = std::numeric_limits<float>::max();
  float below_one = kMax;  // inv_start = 0: every finite q
  if (inv_start > 0.0f) {
    below_one = std::min(1.0f / inv_start, kMax);
    while (below_one > 0.0f && !(below_one * inv_start <= 1.0f)) below_one = std::nextafter(below_one, 0.0f);
    while (below_one < kMax && std::nextafter(below_one, kInf) * inv_start <= 1.0f)
      below_one = std::nextafter(below_one, kInf);
  }
  return std::min(below_one, std::nextafter(end, 0.0f));
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
      float inv_start = 0.0f, end = kInf, inv = 0.0f;
      const bool morph = r + 1 < r1 && levels.has_morph.count && levels.has_morph[r] != 0;
      if (morph) {
        const double hi = static_cast<double>(levels.cell_width[r + 1]) / static_cast<double>(ctx.h1);
        const double w = levels.cell_width[r];
        const double lo = w > 0.0 ? w : 0.5 * hi;
        end = static_cast<float>(hi);
        inv_start = end > 0.0f ? 1.0f / end : kInf;  // a step at `end` when the band is empty (inv = 0)
        if (hi > lo && lo > 0.0) {
          const float start = static_cast<float>(hi * std::exp(band * (std::log(lo) - std::log(hi))));
          const float len = bandLog(end * (1.0f / start));
          if (start < end && len > 0.0f && std::isfinite(1.0f / len)) {
            inv_start = 1.0f / start;
            inv = 1.0f / len;
          }
        }
      }
      ctx.row_morph_inv_start[r] = inv_start;
      ctx.row_morph_end[r] = end;
      ctx.row_morph_inv[r] = inv;
      ctx.row_morph_zero_to[r] = zeroTo(inv_start, end);
    }
  }
}

namespace {

// The morph factors of m slots at their rows into morph_out by object, which holds 0 for every
// object on entry; kDrawnFlags: the slot's level is level_of[object] (-1: not drawn, factor 0),
// else it is at row0 (its row). Most slots have factor 0 (below their row's band, or on a row that
// never morphs): one compare against the row's zero_to finds them, and only the others (a few per
// cent on the benchmark scene) are gathered and computed. A slot skipped has factor exactly +0:
// q in [0, zero_to], or not drawn with q >= 0 (its factor times 0; a factor is finite for q >= 0).
template <bool kDrawnFlags>
inline __attribute__((always_inline)) void morphBlocks(const SelectorContext& ctx, const uint32_t* object,
                                                      const uint32_t* row0, const float* q, const int8_t* level_of,
                                                      size_t m, float* morph_out) {
  const float* const inv_start = ctx.row_morph_inv_start;
  const float* const end = ctx.row_morph_end;
  const float* const inv = ctx.row_morph_inv;
  const float* const zero_to = ctx.row_morph_zero_to;
  // blocks of kSlotBlock: the slots that may have a factor above 0 listed, their rows' terms
  // gathered, the arithmetic in plain loops over local columns (vectorised), the factors scattered
  // by object
  // (8 lanes more: a vector's padding past the last entry)
  alignas(32) float gs[kSlotBlock + 8], ge[kSlotBlock + 8], gi[kSlotBlock + 8], gq[kSlotBlock + 8];
  alignas(32) float gd[kSlotBlock + 8], gm[kSlotBlock + 8], gl[kSlotBlock];
  alignas(32) uint32_t pick[kSlotBlock], prow[kSlotBlock];
  alignas(32) int32_t gn[kSlotBlock];  // kDrawnFlags: the slot's level (-1: not drawn)
  for (size_t j0 = 0; j0 < m; j0 += kSlotBlock) {
    const size_t b = std::min(kSlotBlock, m - j0);
    // each slot's accuracy term and the largest one with factor 0 at its row, 4 lanes compared at
    // a time into a mask of the slots to compute (lanes past b: 0 and +inf, not picked)
    // (kDrawnFlags: a slot not drawn compares as at its level 0 with bound +inf, without a branch:
    // drawn and not drawn alternate unpredictably)
    for (size_t j = 0; j < b; ++j) {
      uint32_t row = row0[j0 + j];
      if (kDrawnFlags) {
        const int l = level_of[object[j0 + j]];
        row += static_cast<uint32_t>(std::max(l, 0));
        gn[j] = l;
      }
      gl[j] = zero_to[row];
      prow[j] = row;
      gq[j] = q[j0 + j];
    }
    const size_t b4 = (b + 3) & ~size_t(3);
    for (size_t j = b; j < b4; ++j) {
      gq[j] = 0.0f;
      gl[j] = kInf;
      gn[j] = 0;
    }
    uint64_t bits = 0;
    for (size_t j = 0; j < b4; j += 4) {
      const __m128 vq = _mm_load_ps(gq + j);
      __m128 below = _mm_cmple_ps(vq, _mm_load_ps(gl + j));
      if (kDrawnFlags)
        below = _mm_or_ps(below, _mm_castsi128_ps(_mm_cmplt_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(gn + j)),
                                                                  _mm_setzero_si128())));
      const __m128 zero = _mm_and_ps(_mm_cmpge_ps(vq, _mm_setzero_ps()), below);
      bits |= static_cast<uint64_t>(~_mm_movemask_ps(zero) & 15) << j;
    }
    size_t c = 0;
    for (; bits; bits &= bits - 1, ++c) {
      const size_t j = static_cast<size_t>(__builtin_ctzll(bits));
      pick[c] = static_cast<uint32_t>(j0 + j);
      prow[c] = prow[j];  // c <= j: an entry not read again
    }
    if (c == 0) continue;
    for (size_t k = 0; k < c; ++k) {
      const uint32_t row = prow[k];
      if (kDrawnFlags) gd[k] = static_cast<float>(gn[pick[k] - j0] >= 0);  // not drawn: 0
      gs[k] = inv_start[row];
      ge[k] = end[row];
      gi[k] = inv[row];
      gq[k] = q[pick[k]];
    }
    // whole vectors: the lanes past c hold zeros (their results are not read)
    const size_t c8 = (c + 7) & ~size_t(7);
    for (size_t k = 0; k < 8; ++k) gs[c + k] = ge[c + k] = gi[c + k] = gq[c + k] = gd[c + k] = 0.0f;
    if (kDrawnFlags) {
      for (size_t k = 0; k < c8; ++k) gm[k] = morphFactor(gq[k], gs[k], ge[k], gi[k]) * gd[k];
    } else {
      for (size_t k = 0; k < c8; ++k) gm[k] = morphFactor(gq[k], gs[k], ge[k], gi[k]);
    }
    for (size_t k = 0; k < c; ++k) morph_out[object[pick[k]]] = gm[k];
  }
}

}  // namespace

void morphFactors(const SelectorContext& ctx, const uint32_t* object, const uint32_t* row0, const float* q,
                  const int8_t* level_of, size_t m, float* morph_out) {
  morphBlocks<true>(ctx, object, row0, q, level_of, m, morph_out);
}

void morphFactorsAtRows(const SelectorContext& ctx, const uint32_t* object, const uint32_t* row, const float* q,
                        size_t m, float* morph_out) {
  morphBlocks<false>(ctx, object, row, q, nullptr, m, morph_out);
}

double fadeReserve(SelectorContext& ctx, const SelectionJob& job, size_t slots, double cap) {
  const SelectionParams& p = job.params;
  if (!ctx.transitions_valid || p.transitions == Transitions::kNone) return 0.0;
  const float dt = p.dt_ms, fade_ms = p.fade_ms;
  const size_t n = job.centers.count;
  // locals: the byte store below may alias the context's fields
  uint8_t* const fading = ctx.fading;
  const int8_t* const fade_from = ctx.fade_from;
  const float* const fade_elapsed = ctx.fade_elapsed;
  const uint32_t* const slot_object = ctx.slot_object;
  const uint8_t* const slot_levels = ctx.slot_levels;
  const float* const slot_a = ctx.slot_a;
  const uint32_t* const slot_row0 = ctx.slot_row0;
  const float* const row_cost = ctx.row_cost;
  double reserve = 0.0;
  size_t s = 0;
  for (size_t i0 = 0; i0 < n; i0 += 16) {
    // 16 flags at a time: most blocks have no fade running
    uint64_t w[2] = {0, 0};
    std::memcpy(w, fading + i0, std::min<size_t>(16, n - i0));
    if ((w[0] | w[1]) == 0) continue;
    for (size_t i = i0; i < std::min(n, i0 + 16); ++i) {
      if (!fading[i]) continue;
      // a fade in from nothing or one that ends in this frame reserves nothing
      const int from = fade_from[i];
      if (from < 0 || !(fade_elapsed[i] + dt < fade_ms)) continue;
      if (!slotOf(slot_object, slots, static_cast<uint32_t>(i), &s)) continue;  // out of view: ends
      if (from >= slot_levels[s]) continue;
      const double cost = slot_a[s] + row_cost[slot_row0[s] + static_cast<uint32_t>(from)];
      if (reserve + cost <= cap)
        reserve += cost;
      else
        fading[i] = 0;  // ends now: the budget has no room for both levels
    }
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
  if (!ctx.transitions_valid) std::memset(ctx.fading, 0, ctx.max_objects);
  // last frame's view tags tell dropped objects (in view, not drawn) from culled ones
  const bool tags = ctx.transitions_valid && ctx.transitions_budget;
  const uint8_t last = ctx.last_view_tag;
  const uint32_t* const chain_of = job.chains.data;
  const uint32_t* const offset = job.levels.chain_level_offset.data;
  const uint8_t* const has_morph = job.levels.has_morph.count ? job.levels.has_morph.data : nullptr;
  const int8_t* const level_of = job.levels_out.data;
  int8_t* const prev_out = job.previous_levels_out.count ? job.previous_levels_out.data : nullptr;
  float* const fade_out = job.fade_out.count ? job.fade_out.data : nullptr;
  // fade mode: every morph factor 0 (morph mode: cleared before the slot pass, and set there)
  float* const morph_zero = !morph_mode && job.morph_out.count ? job.morph_out.data : nullptr;
  // each run of objects' outputs before its marked objects': no fade (the level itself, weight 1)
  auto defaults = [&](size_t i0, size_t count) __attribute__((always_inline)) {
    if (count == 16) {
      if (prev_out) std::memcpy(prev_out + i0, level_of + i0, 16);
      const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
      for (size_t k = 0; k < 16; k += 4) {
        if (fade_out) _mm_storeu_ps(fade_out + i0 + k, one);
        if (morph_zero) _mm_storeu_ps(morph_zero + i0 + k, zero);
      }
      return;
    }
    for (size_t k = i0; k < i0 + count; ++k) {
      if (prev_out) prev_out[k] = level_of[k];
      if (fade_out) fade_out[k] = 1.0f;
      if (morph_zero) morph_zero[k] = 0.0f;
    }
  };

  // the objects that switched or have a fade running: a handful per frame
  TransitionSums sums;
  double new_fades = 0.0;  // the outgoing levels' cost of the fades started in this frame
  size_t s = 0;
  // in distance mode no object is in view at level -1, and last frame's -1 was out of view unless
  // last frame's budget dropped it: a switch from or to -1 without a fade running is no fade
  const bool skip_none = !budget && !tags;
  forEachMarked(level_of, ctx.prev_level, ctx.fading, n, skip_none, defaults, [&](size_t i) {
    const int l = level_of[i];
    const int prev = ctx.prev_level[i];
    if (!slotOf(ctx.slot_object, slots, static_cast<uint32_t>(i), &s)) {
      ctx.fading[i] = 0;  // out of view: no fade
      return;
    }
    const uint32_t r0 = offset[chain_of[i]];
    const int count = static_cast<int>(offset[chain_of[i] + 1] - r0);
    int from = ctx.fade_from[i];
    float elapsed = ctx.fade_elapsed[i] + dt;
    bool active = ctx.fading[i] != 0 && elapsed < fade_ms && from < count;
    if (l != prev) {
      const bool was_in_view = prev >= 0 || (tags && ctx.view_tag[i] == last);
      const int finer = std::min(l, prev);
      const bool morph = morph_mode && l >= 0 && prev >= 0 && (l - prev == 1 || prev - l == 1) && has_morph &&
                         has_morph[r0 + static_cast<uint32_t>(finer)] != 0 &&
                         (!budget || l == distanceRule(ctx, ctx.slot_q[s], ctx.slot_finest[s], prev, count, r0));
      if (!was_in_view) {
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
    ctx.fading[i] = active ? 1 : 0;
    if (!active) return;
    ctx.fade_from[i] = static_cast<int8_t>(from);
    ctx.fade_elapsed[i] = elapsed;
    if (prev_out) prev_out[i] = static_cast<int8_t>(from);
    if (fade_out) fade_out[i] = std::min(1.0f, elapsed * inv_fade);
    if (from >= 0) {
      const uint32_t row = r0 + static_cast<uint32_t>(from);
      sums.count += 1;
      sums.cost += ctx.slot_a[s] + ctx.row_cost[row];
      sums.pixels += ctx.slot_px[s];
      sums.tri += job.levels.triangle_count[row];
      sums.vert += job.levels.vertex_count[row];
      sums.lines += job.levels.line_point_count[row];
    }
  });

  // budget mode: this frame's view tags, and the morph factors
  if (budget) {
    const uint8_t tag = nextViewTag(ctx, n);
    // locals: a byte store may alias the context's fields, which would be reloaded every slot
    uint8_t* const view_tag = ctx.view_tag;
    const uint32_t* const slot_object = ctx.slot_object;
    for (size_t k = 0; k < slots; ++k) view_tag[slot_object[k]] = tag;
    ctx.last_view_tag = tag;
    if (morph_mode && job.morph_out.count)
      morphFactors(ctx, ctx.slot_object, ctx.slot_row0, ctx.slot_q, level_of, slots, job.morph_out.data);
  }
  ctx.transitions_valid = true;
  ctx.transitions_budget = budget;
  return sums;
}

}  // namespace scenelod::selection
