// LOD chains by vertex clustering (Low & Tan 1997 §3.2.2, §4): the mesh is graded and sorted once,
// then every level is clustered from the original at w_k = w_1 * growth^(k-1), in parallel (each
// level only reads the shared prepared mesh, so the result is the same for any thread count).
#include "scenelod/lodcore/chain.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <mutex>
#include <optional>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "attribute_level.h"
#include "chain_internal.h"
#include "cluster_internal.h"
#include "test_hooks.h"
#include "scenelod/lodcore/scrooge.h"
#include "scenelod/lodcore/zhang.h"

namespace scenelod {

Sphere computeBoundingSphere(const Mesh& mesh) {
  Sphere s;
  if (mesh.positions.empty()) return s;
  const Aabb box = computeBounds(mesh);
  s.center = box.center();
  float r2 = 0.0f;
  for (const glm::vec3& p : mesh.positions) r2 = std::max(r2, glm::dot(p - s.center, p - s.center));
  // one ulp of slack so that every vertex tests inside despite rounding
  s.radius = std::sqrt(r2) * (1.0f + 1e-6f);
  return s;
}

namespace detail {
namespace {
// how a chain builds its coarse levels during the w_1 search's first probe: 0 not at all, 1 on
// another thread while the probe runs (the default), 2 all of them before the probe, on the
// calling thread (a test's way to make every one of them and so exercise their dropping)
std::atomic<int> g_speculation{1};
// levels (bit k: level k) that finishChain rebuilds as though they gained primitives
std::atomic<unsigned> g_rebuild{0};
}  // namespace

// (test_hooks.h)
int setChainSpeculationForTest(int mode) { return g_speculation.exchange(mode); }
unsigned setChainRebuildForTest(unsigned levels) { return g_rebuild.exchange(levels); }
}  // namespace detail

namespace {

// The search's first width. The area formula, count = 2 * tiling * area / w^2, assumes that every
// triangle is smaller than its share of a cell; on meshes of very unequal triangles (CAD parts,
// scans with flat regions) the large ones survive whole and the formula's width was too wide: the
// count at it was 0.30-0.67 x the target on 2CylinderEngine's parts, BrainStem and DamagedHelmet at
// half the triangles. So the count is modelled per vertex, sum_v min(T / V, 2 * tiling * a_v / w^2)
// with a_v a third of the vertex's incident area (the prepared face sums hold it: one streaming pass
// over V floats) and T / V the mesh's triangles per vertex, i.e. a vertex keeps at most its share of
// triangles; the areas are binned in quarter octaves (a float's exponent and two mantissa bits) and
// the model solved for w by bisection. Where no vertex is capped at the area formula's width, or the
// two widths differ by less than half the search's tolerance (the count going as w^-2), the area
// formula is kept: near-uniform meshes (the bunny, spheres) then start where they always did.
double firstWidth(const PreparedMesh& p, double tiling, size_t target, double tolerance) {
  const double uniform = std::sqrt(2.0 * tiling * p.surface_area / double(target));
  const size_t vn = p.face_sums.size();
  if (!(uniform > 0.0) || vn == 0 || p.order.empty()) return uniform;  // a hand-made PreparedMesh
  constexpr size_t kBins = 1024;  // positive floats: 8 exponent bits and 2 mantissa bits
  std::vector<double> sum(kBins, 0.0);
  std::vector<uint32_t> count(kBins, 0);
  float largest = 0.0f;
  for (size_t v = 0; v < vn; ++v) {
    const float area = p.face_sums[v].area * (1.0f / 3.0f);
    if (!(area > 0.0f) || !std::isfinite(area)) continue;
    uint32_t bits;
    std::memcpy(&bits, &area, sizeof bits);
    const size_t bin = bits >> 21;
    ++count[bin];
    sum[bin] += double(area);
    largest = std::max(largest, area);
  }
  const double c = 2.0 * tiling;
  const double share = double(p.mesh->triangleCount()) / double(p.order.size());  // triangles per vertex
  if (double(largest) * c <= share * uniform * uniform) return uniform;  // no vertex capped
  // the occupied bins only (a few dozen), as (most triangles, c * area)
  std::vector<std::pair<double, double>> bins;
  double most = 0.0;
  for (size_t b = 0; b < kBins; ++b)
    if (count[b]) bins.push_back({share * double(count[b]), c * sum[b]}), most += share * double(count[b]);
  auto model = [&](double w2) {
    double n = 0.0;
    for (const auto& [k, ca] : bins) n += std::min(k, ca / w2);
    return n;
  };
  // model(w2) decreases in w2, from about the triangle count (w2 -> 0) to 0; capping only lowers
  // it, so at the area formula's width it is at most the target and the root is narrower: bracket
  // it by quartering w2, then bisect on log w2
  if (most <= double(target)) return uniform;
  double hi = uniform * uniform, lo = hi;
  while (model(lo) <= double(target) && lo > 1e-300) lo *= 0.25;
  for (int i = 0; i < 64 && hi / lo > 1.0 + 1e-4; ++i) {
    const double mid = std::sqrt(lo * hi);
    if (model(mid) > double(target)) lo = mid; else hi = mid;
  }
  const double capped = std::sqrt(std::sqrt(lo * hi));
  return std::abs(capped / uniform - 1.0) <= 0.5 * tolerance ? uniform : capped;
}

// A chain's hooks into its w_1 search (buildClusterChain): on small meshes the search's first round
// is then one probe at the narrower of the pair's widths, `before` called with that width just
// before it and `after` with whether it ended the search just after it (also when it failed), so
// that the chain can build its coarse levels at that width meanwhile.
struct FirstProbeHooks {
  std::function<void(float)> before;
  std::function<void(bool)> after;
};

// The search of findCellWidthForTarget. With `keep`, the assignment of the probe that ends the
// search within the tolerance is moved there (a chain's first level at that width is then spared
// its assignment, a third of the level); `keep` stays empty when the width chosen is not the last
// probed (the search ended outside the tolerance).
Error searchCellWidth(const PreparedMesh& p, const ClusterParams& params, size_t target, float& cell_width,
                      double tolerance, detail::Assignment* keep, size_t* probes = nullptr,
                      const FirstProbeHooks* hooks = nullptr) {
  cell_width = 0.0f;
  if (probes) *probes = 0;
  if (target == 0) return {Status::kInvalidArgument, "target triangle count is 0"};
  if (!p.mesh || p.mesh->triangleCount() == 0 || p.order.empty())
    return {Status::kInvalidArgument, "cannot search a cell width for a mesh without triangles"};
  if (!(tolerance >= 0.0) || !std::isfinite(tolerance))
    return {Status::kInvalidArgument, "tolerance must be a finite number >= 0"};
  const double diag = std::max(double(p.bounds.diagonal()), 1e-30);
  // bracket: lo keeps (nearly) every triangle, hi merges the mesh into one or two cells
  double lo = std::max(double(p.mean_edge_length) / 16.0, diag * 1e-6);
  double hi = diag * 2.0;
  size_t best_diff = SIZE_MAX;
  float best = static_cast<float>(lo);
  const bool keep_last = keep != nullptr;
  detail::Assignment a;
  // countClusteredTriangles into `as`, whose assignment is kept for `keep` (a thread's own: the
  // first round below runs two at once)
  auto probe = [&](double w, detail::Assignment& as, size_t& n) -> Error {
    ClusterParams cp = params;
    cp.cell_width = static_cast<float>(w);
    n = 0;
    as = detail::Assignment();
    if (Error e = detail::assign(p, cp, as); !e.ok()) return e;
    detail::Eliminated el;
    detail::eliminate(p, as, false, false, false, el);
    n = el.triangles.size() / 3;
    return {};
  };
  auto count = [&](double w, size_t& n) -> Error {
    if (probes) ++*probes;
    return probe(w, a, n);
  };
  auto within = [&](size_t diff) { return double(diff) <= tolerance * double(target); };
  auto distance = [&](size_t n) { return n > target ? n - target : target - n; };
  // the exponent alpha of count ~ w^-alpha between two probes (a secant on log count against log
  // width); 2, the model's, where a count is 0, the counts are equal, or the count rose with the
  // width (cells float), and clamped to [0.25, 4] against implausible slopes
  auto slope = [](double w0, size_t n0, double w1, size_t n1) {
    if (n0 == 0 || n1 == 0 || n0 == n1 || w0 == w1) return 2.0;
    const double alpha = std::log(double(n0) / double(n1)) / std::log(w1 / w0);
    return alpha > 0.25 ? std::min(alpha, 4.0) : 2.0;
  };
  size_t n = 0;
  // safeguarded secant on log count against log width: a first width from the areas (firstWidth),
  // then w * (count / target)^(1 / alpha), falling back to bisection of the bracket [lo, hi]. Floating
  // cells, centred on vertices, tile a surface less tightly than the grid: their count at the area
  // guess was 1.39-1.65 x the target (bumpy sphere, bunny), so their first guess is sqrt(1.4) wider.
  const double tiling = params.method == LodMethod::kUniform ? 1.0 : 1.4;
  double w = p.surface_area > 0.0 ? firstWidth(p, tiling, target, tolerance) : std::sqrt(lo * hi);
  // the previous probe: from the third probe on, the exponent of count ~ w^-alpha is the one
  // between the last two probes (a secant on log count against log width), not 2: at half the
  // triangles of unequal meshes the count falls more slowly than w^-2 (the large triangles stay)
  double previous_w = 0.0;
  size_t previous_n = 0;
  // Small meshes (those whose chain drops the sorted copy of positions: the probes' scratch is then
  // small beside the chain's peak) first probe the narrower width w (1 - 0.7 tolerance) alone: the
  // first width's count is under the target on 22 of the 23 meshes below (from 0.61 to 1.25 x it,
  // 0.79 in the median, at w), so the narrower is the likelier to end the search; a chain builds its
  // coarse levels at that width on its other thread meanwhile (`hooks`), kept if it becomes w_1.
  // When it misses, two widths w' (1 -/+ 0.7 tolerance) around the next width are probed at once, on
  // two threads where there are two, their slope giving the width after; both are always probed and
  // compared in a fixed order, so the result does not depend on the number of threads. Over the
  // bunny, a bumpy sphere and the shared models' 21 meshes of 1,000 triangles or more the chains'
  // searches took 83 rounds of probes (78 with the pair first, 93 without a pair), and 3 of them
  // end at the first probe (docs/bench/clustering.md, "w_1 search" and "first probe alone").
  // one probe at w: the closest width so far; within the tolerance, `ended` and the assignment kept;
  // otherwise the bracket, and w becomes the next width (the secant with the previous probe)
  auto step = [&](double& w, bool& ended) -> Error {
    if (Error e = count(w, n); !e.ok()) return e;
    const size_t diff = distance(n);
    if (diff < best_diff) best_diff = diff, best = static_cast<float>(w);
    if (within(diff)) {
      if (keep_last) *keep = std::move(a);
      ended = true;
      return {};
    }
    if (n > target) lo = w; else hi = w;
    const double alpha = slope(previous_w, previous_n, w, n);  // 2 after the first probe (none before)
    previous_w = w, previous_n = n;
    w = n > 0 ? w * std::pow(double(n) / double(target), 1.0 / alpha) : std::sqrt(lo * hi);
    return {};
  };
  const double spread = std::min(0.7 * tolerance, 0.1);
  const bool small = p.order.size() * sizeof(glm::vec3) < detail::kSortedCopyMinBytes;
  if (spread > 0.0 && small && w * (1.0 - spread) > lo && w < hi) {
    w *= 1.0 - spread;
    if (hooks) hooks->before(static_cast<float>(w));
    bool ended = false;
    const Error e = step(w, ended);
    if (hooks) hooks->after(e.ok() && ended);
    if (!e.ok()) return e;
    if (ended) {
      cell_width = best;
      return {};
    }
  }
  if (spread > 0.0 && small && w * (1.0 - spread) > lo && w * (1.0 + spread) < hi) {
    const double wa = w * (1.0 - spread), wb = w * (1.0 + spread);
    detail::Assignment b;
    size_t na = 0, nb = 0;
    Error ea, eb;
    tbb::parallel_invoke([&] { ea = probe(wa, a, na); }, [&] { eb = probe(wb, b, nb); });
    if (probes) *probes += 2;
    if (!ea.ok()) return ea;
    if (!eb.ok()) return eb;
    const size_t da = distance(na), db = distance(nb);
    const bool a_closer = da <= db;  // ties: the narrower
    // (after a chain's first probe, which may have been closer)
    if ((a_closer ? da : db) < best_diff) {
      best_diff = a_closer ? da : db;
      best = static_cast<float>(a_closer ? wa : wb);
    }
    if (within(best_diff)) {  // (a first probe within the tolerance ended the search above)
      if (keep_last) *keep = std::move(a_closer ? a : b);
      cell_width = best;
      return {};
    }
    for (const auto& [wx, nx] : {std::pair<double, size_t>{wa, na}, std::pair<double, size_t>{wb, nb}}) {
      if (nx > target) lo = std::max(lo, wx);
      else hi = std::min(hi, wx);
    }
    // the next width from the closer probe, with the slope between the two
    const double wc = a_closer ? wa : wb;
    const size_t nc = a_closer ? na : nb;
    const double alpha = slope(wa, na, wb, nb);
    previous_w = wc, previous_n = nc;
    w = nc > 0 ? wc * std::pow(double(nc) / double(target), 1.0 / alpha) : std::sqrt(lo * hi);
  }
  for (int it = 0; it < 48; ++it) {
    if (!(w > lo && w < hi)) w = std::sqrt(lo * hi);
    bool ended = false;
    if (Error e = step(w, ended); !e.ok()) return e;
    if (ended || hi / lo < 1.0 + 1e-6) break;
  }
  // the count is not monotone in the width (cells float): when bisection ends outside the tolerance,
  // scan widths around the best one and keep the closest
  if (!within(best_diff)) {
    const double centre = best;
    for (int k = -16; k <= 16 && !within(best_diff); ++k) {
      const double w = centre * std::pow(1.25, double(k) / 16.0);
      if (Error e = count(w, n); !e.ok()) return e;
      const size_t diff = distance(n);
      if (diff < best_diff) best_diff = diff, best = static_cast<float>(w);
      if (keep_last && within(diff)) *keep = std::move(a);
    }
  }
  cell_width = best;
  return {};
}

// w_1 for a mesh of fewer than two triangles (no half to search for): its mean edge, else a 64th
// of its diagonal
float smallMeshFirstWidth(const PreparedMesh& p) {
  return p.mean_edge_length > 0.0f ? p.mean_edge_length : std::max(p.bounds.diagonal() / 64.0f, 1e-6f);
}

}  // namespace

Error findCellWidthForTarget(const PreparedMesh& p, const ClusterParams& params, size_t target, float& cell_width,
                             double tolerance) {
  return searchCellWidth(p, params, target, cell_width, tolerance, nullptr);
}

Error findCellWidthForTarget(const Mesh& original, const ClusterParams& params, size_t target, float& cell_width,
                             double tolerance) {
  cell_width = 0.0f;
  if (target == 0) return {Status::kInvalidArgument, "target triangle count is 0"};
  PreparedMesh p;
  if (Error e = prepareMesh(original, params, p); !e.ok()) return e;
  return findCellWidthForTarget(p, params, target, cell_width, tolerance);
}

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The levels of one chain, built on TBB's threads from one prepared mesh. What the members hold and
// why each step is ordered as it is:
// - Levels get cheaper with k (level 1 alone is about a third of the work): whichever thread is free
//   takes the next level of the order 1, n, n-1, ..., 2, so level 1 overlaps the smallest levels
//   (wall time near the ideal split, and the two largest levels never hold their scratch at once).
// - That order alone keeps levels 1 and 2 apart only while level 1 keeps pace: when its thread is
//   held up (descheduled on a loaded machine, or a first chain's thread start), the other thread ran
//   through levels n .. 3 and took level 2 while level 1 was still in synthesis, and the 1 M sphere's
//   chain peaked at 51.7-52.5 MB instead of 49.6 (budget 49.79; level 1's primitives,
//   representatives and synthesis scratch, ~17 MB, beside level 2's grid and ids, ~6 MB). So level 2
//   starts once level 1 is past synthesis. In an unhindered run level 1 is done first (the other
//   levels together take longer), so nothing waits; with two levels there is nothing else to run
//   beside level 1, and they overlap as before.
// - Where the levels read positions through the order (no sorted copy), level 2 goes to the first
//   thread free once level 1 is past synthesis, ahead of the levels still unclaimed, the level it
//   displaces taking the last claim: on the bunny's chain the thread that finished level 1 took
//   level 3 while level 2 waited for the other thread's level 4, and level 1's held output pass
//   waited for level 2's synthesis (trace: level 1 past synthesis at 5.76 ms, level 2 from 6.19).
//   Not with the sorted copy (the 1 M sphere): the copy, 12 bytes per vertex, lives until the last
//   assignment, which the displaced level then made after level 2's synthesis scratch was taken; the
//   1 M chain peaked at 53.7-55.2 MB in 2 of 35 loaded runs (budget 49.79), against 49.66 with level
//   2 last. Without the copy the order alone (4 bytes per vertex) outlives it.
// - The finest level's output pass (face normals, corner lists and the output arrays, on top of its
//   eliminated primitives and representatives) was the chain's peak while the prepared mesh (44
//   bytes per vertex) was still held for the other levels. So that level is held between its
//   synthesis and its output pass until every level has passed synthesis; the level that passes last
//   frees the prepared mesh's arrays (no level reads them after its synthesis) and hands the held
//   output pass to the task group, where the thread that runs out of levels takes it.
// - The sort (order and sorted positions, 16 bytes per vertex) is read by assignments only: freed
//   when every level has made its assignment, before the later levels' elimination and output.
// - Levels n, n - 1, ..., 3 are built at the width of the search's first probe while it runs (small
//   meshes, two threads or more): they are the chain's own if that width becomes w_1, and are dropped
//   otherwise. They take the claims, so the level loop starts after them. Only levels that no other
//   level waits for (not 1 or 2), and no progress is reported for them.
class ChainLevels {
 public:
  ChainLevels(const Mesh& original, const ChainParams& params, PreparedMesh& p, LodChain& out, ChainStats& stats,
              detail::MorphPairs* morphs)
      : original_(original), params_(params), p_(p), out_(out), stats_(stats), morphs_(morphs), n_(params.level_count),
        errors_(n_), synthesis_pending_(n_), second_early_(p.sorted_positions.empty() && n_ >= 3),
        release_pending_(n_) {
    out_.levels.resize(n_ + 1);
    stats_.level_seconds.assign(n_, 0.0);
  }
  ~ChainLevels() {  // (on the way out of an exception only: every other path has waited)
    try {
      speculation_.wait();
    } catch (...) {
    }
  }

