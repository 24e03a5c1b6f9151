// scenelod view: renders a scene with the OpenGL adapter (adapters/gl) headless, the levels chosen
// per frame by the selector under a frame-time budget, and reports the measured frame times back to
// the selector so its cost model is fitted to real rendering. Built only with SCENELOD_HAVE_GL.
#ifdef SCENELOD_HAVE_GL
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/stat.h>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "args.h"
#include "cluster_options.h"
#include "command.h"
#include "scenelod/eval/image.h"
#include "scenelod/gl/renderer.h"
#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/selection/camera_path.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_scene.h"
#include "scenelod/selection/selector.h"

namespace scenelod::tool {
namespace {

using namespace scenelod::selection;

// exit code when the machine cannot render (no EGL display or no OpenGL 3.3 context): CTest skips
constexpr int kExitUnavailable = 77;

const char kUsage[] =
    "usage: scenelod view [SCENE] [--replay R] --headless --frames N --png DIR [options]\n"
    "\n"
    "Renders SCENE (a .gltf/.glb/.obj file, or `builtin` / nothing for the built-in demo scene) with\n"
    "the OpenGL renderer through EGL without a display. Each frame the selector picks every object's\n"
    "level under the budget, the renderer draws those levels and measures the frame (CPU time of\n"
    "issuing the draws + glFinish), and the time goes back to the selector (reportFrameTime) so the\n"
    "cost model is fitted to the real renderer. The camera follows the replay R (its moves too), or\n"
    "an orbit around the scene. Prints predicted vs measured ms per frame and the mean relative\n"
    "prediction error after 30 warm-up frames. Exit code 77: EGL or OpenGL 3.3 cannot start here.\n"
    "\n"
    "options:\n"
    "  --headless          render offscreen through EGL (required: no windowed mode is built)\n"
    "  --replay R          camera path and moves of a replay file (docs/REPLAY.md); without SCENE,\n"
    "                      its scene (which must have meshes: a glTF/GLB/OBJ file)\n"
    "  --frames N          frames to render (default: the replay's frame count, or 120 on the orbit)\n"
    "  --png DIR           write DIR/frame_NNNN.png every --every frames (and the last frame)\n"
    "  --every K           screenshot interval (default: frames / 8, at least 1)\n"
    "  --size W H          render target size (default 640 360)\n"
    "  --budget MS         frame-time budget of the selection (default: the replay's, else 16.7)\n"
    "  --pixels X          pixels per cell of the accuracy test (default 1)\n"
    "  --no-calibrate      keep the selector's prior cost model (measured times are still printed)\n"
    "  --shadows           also render a shadow map: a directional light from above the scene, its\n"
    "                      orthographic camera a shadow view of the same selection (docs/SELECTION.md,\n"
    "                      \"Views\"), which picks the casters' levels under the same budget\n"
    "  --shadow-pixels X   pixels (texels) per cell of the shadow view (default 4)\n"
    "  --shadow-map N      shadow map side in texels (default 2048); with --png, each screenshot\n"
    "                      has a DIR/light_NNNN.png beside it: the shadow levels seen from the light\n"
    "  --distance          distance mode: each object at the coarsest level accurate to --pixels (no budget)\n"
    "  --transitions MODE  none (default: hard switches), fade (dithered cross-fades) or morph (geomorphs\n"
    "                      where levels have morph data, fades elsewhere); time between frames from the\n"
    "                      replay's time_s, or 1000/60 ms on the orbit; the frame lines add the objects\n"
    "                      fading (docs/GL.md, \"Level transitions\")\n"
    "  --fade-ms MS        duration of a cross-fade (default 250)\n"
    "  --morph-band F      share of a level's log pixel-size interval the morph takes, (0, 1] (default 0.3)\n"
    "  --nested, --independent  chains built here (glTF/GLB/OBJ without MSFT_lod levels, builtin): each\n"
    "                      level clusters the one before, or the original (default)\n"
    "  --quiet             no per-frame lines";

// World matrix of every node from parents and local transforms (validated scenes have no cycles).
void computeNodeWorld(const ReplayScene& s, std::vector<glm::mat4>& world) {
  const size_t n = s.node_local.size();
  world.assign(n, glm::mat4(1.0f));
  std::vector<uint8_t> done(n, 0);
  std::vector<int32_t> stack;
  for (size_t i = 0; i < n; ++i) {
    int32_t cur = static_cast<int32_t>(i);
    stack.clear();
    while (cur >= 0 && !done[static_cast<size_t>(cur)]) {
      stack.push_back(cur);
      cur = s.node_parent[static_cast<size_t>(cur)];
    }
    glm::mat4 parent = cur >= 0 ? world[static_cast<size_t>(cur)] : glm::mat4(1.0f);
    for (auto it = stack.rbegin(); it != stack.rend(); ++it) {
      parent = parent * s.node_local[static_cast<size_t>(*it)];
      world[static_cast<size_t>(*it)] = parent;
      done[static_cast<size_t>(*it)] = 1;
    }
  }
}

// The scene to draw and, in `materials`, the scene data whose materials and textures its chains'
// groups refer to (chain c is mesh c; empty for scenes without meshes).
Error loadViewScene(const std::string& path, ReplayScene& out, scene::SceneData& materials, const ChainParams* chain) {
  if (path.empty() || path == "builtin") {
    scene::DemoSceneInfo info;
    if (Error e = scene::makeDemoScene(materials, scene::DemoSceneParams(), &info); !e.ok()) return e;
    if (!info.note.empty()) std::printf("%s\n", info.note.c_str());
    scene::SceneLods lods;
    scene::LodBuildParams build;
    if (chain) build.chain = *chain;
    if (Error e = scene::buildLods(materials, build, lods, nullptr, "demo scene"); !e.ok()) return e;
    return replaySceneFromSceneData(materials, lods.chains, "demo scene", out, &lods.chain_spheres);
  }
  if (Error e = chain ? loadReplayScene(path, out, *chain) : loadReplayScene(path, out); !e.ok()) return e;
  std::string ext = path.size() > 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::vector<LodChain> unused;
  if (ext == "gltf" || ext == ".glb") {
    if (Error e = scene::importGltfLods(path, materials, unused); !e.ok()) return e;
  } else if (ext == ".obj") {
    if (Error e = scene::loadScene(path, materials); !e.ok()) return e;
  }
  if (out.chains.size() != out.table.chainCount())
    return Error(Status::kUnsupported, path + ": the scene has no meshes to render (level-scene, pack and builtin:NAME "
                                              "scenes carry only level rows); give a glTF/GLB/OBJ file or `builtin`");
  return {};
}

// `--size W H` takes two values: rewritten to `--size=WxH` before parsing (`--size WxH` works too).
std::vector<std::string> joinSize(const std::vector<std::string>& argv) {
  std::vector<std::string> out;
  for (size_t i = 0; i < argv.size(); ++i) {
    if (argv[i] == "--size" && i + 2 < argv.size() && argv[i + 1].find('x') == std::string::npos) {
      out.push_back("--size=" + argv[i + 1] + "x" + argv[i + 2]);
      i += 2;
    } else {
      out.push_back(argv[i]);
    }
  }
  return out;
}

bool parseSize(const std::string& s, long& w, long& h) {
  const size_t x = s.find('x');
  if (x == std::string::npos) return false;
  char* end = nullptr;
  w = std::strtol(s.c_str(), &end, 10);
  if (end != s.c_str() + x) return false;
  h = std::strtol(s.c_str() + x + 1, &end, 10);
  return *end == '\0' && x + 1 < s.size() && w >= 16 && h >= 16 && w <= 8192 && h <= 8192;
}

// The light of --shadows: a directional light from above the scene (its up direction `up`, tilted
// 35 degrees), as an orthographic camera whose box holds the whole scene sphere, so that every
// caster lies between the light and what it shadows.
Camera shadowCamera(const Sphere& bounds, glm::vec3 up, uint32_t texels) {
  up = glm::length(up) > 0.0f ? glm::normalize(up) : glm::vec3(0.0f, 1.0f, 0.0f);
  const glm::vec3 side = std::fabs(up.x) < 0.9f ? glm::normalize(glm::cross(up, glm::vec3(1, 0, 0)))
                                                 : glm::normalize(glm::cross(up, glm::vec3(0, 0, 1)));
  const glm::vec3 to_light = glm::normalize(up * std::cos(0.61f) + side * std::sin(0.61f));
  const float r = std::max(bounds.radius, 1e-3f);
  Camera c;
  c.projection = Projection::kOrthographic;
  c.target = bounds.center;
  c.eye = bounds.center + to_light * (2.0f * r);
  c.up = glm::normalize(glm::cross(to_light, glm::cross(side, to_light)) + 1e-3f * side);
  c.ortho_height = 2.05f * r;
  c.near_plane = 0.5f * r;
  c.far_plane = 3.5f * r;
  c.viewport_width_px = c.viewport_height_px = texels;
  return c;
}

// The renderer's materials from the scene's: factor, the decoded base colour texture (an undecoded
// one drawn as its mean colour), wrap modes, KHR_texture_transform; and each chain's group
// materials (its mesh's primitive materials).
void viewMaterials(const scene::SceneData& s, size_t chain_count, std::vector<gl::MaterialDesc>& out,
                   std::vector<std::vector<int32_t>>& groups) {
  out.assign(s.materials.size(), gl::MaterialDesc());
  for (size_t i = 0; i < s.materials.size(); ++i) {
    const scene::MaterialData& m = s.materials[i];
    gl::MaterialDesc& d = out[i];
    for (int k = 0; k < 4; ++k) d.base_color[k] = m.base_color[k];
    const int32_t t = m.base_color_texture;
    const int32_t image = t >= 0 && static_cast<size_t>(t) < s.textures.size() ? s.textures[static_cast<size_t>(t)].image : -1;
    const scene::ImageData* img = image >= 0 && static_cast<size_t>(image) < s.images.size() ? &s.images[static_cast<size_t>(image)] : nullptr;
    if (img && !img->rgba8.empty()) {
      d.rgba8 = img->rgba8.data();
      d.width = img->width;
      d.height = img->height;
      d.wrap_s = s.textures[static_cast<size_t>(t)].wrap_s;
      d.wrap_t = s.textures[static_cast<size_t>(t)].wrap_t;
      const scene::TextureTransform& x = m.base_color_transform;
      glm::mat3 translate(1.0f), rotate(1.0f), scale(1.0f);
      translate[2] = glm::vec3(x.offset, 1.0f);
      rotate[0] = glm::vec3(std::cos(x.rotation), -std::sin(x.rotation), 0.0f);
      rotate[1] = glm::vec3(std::sin(x.rotation), std::cos(x.rotation), 0.0f);
      scale[0][0] = x.scale.x;
      scale[1][1] = x.scale.y;
      const glm::mat3 uv = translate * rotate * scale;
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) d.uv_transform[3 * c + r] = uv[c][r];
    } else if (m.textured) {
      for (int k = 0; k < 3; ++k) d.base_color[k] *= m.average_texel_color[k];
    }
  }
  groups.assign(std::min(chain_count, s.meshes.size()), {});
  for (size_t c = 0; c < groups.size(); ++c) groups[c] = s.meshes[c].primitive_materials;
  if (s.materials.empty()) groups.clear();
}

bool makeDir(const std::string& dir) {
  struct stat st;
  if (stat(dir.c_str(), &st) == 0) return S_ISDIR(st.st_mode);
  return mkdir(dir.c_str(), 0755) == 0;
}

int run(const std::vector<std::string>& raw_argv) {
  Args args(joinSize(raw_argv), {"--headless", "--no-calibrate", "--quiet", "--shadows", "--distance", "--nested", "--independent"},
            {"--replay", "--frames", "--png", "--every", "--size", "--budget", "--pixels", "--shadow-pixels", "--shadow-map",
             "--transitions", "--fade-ms", "--morph-band"});
  if (!args.ok()) return usageError("view", args.error());
  if (args.positional().size() > 1) return usageError("view", "expected at most one scene");
  if (!args.has("--headless"))
    return runError("view", "only --headless rendering is built (no windowing library such as GLFW was available "
                            "at configure time); add --headless --png DIR");
  long frames = -1, every = 0;
  double budget = 16.7, pixels = 1.0;
  if (!args.getInt("--frames", frames) || !args.getInt("--every", every) || !args.getDouble("--budget", budget) ||
      !args.getDouble("--pixels", pixels))
    return usageError("view", args.error());
  if (args.has("--frames") && (frames < 1 || frames > 1000000)) return usageError("view", "--frames must be in 1..1000000");
  if (args.has("--every") && every < 1) return usageError("view", "--every must be >= 1");
  if (args.has("--budget") && !(budget > 0.0 && budget < 1e6)) return usageError("view", "--budget must be in (0, 1e6)");
  if (!(pixels > 0.0 && pixels < 1e6)) return usageError("view", "--pixels must be > 0");
  const bool shadows = args.has("--shadows");
  double shadow_pixels = 4.0;
  long shadow_map = 2048;
  if (!args.getDouble("--shadow-pixels", shadow_pixels) || !args.getInt("--shadow-map", shadow_map))
    return usageError("view", args.error());
  if (!shadows && (args.has("--shadow-pixels") || args.has("--shadow-map")))
    return usageError("view", "--shadow-pixels and --shadow-map need --shadows");
  if (!(shadow_pixels > 0.0 && shadow_pixels < 1e6)) return usageError("view", "--shadow-pixels must be > 0");
  if (shadow_map < 16 || shadow_map > 8192) return usageError("view", "--shadow-map must be in 16..8192");
  long width = 640, height = 360;
  if (args.has("--size") && !parseSize(args.get("--size"), width, height))
    return usageError("view", "--size needs W H (or WxH), each 16..8192, got '" + args.get("--size") + "'");
  const std::string transition_name = args.get("--transitions", "none");
  Transitions transitions = Transitions::kNone;
  if (transition_name == "fade") transitions = Transitions::kFade;
  else if (transition_name == "morph") transitions = Transitions::kMorph;
  else if (transition_name != "none") return usageError("view", "--transitions must be none, fade or morph");
  double fade_ms = 250.0, morph_band = 0.3;
  if (!args.getDouble("--fade-ms", fade_ms) || !args.getDouble("--morph-band", morph_band)) return usageError("view", args.error());
  if (!(fade_ms >= 0.0) || !std::isfinite(fade_ms)) return usageError("view", "--fade-ms must be >= 0 and finite");
  if (!(morph_band > 0.0 && morph_band <= 1.0)) return usageError("view", "--morph-band must be in (0, 1]");
  if (shadows && transitions != Transitions::kNone)
    return usageError("view", "--shadows selects with views, which do not support --transitions");
  const bool distance = args.has("--distance");
  if (distance && args.has("--budget")) return usageError("view", "--distance and --budget exclude each other");
  ChainParams chain;
  std::string nesting_error;
  if (!parseNesting(args, chain, nesting_error)) return usageError("view", nesting_error);
  const bool chain_options = args.has("--nested") || args.has("--independent");
  const std::string png_dir = args.get("--png");
  if (!png_dir.empty() && !makeDir(png_dir)) return runError("view", png_dir + ": cannot create the screenshot folder");

  // the camera path: the replay's, or an orbit
  Replay replay;
  const bool has_replay = args.has("--replay");
  std::string scene_path = args.positional().empty() ? "" : args.positional()[0];
  if (has_replay) {
    if (Error e = readReplay(args.get("--replay"), replay); !e.ok()) return runError("view", e.message);
    if (replay.frames.empty()) return runError("view", args.get("--replay") + ": the replay has no frames");
    if (args.positional().empty()) scene_path = resolveReplayScene(args.get("--replay"), replay.header.scene);
    if (!args.has("--budget") && replay.header.has_budget) budget = replay.header.budget_ms;
  }
  ReplayScene scene;
  scene::SceneData scene_materials;
  if (Error e = loadViewScene(scene_path, scene, scene_materials, chain_options ? &chain : nullptr); !e.ok())
    return runError("view", e.message);
  if (Error e = validateReplayScene(scene, scene_path.empty() ? "demo scene" : scene_path); !e.ok()) return runError("view", e.message);
  if (scene.objectCount() == 0) return runError("view", scene_path + ": the scene has no objects");
  const Sphere bounds = sceneBounds(scene);
  if (!has_replay) makeCameraPath(bounds, CameraPathKind::kOrbit, frames > 0 ? static_cast<size_t>(frames) : 120, 30.0, replay);
  const size_t frame_count = frames > 0 ? std::min(static_cast<size_t>(frames), replay.frames.size()) : replay.frames.size();
  if (every == 0) every = std::max<long>(1, static_cast<long>(frame_count) / 8);

  gl::RendererConfig rc;
  rc.width_px = static_cast<uint32_t>(width);
  rc.height_px = static_cast<uint32_t>(height);
  rc.shadow_map_px = static_cast<uint32_t>(shadow_map);
  gl::Renderer renderer;
  bool unavailable = false;
  if (Error e = renderer.init(rc, &unavailable); !e.ok()) {
    std::fprintf(stderr, "scenelod view: %s\n", e.message.c_str());
    if (unavailable) {
      std::fprintf(stderr, "scenelod view: headless OpenGL cannot start on this machine (see docs/GL.md: Debian "
                           "packages libegl1 libegl-mesa0 libgl1-mesa-dri); exit code %d\n", kExitUnavailable);
      return kExitUnavailable;
    }
    return 1;
  }
  std::vector<gl::MaterialDesc> materials;
  std::vector<std::vector<int32_t>> group_materials;
  viewMaterials(scene_materials, scene.chains.size(), materials, group_materials);
  if (Error e = renderer.uploadMaterials({materials.data(), materials.size()}); !e.ok()) return runError("view", e.message);
  if (Error e = renderer.uploadChains(scene.chains, group_materials); !e.ok()) return runError("view", e.message);
  std::printf("%s\n", renderer.description().c_str());
  char mode_text[64];
  if (distance) std::snprintf(mode_text, sizeof(mode_text), "distance mode at X = %.3g", pixels);
  else std::snprintf(mode_text, sizeof(mode_text), "budget %.3g ms", budget);
  std::printf("scene %s: %zu objects, %zu chains, %zu level rows, %.1f MB on the GPU; %zu frames at %ldx%ld, %s\n",
              scene_path.empty() ? "builtin (demo)" : scene_path.c_str(), scene.objectCount(), scene.table.chainCount(),
              scene.table.cell_width.size(), renderer.gpuBytes() / 1e6, frame_count, width, height,
              mode_text);

  const size_t n = scene.objectCount();
  SelectorConfig sc;
  sc.max_object_count = n;
  sc.max_levels_per_chain = std::max<size_t>(1, scene.table.maxLevelsPerChain());
  sc.max_level_rows = std::max<size_t>(1, scene.table.cell_width.size());
  sc.max_view_groups = shadows ? 2 : 0;
  if (shadows && scene.table.maxLevelsPerChain() > kMaxViewLevels)
    return runError("view", "--shadows selects with views, which take chains of at most " + std::to_string(kMaxViewLevels) + " levels");
  SelectorContext* ctx = createSelectorContext(sc);
  if (!ctx) return runError("view", "cannot create the selector context (levels per chain above 64?)");
  std::vector<glm::vec3> centers;
  std::vector<float> radii, max_scales;
  std::vector<glm::mat4> node_world, object_world(n);
  std::vector<int8_t> levels(n, -1), group_levels(shadows ? 2 * n : 0, -1), previous_levels(n, -1);
  std::vector<float> morph(n, 0.0f), fade(n, 1.0f);
  const bool transitioning = transitions != Transitions::kNone;
  uint64_t sum_triangles = 0, sum_shadow_triangles = 0;
  Camera cam;
  cam.viewport_width_px = rc.width_px;
  cam.viewport_height_px = rc.height_px;
  cam.fov_y_rad = static_cast<float>(replay.header.fov_y_deg * 3.14159265358979 / 180.0);
  Sphere draw_bounds = bounds;  // the scene's bounds as moves leave them
  cam.near_plane = std::max(1e-4f, bounds.radius * 1e-3f);
  cam.far_plane = std::max(1.0f, bounds.radius * 100.0f);
  std::vector<double> rel_errors;
  double sum_pred = 0.0, sum_meas = 0.0;
  size_t pngs = 0;
  int rc_exit = 0;
  for (size_t f = 0; f < frame_count; ++f) {
    const ReplayFrame& rf = replay.frames[f];
    if (!rf.moves.empty())
      if (Error e = applyMoves(scene, rf.moves, "frame " + std::to_string(rf.frame)); !e.ok()) {
        rc_exit = runError("view", e.message);
        break;
      }
    if (f == 0 || !rf.moves.empty()) {
      computeWorldSpheres(scene, centers, radii, max_scales);
      computeNodeWorld(scene, node_world);
      draw_bounds = sceneBounds(scene);
      for (size_t o = 0; o < n; ++o) object_world[o] = node_world[static_cast<size_t>(scene.object_node[o])];
    }
    cam.eye = rf.eye;
    cam.target = rf.target;
    cam.up = rf.up;
    if (!cameraValid(cam)) {
      rc_exit = runError("view", "frame " + std::to_string(rf.frame) + ": degenerate camera (eye == target?)");
      break;
    }
    SelectionJob job;
    job.camera = &cam;
    job.params.mode = distance ? SelectionMode::kDistance : SelectionMode::kBudget;
    job.params.budget_ms = static_cast<float>(budget);
    job.params.pixels_per_cell = static_cast<float>(pixels);
    job.params.calibrate = !args.has("--no-calibrate");
    job.levels = scene.table.view();
    job.centers = {centers.data(), n};
    job.radii = {radii.data(), n};
    job.max_scales = {max_scales.data(), n};
    job.chains = {scene.object_chain.data(), n};
    job.importance = {scene.importance.data(), scene.importance.size()};
    job.must_draw = {scene.must_draw.data(), scene.must_draw.size()};
    job.levels_out = {levels.data(), n};
    if (transitioning) {
      // time between frames: the replay's time_s (the orbit is a 60 Hz one)
      double dt_ms = 1000.0 / 60.0;
      if (f == 0) dt_ms = 0.0;
      else if (has_replay) dt_ms = (rf.time_s - replay.frames[f - 1].time_s) * 1000.0;
      if (!(dt_ms >= 0.0) || !std::isfinite(dt_ms)) {
        rc_exit = runError("view", "frame " + std::to_string(rf.frame) + ": time_s goes back; fades need time to run forward");
        break;
      }
      job.params.transitions = transitions;
      job.params.dt_ms = static_cast<float>(dt_ms);
      job.params.fade_ms = static_cast<float>(fade_ms);
      job.params.morph_band = static_cast<float>(morph_band);
      job.morph_out = {morph.data(), n};
      job.previous_levels_out = {previous_levels.data(), n};
      job.fade_out = {fade.data(), n};
    }
    View views[2];
    if (shadows) {
      views[0].camera = cam;
      views[0].kind = ViewKind::kPrimary;
      views[0].group = 0;
      views[0].pixels_per_cell = static_cast<float>(pixels);
      views[1].camera = shadowCamera(bounds, replay.frames[0].up, rc.shadow_map_px);
      views[1].kind = ViewKind::kShadow;
      views[1].group = 1;
      views[1].pixels_per_cell = static_cast<float>(shadow_pixels);
      job.views = {views, 2};
      job.group_levels_out = {group_levels.data(), group_levels.size()};
    }
    SelectionStats stats;
    job.stats = &stats;
    job.context = ctx;
    if (!job.run()) {
      rc_exit = runError("view", "frame " + std::to_string(rf.frame) + ": the selection rejected its inputs");
      break;
    }
    // the drawing camera's depth planes tight around the scene (the selection's are not for a depth buffer)
    Camera draw_cam = cam;
    gl::fitDepthPlanes(draw_cam, draw_bounds);
    gl::FrameInput in;
    in.camera = &draw_cam;
    in.object_world = {object_world.data(), n};
    in.object_chain = {scene.object_chain.data(), n};
    in.levels = {levels.data(), n};
    if (transitioning) {
      in.morph = {morph.data(), n};
      in.previous_levels = {previous_levels.data(), n};
      in.fade = {fade.data(), n};
    }
    if (shadows) {
      in.shadow_camera = &views[1].camera;
      in.shadow_levels = {group_levels.data() + n, n};
    }
    gl::FrameResult fr;
    // the first draw of a level compiles shader variants and touches fresh buffers in the driver:
    // the first frame is drawn once unmeasured so that cost does not reach the calibration
    if (f == 0 && !renderer.drawFrame(in, &fr)) {
      rc_exit = runError("view", "the renderer refused the frame (shadow map incomplete?)");
      break;
    }
    renderer.drawFrame(in, &fr);
    sum_triangles += fr.triangles;
    sum_shadow_triangles += fr.shadow_triangles;
    reportFrameTime(ctx, stats.frame, static_cast<float>(fr.measured_ms));
    const double rel = fr.measured_ms > 0 ? std::fabs(stats.predicted_ms - fr.measured_ms) / fr.measured_ms : 0.0;
    if (f >= 30) {
      rel_errors.push_back(rel);
      sum_pred += stats.predicted_ms;
      sum_meas += fr.measured_ms;
    }
    if (!args.has("--quiet"))
      std::printf("frame %4zu: predicted %8.3f ms, measured %8.3f ms (%+6.1f %%), drawn %u, culled %u, dropped %u, "
                  "%llu triangles, %llu edges, %llu points, %u draws%s\n",
                  f, stats.predicted_ms, fr.measured_ms,
                  fr.measured_ms > 0 ? 100.0 * (stats.predicted_ms - fr.measured_ms) / fr.measured_ms : 0.0,
                  stats.drawn_count, stats.culled_count, stats.dropped_count,
                  static_cast<unsigned long long>(fr.triangles), static_cast<unsigned long long>(fr.edges),
                  static_cast<unsigned long long>(fr.points), fr.draw_calls,
                  transitioning ? (", fading " + std::to_string(stats.fading_count)).c_str() : "");
    if (!args.has("--quiet") && shadows)
      std::printf("            shadow map: %llu triangles, %u draws\n", static_cast<unsigned long long>(fr.shadow_triangles),
                  fr.shadow_draw_calls);
    if (!png_dir.empty() && (f % static_cast<size_t>(every) == 0 || f + 1 == frame_count)) {
      eval::Image img;
      char name[32];
      std::snprintf(name, sizeof(name), "/frame_%04zu.png", f);
      if (Error e = renderer.readPixels(img); !e.ok()) {
        rc_exit = runError("view", e.message);
        break;
      }
      if (Error e = eval::writePng(png_dir + name, img); !e.ok()) {
        rc_exit = runError("view", e.message);
        break;
      }
      ++pngs;
      if (shadows) {
        // what the shadow map holds: the shadow levels seen from the light (unmeasured)
        gl::FrameInput light_in = in;
        light_in.camera = &views[1].camera;
        light_in.levels = light_in.shadow_levels;
        light_in.shadow_camera = nullptr;
        light_in.shadow_levels = {};
        std::snprintf(name, sizeof(name), "/light_%04zu.png", f);
        gl::FrameResult unused;
        Error e = renderer.drawFrame(light_in, &unused) ? renderer.readPixels(img) : Error(Status::kUnsupported, "the light view was refused");
        if (e.ok()) e = eval::writePng(png_dir + name, img);
        if (!e.ok()) {
          rc_exit = runError("view", e.message);
          break;
        }
      }
    }
  }
  const CostCoefficients model = selectorCostModel(ctx);
  destroySelectorContext(ctx);
  if (rc_exit) return rc_exit;
  std::printf("cost model at the end: %.4g ms/frame + %.4g ms/object + %.4g ms/triangle + %.4g ms/vertex + "
              "%.4g ms/edge-or-point + %.4g ms/pixel\n", model.per_frame_ms, model.per_object_ms, model.per_triangle_ms,
              model.per_vertex_ms, model.per_line_point_ms, model.per_pixel_ms);
  if (shadows)
    std::printf("shadow map cost factors (learnt, on the shadow kind's scales 1, 0.25, 0.5): object %.3g, pixel %.3g, "
                "geometry %.3g\n", model.shadow_object_factor, model.shadow_pixel_factor, model.shadow_geometry_factor);
  if (pngs) std::printf("%zu screenshots in %s\n", pngs, png_dir.c_str());
  if (shadows && sum_triangles > 0)
    std::printf("shadow map at X = %g: %.0f triangles per frame against the camera's %.0f (%.0f %%)\n", shadow_pixels,
                double(sum_shadow_triangles) / double(frame_count), double(sum_triangles) / double(frame_count),
                100.0 * double(sum_shadow_triangles) / double(sum_triangles));
  if (rel_errors.empty()) {
    std::printf("fewer than 31 frames: no prediction error after the 30-frame warm-up\n");
  } else {
    double mean = 0.0;
    for (double r : rel_errors) mean += r;
    mean /= static_cast<double>(rel_errors.size());
    std::vector<double> sorted = rel_errors;
    std::sort(sorted.begin(), sorted.end());
    std::printf("after 30 warm-up frames (%zu frames): mean predicted %.3f ms, mean measured %.3f ms, mean relative "
                "prediction error %.1f %% (median %.1f %%)\n",
                rel_errors.size(), sum_pred / rel_errors.size(), sum_meas / rel_errors.size(), 100.0 * mean,
                100.0 * sorted[sorted.size() / 2]);
  }
  return 0;
}

const CommandRegistration kRegistration({"view", "render a scene headless with OpenGL; predicted vs measured frame time", kUsage, run});

}  // namespace
}  // namespace scenelod::tool
#endif
