// Replay files: JSON lines (docs/REPLAY.md), read with nlohmann-json.
#include "scenelod/selection/replay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "scenelod/lodcore/json_limits.h"
#include "scenelod/lodcore/atomic_file.h"

namespace scenelod::selection {

namespace {

using json = nlohmann::json;

struct LineError {
  std::string message;
};

double number(const json& j, const char* key, bool required, double fallback, std::string& err) {
  auto it = j.find(key);
  if (it == j.end() || it->is_null()) {
    if (required) err = std::string("missing key \"") + key + "\"";
    return fallback;
  }
  if (!it->is_number()) {
    err = std::string("key \"") + key + "\" must be a number";
    return fallback;
  }
  const double v = it->get<double>();
  if (!std::isfinite(v)) err = std::string("key \"") + key + "\" is not finite";
  return v;
}

bool vec3(const json& j, const char* key, bool required, glm::vec3& out, std::string& err) {
  auto it = j.find(key);
  if (it == j.end()) {
    if (required) err = std::string("missing key \"") + key + "\"";
    return false;
  }
  if (!it->is_array() || it->size() != 3) {
    err = std::string("key \"") + key + "\" must be an array of 3 numbers";
    return false;
  }
  for (int i = 0; i < 3; ++i) {
    if (!(*it)[i].is_number() || !(std::fabs((*it)[i].get<double>()) <= kMaxReplayCoordinate)) {
      err = std::string("key \"") + key + "\" must be an array of 3 numbers within +-1e18";
      return false;
    }
    out[i] = (*it)[i].get<float>();
  }
  return true;
}

// the optional "viewport" [width, height] into w and h (unchanged when absent); false when malformed
bool viewport(const json& j, uint32_t& w, uint32_t& h) {
  auto vp = j.find("viewport");
  if (vp == j.end()) return true;
  int64_t width = 0, height = 0;
  if (!vp->is_array() || vp->size() != 2 || !jsonWholeNumber((*vp)[0], 1, 65536, width) ||
      !jsonWholeNumber((*vp)[1], 1, 65536, height))
    return false;
  w = static_cast<uint32_t>(width);
  h = static_cast<uint32_t>(height);
  return true;
}

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

}  // namespace

std::string resolveReplayScene(const std::string& replay_path, const std::string& scene) {
  if (scene.empty() || scene[0] == '/' || scene.rfind("builtin:", 0) == 0) return scene;
  const size_t slash = replay_path.find_last_of('/');
  if (slash == std::string::npos) return scene;
  return replay_path.substr(0, slash + 1) + scene;
}

namespace {

// the header line's keys into `h`; an empty string when they are valid, else what is wrong
std::string parseHeader(const json& j, ReplayHeader& h) {
  std::string err;
  auto v = j.find("scenelod_replay");
  if (v == j.end()) return "the first line must be the header with \"scenelod_replay\"";
  int64_t version = 0;
  if (!jsonWholeNumber(*v, 1, 2, version)) return "unsupported replay version (this reader knows versions 1 and 2)";
  h.version = static_cast<int>(version);
  auto s = j.find("scene");
  if (s == j.end() || !s->is_string() || s->get<std::string>().empty()) return "missing key \"scene\" (a path)";
  h.scene = s->get<std::string>();
  if (!viewport(j, h.viewport_width_px, h.viewport_height_px))
    return "\"viewport\" must be [width, height] in whole pixels, 1..65536";
  h.fov_y_deg = number(j, "fov_y_deg", false, 60.0, err);
  if (!err.empty()) return err;
  if (!(h.fov_y_deg > 0.0 && h.fov_y_deg < 180.0)) return "\"fov_y_deg\" must be in (0, 180)";
  auto b = j.find("budget_ms");
  if (b != j.end() && !b->is_null()) {
    h.budget_ms = number(j, "budget_ms", true, 0.0, err);
    if (!err.empty()) return err;
    if (!(h.budget_ms > 0.0)) return "\"budget_ms\" must be > 0 (or null for distance mode)";
    h.has_budget = true;
  }
  h.pixels_per_cell = number(j, "pixels_per_cell", false, 1.0, err);
  if (!err.empty()) return err;
  if (!(h.pixels_per_cell > 0.0)) return "\"pixels_per_cell\" must be > 0";
  return {};
}

const char* const kViewKindNames[kViewKindCount] = {"primary", "shadow", "eye", "secondary"};

// one entry of a frame's "views" into `v` (camera defaults from the header); empty when valid
std::string parseView(const json& j, const ReplayHeader& h, ReplayView& v) {
  if (!j.is_object()) return "each view must be an object";
  std::string err;
  auto k = j.find("kind");
  if (k == j.end() || !k->is_string()) return "a view needs \"kind\": \"primary\", \"shadow\", \"eye\" or \"secondary\"";
  const auto* name = std::find(kViewKindNames, kViewKindNames + kViewKindCount, k->get<std::string>());
  if (name == kViewKindNames + kViewKindCount) return "unknown view kind \"" + k->get<std::string>() + "\"";
  v.kind = static_cast<ViewKind>(name - kViewKindNames);
  auto g = j.find("group");
  int64_t group = 0;
  if (g == j.end() || !jsonWholeNumber(*g, 0, UINT32_MAX, group)) return "a view needs \"group\": a whole number";
  v.group = static_cast<uint32_t>(group);
  Camera& c = v.camera;
  vec3(j, "eye", true, c.eye, err);
  if (err.empty()) vec3(j, "target", true, c.target, err);
  if (err.empty()) vec3(j, "up", false, c.up, err);
  if (!err.empty()) return "view: " + err;
  const bool has_fov = j.contains("fov_y_deg"), has_ortho = j.contains("ortho_height");
  if (has_fov == has_ortho) return "a view needs exactly one of \"fov_y_deg\" and \"ortho_height\"";
  if (has_fov) c.fov_y_rad = static_cast<float>(number(j, "fov_y_deg", true, 60.0, err) * 3.14159265358979 / 180.0);
  if (has_ortho) {
    c.projection = Projection::kOrthographic;
    c.ortho_height = static_cast<float>(number(j, "ortho_height", true, 1.0, err));
  }
  c.near_plane = static_cast<float>(number(j, "near", false, 0.05, err));
  if (err.empty()) c.far_plane = static_cast<float>(number(j, "far", false, 1.0e6, err));
  if (err.empty()) v.pixels_per_cell = static_cast<float>(number(j, "pixels_per_cell", false, h.pixels_per_cell, err));
  if (err.empty()) v.lod_bias = static_cast<float>(number(j, "lod_bias", false, 1.0, err));
  if (!err.empty()) return "view: " + err;
  c.viewport_width_px = h.viewport_width_px;
  c.viewport_height_px = h.viewport_height_px;
  if (!viewport(j, c.viewport_width_px, c.viewport_height_px))
    return "a view's \"viewport\" must be [width, height] in whole pixels, 1..65536";
  if (!cameraValid(c)) return "a view's camera is degenerate (eye = target, up along the view, fov, near/far or ortho_height)";
  if (!(v.pixels_per_cell > 0.0f) || !(v.lod_bias > 0.0f)) return "a view's pixels_per_cell and lod_bias must be > 0";
  return {};
}

// a frame's "views" into f.views; empty when valid
std::string parseViews(const json& views, const ReplayHeader& h, ReplayFrame& f) {
  if (h.version < 2) return "\"views\" needs a version 2 replay (\"scenelod_replay\": 2)";
  if (!views.is_array() || views.empty() || views.size() > kMaxViews) return "\"views\" must be a list of 1 to 8 views";
  for (const json& e : views) {
    ReplayView v;
    if (std::string err = parseView(e, h, v); !err.empty()) return err;
    f.views.push_back(v);
  }
  return {};
}

// a frame line's keys into `f`; an empty string when they are valid, else what is wrong
std::string parseFrame(const json& j, const ReplayHeader& h, ReplayFrame& f) {
  std::string err;
  auto fr = j.find("frame");
  if (fr == j.end()) return "missing key \"frame\"";
  int64_t frame = 0;
  if (!jsonWholeNumber(*fr, 0, int64_t(1) << 53, frame)) return "\"frame\" must be a whole number from 0 to 2^53";
  f.frame = static_cast<uint64_t>(frame);
  f.time_s = number(j, "time_s", false, 0.0, err);
  if (!err.empty()) return err;
  auto views = j.find("views");
  if (views != j.end() && !views->is_null())
    if (std::string verr = parseViews(*views, h, f); !verr.empty()) return verr;
  // a frame with views may leave out the single camera
  const bool camera_required = f.views.empty();
  vec3(j, "eye", camera_required, f.eye, err);
  if (!err.empty()) return err;
  vec3(j, "target", camera_required, f.target, err);
  if (!err.empty()) return err;
  vec3(j, "up", false, f.up, err);
  if (!err.empty()) return err;
  auto m = j.find("measured_ms");
  if (m != j.end() && !m->is_null()) {
    f.measured_ms = number(j, "measured_ms", true, 0.0, err);
    if (!err.empty()) return err;
    if (f.measured_ms < 0.0) return "\"measured_ms\" must be >= 0";
    f.has_measured = true;
  }
  auto p = j.find("pick");
  if (p != j.end() && !p->is_null()) {
    if (!p->is_array() || p->size() != 2 || !(*p)[0].is_number() || !(*p)[1].is_number())
      return "\"pick\" must be [x, y] in pixels";
    f.has_pick = true;
    f.pick_px[0] = (*p)[0].get<float>();
    f.pick_px[1] = (*p)[1].get<float>();
  }
  auto mv = j.find("moves");
  if (mv != j.end() && !mv->is_null()) {
    if (!mv->is_array()) return "\"moves\" must be an array of [object, tx, ty, tz, qx, qy, qz, qw, s]";
    for (const json& e : *mv) {
      if (!e.is_array() || e.size() != 9) return "each move must be [object, tx, ty, tz, qx, qy, qz, qw, s]";
      for (const json& x : e)
        if (!x.is_number() || !(std::fabs(x.get<double>()) <= kMaxReplayCoordinate))
          return "a move holds a value that is not a number within +-1e18";
      int64_t object = 0;
      if (!jsonWholeNumber(e[0], 0, UINT32_MAX - 1, object))
        return "a move's object must be a whole number from 0 to 4294967294";
      ReplayMove rm;
      rm.object = static_cast<uint32_t>(object);
      rm.translation = glm::vec3(e[1].get<float>(), e[2].get<float>(), e[3].get<float>());
      rm.rotation = glm::quat(e[7].get<float>(), e[4].get<float>(), e[5].get<float>(), e[6].get<float>());
      rm.scale = e[8].get<float>();
      if (!(rm.scale > 0.0f)) return "a move's scale must be > 0";
      const float qn = glm::dot(rm.rotation, rm.rotation);
      if (!(qn > 1e-12f)) return "a move's rotation quaternion has zero length";
      f.moves.push_back(rm);
    }
  }
  return {};
}

}  // namespace

namespace {

// one line of a replay as a JSON object; an empty string when it is one, else what is wrong
std::string parseObject(const std::string& line, json& out) {
  if (jsonNestingDepth(line.data(), line.size()) > kMaxJsonNesting)
    return "JSON nested deeper than " + std::to_string(kMaxJsonNesting) + " levels";
  out = json::parse(line, nullptr, false);
  if (out.is_discarded()) return "not valid JSON";
  if (!out.is_object()) return "expected a JSON object";
  return {};
}

}  // namespace

Error ReplayReader::open(const std::string& path) {
  path_ = path;
  line_no_ = 0;
  frames_read_ = 0;
  header_ = ReplayHeader();
  in_.close();
  in_.clear();
  in_.open(path);
  if (!in_) return Error(Status::kIoError, path + ": cannot open replay file");
  std::string line;
  if (!nextLine(line)) return Error(Status::kParseError, path + ": empty replay (no header line)");
  json j;
  std::string err = parseObject(line, j);
  if (err.empty()) err = parseHeader(j, header_);
  return err.empty() ? Error() : lineError(err);
}

bool ReplayReader::next(ReplayFrame& frame, Error& error) {
  error = Error();
  std::string line;
  if (!nextLine(line)) return false;
  json j;
  frame = ReplayFrame();
  std::string err = parseObject(line, j);
  if (err.empty()) err = parseFrame(j, header_, frame);
  if (err.empty() && frames_read_ > 0 && frame.frame <= last_frame_) err = "frames must be in increasing order";
  if (!err.empty()) {
    error = lineError(err);
    return false;
  }
  last_frame_ = frame.frame;
  ++frames_read_;
  return true;
}

Error ReplayReader::lineError(const std::string& what) const {
  return Error(Status::kParseError, path_ + ":" + std::to_string(line_no_) + ": " + what);
}

bool ReplayReader::nextLine(std::string& line) {
  while (std::getline(in_, line)) {
    ++line_no_;
    if (line.find_first_not_of(" \t\r") != std::string::npos) return true;
  }
  return false;
}

static Error readReplayImpl(const std::string& path, Replay& out) {
  out = Replay();
  ReplayReader reader;
  if (Error e = reader.open(path); !e.ok()) return e;
  out.header = reader.header();
  ReplayFrame f;
  Error e;
  while (reader.next(f, e)) out.frames.push_back(std::move(f));
  return e;
}

namespace {

std::string v3(const glm::vec3& v) { return "[" + fmt(v.x) + ", " + fmt(v.y) + ", " + fmt(v.z) + "]"; }

// a frame's "views" as JSON
std::string viewsText(const std::vector<ReplayView>& views) {
  std::ostringstream o;
  o << "[";
  for (size_t i = 0; i < views.size(); ++i) {
    const ReplayView& v = views[i];
    const Camera& c = v.camera;
    o << (i ? ", " : "") << "{\"kind\": \"" << kViewKindNames[static_cast<size_t>(v.kind)] << "\", \"group\": " << v.group
      << ", \"eye\": " << v3(c.eye) << ", \"target\": " << v3(c.target) << ", \"up\": " << v3(c.up);
    if (c.projection == Projection::kOrthographic)
      o << ", \"ortho_height\": " << fmt(c.ortho_height);
    else
      o << ", \"fov_y_deg\": " << fmt(static_cast<double>(c.fov_y_rad) * 180.0 / 3.14159265358979);
    o << ", \"near\": " << fmt(c.near_plane) << ", \"far\": " << fmt(c.far_plane) << ", \"viewport\": ["
      << c.viewport_width_px << ", " << c.viewport_height_px << "], \"pixels_per_cell\": " << fmt(v.pixels_per_cell)
      << ", \"lod_bias\": " << fmt(v.lod_bias) << "}";
  }
  o << "]";
  return o.str();
}

}  // namespace

static Error writeReplayImpl(const std::string& path, const Replay& r) {
  std::ostringstream out;
  const ReplayHeader& h = r.header;
  const bool with_views = std::any_of(r.frames.begin(), r.frames.end(), [](const ReplayFrame& f) { return !f.views.empty(); });
  std::ostringstream s;
  s << "{\"scenelod_replay\": " << (with_views ? 2 : 1) << ", \"scene\": " << json(h.scene).dump() << ", \"viewport\": [" << h.viewport_width_px
    << ", " << h.viewport_height_px << "], \"fov_y_deg\": " << fmt(h.fov_y_deg)
    << ", \"budget_ms\": " << (h.has_budget ? fmt(h.budget_ms) : std::string("null"))
    << ", \"pixels_per_cell\": " << fmt(h.pixels_per_cell) << "}\n";
  out << s.str();
  for (const ReplayFrame& f : r.frames) {
    std::ostringstream l;
    l << "{\"frame\": " << f.frame << ", \"time_s\": " << fmt(f.time_s) << ", \"eye\": " << v3(f.eye)
      << ", \"target\": " << v3(f.target) << ", \"up\": " << v3(f.up);
    if (!f.views.empty()) l << ", \"views\": " << viewsText(f.views);
    if (f.has_measured) l << ", \"measured_ms\": " << fmt(f.measured_ms);
    if (f.has_pick) l << ", \"pick\": [" << fmt(f.pick_px[0]) << ", " << fmt(f.pick_px[1]) << "]";
    if (!f.moves.empty()) {
      l << ", \"moves\": [";
      for (size_t i = 0; i < f.moves.size(); ++i) {
        const ReplayMove& m = f.moves[i];
        l << (i ? ", " : "") << "[" << m.object << ", " << fmt(m.translation.x) << ", " << fmt(m.translation.y) << ", "
          << fmt(m.translation.z) << ", " << fmt(m.rotation.x) << ", " << fmt(m.rotation.y) << ", " << fmt(m.rotation.z)
          << ", " << fmt(m.rotation.w) << ", " << fmt(m.scale) << "]";
      }
      l << "]";
    }
    l << "}\n";
    out << l.str();
  }
  const std::string text = out.str();
  return writeFileAtomic(path, text.data(), text.size());
}

Error readReplay(const std::string& path, Replay& out) {
  try {
    return readReplayImpl(path, out);
  } catch (const std::exception& e) {
    return Error(Status::kParseError, path + ": " + e.what());
  }
}

Error writeReplay(const std::string& path, const Replay& replay) {
  try {
    return writeReplayImpl(path, replay);
  } catch (const std::exception& e) {
    return Error(Status::kIoError, path + ": " + e.what());
  }
}

}  // namespace scenelod::selection
