// `scenelod replay --popping`: each frame rendered with last frame's and this frame's level state,
// compared pixel by pixel (replay_popping.h).
#include "replay_popping.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <glm/geometric.hpp>

#include "scenelod/selection/camera_path.h"

#ifdef SCENELOD_HAVE_GL
#include "scenelod/gl/renderer.h"
#endif

namespace scenelod::tool {

using namespace scenelod::selection;

double poppingShare(const eval::Image& a, const eval::Image& b, const uint8_t background[3]) {
  if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) return 1.0;
  size_t covered = 0, changed = 0;
  for (size_t i = 0; i + 2 < a.rgb.size(); i += 3) {
    const uint8_t* p = &a.rgb[i];
    const uint8_t* q = &b.rgb[i];
    const bool in_a = p[0] != background[0] || p[1] != background[1] || p[2] != background[2];
    const bool in_b = q[0] != background[0] || q[1] != background[1] || q[2] != background[2];
    if (!in_a && !in_b) continue;
    ++covered;
    if (std::abs(p[0] - q[0]) > kPoppingThreshold || std::abs(p[1] - q[1]) > kPoppingThreshold ||
        std::abs(p[2] - q[2]) > kPoppingThreshold)
      ++changed;
  }
  return covered ? static_cast<double>(changed) / static_cast<double>(covered) : 0.0;
}

std::string withPopping(const std::string& line, double popping, double camera_popping) {
  char buf[96];
  if (camera_popping >= 0.0)
    std::snprintf(buf, sizeof(buf), ", \"popping\": %.5f, \"camera_popping\": %.5f}", popping, camera_popping);
  else
    std::snprintf(buf, sizeof(buf), ", \"popping\": %.5f}", popping);
  if (line.empty() || line.back() != '}') return line;
  return line.substr(0, line.size() - 1) + buf;
}

struct ReplayPopping::Impl {
  Camera camera, last_camera;
  bool has_last_camera = false;
  uint64_t frame = 0;
  // last frame's level state
  bool has_last = false;
  std::vector<int8_t> levels, previous_levels;
  std::vector<float> morph, fade;
  std::vector<double> values;  // per measured frame
  double max = 0.0;
  uint64_t max_frame = 0;
  std::vector<glm::mat4> worlds;
  eval::Image before, after, full;
  uint32_t supersample = 1;
#ifdef SCENELOD_HAVE_GL
  gl::Renderer renderer;
#endif
  bool ready = false;
  bool frame_set = false;  // setFrame was called before (last_camera is a frame's)
};

namespace {

// the sentinel background: pixels of this colour are not covered by any object (a surface lit
// exactly to pure magenta would be taken for background)
constexpr uint8_t kBackground[3] = {255, 0, 255};

// The mean of every k x k block of `in` (k = 1: a copy). A pixel stays the background colour only
// when its whole block is, so a pixel counts as covered when any of its samples is.
void downsample(const eval::Image& in, uint32_t k, eval::Image& out) {
  if (k <= 1) {
    out = in;
    return;
  }
  const int w = in.width / static_cast<int>(k), h = in.height / static_cast<int>(k);
  out = eval::Image(w, h, 0);
  const int n = static_cast<int>(k * k);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int sum[3] = {0, 0, 0};
      bool all_background = true;
      for (int dy = 0; dy < static_cast<int>(k); ++dy)
        for (int dx = 0; dx < static_cast<int>(k); ++dx) {
          const uint8_t* p = in.pixel(x * static_cast<int>(k) + dx, y * static_cast<int>(k) + dy);
          all_background = all_background && p[0] == kBackground[0] && p[1] == kBackground[1] && p[2] == kBackground[2];
          for (int c = 0; c < 3; ++c) sum[c] += p[c];
        }
      uint8_t* d = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) d[c] = static_cast<uint8_t>((sum[c] + n / 2) / n);
      // a covered block whose mean happens to equal the background is nudged off it
      if (!all_background && d[0] == kBackground[0] && d[1] == kBackground[1] && d[2] == kBackground[2]) d[1] = 1;
    }
}

}  // namespace

ReplayPopping::ReplayPopping() : impl_(new Impl) {}
ReplayPopping::~ReplayPopping() = default;

Error ReplayPopping::init(const ReplayScene& scene, const ReplayHeader& header, const std::string& scene_path,
                          uint32_t supersample, bool* unavailable) {
  if (unavailable) *unavailable = false;
  if (supersample < 1 || supersample > 4) return Error(Status::kInvalidArgument, "popping: supersampling must be 1..4");
  if (scene.chains.size() != scene.table.chainCount() || scene.chains.empty())
    return Error(Status::kUnsupported, scene_path + ": --popping renders the scene, which has no meshes (level-scene, pack "
                                                    "and builtin:NAME scenes carry only level rows); give the replay a "
                                                    "glTF/GLB/OBJ scene");
#ifdef SCENELOD_HAVE_GL
  Impl& m = *impl_;
  gl::RendererConfig rc;
  m.supersample = supersample;
  rc.width_px = std::min<uint32_t>(header.viewport_width_px * supersample, 8192);
  rc.height_px = std::min<uint32_t>(header.viewport_height_px * supersample, 8192);
  for (int k = 0; k < 3; ++k) rc.background[k] = kBackground[k] / 255.0f;
  if (Error e = m.renderer.init(rc, unavailable); !e.ok()) return e;
  if (Error e = m.renderer.uploadChains(scene.chains); !e.ok()) return e;
  m.camera.viewport_width_px = rc.width_px;
  m.camera.viewport_height_px = rc.height_px;
  m.camera.fov_y_rad = static_cast<float>(header.fov_y_deg * 3.14159265358979 / 180.0);
  m.ready = true;
  return {};
#else
  (void)header;
  (void)supersample;
  return Error(Status::kUnsupported, "--popping renders with the OpenGL adapter, which this build of scenelod does not "
                                     "have (adapters/gl needs EGL and OpenGL at configure time; docs/GL.md)");
#endif
}

