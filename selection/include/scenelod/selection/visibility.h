#pragma once
// Ray-query visibility for selection: a ray scene mirroring the objects (one instance per object,
// pointing at a shared per-mesh level), picking against the level drawn this frame, the focus factor
// of Funkhouser & Séquin 1993 around a picked or user-set point, and an amortised occlusion estimate
// (visible fraction per object) under a fixed ray budget per frame. Embree stays behind these
// interfaces. See docs/VISIBILITY.md for the design and how a wrong 'hidden' is bounded.
#include <cstddef>
#include <cstdint>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/selection/camera.h"

namespace scenelod::scene {
class Scene;
}

namespace scenelod::selection {

// A ray in world space: origin and (not necessarily unit) direction; points are origin + t * direction.
struct Ray {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, -1.0f};
};

// The ray through the continuous pixel position `pixel_px` (x right, y down, (0, 0) the top-left
// corner of the viewport, so pixel (i, j) has its centre at (i + 0.5, j + 0.5)). Perspective: from the
// eye, unit direction. Orthographic: from the eye's plane, along the view direction.
// Cost: a few flops, thread-safe.
Ray pixelRay(const Camera& camera, glm::vec2 pixel_px);

struct RaySceneParams {
  // occluder level of a mesh: the coarsest level whose max_error is at most this fraction of the
  // mesh's bounding radius (0 = always the full mesh, level 0)
  float occluder_relative_error = 0.02f;
  // a ray blocked by an occluder was traced at a level whose world-space max_error projects to at
  // most this many pixels where the ray enters the occluder's box (error <= occluder_error_px * R(t),
  // level 0 when no coarser level is within it), so a wrong 'hidden' sample lies within this many
  // pixels of an occluder's silhouette
  float occluder_error_px = 1.0f;
  // Embree device configuration string ("threads=1", ...); null = Embree's defaults
  const char* device_config = nullptr;
};

// What pick() found. object is -1 when the ray hit nothing drawn.
struct PickHit {
  int32_t object = -1;
  int32_t level = -1;         // the level drawn for that object, the one the ray hit
  glm::vec3 point{0.0f};      // world-space hit point
  float distance = 0.0f;      // from the ray origin (the eye for a perspective camera), world units
};

// A ray scene mirroring the objects: per chain one Embree scene per level with triangles, and per
// object an instance of it with the object's world transform (one instance level, so callers flatten
// their hierarchy into world matrices). Picking sees each object at the level drawn this frame,
// occlusion at its chain's occluder level. The instance level is a BVH over the objects' world
// boxes: moving objects refits it, added objects wait in a short list tested linearly, removed ones
// leave empty boxes, and commit() rebuilds only when those lists grow past max(64, n/8) or refits
// doubled the tree's summed box area. Object ids are small integers: setObjects() numbers 0..n-1,
// addObject() takes the lowest free id. Edges and points of a level are not ray-traced (triangles
// only).
//
// Thread safety: setters and commit() are single-threaded; after commit(), pick(), intersect() and
// OcclusionEstimator::update() (each estimator on its own thread) may run concurrently until the next
// setter call.
class RayScene {
 public:
  RayScene();
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  // Creates the Embree device and one prototype per chain level with triangles. `chains` need
  // not outlive the call: geometry is copied. Replaces any previous content. Errors: a null chain, an empty chain,
  // a mesh failing validateMesh, an Embree device or build error. Allocates; O(total triangles).
  Error init(Span<const LodChain* const> chains, const RaySceneParams& params = {});

  // Replaces all objects by objects 0..n-1. Preconditions: the three spans have the same length;
  // chain_ids[i] < chain count; drawn_levels[i] in [-1, level count of its chain) (-1 = not drawn);
  // transforms finite and invertible. Errors name the object and the problem. Call commit() after.
  // Allocates; O(n).
  Error setObjects(Span<const glm::mat4> world, Span<const uint32_t> chain_ids, Span<const int32_t> drawn_levels);

