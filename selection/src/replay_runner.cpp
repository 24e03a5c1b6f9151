// Replay driver: the selector in a simulated frame loop, with a synthetic renderer whose true costs
// follow the same linear model (Funkhouser & Sequin 1993 §4.1) plus seeded Gaussian noise.
#include "scenelod/selection/replay_runner.h"

#include "scenelod/selection/replay_visibility.h"
#include "scenelod/lodcore/atomic_file.h"

#include <algorithm>

#include <glm/geometric.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

namespace scenelod::selection {

namespace {

// the world spheres reach the selector, whose preconditions want finite values (and squared
// distances that stay finite): a move or a transform large enough to overflow float is refused here, naming the object, instead of printing
// NaN costs into the log
Error checkWorldSpheres(const std::vector<glm::vec3>& centers, const std::vector<float>& radii,
                        const std::vector<float>& scales, const std::string& where) {
  const float limit = static_cast<float>(kMaxReplayCoordinate);
  for (size_t i = 0; i < centers.size(); ++i) {
    const glm::vec3& c = centers[i];
    if (!(std::fabs(c.x) <= limit && std::fabs(c.y) <= limit && std::fabs(c.z) <= limit && radii[i] <= limit &&
          std::isfinite(scales[i])))
      return Error(Status::kInvalidArgument, where + ": object " + std::to_string(i) +
                                                 "'s world bounding sphere is beyond +-1e18 or not finite (a move or transform too large)");
  }
  return Error();
}

// Box-Muller on mt19937_64 (fully specified), so the noise is the same with every standard library
class Gaussian {
 public:
  explicit Gaussian(uint64_t seed) : rng_(seed) {}
  double next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(rng_() >> 11) + 1.0) * (1.0 / 9007199254740993.0);
    const double u2 = static_cast<double>(rng_() >> 11) * (1.0 / 9007199254740992.0);
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(6.283185307179586 * u2);
    has_spare_ = true;
    return r * std::cos(6.283185307179586 * u2);
  }

 private:
  std::mt19937_64 rng_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// A frame's views as the selector takes them (empty for a frame with the one camera); returns the
// number of groups they make.
size_t frameViews(const ReplayFrame& f, std::vector<View>& views) {
  views.clear();
  std::vector<uint32_t> groups;
  for (const ReplayView& rv : f.views) {
    View v;
    v.camera = rv.camera;
    v.kind = rv.kind;
    v.group = rv.group;
    v.pixels_per_cell = rv.pixels_per_cell;
    v.lod_bias = rv.lod_bias;
    views.push_back(v);
    if (std::find(groups.begin(), groups.end(), rv.group) == groups.end()) groups.push_back(rv.group);
  }
  return groups.size();
}

struct ContextDeleter {
  SelectorContext* c;
  ~ContextDeleter() { destroySelectorContext(c); }
};

}  // namespace

CostCoefficients syntheticTrueCost() {
  CostCoefficients t;
  t.per_frame_ms = 0.8;
  t.per_object_ms = 3.0e-3;
  t.per_triangle_ms = 1.5e-6;
  t.per_vertex_ms = 0.4e-6;
  t.per_line_point_ms = 2.0e-6;
  t.per_pixel_ms = 0.6e-7;
  return t;
}