void ReplayPopping::setFrame(const ReplayFrame& f) {
  Impl& m = *impl_;
  m.frame = f.frame;
  m.last_camera = m.camera;
  m.has_last_camera = m.frame_set;
  m.frame_set = true;
  const uint32_t w = m.camera.viewport_width_px, h = m.camera.viewport_height_px;
  const float fov = m.camera.fov_y_rad;
  m.camera = Camera();
  m.camera.viewport_width_px = w;
  m.camera.viewport_height_px = h;
  m.camera.fov_y_rad = fov;
  m.camera.eye = f.eye;
  m.camera.target = f.target;
  m.camera.up = f.up;
  for (const ReplayView& v : f.views)
    if (v.kind == ViewKind::kPrimary) {
      m.camera = v.camera;
      m.camera.viewport_width_px = w;
      m.camera.viewport_height_px = h;
      break;
    }
}

Error ReplayPopping::measure(const ReplayScene& scene, const ReplayLogFrame& log, double& popping, double* camera_popping) {
  Impl& m = *impl_;
  (void)scene;  // drawn only in builds with the GL adapter
  popping = 0.0;
  if (camera_popping) *camera_popping = -1.0;
  if (!m.ready) return Error(Status::kInvalidArgument, "popping: measure before init");
  const bool same = m.has_last && m.levels == log.levels && m.morph == log.morph && m.fade == log.fade &&
                    m.previous_levels == log.previous_levels;
  if (m.has_last && !same) {
#ifdef SCENELOD_HAVE_GL
    // near and far planes tight around the scene's bounds as they are now (the run's camera planes
    // are for selection, not for a depth buffer: a far scene's two sides would share depth steps)
    Camera cam = m.camera;
    gl::fitDepthPlanes(cam, sceneBounds(scene));
    if (!cameraValid(cam))
      return Error(Status::kInvalidArgument, "popping: frame " + std::to_string(m.frame) + ": degenerate camera");
    computeObjectWorlds(scene, m.worlds);
    const size_t n = scene.objectCount();
    gl::FrameInput in;
    in.camera = &cam;
    in.object_world = {m.worlds.data(), n};
    in.object_chain = {scene.object_chain.data(), n};
    in.levels = {m.levels.data(), m.levels.size()};
    in.morph = {m.morph.data(), m.morph.size()};
    in.previous_levels = {m.previous_levels.data(), m.previous_levels.size()};
    in.fade = {m.fade.data(), m.fade.size()};
    const std::string where = "popping: frame " + std::to_string(m.frame);
    if (!m.renderer.drawFrame(in, nullptr)) return Error(Status::kInvalidArgument, where + ": the renderer refused last frame's levels");
    if (Error e = m.renderer.readPixels(m.full); !e.ok()) return Error(e.status, where + ": " + e.message);
    downsample(m.full, m.supersample, m.before);
    in.levels = {log.levels.data(), log.levels.size()};
    in.morph = {log.morph.data(), log.morph.size()};
    in.previous_levels = {log.previous_levels.data(), log.previous_levels.size()};
    in.fade = {log.fade.data(), log.fade.size()};
    if (!m.renderer.drawFrame(in, nullptr)) return Error(Status::kInvalidArgument, where + ": the renderer refused this frame's levels");
    if (Error e = m.renderer.readPixels(m.full); !e.ok()) return Error(e.status, where + ": " + e.message);
    downsample(m.full, m.supersample, m.after);
    popping = poppingShare(m.before, m.after, kBackground);
    if (camera_popping && m.has_last_camera) {
      // this frame's state under last frame's camera (its own depth planes)
      Camera last = m.last_camera;
      gl::fitDepthPlanes(last, sceneBounds(scene));
      in.camera = &last;
      if (!m.renderer.drawFrame(in, nullptr)) return Error(Status::kInvalidArgument, where + ": the renderer refused last frame's camera");
      if (Error e = m.renderer.readPixels(m.full); !e.ok()) return Error(e.status, where + ": " + e.message);
      downsample(m.full, m.supersample, m.before);
      *camera_popping = poppingShare(m.before, m.after, kBackground);
    }
#endif
  }
  // the same level state under the same camera renders the same picture: popping 0 without drawing
  if (m.has_last) {
    m.values.push_back(popping);
    if (popping > m.max) {
      m.max = popping;
      m.max_frame = log.frame;
    }
  }
  m.has_last = true;
  m.levels = log.levels;
  m.morph = log.morph;
  m.fade = log.fade;
  m.previous_levels = log.previous_levels;
  return {};
}

PoppingSummary ReplayPopping::summary() const {
  const Impl& m = *impl_;
  PoppingSummary s;
  s.frames = m.values.size();
  if (s.frames == 0) return s;
  std::vector<double> sorted = m.values;
  std::sort(sorted.begin(), sorted.end());
  const size_t rank = static_cast<size_t>(std::ceil(0.99 * static_cast<double>(sorted.size())));
  s.p99 = sorted[std::max<size_t>(rank, 1) - 1];
  s.max = m.max;
  s.max_frame = m.max_frame;
  double sum = 0.0;
  for (double v : m.values) {
    sum += v;
    if (v > 0.0) ++s.popping_frames;
  }
  s.mean = sum / static_cast<double>(s.frames);
  return s;
}

}  // namespace scenelod::tool