  // Chooses w_1 (searched when params.first_cell_width is 0), builds levels 1..n, and sets
  // `base_bounds` to level 0's sphere. On an error the levels are cleared.
  Error run(std::optional<Sphere>& base_bounds);

 private:
  static constexpr size_t kNoLevel = SIZE_MAX;

  ClusterParams levelParams(size_t k, float first_width) const;
  size_t claimLevel();
  bool allClaimed();
  void firstSynthesized();
  void passSynthesis();
  static void releaseSorted(void* self);
  void runLevel(size_t k, float first_width, bool report);
  void finishLevel(size_t k, detail::LevelParts& parts, const ClusterParams& cp, double seconds, bool report);
  void speculate();
  void dropSpeculativeLevels();
  FirstProbeHooks speculationHooks();
  Error chooseFirstWidth();

  const Mesh& original_;
  const ChainParams& params_;
  PreparedMesh& p_;
  LodChain& out_;
  ChainStats& stats_;
  detail::MorphPairs* morphs_;  // given each level as it is built, when the chain has geomorphs
  const size_t n_;
  float w1_ = 0.0f;  // level 1's width, searched when 0 (level 1 is only ever built at it)
  std::vector<Error> errors_;
  std::mutex progress_mutex_;
  std::atomic<size_t> done_{0};
  detail::LevelParts held_;  // level 1 between its synthesis and its output pass
  double held_seconds_ = 0.0;
  std::atomic<size_t> synthesis_pending_;
  std::atomic<bool> first_ready_{false};  // level 1's parts are held (set after held_ is written)
  tbb::task_group finish_group_;
  // the claims: guarded by first_mutex_, as is first_synthesized_
  bool first_claimed_ = false;  // level 1 (k = 0)
  size_t next_claim_ = 0;       // claim c is level n - c (k = n - 1 - c), c < n - 1
  std::mutex first_mutex_;
  std::condition_variable first_cv_;
  bool first_synthesized_ = false;
  const bool second_early_;
  bool second_taken_ = false;
  size_t displaced_ = 1;
  std::atomic<size_t> release_pending_;  // assignments still to be made before the sort is freed
  detail::Assignment first_;  // the search's last probe, at w_1 (empty when w_1 is given or not probed last)
  tbb::task_group speculation_;
  std::atomic<bool> speculating_{false};
  float speculative_w1_ = 0.0f;
};

ClusterParams ChainLevels::levelParams(size_t k, float first_width) const {
  ClusterParams cp = params_.cluster;
  cp.cell_width = static_cast<float>(double(first_width) * std::pow(double(params_.growth), double(k)));
  return cp;
}

size_t ChainLevels::claimLevel() {
  std::unique_lock<std::mutex> lock(first_mutex_);
  if (!first_claimed_) {
    first_claimed_ = true;
    return 0;
  }
  if (next_claim_ + 1 >= n_) return kNoLevel;
  const size_t natural = n_ - 1 - next_claim_++;  // n - 1, n - 2, ..., 1
  size_t k = natural;
  if (natural == 1 && second_taken_) k = displaced_;
  else if (second_early_ && natural >= 2 && first_synthesized_ && !second_taken_) k = 1, displaced_ = natural;
  if (k == 1) {
    second_taken_ = true;
    // (level 1 was claimed first, by a thread running it now: the wait ends; no level calls TBB, so
    // a waiting thread holds no task another one needs)
    if (n_ >= 3) first_cv_.wait(lock, [&] { return first_synthesized_; });
  }
  return k;
}

bool ChainLevels::allClaimed() {
  std::lock_guard<std::mutex> lock(first_mutex_);
  return first_claimed_ && next_claim_ + 1 >= n_;
}

void ChainLevels::firstSynthesized() {
  {
    std::lock_guard<std::mutex> lock(first_mutex_);
    first_synthesized_ = true;
  }
  first_cv_.notify_all();
}

void ChainLevels::passSynthesis() {
  if (--synthesis_pending_ != 0) return;
  // every level is past synthesis (and assignment): only the mesh itself is read from here on
  std::vector<float>().swap(p_.weights);
  std::vector<VertexFaceSums>().swap(p_.face_sums);
  std::vector<glm::vec4>().swap(p_.face_colors);
  if (first_ready_.load())
    finish_group_.run([this] { finishLevel(0, held_, levelParams(0, w1_), held_seconds_, true); });
}

void ChainLevels::releaseSorted(void* self) {
  ChainLevels& c = *static_cast<ChainLevels*>(self);
  if (--c.release_pending_ == 0) {
    std::vector<uint32_t>().swap(c.p_.order);
    std::vector<glm::vec3>().swap(c.p_.sorted_positions);
  }
}

// (levels built while the search's first probe runs report no progress: they may be dropped)
void ChainLevels::finishLevel(size_t k, detail::LevelParts& parts, const ClusterParams& cp, double seconds,
                              bool report) {
  const Clock::time_point start = Clock::now();
  LodLevel& level = out_.levels[k + 1];
  std::vector<uint32_t> vertex_cluster;
  detail::finishLevel(parts, cp, level.mesh, nullptr, morphs_ ? &vertex_cluster : nullptr);
  detail::carryUniformGroup(original_, level.mesh);
  level.bounds = computeBoundingSphere(level.mesh);
  stats_.level_seconds[k] = seconds + since(start);
  // the geomorphs' second steps to and from the levels next to it that are built
  if (morphs_) morphs_->levelBuilt(k + 1, std::move(vertex_cluster));
  const size_t d = ++done_;
  if (report && params_.progress.fn) {
    std::lock_guard<std::mutex> lock(progress_mutex_);
    params_.progress(0.1 + 0.9 * double(d) / double(n_), "clustering levels");
  }
}

void ChainLevels::runLevel(size_t k, float first_width, bool report) {
  const Clock::time_point start = Clock::now();
  const ClusterParams cp = levelParams(k, first_width);
  LodLevel& level = out_.levels[k + 1];
  detail::LevelParts parts;
  parts.keep_cluster_of = morphs_ != nullptr;
  ClusterStats cs;
  // level 2, where it was claimed early, is synthesized before its elimination: the last level past
  // synthesis, it then frees the prepared arrays and hands over level 1's held output pass an
  // elimination sooner (the bunny: 0.65 ms), the other thread, idle, taking it
  const bool synthesis_first = k == 1 && second_early_;
  auto passed = [](void* self) { static_cast<ChainLevels*>(self)->passSynthesis(); };
  if (k == 0 && !first_.cluster_of.empty()) {
    releaseSorted(this);
    errors_[k] = detail::clusterLevelParts(p_, cp, first_, parts, &cs);
  } else if (synthesis_first) {
    errors_[k] = detail::clusterLevelParts(p_, cp, parts, &cs, releaseSorted, this, passed, this);
  } else {
    errors_[k] = detail::clusterLevelParts(p_, cp, parts, &cs, releaseSorted, this);
  }
  level.cell_width = cp.cell_width;
  level.max_error = cs.max_error;
  level.method = cp.method;
  const double seconds = since(start);
  std::vector<uint32_t> cluster_of = std::move(parts.cluster_of);  // (kept for the geomorphs only)
  if (k == 0) {
    held_ = std::move(parts);
    held_seconds_ = seconds;
    first_ready_.store(errors_[0].ok());
    firstSynthesized();  // also after an error: level 2 must not wait for ever
  }
  // (a level's only error is its assignment's, before synthesis: then the callback was not made)
  if (!synthesis_first || !errors_[k].ok()) passSynthesis();
  // the geomorphs' first steps with the levels next to it whose assignments are made (frees theirs
  // and this one's where no other step reads them), before the output pass
  if (morphs_ && errors_[k].ok()) morphs_->levelClustered(k + 1, std::move(cluster_of));
  if (k != 0 && errors_[k].ok()) finishLevel(k, parts, cp, seconds, report);
}

void ChainLevels::speculate() {
  while (speculating_.load()) {
    size_t k = kNoLevel;
    {
      std::lock_guard<std::mutex> lock(first_mutex_);
      if (speculating_.load() && next_claim_ + 3 <= n_) k = n_ - 1 - next_claim_++;  // k >= 2
    }
    if (k == kNoLevel) break;
    runLevel(k, speculative_w1_, false);
  }
}

// the speculative levels were built at a width that did not become w_1
void ChainLevels::dropSpeculativeLevels() {
  speculation_.wait();  // the level under way, then drop what was built
  std::lock_guard<std::mutex> lock(first_mutex_);
  for (size_t c = 0; c < next_claim_; ++c) {
    const size_t k = n_ - 1 - c;
    out_.levels[k + 1] = LodLevel();
    stats_.level_seconds[k] = 0.0;
    errors_[k] = Error();
  }
  if (morphs_) morphs_->reset();
  synthesis_pending_ += next_claim_;
  release_pending_ += next_claim_;
  done_ -= next_claim_;
  next_claim_ = 0;
}

FirstProbeHooks ChainLevels::speculationHooks() {
  FirstProbeHooks hooks;
  const int mode = detail::g_speculation.load();
  hooks.before = [this, mode](float wa) {
    if (!second_early_ || mode == 0) return;
    if (mode == 1 && tbb::this_task_arena::max_concurrency() < 2) return;
    speculative_w1_ = wa;
    speculating_.store(true);
    if (mode == 2) speculate();
    else speculation_.run([this] { speculate(); });
  };
  hooks.after = [this](bool hit) {
    if (speculating_.exchange(false) && !hit) dropSpeculativeLevels();
  };
  return hooks;
}

Error ChainLevels::chooseFirstWidth() {
  w1_ = params_.first_cell_width;
  if (w1_ == 0.0f) {
    params_.progress(0.05, "choosing w1");
    const size_t tn = original_.triangleCount();
    if (tn >= 2) {
      const FirstProbeHooks hooks = speculationHooks();
      if (Error e = searchCellWidth(p_, params_.cluster, tn / 2, w1_, 0.05, &first_, &stats_.first_width_probes, &hooks);
          !e.ok())
        return e;
    } else {
      w1_ = smallMeshFirstWidth(p_);
    }
  }
  return detail::checkCellWidth(p_, w1_);
}

Error ChainLevels::run(std::optional<Sphere>& base_bounds) {
  const Clock::time_point t0 = Clock::now();
  const Error chosen = chooseFirstWidth();
  stats_.first_width_seconds = since(t0);
  if (!chosen.ok()) {
    speculation_.wait();
    out_.levels.clear();
    return chosen;
  }
  std::atomic<bool> bounds_taken{false};
  tbb::parallel_for(size_t(0), n_, [&](size_t) {
    const size_t k = claimLevel();
    if (k == kNoLevel) return;  // (taken while the search ran)
    runLevel(k, w1_, true);
    // level 0's bounds by the first thread to find no level left to claim: it would otherwise wait
    // for the last levels' synthesis (the held output pass) or for the other thread's last level
    // (the bunny chain: 0.16 ms that came after both, at the end)
    if (allClaimed() && !bounds_taken.exchange(true)) base_bounds = computeBoundingSphere(original_);
  });
  speculation_.wait();
  if (!base_bounds) base_bounds = computeBoundingSphere(original_);
  finish_group_.wait();
  for (const Error& e : errors_)
    if (!e.ok()) {
      out_.levels.clear();
      return e;
    }
  return {};
}

// level 0: the input (taken from `take` when handed over, else copied) and its sphere
void setBaseLevel(const Mesh& original, Mesh* take, const Sphere& bounds, LodLevel& base) {
  base.bounds = bounds;
  if (take) base.mesh = std::move(*take);
  else base.mesh = original;
  base.cell_width = 0.0f;
  base.max_error = 0.0f;
  base.method = LodMethod::kOriginal;
}

// a level's clusters of an attribute mesh's welded vertices taken to the input's vertices
void inputMap(const detail::AttributeMesh& am, std::vector<uint32_t>& cluster_of, detail::LevelMap& map) {
  if (am.did_weld) {
    map.cluster_of.resize(am.welded_of.size());
    for (size_t v = 0; v < am.welded_of.size(); ++v) map.cluster_of[v] = cluster_of[am.welded_of[v]];
    std::vector<uint32_t>().swap(cluster_of);
  } else {
    map.cluster_of = std::move(cluster_of);
  }
}

// The maps of an independent clustering level of `original` (levels[0]) made again, its clustering
// repeated at its width as buildClusterChain or buildAttributeChain made it: for finishChain, once
// the maps made while the level was built are freed. A level's clustering depends on nothing else,
// so these are its maps; false (none) should the level come out otherwise.
bool levelMapsAgain(const ChainParams& params, const Mesh& original, const LodLevel& level, detail::LevelMap& map) {
  map = detail::LevelMap();
  ClusterParams cp = params.cluster;
  cp.cell_width = level.cell_width;
  Mesh mesh;
  PreparedMesh p;
  if (detail::hasAttributes(original)) {
    detail::AttributeMesh am;
    detail::makeAttributeMesh(original, am);
    detail::AttributeLevelParts parts;
    if (!prepareMesh(am.mesh(), params.cluster, p).ok() || !detail::clusterAttributeParts(p, cp, parts, nullptr).ok())
      return false;
    p = PreparedMesh();
    std::vector<uint32_t> source, cluster_of;
    detail::finishAttributeLevel(am, cp, parts, mesh, &source, &cluster_of, &map.vertex_cluster);
    inputMap(am, cluster_of, map);
  } else {
    if (!prepareMesh(original, params.cluster, p).ok()) return false;
    if (p.sorted_positions.size() * sizeof(glm::vec3) < detail::kSortedCopyMinBytes)
      std::vector<glm::vec3>().swap(p.sorted_positions);
    detail::LevelParts parts;
    parts.keep_cluster_of = true;
    if (!detail::clusterLevelParts(p, cp, parts, nullptr).ok()) return false;
    p = PreparedMesh();
    map.cluster_of = std::move(parts.cluster_of);
    detail::finishLevel(parts, cp, mesh, nullptr, &map.vertex_cluster);
  }
  const bool same = map.cluster_of.size() == original.vertexCount() && mesh.positions == level.mesh.positions &&
                    mesh.triangles == level.mesh.triangles;
  if (!same) map = detail::LevelMap();
  return same;
}

// `take`, when given, is `original` itself, handed over by the caller: level 0 takes it by move
// instead of a copy once the levels are done
Error buildClusterChain(const Mesh& original, Mesh* take, const ChainParams& params, LodChain& out,
                        ChainStats& stats) {
  params.progress(0.0, "grading");
  PreparedMesh p;
  Clock::time_point t0 = Clock::now();
  if (Error e = prepareMesh(original, params.cluster, p); !e.ok()) return e;
  stats.prepare_seconds = since(t0);
  // a small mesh's levels read its positions through the order (detail::PositionsByWeight)
  if (p.sorted_positions.size() * sizeof(glm::vec3) < detail::kSortedCopyMinBytes)
    std::vector<glm::vec3>().swap(p.sorted_positions);
  // level 0, the copy of the input, is made last, once the prepared mesh and the levels' scratch are
  // freed, so that it does not add to the peak memory of the levels
  std::optional<Sphere> base_bounds;
  out.levels.resize(1);
  const bool no_levels = p.order.empty() || params.level_count == 0;
  if (!no_levels) {
    std::optional<detail::MorphPairs> morphs;
    if (params.morphs) morphs.emplace(original, out.levels, params.level_count);
    ChainLevels levels(original, params, p, out, stats, morphs ? &*morphs : nullptr);
    if (Error e = levels.run(base_bounds); !e.ok()) return e;
  }
  p = PreparedMesh();
  setBaseLevel(original, take, base_bounds ? *base_bounds : computeBoundingSphere(original), out.levels[0]);
  if (no_levels) params.progress(1.0, "done");
  return {};
}

// The chain of a mesh with attributes (detail::hasAttributes): welded and split into UV charts once,
// prepared once, then every level through the attribute output pass in parallel (each reads only
// the shared welded mesh and its preparation, so the result is the same on any number of threads).
// Each level records its source vertices in the input's indices.
Error buildAttributeChain(const Mesh& original, Mesh* take, const ChainParams& params, LodChain& out,
                          ChainStats& stats) {
  params.progress(0.0, "grading");
  Clock::time_point t0 = Clock::now();
  if (Error e = validateMesh(original, "mesh"); !e.ok()) return e;
  detail::AttributeMesh am;
  detail::makeAttributeMesh(original, am);
  PreparedMesh p;
  if (Error e = prepareMesh(am.mesh(), params.cluster, p); !e.ok()) return e;
  stats.prepare_seconds = since(t0);
  const size_t n = p.order.empty() ? 0 : params.level_count;
  out.levels.resize(n + 1);
  std::optional<detail::MorphPairs> morphs;
  if (params.morphs && n > 0) morphs.emplace(original, out.levels, n);
  const bool maps = morphs.has_value();
  // a level's maps, its clusters of the welded vertices taken to the input's, to the geomorphs
  auto built = [&](size_t k, std::vector<uint32_t>& cluster_of, std::vector<uint32_t>& vertex_cluster) {
    detail::LevelMap map;
    inputMap(am, cluster_of, map);
    morphs->levelClustered(k + 1, std::move(map.cluster_of));
    morphs->levelBuilt(k + 1, std::move(vertex_cluster));
  };
  if (n > 0) {
    t0 = Clock::now();
    float w1 = params.first_cell_width;
    const size_t tn = am.mesh().triangleCount();
    if (w1 == 0.0f && tn >= 2) {
      params.progress(0.05, "choosing w1");
      if (Error e = searchCellWidth(p, params.cluster, tn / 2, w1, 0.05, nullptr, &stats.first_width_probes); !e.ok())
        return e;
    } else if (w1 == 0.0f) {
      w1 = smallMeshFirstWidth(p);
    }
    if (Error e = detail::checkCellWidth(p, w1); !e.ok()) return e;
    stats.first_width_seconds = since(t0);
    stats.level_seconds.assign(n, 0.0);
    std::vector<Error> errors(n);
    std::atomic<size_t> done{0};
    std::mutex progress_mutex;
    auto levelParams = [&](size_t k) {
      ClusterParams cp = params.cluster;
      cp.cell_width = static_cast<float>(double(w1) * std::pow(double(params.growth), double(k)));
      return cp;
    };
    // level k + 1's record once its mesh is made, and the progress
    auto record = [&](size_t k, const ClusterStats& cs, double seconds) {
      LodLevel& level = out.levels[k + 1];
      level.cell_width = levelParams(k).cell_width;
      level.max_error = cs.max_error;
      level.method = params.cluster.method;
      level.bounds = computeBoundingSphere(level.mesh);
      stats.level_seconds[k] = seconds;
      const size_t d = ++done;
      if (params.progress.fn) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        params.progress(0.1 + 0.9 * double(d) / double(n), "clustering levels");
      }
    };
    // level 1, the largest, is held between its two steps while the others are built, so that its
    // output pass, the chain's largest scratch, comes after the prepared arrays are freed
    detail::AttributeLevelParts first;
    ClusterStats first_stats;
    double first_seconds = 0.0;
    tbb::parallel_invoke(
        [&] {
          const Clock::time_point start = Clock::now();
          errors[0] = detail::clusterAttributeParts(p, levelParams(0), first, &first_stats);
          first_seconds = since(start);
        },
        [&] {
          tbb::parallel_for(size_t(1), n, [&](size_t k) {
            const Clock::time_point start = Clock::now();
            LodLevel& level = out.levels[k + 1];
            ClusterStats cs;
            detail::AttributeLevelParts parts;
            errors[k] = detail::clusterAttributeParts(p, levelParams(k), parts, &cs);
            if (!errors[k].ok()) return;
            std::vector<uint32_t> cluster_of, vertex_cluster;
            detail::finishAttributeLevel(am, levelParams(k), parts, level.mesh, &level.source_vertex,
                                         maps ? &cluster_of : nullptr, maps ? &vertex_cluster : nullptr);
            record(k, cs, since(start));
            if (maps) built(k, cluster_of, vertex_cluster);
          });
        });
    p = PreparedMesh();
    if (errors[0].ok()) {
      const Clock::time_point start = Clock::now();
      std::vector<uint32_t> cluster_of, vertex_cluster;
      detail::finishAttributeLevel(am, levelParams(0), first, out.levels[1].mesh, &out.levels[1].source_vertex,
                                   maps ? &cluster_of : nullptr, maps ? &vertex_cluster : nullptr);
      record(0, first_stats, first_seconds + since(start));
      if (maps) built(0, cluster_of, vertex_cluster);
    }
    for (const Error& e : errors)
      if (!e.ok()) {
        out.levels.clear();
        return e;
      }
  }
  p = PreparedMesh();
  am = detail::AttributeMesh();
  setBaseLevel(original, take, computeBoundingSphere(original), out.levels[0]);
  if (n == 0) params.progress(1.0, "done");
  return {};
}