  // Mirrors a scene::Scene whose update() has run: ray-scene object i is the scene's object at dense
  // index i, with its node's world transform and its chain id (an index into the chains given to
  // init()). drawn_levels holds one level per dense index, or is empty (every object at level 0).
  // Only what changed is touched: a moved object gets setTransform, an object whose handle or chain
  // changed at an index (the scene swap-removes) is replaced (a new generation, so its occlusion
  // estimate restarts as untested), indices past the scene's object count are removed. Call commit()
  // after. Errors: a chain id out of range, drawn_levels of the wrong size or with a level out of
  // range, a singular world transform. O(objects); allocates only when the object count grows.
  Error syncFromScene(const scene::Scene& scene, Span<const int32_t> drawn_levels = {});

  // Adds one object (same preconditions as setObjects) without rebuilding the others; writes its id
  // (the lowest free id) to `id`. Call commit() after. May allocate.
  Error addObject(const glm::mat4& world, uint32_t chain_id, int32_t drawn_level, uint32_t& id);
  // Removes an object (no rebuild: its box becomes empty) and frees its id. Errors: unknown id.
  Error removeObject(uint32_t id);

  // Moves a live object (its instance transform and world box change; the tree is refitted at
  // commit). Precondition: id live, matrix finite and invertible. O(1), no allocation.
  void setTransform(uint32_t id, const glm::mat4& world);
  // Sets the level drawn this frame (-1 = not drawn), which is the level pick() hits; takes effect
  // at once (no commit needed). Precondition: id live, level in [-1, level count). O(1), no allocation.
  void setDrawnLevel(uint32_t id, int32_t level);

  // Commits pending changes: refits the instance BVH after moves (O(n), no allocation), rebuilds it
  // (O(n log n), allocates) when it is missing or the thresholds above are passed; prototypes are
  // untouched. Must be called after changes and before queries.
  void commit();

  // The first drawn object along the ray through `pixel_px` (see pixelRay), against the level each
  // object draws this frame. Precondition: committed. No allocation; thread-safe after commit().
  PickHit pick(const Camera& camera, glm::vec2 pixel_px) const;
  // The same for any world ray, hits with t in [t_near, t_far].
  PickHit intersect(const Ray& ray, float t_near = 0.0f, float t_far = 3.0e38f) const;

  size_t chainCount() const;
  // One past the largest id ever used: per-object arrays are indexed by id and sized by this.
  size_t objectCapacity() const;
  bool isLive(uint32_t id) const;
  // Incremented each time an id is (re)used by setObjects/addObject, so per-object state kept
  // elsewhere can tell a new object from the old one with the same id.
  uint32_t objectGeneration(uint32_t id) const;
  uint32_t chainOf(uint32_t id) const;
  int32_t drawnLevel(uint32_t id) const;
  // The level used for occlusion for objects of this chain (see RaySceneParams).
  int32_t occluderLevel(uint32_t chain_id) const;
  // World bounding sphere of each id (xyz centre, w radius; radius 0 for free ids); objectCapacity()
  // entries. Contains every level of the object's chain.
  Span<const glm::vec4> worldSpheres() const;
  const glm::mat4& worldTransform(uint32_t id) const;
  const RaySceneParams& params() const;

  struct Impl;

 private:
  friend class OcclusionEstimator;
  Impl* impl_ = nullptr;
};

// Focus (Funkhouser & Séquin 1993, the "focus" factor of benefit): objects near the point the user
// looks at get more detail. For an object whose bounding sphere (centre c, radius r) lies at distance
// d = max(0, |c - point| - r) from the focus point:
//   focus = 1 + gain * (1 - (d / radius)^2)^2   for d < radius,   1 otherwise,
// so the object at the point gets 1 + gain, the factor falls smoothly to exactly 1 at `radius`.
struct FocusParams {
  bool enabled = false;
  glm::vec3 point{0.0f};   // world space
  float radius = 1.0f;     // falloff radius, world units, > 0
  float gain = 2.0f;       // >= 0
};

// Focus around a pick: the hit point, with radius = radius_scale * the picked object's bounding
// radius; disabled when nothing was hit. Cost: O(1).
FocusParams focusFromPick(const RayScene& scene, const PickHit& hit, float radius_scale = 4.0f, float gain = 2.0f);

