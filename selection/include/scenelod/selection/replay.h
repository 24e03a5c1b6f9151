#pragma once
// Replay files (JSON lines, docs/REPLAY.md): a header line, then one line per frame with the camera
// (or, in version 2, a list of views), optionally the measured frame time, a pick point and object
// moves. Offline code: allocates, returns Error naming the file and line.
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "scenelod/lodcore/status.h"
#include "scenelod/selection/selector.h"

namespace scenelod::selection {

// The largest coordinate a replay takes (eye, target, up, move values) and the farthest a world
// bounding sphere may reach in a run: squared distances then stay finite in float.
constexpr double kMaxReplayCoordinate = 1e18;

struct ReplayHeader {
  int version = 1;               // "scenelod_replay": 1, or 2 when frames carry "views" (writeReplay
                                 // sets it from the frames)
  std::string scene;             // glTF/GLB, pack, level-scene JSON or "builtin:NAME"; relative to the replay file
  uint32_t viewport_width_px = 1280;
  uint32_t viewport_height_px = 720;
  double fov_y_deg = 60.0;
  bool has_budget = false;       // false: distance mode (budget_ms null or absent)
  double budget_ms = 16.7;
  double pixels_per_cell = 1.0;
};

// A new local transform of an object (its node): translation, rotation (x, y, z, w), uniform scale.
struct ReplayMove {
  uint32_t object = 0;
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // glm order w, x, y, z
  float scale = 1.0f;
};

// One view of a version-2 frame ("views": [{kind, group, eye, target, up, fov_y_deg | ortho_height,
// near, far, viewport, pixels_per_cell, lod_bias}]); kind is "primary", "shadow", "eye" or
// "secondary". The camera's viewport and X default to the header's.
struct ReplayView {
  ViewKind kind = ViewKind::kPrimary;
  uint32_t group = 0;
  Camera camera;             // fov_y_rad or ortho_height by camera.projection
  float pixels_per_cell = 1.0f;
  float lod_bias = 1.0f;
};

struct ReplayFrame {
  uint64_t frame = 0;
  double time_s = 0.0;
  glm::vec3 eye{0.0f, 0.0f, 5.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  bool has_measured = false;
  double measured_ms = 0.0;
  bool has_pick = false;
  float pick_px[2] = {0.0f, 0.0f};
  std::vector<ReplayMove> moves;
  std::vector<ReplayView> views;   // version 2: empty = the one camera above; else eye/target unused
};

struct Replay {
  ReplayHeader header;
  std::vector<ReplayFrame> frames;
};

// Reads a replay. Errors: missing file, a line that is not JSON, a missing or mistyped key, a
// version other than 1 or 2, "views" in a version-1 file, a bad view (unknown kind, both or neither
// of fov_y_deg and ortho_height, more than 8), frames out of order, a non-finite number; each names
// the file and line.
Error readReplay(const std::string& path, Replay& out);

// Reads a replay one frame at a time, for runs whose memory must not grow with their length
// (runReplayStream in replay_runner.h). Same checks and messages as readReplay.
class ReplayReader {
 public:
  // Opens `path` and reads its header line.
  Error open(const std::string& path);
  const ReplayHeader& header() const { return header_; }
  // The next frame into `frame`: true when there was one; false at the end of the file (`error`
  // empty) or on a bad line (`error` names the file and line).
  bool next(ReplayFrame& frame, Error& error);

 private:
  // the next line that is not blank, empty at the end of the file
  bool nextLine(std::string& line);
  Error lineError(const std::string& what) const;

  std::ifstream in_;
  std::string path_;
  size_t line_no_ = 0;
  size_t frames_read_ = 0;
  uint64_t last_frame_ = 0;
  ReplayHeader header_;
};
// Writes a replay (numbers with enough digits to read back the same floats).
Error writeReplay(const std::string& path, const Replay& replay);

// The scene path of a replay resolved against the replay file's folder (absolute paths and
// "builtin:" names are returned unchanged).
std::string resolveReplayScene(const std::string& replay_path, const std::string& scene);

}  // namespace scenelod::selection
