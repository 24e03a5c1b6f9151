#pragma once
// Visibility in replays: a RayScene and OcclusionEstimator that follow the replay's objects, feed
// visible fractions and the focus of the frame's pick point into each selection, and measure what
// occlusion saved: a shadow selection without visibility (same parameters and cost model, its own
// history) tells how much predicted cost it would spend on objects the estimator reads as hidden.
// Offline-tool code: init allocates; a frame allocates nothing after the first.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_scene.h"
#include "scenelod/selection/selector.h"
#include "scenelod/selection/visibility.h"

namespace scenelod::selection {

struct ReplayLogFrame;

struct ReplayVisibilityParams {
  RaySceneParams ray_scene;
  OcclusionParams occlusion;
  float focus_radius_scale = 4.0f;   // focus radius = this x the picked object's bounding radius
  float focus_gain = 2.0f;
  float hidden_below = 0.05f;        // "hidden" for the saving measure: visible fraction below this
};

class ReplayVisibility {
 public:
  ReplayVisibility();
  ~ReplayVisibility();

  // Builds the ray scene for `scene`: its chains' meshes when the scene has them (glTF/GLB/OBJ
  // scenes), otherwise a stand-in per chain, the cube inscribed in the chain's bounding sphere (level
  // and synthetic scenes carry no geometry; their objects are taken to be those cubes). Errors:
  // as RayScene::init and OcclusionEstimator::init.
  Error init(const ReplayScene& scene, const ReplayVisibilityParams& params = {});

  // Before a frame's selection: moves the objects to the scene's current world transforms, commits,
  // runs the estimator, picks at the frame's pick point (if any) and sets the job's
  // visible_fraction, focus and cost_ms_out spans. Errors: a frame on a scene of another size.
  Error beforeSelect(const ReplayScene& scene, const Camera& camera, const ReplayFrame& frame, SelectionJob& job);
  // After the selection ran: runs the shadow selection, records the frame's visibility fields in
  // `out` and sets each object's drawn level for the next pick.
  void afterSelect(const SelectionJob& job, ReplayLogFrame& out);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace scenelod::selection
