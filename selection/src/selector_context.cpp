// The selector's context: its one allocation (every per-object and per-row array, sized once for
// the largest object count), the history that carries from frame to frame, the cost model and the
// mailbox through which another thread reports measured frame times for the calibration.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>

#include "selector_internal.h"

namespace scenelod::selection {

namespace {

void* mallocAllocate(void*, size_t bytes, size_t alignment) {
  const size_t a = std::max<size_t>(alignment, alignof(std::max_align_t));
  const size_t rounded = (bytes + a - 1) / a * a;
  return std::aligned_alloc(a, rounded);
}
void mallocFree(void*, void* p) { std::free(p); }

size_t alignUp(size_t v, size_t a) { return (v + a - 1) / a * a; }

}  // namespace

Allocator defaultAllocator() {
  Allocator a;
  a.allocate = mallocAllocate;
  a.free = mallocFree;
  return a;
}

SelectorContext* createSelectorContext(const SelectorConfig& config) {
  if (config.max_object_count == 0 || config.max_object_count > 0x7fffffffu) return nullptr;
  if (config.max_levels_per_chain < 1 || config.max_levels_per_chain > 64) return nullptr;
  if (config.bracket_capacity < 1 || config.max_level_rows < 1 || config.max_level_rows > (size_t(1) << 31)) return nullptr;
  if (config.max_view_groups > kMaxViews) return nullptr;
  if (!(config.calibration.forgetting > 0.0 && config.calibration.forgetting <= 1.0) ||
      !(config.calibration.prior_weight > 0.0) ||
      !(config.calibration.shadow_forgetting > 0.0 && config.calibration.shadow_forgetting <= 1.0) ||
      !(config.calibration.shadow_prior_weight > 0.0) || !std::isfinite(config.calibration.shadow_prior_weight))
    return nullptr;
  Allocator alloc = config.allocator;
  if (!alloc.allocate || !alloc.free) alloc = defaultAllocator();

  const size_t n = config.max_object_count, stride = config.max_levels_per_chain + 1;
  // one block: the context, then each array aligned to 16 bytes
  size_t offset = alignUp(sizeof(SelectorContext), 16);
  struct Part { size_t bytes; size_t at; };
  const size_t rows = config.max_level_rows;
  // per-object parts first (they define the bytes per object), then the fixed ones
  constexpr size_t kPerObjectParts = 20;
  constexpr size_t kParts = 33;
  Part parts[kParts] = {
      {n * sizeof(int8_t), 0},     {n * sizeof(uint32_t), 0}, {n * sizeof(float), 0},
      {n * sizeof(float), 0},      {n * sizeof(float), 0},    {n * sizeof(float), 0},
      {n, 0},                      {n, 0},                    {n * stride, 0},
      {n, 0},                      {n, 0},                    {n * sizeof(HeapEntry), 0},
      {n * sizeof(uint32_t), 0},   {n, 0},                    {n, 0},
      {n * sizeof(uint16_t), 0},
      {n, 0},                      {n * sizeof(float), 0},    {n, 0},
      {n, 0},
      {config.bracket_capacity * sizeof(BracketEntry), 0}, {(rows + kLanes) * sizeof(float), 0},
      {(rows + kLanes) * sizeof(float), 0},
      {kHistMaxBuckets * sizeof(double), 0}, {kHistMaxBuckets * sizeof(uint32_t), 0},
      {config.bracket_capacity * sizeof(BracketEntry), 0}, {rows * sizeof(uint32_t), 0},
      {(rows + kLanes) * sizeof(float), 0}, {(rows + kLanes) * sizeof(float), 0},
      {(rows + kLanes) * sizeof(float), 0}, {(rows + kLanes) * sizeof(float), 0},
      {(rows + kLanes) * sizeof(float), 0}, {rows * sizeof(float), 0}};
  size_t per_object = 0;
  for (size_t i = 0; i < kParts; ++i) {
    parts[i].at = offset;
    offset = alignUp(offset + parts[i].bytes, 16);
    if (i < kPerObjectParts) per_object += parts[i].bytes;
  }
  void* block = alloc.allocate(alloc.user, offset, 64);
  if (!block) return nullptr;
  auto* c = new (block) SelectorContext();
  auto* base = static_cast<unsigned char*>(block);
  c->allocator = alloc;
  c->max_objects = n;
  c->hull_stride = stride;
  c->bracket_capacity = config.bracket_capacity;
  c->total_bytes = offset;
  c->per_object_bytes = per_object;
  c->prev_level = reinterpret_cast<int8_t*>(base + parts[0].at);
  c->slot_object = reinterpret_cast<uint32_t*>(base + parts[1].at);
  c->slot_a = reinterpret_cast<float*>(base + parts[2].at);
  c->slot_b = reinterpret_cast<float*>(base + parts[3].at);
  c->slot_q = reinterpret_cast<float*>(base + parts[4].at);
  c->slot_px = reinterpret_cast<float*>(base + parts[5].at);
  c->slot_finest = base + parts[6].at;
  c->slot_must = base + parts[7].at;
  c->hull = base + parts[8].at;
  c->hull_count = base + parts[9].at;
  c->chosen = base + parts[10].at;
  c->heap = reinterpret_cast<HeapEntry*>(base + parts[11].at);
  c->slot_row0 = reinterpret_cast<uint32_t*>(base + parts[12].at);
  c->slot_prev = reinterpret_cast<int8_t*>(base + parts[13].at);
  c->slot_levels = base + parts[14].at;
  c->slot_key = reinterpret_cast<uint16_t*>(base + parts[15].at);
  c->bracket = reinterpret_cast<BracketEntry*>(base + parts[20].at);
  c->row_cost = reinterpret_cast<float*>(base + parts[21].at);
  c->row_inv_w = reinterpret_cast<float*>(base + parts[22].at);
  c->hist_cost = reinterpret_cast<double*>(base + parts[23].at);
  c->hist_count = reinterpret_cast<uint32_t*>(base + parts[24].at);
  c->bracket_scratch = reinterpret_cast<BracketEntry*>(base + parts[25].at);
  c->row_drawn = reinterpret_cast<uint32_t*>(base + parts[26].at);
  c->fade_from = reinterpret_cast<int8_t*>(base + parts[16].at);
  c->fade_elapsed = reinterpret_cast<float*>(base + parts[17].at);
  c->view_tag = base + parts[18].at;
  c->fading = base + parts[19].at;
  c->row_morph_inv_start = reinterpret_cast<float*>(base + parts[27].at);
  c->row_morph_end = reinterpret_cast<float*>(base + parts[28].at);
  c->row_morph_inv = reinterpret_cast<float*>(base + parts[29].at);
  c->row_morph_zero_to = reinterpret_cast<float*>(base + parts[32].at);
  c->row_suffix_min = reinterpret_cast<float*>(base + parts[30].at);
  c->row_spread = reinterpret_cast<float*>(base + parts[31].at);
  c->max_rows = rows;
  c->use_avx2 = !config.sse2_only && cpuHasAvx2();
  c->calibrator = CostCalibrator(config.initial_cost, config.calibration);
  for (size_t i = 0; i < kRingSize; ++i) c->ring_frame[i] = ~uint64_t(0);
  if (config.max_view_groups > 0 && !allocateViewScratch(*c, config.max_view_groups)) {
    destroySelectorContext(c);
    return nullptr;
  }
  resetSelectorHistory(c);
  return c;
}

void destroySelectorContext(SelectorContext* c) {
  if (!c) return;
  freeViewScratch(*c);
  const Allocator alloc = c->allocator;
  c->~SelectorContext();
  alloc.free(alloc.user, c);
}

void resetSelectorHistory(SelectorContext* c) {
  if (!c) return;
  std::memset(c->prev_level, 0xFF, c->max_objects);  // all -1
  if (c->views.prev) std::memset(c->views.prev, 0xFF, c->max_objects * c->views.max_groups);
  c->last_lambda = 0.0;
  c->predict_width = kPredictWidthStart;
  c->has_history = false;
  c->last_was_budget = false;
  c->last_slot_count = 0;
  c->transitions_valid = false;
  std::memset(c->fading, 0, c->max_objects);
}

size_t selectorMemoryBytes(const SelectorContext* c) { return c ? c->total_bytes : 0; }
double selectorBytesPerObject(const SelectorContext* c) {
  return c ? static_cast<double>(c->per_object_bytes) / static_cast<double>(c->max_objects) : 0.0;
}

CostCoefficients selectorCostModel(const SelectorContext* c) { return c ? c->calibrator.coefficients() : CostCoefficients(); }
void setSelectorCostModel(SelectorContext* c, const CostCoefficients& k) {
  if (c) c->calibrator.reset(k);
}

void reportFrameTime(SelectorContext* c, uint64_t frame, float measured_ms) {
  if (!c) return;
  uint32_t bits;
  std::memcpy(&bits, &measured_ms, sizeof(bits));
  const uint64_t word = (((frame + 1) & 0xffffffffu) << 32) | bits;
  c->mailbox.store(word, std::memory_order_release);
}

bool selectorLastPoint(const SelectorContext* c, size_t object, int level, double* cost_ms, double* benefit) {
  if (!c || !c->last_was_budget || object >= c->max_objects) return false;
  // slots are in object order: binary search
  const uint32_t* first = c->slot_object;
  const uint32_t* last = c->slot_object + c->last_slot_count;
  const uint32_t* it = std::lower_bound(first, last, static_cast<uint32_t>(object));
  if (it == last || *it != object) return false;
  const size_t s = static_cast<size_t>(it - first);
  if (level < -1 || level >= static_cast<int>(c->slot_levels[s])) return false;
  *cost_ms = c->pointCost(s, level);
  *benefit = c->pointBenefit(s, level);
  return true;
}

CostCoefficients takeReportedFrameTime(SelectorContext& ctx, bool calibrate) {
  const uint64_t word = ctx.mailbox.exchange(0, std::memory_order_acquire);
  if (word != 0 && calibrate) {
    const uint64_t tag = word >> 32;
    const uint32_t bits = static_cast<uint32_t>(word & 0xffffffffu);
    float ms;
    std::memcpy(&ms, &bits, sizeof(ms));
    const uint64_t f = tag - 1;
    const size_t slot = static_cast<size_t>(f % kRingSize);
    if ((ctx.ring_frame[slot] & 0xffffffffu) == f) ctx.calibrator.update(ctx.ring_features[slot], ms);
  }
  return ctx.calibrator.coefficients();
}

void recordFrame(SelectorContext& ctx, const CostFeatures& features, bool budget, size_t slot_count) {
  const size_t ring = static_cast<size_t>(ctx.frame % kRingSize);
  ctx.ring_features[ring] = features;
  ctx.ring_frame[ring] = ctx.frame;
  ctx.has_history = true;
  ctx.last_was_budget = budget;
  ctx.last_slot_count = slot_count;
  ++ctx.frame;
}

}  // namespace scenelod::selection
