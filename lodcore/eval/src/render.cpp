// Orthographic Embree ray casts: pictures, image error over 14 fixed views, and popping between
// consecutive levels at their switch distance (Low & Tan 1997 §3.3.2 dynamic normals for thick
// edges; switch rule cell width <= X pixels from the design's selection).
#include "scenelod/eval/render.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "embree_scene.h"

namespace scenelod::eval {

namespace {

constexpr double kRadToDeg = 57.29577951308232;

// an orthographic camera: pixel (x, y) -> ray origin, all rays along `dir`
struct OrthoCamera {
  glm::vec3 origin0, right, up, dir;
  float half_w, half_h, t_max;
  int width, height;

  OrthoCamera(const View& v, const Sphere& frame, int w, int h) : width(w), height(h) {
    const glm::vec3 from = glm::normalize(v.from);
    dir = -from;
    right = glm::normalize(glm::cross(dir, v.up));
    up = glm::cross(right, dir);
    const float r = frame.radius > 0.0f ? frame.radius : 1.0f;
    // fit the sphere into the smaller side
    half_w = w >= h ? r * static_cast<float>(w) / static_cast<float>(h) : r;
    half_h = h >= w ? r * static_cast<float>(h) / static_cast<float>(w) : r;
    origin0 = frame.center + from * (4.0f * r);
    t_max = 8.0f * r;
  }
  float pixelSize() const { return 2.0f * half_h / static_cast<float>(height); }
  glm::vec3 rayOrigin(int x, int y) const {
    const float sx = ((static_cast<float>(x) + 0.5f) / static_cast<float>(width) * 2.0f - 1.0f) * half_w;
    const float sy = (1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(height) * 2.0f) * half_h;
    return origin0 + sx * right + sy * up;
  }
};

uint8_t toSrgb8(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(s * 255.0f));
}

}  // namespace

