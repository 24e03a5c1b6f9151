#pragma once
// Scripted camera paths for recording replays: orbit, fly-through, approach, fitted to a scene's
// bounding sphere. Offline code.
#include <cstddef>
#include <string>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_scene.h"

namespace scenelod::selection {

enum class CameraPathKind { kOrbit, kFlythrough, kApproach };

// "orbit", "flythrough" or "approach"; false for anything else.
bool parseCameraPathKind(const std::string& name, CameraPathKind& out);

// A sphere containing every object's world sphere (centre of the bounding box of the spheres).
Sphere sceneBounds(const ReplayScene& scene);

// Frames at `fps` along the path, appended to `replay.frames` (replacing them), camera up = +y:
//   orbit: one turn at 1.6 radii from the centre, 0.35 radii above it, looking at the centre;
//   flythrough: across the scene at a tenth of the radius above its centre, weaving, looking ahead;
//   approach: straight from `approach_from` radii away (default 3) to 0.15 radii from the centre at
//   constant speed, looking at it.
// `frames` 0 gives no frames.
void makeCameraPath(const Sphere& bounds, CameraPathKind kind, size_t frames, double fps, Replay& replay,
                    double approach_from = 3.0);

}  // namespace scenelod::selection