// The nested chain: level 1 as an independent chain's (the same w_1 search), then each level
// clusters the one before (nested_level.cpp), one after the other, and (params.morphs) the geomorph
// toward it is made from the two levels' maps, the only ones held.
Error buildNestedChain(const Mesh& original, Mesh* take, const ChainParams& params, LodChain& out, ChainStats& stats) {
  params.progress(0.0, "grading");
  Clock::time_point t0 = Clock::now();
  if (Error e = validateMesh(original, "mesh"); !e.ok()) return e;
  detail::NestedInput in;
  if (Error e = detail::prepareNested(original, nullptr, params.cluster, in); !e.ok()) return e;
  stats.prepare_seconds = since(t0);
  const size_t n = in.p.order.empty() ? 0 : params.level_count;
  out.levels.clear();
  out.levels.reserve(n + 1);
  out.levels.resize(1);
  std::vector<detail::LevelMap> maps(2);
  auto map = [&](size_t level) -> detail::LevelMap& { return maps[level % 2]; };
  detail::identityMap(original.vertexCount(), map(0));
  std::vector<float> area;  // (for the geomorphs of levels 1 and on)
  if (n > 0) {
    t0 = Clock::now();
    float w1 = params.first_cell_width;
    const size_t tn = in.p.mesh->triangleCount();
    if (w1 == 0.0f && tn >= 2) {
      params.progress(0.05, "choosing w1");
      if (Error e = searchCellWidth(in.p, params.cluster, tn / 2, w1, 0.05, nullptr, &stats.first_width_probes); !e.ok())
        return e;
    } else if (w1 == 0.0f) {
      w1 = smallMeshFirstWidth(in.p);
    }
    if (Error e = detail::checkCellWidth(in.p, w1); !e.ok()) return e;
    stats.first_width_seconds = since(t0);
    stats.level_seconds.assign(n, 0.0);
    detail::Carried carried;
    for (size_t k = 0; k < n; ++k) {
      const Clock::time_point start = Clock::now();
      ClusterParams cp = params.cluster;
      cp.cell_width = static_cast<float>(double(w1) * std::pow(double(params.growth), double(k)));
      const LodLevel* prev = k == 0 ? nullptr : &out.levels[k];
      if (prev) {
        if (Error e = detail::prepareNested(prev->mesh, &carried, cp, in); !e.ok()) return e;
      }
      LodLevel level;
      detail::Carried next;
      if (Error e = detail::nestedLevel(in, prev ? prev->mesh : original, &map(k), prev ? &prev->source_vertex : nullptr,
                                        prev ? prev->max_error : 0.0f, original, cp, level, &map(k + 1), &next);
          !e.ok()) {
        out.levels.clear();
        return e;
      }
      out.levels.push_back(std::move(level));
      carried = std::move(next);
      if (params.morphs) {
        if (k == 0) {
          detail::computeMorph(nullptr, nullptr, original, map(1), out.levels[1].mesh, out.levels[0].morph);
        } else {
          if (area.empty()) area = detail::sourceAreas(original);
          detail::computeMorph(&area, &map(k), out.levels[k].mesh, map(k + 1), out.levels[k + 1].mesh,
                               out.levels[k].morph);
        }
      }
      stats.level_seconds[k] = since(start);
      params.progress(0.1 + 0.9 * double(k + 1) / double(n), "clustering levels");
    }
  }
  in = detail::NestedInput();
  setBaseLevel(original, take, computeBoundingSphere(original), out.levels[0]);
  if (n == 0) params.progress(1.0, "done");
  return {};
}

