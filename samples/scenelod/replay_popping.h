#pragma once
// `scenelod replay --popping`: how much of the picture a level change alters from one frame to the
// next. Each frame is rendered twice with the GL adapter (adapters/gl) under the frame's camera and
// object transforms: once with last frame's levels, morph factors and fades, once with this frame's.
// The frame's popping is the share of the pixels covered in either render (any colour other than
// the background) whose colours differ by more than 16/255 in some channel; 0 when nothing about
// the levels changed, 1 when every covered pixel changed. Built with SCENELOD_HAVE_GL; without it
// init() returns an error saying so.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scenelod/eval/image.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_runner.h"
#include "scenelod/selection/replay_scene.h"

namespace scenelod::tool {

// A colour channel must differ by more than this (in 8-bit steps) for a pixel to count as changed.
constexpr int kPoppingThreshold = 16;

// The share of the pixels that are not `background` in `a` or in `b` (images of one size) whose
// colours differ by more than kPoppingThreshold in some channel; 0 when neither covers a pixel.
double poppingShare(const eval::Image& a, const eval::Image& b, const uint8_t background[3]);

struct PoppingSummary {
  size_t frames = 0;         // frames measured (every frame but the first)
  size_t popping_frames = 0; // of those, frames with popping > 0
  double max = 0.0;          // the largest per-frame popping
  uint64_t max_frame = 0;    // the frame where it happened
  double p99 = 0.0;          // 99th percentile (nearest rank) of the per-frame popping
  double mean = 0.0;
};

class ReplayPopping {
 public:
  ReplayPopping();
  ~ReplayPopping();
  ReplayPopping(const ReplayPopping&) = delete;
  ReplayPopping& operator=(const ReplayPopping&) = delete;

  // Starts the renderer at the replay's viewport and uploads the scene's chains. Errors: a scene
  // without meshes (level-scene, pack and builtin:NAME scenes carry only level rows), a tool built
  // without the GL adapter, the renderer's errors; `*unavailable` is set true when EGL or OpenGL 3.3
  // cannot start on this machine.
  // With `supersample` k (1..4) each render is k x k times the viewport and box-filtered down to
  // it before the comparison, as an antialiased display would show it.
  Error init(const selection::ReplayScene& scene, const selection::ReplayHeader& header, const std::string& scene_path,
             uint32_t supersample, bool* unavailable);

  // The camera of the frame just read (its primary view's for a frame with views).
  void setFrame(const selection::ReplayFrame& frame);

  // Renders the frame set by setFrame (the scene as the run left it: moves applied) with last
  // frame's and with this frame's level state and returns the popping in `popping` (0 for the
  // first frame, which has no last frame). With `camera_popping` (not null), on the frames where
  // the level state changed it also renders this frame's state under last frame's camera and
  // returns the popping between that and this frame's picture: what the camera's own motion
  // changes on the same frame, a floor for transitions that move geometry (-1 on frames not
  // drawn). Errors: a degenerate camera, the renderer refusing the frame or its read-back.
  Error measure(const selection::ReplayScene& scene, const selection::ReplayLogFrame& log, double& popping,
                double* camera_popping = nullptr);

  PoppingSummary summary() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// `line` (a replayLogLine, ending in '}') with `"popping": P` added before its closing brace, and
// `"camera_popping": C` after it when `camera_popping` >= 0.
std::string withPopping(const std::string& line, double popping, double camera_popping = -1.0);

}  // namespace scenelod::tool