View standardView(int index) {
  View v;
  if (index < 0 || index >= kStandardViewCount) index = 0;
  if (index < 6) {
    glm::vec3 f(0.0f);
    f[index / 2] = (index % 2) ? -1.0f : 1.0f;
    v.from = f;
    v.up = index / 2 == 1 ? glm::vec3(0.0f, 0.0f, -1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
    if (index == 3) v.up = glm::vec3(0.0f, 0.0f, 1.0f);
  } else {
    const int bits = index - 6;
    v.from = glm::normalize(glm::vec3((bits & 1) ? -1.0f : 1.0f, (bits & 2) ? -1.0f : 1.0f, (bits & 4) ? -1.0f : 1.0f));
    v.up = glm::vec3(0.0f, 1.0f, 0.0f);
  }
  return v;
}

Sphere boundingSphere(const Mesh& mesh) {
  Sphere s;
  if (mesh.positions.empty()) return s;
  s.center = computeBounds(mesh).center();
  float r2 = 0.0f;
  for (const auto& p : mesh.positions) {
    const glm::vec3 d = p - s.center;
    r2 = std::max(r2, glm::dot(d, d));
  }
  s.radius = std::sqrt(r2);
  return s;
}

Error renderMesh(const Mesh& mesh, const RenderParams& params, Image& out) {
  if (params.width < 1 || params.height < 1 || params.width > 16384 || params.height > 16384)
    return {Status::kInvalidArgument, "render: image size " + std::to_string(params.width) + "x" +
                                          std::to_string(params.height) + " is not in [1, 16384]"};
  if (Error e = validateMesh(mesh, "render"); !e.ok()) return e;
  const Sphere frame = params.frame.radius > 0.0f ? params.frame : boundingSphere(mesh);
  if (!(frame.radius > 0.0f)) return {Status::kInvalidMesh, "render: the mesh is empty or a single point, nothing to frame"};
  const OrthoCamera cam(params.view, frame, params.width, params.height);
  detail::EmbreeScene scene;
  if (Error e = scene.build(mesh, params.min_radius_px * cam.pixelSize()); !e.ok()) return e;
  out = Image(params.width, params.height);
  const uint8_t bg[3] = {toSrgb8(params.background.x), toSrgb8(params.background.y), toSrgb8(params.background.z)};
  tbb::parallel_for(0, params.height, [&](int y) {
    for (int x = 0; x < params.width; ++x) {
      uint8_t* px = out.pixel(x, y);
      const detail::RayHit h = scene.intersect(cam.rayOrigin(x, y), cam.dir, cam.t_max);
      if (!h.hit) {
        std::copy_n(bg, 3, px);
        continue;
      }
      const glm::vec3 n = params.smooth ? h.shading : h.normal;
      const float lambert = std::max(0.0f, glm::dot(n, -cam.dir));
      const glm::vec3 c = h.color * (params.ambient + (1.0f - params.ambient) * lambert);
      px[0] = toSrgb8(c.x);
      px[1] = toSrgb8(c.y);
      px[2] = toSrgb8(c.z);
    }
  });
  return {};
}

Error measureImageError(const Mesh& original, const Mesh& simplified, const ImageErrorParams& params,
                        ImageErrorResult& out) {
  out = ImageErrorResult{};
  if (params.resolution < 1 || params.resolution > 8192)
    return {Status::kInvalidArgument, "image error: resolution " + std::to_string(params.resolution) + " is not in [1, 8192]"};
  if (Error e = validateMesh(original, "original mesh"); !e.ok()) return e;
  if (Error e = validateMesh(simplified, "simplified mesh"); !e.ok()) return e;
  const Sphere frame = params.frame.radius > 0.0f ? params.frame : boundingSphere(original);
  if (!(frame.radius > 0.0f))
    return {Status::kInvalidMesh, "image error: the original is empty or a single point, nothing to frame"};
  const int res = params.resolution;
  // the pixel size is the same in every view: both BVHs are built once
  const float pixel = OrthoCamera(standardView(0), frame, res, res).pixelSize();
  detail::EmbreeScene a, b;
  if (Error e = a.build(original, params.min_radius_px * pixel); !e.ok()) return e;
  if (Error e = b.build(simplified, params.min_radius_px * pixel); !e.ok()) return e;

  struct RowSum {
    size_t either = 0, one = 0, both = 0;
    double angle_deg = 0.0;
  };
  std::vector<RowSum> rows(static_cast<size_t>(kStandardViewCount) * res);
  tbb::parallel_for(size_t(0), rows.size(), [&](size_t row) {
    const int view = static_cast<int>(row / res), y = static_cast<int>(row % res);
    const OrthoCamera cam(standardView(view), frame, res, res);
    RowSum s;
    for (int x = 0; x < res; ++x) {
      const glm::vec3 o = cam.rayOrigin(x, y);
      const detail::RayHit ha = a.intersect(o, cam.dir, cam.t_max);
      const detail::RayHit hb = b.intersect(o, cam.dir, cam.t_max);
      if (ha.hit || hb.hit) ++s.either;
      if (ha.hit != hb.hit) ++s.one;
      if (ha.hit && hb.hit) {
        ++s.both;
        // atan2 keeps small angles accurate where acos of a float dot product does not
        const glm::dvec3 na(ha.normal), nb(hb.normal);
        s.angle_deg += std::atan2(glm::length(glm::cross(na, nb)), glm::dot(na, nb)) * kRadToDeg;
      }
    }
    rows[row] = s;
  });
  double angle = 0.0;
  for (const RowSum& s : rows) {  // fixed order: deterministic sums
    out.either_px += s.either;
    out.one_px += s.one;
    out.both_px += s.both;
    angle += s.angle_deg;
  }
  out.silhouette = out.either_px ? static_cast<double>(out.one_px) / static_cast<double>(out.either_px) : 0.0;
  out.normal_deg = out.both_px ? angle / static_cast<double>(out.both_px) : 0.0;
  return {};
}

Error measurePopping(const LodChain& chain, const PoppingParams& params, std::vector<PoppingTransition>& out) {
  out.clear();
  if (chain.levelCount() < 2) return {Status::kInvalidArgument, "popping: the chain has fewer than 2 levels"};
  if (!(params.pixels_per_cell > 0.0f))
    return {Status::kInvalidArgument, "popping: pixels per cell (X) must be > 0"};
  const Sphere frame = boundingSphere(chain.levels[0].mesh);
  if (!(frame.radius > 0.0f)) return {Status::kInvalidMesh, "popping: level 0 is empty, nothing to frame"};
  for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
    const float w = chain.levels[k + 1].cell_width;
    if (!(w > 0.0f) || !std::isfinite(w))
      return {Status::kInvalidArgument, "popping: level " + std::to_string(k + 1) + " has no positive cell width"};
    PoppingTransition t;
    t.from_level = k;
    t.to_level = k + 1;
    t.cell_width = w;
    const double px = 2.0 * frame.radius * params.pixels_per_cell / w;
    t.resolution = static_cast<int>(std::clamp(std::lround(px), static_cast<long>(params.min_resolution),
                                               static_cast<long>(params.max_resolution)));
    ImageErrorParams ip;
    ip.resolution = t.resolution;
    ip.frame = frame;
    ip.min_radius_px = params.min_radius_px;
    if (Error e = measureImageError(chain.levels[k].mesh, chain.levels[k + 1].mesh, ip, t.error); !e.ok()) {
      e.message = "popping, levels " + std::to_string(k) + "-" + std::to_string(k + 1) + ": " + e.message;
      return e;
    }
    out.push_back(t);
  }
  return {};
}

}  // namespace scenelod::eval