// Writes the focus factor (>= 1) of every sphere (xyz centre, w radius) to focus[i]; all 1 when
// disabled. Precondition: focus.count >= spheres.count. O(n), no allocation, thread-safe.
void computeFocusFactors(Span<const glm::vec4> spheres, const FocusParams& params, Span<float> focus);

struct OcclusionParams {
  uint32_t ray_budget = 20000;   // occlusion samples per frame, over all objects
  uint32_t rays_per_test = 16;   // samples per tested object (1..256)
  // priority = (1 + min(projected radius px, kMaxPriorityRadiusPx)) * (frames since last test);
  // an object never tested counts as last tested this many frames before the first frame it was seen
  uint32_t untested_age_frames = 64;
};

// What the last update() did.
struct OcclusionStats {
  uint32_t objects_tested = 0;
  uint32_t samples = 0;          // samples taken (<= ray budget)
  uint32_t self_hits = 0;        // samples counted: whose ray met the object itself (the estimate's
                                 // denominator), or every sample of a test blocked before the object
  uint32_t occlusion_rays = 0;   // sample rays tested against occluders (every sample)
  uint32_t candidates = 0;       // objects in the view frustum and in front of the eye
  uint32_t occluder_candidates = 0;  // objects whose bounding spheres a tested object's rays were checked against
  uint32_t embree_rays = 0;      // single-ray Embree queries: one self ray per sample plus the occluder queries
  uint32_t hidden_samples = 0;   // counted samples found hidden
};

// Amortised visible-fraction estimate. Each update() tests the objects of highest priority (screen
// size times age) with `rays_per_test` samples each until the ray budget is spent. A sample is a ray
// from the eye through a fixed stratified (golden-angle) disc pattern facing the camera, covering the
// object's bounding sphere footprint and rotated on every test; it counts when it meets the object's
// own occluder level at t_self, and it is hidden when another object blocks it before t_self. Another
// object blocks a ray only with a level whose error projects to at most
// RaySceneParams::occluder_error_px pixels where the ray enters that object's box: its occluder level
// when that is trusted there, otherwise a finer one (level 0 is exact). visible fraction = unhidden /
// counted samples of the latest test (1 when no sample met the object; 0 when every sample was
// blocked before the object's bounding sphere, which is then not traced itself). Objects never
// tested (or whose id was reused) read as 1, i.e. visible.
class OcclusionEstimator {
 public:
  static constexpr float kMaxPriorityRadiusPx = 512.0f;

  OcclusionEstimator();
  ~OcclusionEstimator();
  OcclusionEstimator(const OcclusionEstimator&) = delete;
  OcclusionEstimator& operator=(const OcclusionEstimator&) = delete;

  // Sizes the per-object state for ids < max_objects. Errors: max_objects 0, rays_per_test outside
  // [1, 256]. Allocates; everything update() needs is allocated here.
  Error init(size_t max_objects, const OcclusionParams& params = {});

  // False when the scene's objectCapacity() exceeds max_objects or visible_fraction (if given) holds
  // fewer than objectCapacity() entries.
  bool validate(const RayScene& scene, Span<float> visible_fraction) const;
  // One frame: tests the highest-priority objects within the budget, then writes every id's estimate
  // (1 for untested and free ids) into visible_fraction (may be empty). Returns false (doing nothing)
  // when validate() fails. Precondition: scene committed. No allocation; O(objects) for the
  // priority pass plus, per tested object, one walk of the top-level tree with its beam of sample
  // rays (stopped once every ray is blocked), and a second one with a ray per sample against the
  // object itself unless every sample was blocked before the object's bounding sphere.
  bool update(const RayScene& scene, const Camera& camera, Span<float> visible_fraction);

  // Latest estimate of an id (1 when never tested) and how many update() calls ago it was measured
  // (UINT32_MAX when never tested).
  float visibleFraction(const RayScene& scene, uint32_t id) const;
  uint32_t ageFrames(const RayScene& scene, uint32_t id) const;
  const OcclusionStats& lastStats() const;
  uint64_t frameCount() const;

  struct State;

 private:
  State* state_ = nullptr;
};

}  // namespace scenelod::selection