Error runReplayStream(const ReplayHeader& h, const ReplayFrameSource& next_frame, ReplayScene& scene,
                      const ReplayRunOptions& options, const ReplayLogSink& sink) {
  if (Error e = validateReplayScene(scene, scene.name); !e.ok()) return e;
  const size_t n = scene.objectCount();
  SelectorConfig cfg;
  cfg.max_object_count = std::max<size_t>(n, 1);
  cfg.max_levels_per_chain = std::max<size_t>(scene.table.maxLevelsPerChain(), 1);
  cfg.initial_cost = options.initial_cost;
  cfg.calibration = options.calibration;
  cfg.max_view_groups = h.version >= 2 ? kMaxViews : 0;
  ContextDeleter ctx{createSelectorContext(cfg)};
  if (!ctx.c) return Error(Status::kOutOfMemory, scene.name + ": cannot create the selector context");

  Camera cam;
  cam.viewport_width_px = h.viewport_width_px;
  cam.viewport_height_px = h.viewport_height_px;
  cam.fov_y_rad = static_cast<float>(h.fov_y_deg * 3.14159265358979 / 180.0);
  cam.near_plane = 0.05f;
  cam.far_plane = 1.0e6f;

  SelectionParams params = options.params;
  params.pixels_per_cell = static_cast<float>(h.pixels_per_cell);
  bool budget = h.has_budget;
  double budget_ms = h.budget_ms;
  if (options.override_budget) {
    budget = true;
    budget_ms = options.budget_ms;
  }
  if (options.force_distance) budget = false;
  params.mode = budget ? SelectionMode::kBudget : SelectionMode::kDistance;
  params.budget_ms = static_cast<float>(budget ? budget_ms : 1.0);

  std::vector<glm::vec3> centers;
  std::vector<float> radii, scales;
  computeWorldSpheres(scene, centers, radii, scales);
  if (Error e = checkWorldSpheres(centers, radii, scales, scene.name); !e.ok()) return e;
  const LevelTable table = scene.table.view();
  Gaussian noise(options.seed);

  ReplayFrame f;
  Error read_error;
  std::vector<View> views;
  std::vector<int8_t> group_levels;
  const bool transitions = params.transitions != Transitions::kNone;
  bool first_frame = true;
  double last_time_s = 0.0;
  while (next_frame(f, read_error)) {
    const std::string where = scene.name + ": replay frame " + std::to_string(f.frame);
    if (!f.moves.empty()) {
      if (Error e = applyMoves(scene, f.moves, where); !e.ok()) return e;
      computeWorldSpheres(scene, centers, radii, scales);
      if (Error e = checkWorldSpheres(centers, radii, scales, where); !e.ok()) return e;
    }
    cam.eye = f.eye;
    cam.target = f.target;
    cam.up = f.up;
    if (!f.views.empty() && options.visibility)
      return Error(Status::kInvalidArgument, where + ": visibility estimates are for one camera, not for a frame with views");
    if (f.views.empty() && !cameraValid(cam)) return Error(Status::kInvalidArgument, where + ": degenerate camera (eye equals target, or up along the view)");
    ReplayLogFrame out;
    out.levels.assign(n, -1);
    SelectionStats st;
    SelectionJob job;
    job.camera = &cam;
    job.params = params;
    job.levels = table;
    job.centers = Span<const glm::vec3>(centers.data(), n);
    job.radii = Span<const float>(radii.data(), n);
    job.max_scales = Span<const float>(scales.data(), n);
    job.chains = Span<const uint32_t>(scene.object_chain.data(), n);
    job.importance = Span<const float>(scene.importance.data(), n);
    job.must_draw = Span<const uint8_t>(scene.must_draw.data(), n);
    job.levels_out = Span<int8_t>(out.levels.data(), n);
    if (transitions) {
      const double dt_ms = first_frame ? 0.0 : (f.time_s - last_time_s) * 1000.0;
      if (!(dt_ms >= 0.0) || !std::isfinite(dt_ms))
        return Error(Status::kInvalidArgument, where + ": time_s goes back (" + std::to_string(f.time_s) + " after " +
                                                   std::to_string(last_time_s) + "): fades need time to run forward");
      job.params.dt_ms = static_cast<float>(dt_ms);
      out.has_transitions = true;
      out.morph.assign(n, 0.0f);
      out.fade.assign(n, 1.0f);
      out.previous_levels.assign(n, -1);
      job.morph_out = Span<float>(out.morph.data(), n);
      job.fade_out = Span<float>(out.fade.data(), n);
      job.previous_levels_out = Span<int8_t>(out.previous_levels.data(), n);
    }
    first_frame = false;
    last_time_s = f.time_s;
    job.stats = &st;
    job.context = ctx.c;
    const size_t groups = frameViews(f, views);
    group_levels.assign(groups * n, -1);
    job.views = Span<const View>(views.data(), views.size());
    job.group_levels_out = Span<int8_t>(group_levels.data(), group_levels.size());
    if (options.visibility)
      if (Error e = options.visibility->beforeSelect(scene, cam, f, job); !e.ok()) return Error(e.status, where + ": " + e.message);
    if (const char* e = job.error()) return Error(Status::kInvalidArgument, where + ": the selector refused the frame: " + e);
    job.run();
    if (options.visibility) options.visibility->afterSelect(job, out);
    for (size_t g = 0; g < groups; ++g)
      out.view_levels.emplace_back(group_levels.begin() + g * n, group_levels.begin() + (g + 1) * n);
    out.frame = f.frame;
    out.time_s = f.time_s;
    out.has_budget = budget;
    out.budget_ms = budget ? budget_ms : 0.0;
    out.predicted_ms = st.predicted_ms;
    out.switches = st.switch_count;
    out.drawn = st.drawn_count;
    out.culled = st.culled_count;
    out.dropped = st.dropped_count;
    out.fading = st.fading_count;
    if (st.dropped_count > 0 && f.views.empty()) {
      // the largest object left out: objects in view (with levels) not drawn
      const Frustum frustum = computeFrustum(cam);
      for (size_t i = 0; i < n; ++i) {
        if (out.levels[i] >= 0 || !sphereInFrustum(frustum, centers[i], radii[i])) continue;
        const uint32_t c = scene.object_chain[i];
        if (table.chain_level_offset[c + 1] == table.chain_level_offset[c]) continue;
        const float d = glm::length(centers[i] - cam.eye) - radii[i];
        const double r_px = radii[i] / pixelSize(cam, std::max(d, cam.near_plane));
        out.max_dropped_radius_px = std::max(out.max_dropped_radius_px, r_px);
      }
    }
    out.flags = st.flags;
    out.benefit = st.total_benefit;
    out.triangles = st.features.triangles + st.features.shadow_triangles;  // shadow views at their kind's scale
    if (f.has_measured) {
      out.has_measured = true;
      out.measured_from_file = true;
      out.measured_ms = f.measured_ms;
    } else if (options.synthetic_renderer) {
      const double truth = predictFrameMs(options.true_cost, st.features);
      out.has_measured = true;
      out.measured_ms = std::max(0.0, truth * (1.0 + options.noise * noise.next()));
    }
    if (out.has_measured) reportFrameTime(ctx.c, st.frame, static_cast<float>(out.measured_ms));
    if (Error e = sink(out); !e.ok()) return e;
  }
  return read_error;
}