// whether level `b` has more triangles, or more primitives, than the level `a` before it
bool gainsPrimitives(const Mesh& a, const Mesh& b) {
  const size_t pa = a.triangleCount() + a.edgeCount() + a.pointCount();
  const size_t pb = b.triangleCount() + b.edgeCount() + b.pointCount();
  return b.triangleCount() > a.triangleCount() || pb > pa;
}

// A built chain's last step: no level gains primitives. A clustering level that would is rebuilt by
// a nested step from the level before at its own width, another generator's is dropped (and the
// geomorph of the level before it with it). The geomorphs were made as the levels were built; those
// to and from a rebuilt level are made again here, from the maps of the levels next to it made again
// (levelMapsAgain; a nested chain's levels never gain).
Error finishChain(const ChainParams& params, bool clustering, LodChain& out) {
  std::vector<LodLevel>& levels = out.levels;
  const bool maps = clustering && params.morphs && !params.nested;
  std::vector<float> area;
  auto areas = [&]() -> const std::vector<float>* {
    if (area.empty()) area = detail::sourceAreas(levels[0].mesh);
    return &area;
  };
  bool prev_rebuilt = false;     // level k - 1 was rebuilt here
  bool have_rebuilt_map = false;  // and rebuilt_map holds its maps
  detail::LevelMap rebuilt_map;
  const unsigned forced = detail::g_rebuild.load();
  for (size_t k = 1; k < levels.size(); ++k) {
    if (!(k < 32 && (forced >> k & 1u)) && !gainsPrimitives(levels[k - 1].mesh, levels[k].mesh)) {
      detail::LevelMap map;
      if (have_rebuilt_map && levelMapsAgain(params, levels[0].mesh, levels[k], map))
        detail::computeMorph(areas(), &rebuilt_map, levels[k - 1].mesh, map, levels[k].mesh, levels[k - 1].morph);
      prev_rebuilt = have_rebuilt_map = false;
      rebuilt_map = detail::LevelMap();
      continue;
    }
    if (!clustering) {
      levels.erase(levels.begin() + std::ptrdiff_t(k));
      levels[k - 1].morph = LevelMorph();  // (its targets were in the level dropped)
      --k;
      continue;
    }
    // level k - 1's maps: rebuilt here, level 0's, or made again
    detail::LevelMap prev_map;
    bool have_prev = false;
    if (maps) {
      if (prev_rebuilt) {
        have_prev = have_rebuilt_map;
        prev_map = std::move(rebuilt_map);
      } else if (k == 1) {
        detail::identityMap(levels[0].mesh.vertexCount(), prev_map);
        have_prev = true;
      } else {
        have_prev = levelMapsAgain(params, levels[0].mesh, levels[k - 1], prev_map);
      }
    }
    ClusterParams cp = params.cluster;
    cp.cell_width = levels[k].cell_width;
    detail::NestedInput in;
    if (Error e = detail::prepareNested(levels[k - 1].mesh, nullptr, cp, in); !e.ok()) return e;
    LodLevel rebuilt;
    detail::LevelMap map;
    const LodLevel& prev = levels[k - 1];
    if (Error e = detail::nestedLevel(in, prev.mesh, have_prev ? &prev_map : nullptr,
                                      k == 1 ? nullptr : &prev.source_vertex, prev.max_error, levels[0].mesh, cp, rebuilt,
                                      have_prev ? &map : nullptr, nullptr);
        !e.ok())
      return e;
    levels[k] = std::move(rebuilt);
    levels[k - 1].morph = LevelMorph();
    if (have_prev && params.morphs)
      detail::computeMorph(k == 1 ? nullptr : areas(), k == 1 ? nullptr : &prev_map, levels[k - 1].mesh, map,
                           levels[k].mesh, levels[k - 1].morph);
    prev_rebuilt = true;
    have_rebuilt_map = have_prev;
    rebuilt_map = std::move(map);
  }
  return {};
}

