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
#include "shader.h"

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
  // the ray direction and the world-space steps of one pixel across and down the image
  detail::PixelFootprint footprint() const { return {dir, right * pixelSize(), -up * pixelSize()}; }
  glm::vec3 rayOrigin(int x, int y) const {
    const float sx = ((static_cast<float>(x) + 0.5f) / static_cast<float>(width) * 2.0f - 1.0f) * half_w;
    const float sy = (1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(height) * 2.0f) * half_h;
    return origin0 + sx * right + sy * up;
  }
};

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
  if (Error e = validateMaterials(params.materials, "render"); !e.ok()) return e;
  const Sphere frame = params.frame.radius > 0.0f ? params.frame : boundingSphere(mesh);
  if (!(frame.radius > 0.0f)) return {Status::kInvalidMesh, "render: the mesh is empty or a single point, nothing to frame"};
  const OrthoCamera cam(params.view, frame, params.width, params.height);
  detail::EmbreeScene scene;
  if (Error e = scene.build(mesh, params.min_radius_px * cam.pixelSize()); !e.ok()) return e;
  const detail::Shader shader(mesh, params.materials);
  out = Image(params.width, params.height);
  const detail::PixelFootprint fp = cam.footprint();
  const uint8_t bg[3] = {detail::toSrgb8(params.background.x), detail::toSrgb8(params.background.y),
                         detail::toSrgb8(params.background.z)};
  tbb::parallel_for(0, params.height, [&](int y) {
    for (int x = 0; x < params.width; ++x) {
      uint8_t* px = out.pixel(x, y);
      const detail::RayHit h = scene.intersect(cam.rayOrigin(x, y), cam.dir, cam.t_max);
      if (!h.hit) {
        std::copy_n(bg, 3, px);
        continue;
      }
      shader.shade(h, fp, params.ambient, params.smooth, px);
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
  if (Error e = validateMaterials(params.original_materials, "original mesh"); !e.ok()) return e;
  if (Error e = validateMaterials(params.simplified_materials, "simplified mesh"); !e.ok()) return e;
  const Sphere frame = params.frame.radius > 0.0f ? params.frame : boundingSphere(original);
  if (!(frame.radius > 0.0f))
    return {Status::kInvalidMesh, "image error: the original is empty or a single point, nothing to frame"};
  const int res = params.resolution;
  // the pixel size is the same in every view: both BVHs are built once
  const float pixel = OrthoCamera(standardView(0), frame, res, res).pixelSize();
  detail::EmbreeScene a, b;
  if (Error e = a.build(original, params.min_radius_px * pixel); !e.ok()) return e;
  if (Error e = b.build(simplified, params.min_radius_px * pixel); !e.ok()) return e;

  const detail::Shader shade_a(original, params.original_materials), shade_b(simplified, params.simplified_materials);
  const RenderParams look;  // the default shading of renderMesh

  struct RowSum {
    size_t either = 0, one = 0, both = 0, color_off = 0;
    double angle_deg = 0.0, color_abs = 0.0;
  };
  std::vector<RowSum> rows(static_cast<size_t>(kStandardViewCount) * res);
  tbb::parallel_for(size_t(0), rows.size(), [&](size_t row) {
    const int view = static_cast<int>(row / res), y = static_cast<int>(row % res);
    const OrthoCamera cam(standardView(view), frame, res, res);
    const detail::PixelFootprint fp = cam.footprint();
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
        uint8_t pa[3], pb[3];
        shade_a.shade(ha, fp, look.ambient, look.smooth, pa);
        shade_b.shade(hb, fp, look.ambient, look.smooth, pb);
        int worst = 0;
        for (int c = 0; c < 3; ++c) {
          const int d = std::abs(int(pa[c]) - int(pb[c]));
          worst = std::max(worst, d);
          s.color_abs += d;
        }
        s.color_off += worst > kColorTolerance;
      }
    }
    rows[row] = s;
  });
  double angle = 0.0, color_abs = 0.0;
  for (const RowSum& s : rows) {  // fixed order: deterministic sums
    out.either_px += s.either;
    out.one_px += s.one;
    out.both_px += s.both;
    out.color_off_px += s.color_off;
    angle += s.angle_deg;
    color_abs += s.color_abs;
  }
  out.silhouette = out.either_px ? static_cast<double>(out.one_px) / static_cast<double>(out.either_px) : 0.0;
  out.normal_deg = out.both_px ? angle / static_cast<double>(out.both_px) : 0.0;
  out.color_off = out.both_px ? static_cast<double>(out.color_off_px) / static_cast<double>(out.both_px) : 0.0;
  out.color_mad = out.both_px ? color_abs / (3.0 * static_cast<double>(out.both_px)) : 0.0;
  return {};
}

int switchResolution(const Sphere& frame, float cell_width, float pixels_per_cell, int min_resolution,
                     int max_resolution) {
  const double px = 2.0 * frame.radius * pixels_per_cell / cell_width;
  if (!(px >= min_resolution)) return min_resolution;  // NaN too
  return px >= max_resolution ? max_resolution : static_cast<int>(std::lround(px));
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
    t.resolution = switchResolution(frame, w, params.pixels_per_cell, params.min_resolution, params.max_resolution);
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