Error runReplay(const Replay& replay, ReplayScene& scene, const ReplayRunOptions& options, std::vector<ReplayLogFrame>& log) {
  log.clear();
  size_t next = 0;
  auto frames = [&](ReplayFrame& f, Error&) {
    if (next == replay.frames.size()) return false;
    f = replay.frames[next++];
    return true;
  };
  auto keep = [&](const ReplayLogFrame& out) {
    log.push_back(out);
    return Error();
  };
  return runReplayStream(replay.header, frames, scene, options, keep);
}

std::string replayLogLine(const ReplayLogFrame& f) {
  std::ostringstream o;
  char buf[96];
  o << "{\"frame\": " << f.frame;
  std::snprintf(buf, sizeof(buf), ", \"time_s\": %.4f", f.time_s);
  o << buf;
  if (f.has_budget) std::snprintf(buf, sizeof(buf), ", \"budget_ms\": %.4f", f.budget_ms);
  else std::snprintf(buf, sizeof(buf), ", \"budget_ms\": null");
  o << buf;
  std::snprintf(buf, sizeof(buf), ", \"predicted_ms\": %.4f", f.predicted_ms);
  o << buf;
  if (f.has_measured) std::snprintf(buf, sizeof(buf), ", \"measured_ms\": %.4f", f.measured_ms);
  else std::snprintf(buf, sizeof(buf), ", \"measured_ms\": null");
  o << buf << ", \"levels\": [";
  for (size_t i = 0; i < f.levels.size(); ++i) o << (i ? "," : "") << static_cast<int>(f.levels[i]);
  o << "]";
  if (!f.view_levels.empty()) {
    o << ", \"view_levels\": [";
    for (size_t g = 0; g < f.view_levels.size(); ++g) {
      o << (g ? ", [" : "[");
      for (size_t i = 0; i < f.view_levels[g].size(); ++i) o << (i ? "," : "") << static_cast<int>(f.view_levels[g][i]);
      o << "]";
    }
    o << "]";
  }
  if (f.has_transitions) {
    o << ", \"morph\": [";
    for (size_t i = 0; i < f.morph.size(); ++i) {
      std::snprintf(buf, sizeof(buf), "%s%.3f", i ? "," : "", f.morph[i]);
      o << buf;
    }
    o << "], \"fade\": [";
    for (size_t i = 0; i < f.fade.size(); ++i) {
      std::snprintf(buf, sizeof(buf), "%s%.3f", i ? "," : "", f.fade[i]);
      o << buf;
    }
    o << "], \"previous_levels\": [";
    for (size_t i = 0; i < f.previous_levels.size(); ++i) o << (i ? "," : "") << static_cast<int>(f.previous_levels[i]);
    o << "], \"fading\": " << f.fading;
  }
  o << ", \"switches\": " << f.switches << ", \"drawn\": " << f.drawn << ", \"culled\": " << f.culled
    << ", \"dropped\": " << f.dropped << ", \"flags\": " << f.flags;
  std::snprintf(buf, sizeof(buf), ", \"triangles\": %.0f", f.triangles);
  o << buf;
  if (f.has_visibility) {
    o << ", \"visible\": [";
    for (size_t i = 0; i < f.visible.size(); ++i) {
      std::snprintf(buf, sizeof(buf), "%s%.2f", i ? "," : "", f.visible[i]);
      o << buf;
    }
    o << "], \"pick_object\": " << f.pick_object << ", \"hidden_count\": " << f.hidden_count;
    std::snprintf(buf, sizeof(buf), ", \"hidden_cost_ms\": %.4f, \"hidden_cost_without_ms\": %.4f", f.hidden_cost_ms,
                  f.hidden_cost_without_ms);
    o << buf;
    std::snprintf(buf, sizeof(buf), ", \"occlusion_saved_ms\": %.4f", f.occlusion_saved_ms);
    o << buf;
  }
  o << "}";
  return o.str();
}