Error buildChainImpl(const Mesh& original, Mesh* take, const ChainParams& params, LodChain& out,
                     ChainStats* stats_out) {
  out.levels.clear();
  ChainStats local;
  ChainStats& stats = stats_out ? *stats_out : local;
  stats = ChainStats();
  if (!std::isfinite(params.first_cell_width) || params.first_cell_width < 0.0f)
    return {Status::kInvalidArgument,
            "first cell width " + std::to_string(params.first_cell_width) + " is negative or not finite"};
  if (!std::isfinite(params.growth) || !(params.growth > 1.0f))
    return {Status::kInvalidArgument, "growth " + std::to_string(params.growth) + " must be finite and > 1"};
  switch (params.cluster.method) {
    case LodMethod::kUniform:
    case LodMethod::kFloatingHeaviest:
    case LodMethod::kFloatingNearest:
    {
      const Clock::time_point t0 = Clock::now();
      Error e = params.nested ? buildNestedChain(original, take, params, out, stats)
                : detail::hasAttributes(original) ? buildAttributeChain(original, take, params, out, stats)
                                                  : buildClusterChain(original, take, params, out, stats);
      if (e.ok()) e = finishChain(params, true, out);
      if (!e.ok()) out.levels.clear();
      stats.total_seconds = since(t0);
      return e;
    }
    case LodMethod::kZhang:
    {
      Error e = buildZhangChain(original, params, out);  // (its geomorphs made there)
      // these generators copy level 0; a handed-over mesh replaces the copy, as documented
      if (e.ok() && take && !out.levels.empty()) out.levels[0].mesh = std::move(*take);
      if (e.ok()) e = finishChain(params, false, out);
      if (!e.ok()) out.levels.clear();
      return e;
    }
    case LodMethod::kScrooge:
    {
      const Clock::time_point t0 = Clock::now();
      Error e = buildScroogeChain(original, params, out);  // default ScroogeParams
      stats.total_seconds = since(t0);
      if (e.ok() && take && !out.levels.empty()) out.levels[0].mesh = std::move(*take);
      if (e.ok()) e = finishChain(params, false, out);
      if (!e.ok()) out.levels.clear();
      return e;
    }
    case LodMethod::kOriginal:
      break;
  }
  return {Status::kInvalidArgument, std::string("method '") + lodMethodName(params.cluster.method) +
                                        "' does not generate levels"};
}

}  // namespace

Error buildChain(const Mesh& original, const ChainParams& params, LodChain& out, ChainStats* stats) {
  return buildChainImpl(original, nullptr, params, out, stats);
}

Error buildChain(Mesh&& original, const ChainParams& params, LodChain& out, ChainStats* stats) {
  return buildChainImpl(original, &original, params, out, stats);
}

}  // namespace scenelod