Error writeReplayLog(const std::string& path, const std::vector<ReplayLogFrame>& log) {
  AtomicFile out;
  if (Error e = out.open(path); !e.ok()) return e;
  for (const ReplayLogFrame& f : log) out.write(replayLogLine(f) + "\n");
  return out.commit();
}

ReplaySummaryBuilder::ReplaySummaryBuilder(size_t warmup) { s_.warmup = warmup; }

void ReplaySummaryBuilder::add(const ReplayLogFrame& f) {
  const size_t i = s_.frames++;
  if (i == 0) {
    s_.objects = f.levels.size();
    first_time_s_ = f.time_s;
  }
  s_.duration_s = f.time_s - first_time_s_;
  if (f.flags & kFlagOverBudget) ++s_.over_budget_flagged;
  predicted_sum_ += f.predicted_ms;
  triangles_sum_ += f.triangles;
  benefit_sum_ += f.benefit;
  if (i > 0) switches_ += f.switches;  // the first frame's switches are the initial choice
  s_.drawn_object_frames += f.drawn;
  s_.dropped_object_frames += f.dropped;
  s_.max_dropped_radius_px = std::max(s_.max_dropped_radius_px, f.max_dropped_radius_px);
  for (int8_t l : f.levels) {
    const size_t bin = static_cast<size_t>(l + 1);
    if (s_.level_histogram.size() <= bin) s_.level_histogram.resize(bin + 1, 0);
    ++s_.level_histogram[bin];
  }
  if (f.has_visibility) {
    ++s_.visibility_frames;
    if (!f.visible.empty()) hidden_share_sum_ += static_cast<double>(f.hidden_count) / static_cast<double>(f.visible.size());
    saved_sum_ += f.occlusion_saved_ms;
    hidden_without_sum_ += f.hidden_cost_without_ms;
    if (f.pick_object >= 0) ++s_.pick_frames;
  }
  if (i < s_.warmup || !f.has_measured) return;
  ++measured_;
  measured_sum_ += f.measured_ms;
  if (f.measured_ms > 0.0) error_sum_ += std::fabs(f.predicted_ms - f.measured_ms) / f.measured_ms;
  if (f.has_budget) {
    ++s_.budget_frames;
    if (f.measured_ms <= 1.1 * f.budget_ms) ++s_.within_10_percent;
  }
}

ReplaySummary ReplaySummaryBuilder::summary() const {
  ReplaySummary s = s_;
  if (s.frames == 0) return s;
  const double frames = static_cast<double>(s.frames);
  s.mean_predicted_ms = predicted_sum_ / frames;
  s.mean_triangles = triangles_sum_ / frames;
  s.mean_benefit = benefit_sum_ / frames;
  if (measured_) {
    s.mean_measured_ms = measured_sum_ / static_cast<double>(measured_);
    s.mean_abs_prediction_error = error_sum_ / static_cast<double>(measured_);
  }
  if (s.visibility_frames) {
    const double k = static_cast<double>(s.visibility_frames);
    s.mean_hidden_share = hidden_share_sum_ / k;
    s.mean_occlusion_saved_ms = saved_sum_ / k;
    s.mean_hidden_cost_without_ms = hidden_without_sum_ / k;
  }
  if (s.duration_s > 0.0 && s.objects > 0)
    s.switches_per_object_per_second = static_cast<double>(switches_) / static_cast<double>(s.objects) / s.duration_s;
  return s;
}

ReplaySummary summarizeReplay(const std::vector<ReplayLogFrame>& log, size_t warmup) {
  ReplaySummaryBuilder b(warmup);
  for (const ReplayLogFrame& f : log) b.add(f);
  return b.summary();
}

}  // namespace scenelod::selection
