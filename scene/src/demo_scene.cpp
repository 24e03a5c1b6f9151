// The demo scene generator: simple CAD polyhedra (the test objects of Low & Tan 1997, "Model
// simplification using vertex-clustering": mechanical parts with thin features) and bunny instances.
#include "scenelod/scene/demo_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <stb_image_write.h>

#include "scenelod/lodcore/obj_io.h"

namespace scenelod::scene {

namespace {

constexpr float kPi = 3.14159265358979f;

// flat-shaded faces get their own vertices; smooth surfaces share them
struct Builder {
  Mesh m;
  glm::vec3 color{0.8f};

  uint32_t vertex(const glm::vec3& p, const glm::vec3& n) {
    m.positions.push_back(p);
    m.normals.push_back(n);
    m.colors.push_back(color);
    return static_cast<uint32_t>(m.positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) { m.triangles.insert(m.triangles.end(), {a, b, c}); }
  // a flat convex polygon, counter-clockwise seen from its normal side
  void polygon(const std::vector<glm::vec3>& p) {
    const glm::vec3 n = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
    const uint32_t first = vertex(p[0], n);
    for (size_t i = 1; i < p.size(); ++i) vertex(p[i], n);
    for (uint32_t i = 1; i + 1 < p.size(); ++i) tri(first, first + i, first + i + 1);
  }
  // a flat polygon that is star-shaped around `centre` (gear faces): a fan from the centre
  void starPolygon(const glm::vec3& centre, const std::vector<glm::vec3>& ring, const glm::vec3& n) {
    const uint32_t c = vertex(centre, n);
    const uint32_t first = vertex(ring[0], n);
    for (size_t i = 1; i < ring.size(); ++i) vertex(ring[i], n);
    const uint32_t k = static_cast<uint32_t>(ring.size());
    for (uint32_t i = 0; i < k; ++i) {
      const uint32_t a = first + i, b = first + (i + 1) % k;
      if (glm::dot(glm::cross(ring[(i + 1) % k] - ring[i], centre - ring[i]), n) >= 0) tri(a, b, c);
      else tri(b, a, c);
    }
  }
  // extrude a closed profile (in xz, counter-clockwise seen from +y) from y0 to y1, flat side quads
  void extrudeSides(const std::vector<glm::vec2>& profile, float y0, float y1, bool smooth) {
    const size_t k = profile.size();
    if (smooth) {
      const uint32_t base = static_cast<uint32_t>(m.positions.size());
      for (size_t i = 0; i < k; ++i) {
        const glm::vec3 n = glm::normalize(glm::vec3(profile[i].x, 0, profile[i].y));
        vertex({profile[i].x, y0, profile[i].y}, n);
        vertex({profile[i].x, y1, profile[i].y}, n);
      }
      for (uint32_t i = 0; i < k; ++i) {
        const uint32_t j = (i + 1) % static_cast<uint32_t>(k);
        const uint32_t a = base + 2 * i, b = base + 2 * i + 1, c = base + 2 * j, d = base + 2 * j + 1;
        tri(a, d, c);
        tri(a, b, d);
      }
      return;
    }
    for (size_t i = 0; i < k; ++i) {
      const glm::vec2 p = profile[i], q = profile[(i + 1) % k];
      polygon({{p.x, y0, p.y}, {p.x, y1, p.y}, {q.x, y1, q.y}, {q.x, y0, q.y}});
    }
  }
  void caps(const std::vector<glm::vec2>& profile, float y0, float y1) {
    std::vector<glm::vec3> top, bottom;
    for (const glm::vec2& p : profile) top.push_back({p.x, y1, p.y});
    for (auto it = profile.rbegin(); it != profile.rend(); ++it) bottom.push_back({it->x, y0, it->y});
    starPolygon({0, y1, 0}, top, {0, 1, 0});
    starPolygon({0, y0, 0}, bottom, {0, -1, 0});
  }
  void transformFrom(size_t first_vertex, const glm::mat4& t) {
    const glm::mat3 nt = glm::transpose(glm::inverse(glm::mat3(t)));
    for (size_t v = first_vertex; v < m.positions.size(); ++v) {
      m.positions[v] = glm::vec3(t * glm::vec4(m.positions[v], 1.0f));
      m.normals[v] = glm::normalize(nt * m.normals[v]);
    }
  }
};

// profiles as (x, z), turning from +x towards +z: extrudeSides then winds the walls outwards
std::vector<glm::vec2> circle(float r, size_t n) {
  std::vector<glm::vec2> p(n);
  for (size_t i = 0; i < n; ++i) {
    const float a = 2.0f * kPi * float(i) / float(n);
    p[i] = {r * std::cos(a), r * std::sin(a)};
  }
  return p;
}

std::vector<glm::vec2> gearProfile(size_t teeth, float r_root, float r_tip) {
  std::vector<glm::vec2> p;
  for (size_t t = 0; t < teeth; ++t) {
    // root, rise, tip, tip, fall: trapezoidal teeth
    const float a0 = 2.0f * kPi * float(t) / float(teeth), step = 2.0f * kPi / float(teeth);
    const float angles[4] = {a0, a0 + step * 0.25f, a0 + step * 0.45f, a0 + step * 0.7f};
    const float radii[4] = {r_root, r_tip, r_tip, r_root};
    for (int k = 0; k < 4; ++k) p.push_back({radii[k] * std::cos(angles[k]), radii[k] * std::sin(angles[k])});
  }
  return p;
}

Mesh box(glm::vec3 size, glm::vec3 color) {
  Builder b;
  b.color = color;
  const glm::vec3 h = size * 0.5f;
  const std::vector<glm::vec2> square = {{h.x, -h.z}, {h.x, h.z}, {-h.x, h.z}, {-h.x, -h.z}};
  b.extrudeSides(square, -h.y, h.y, false);
  b.polygon({{h.x, h.y, h.z}, {h.x, h.y, -h.z}, {-h.x, h.y, -h.z}, {-h.x, h.y, h.z}});
  b.polygon({{-h.x, -h.y, h.z}, {-h.x, -h.y, -h.z}, {h.x, -h.y, -h.z}, {h.x, -h.y, h.z}});
  return b.m;
}

Mesh prism(size_t sides, float r, float height, glm::vec3 color) {
  Builder b;
  b.color = color;
  const auto p = circle(r, sides);
  b.extrudeSides(p, -height * 0.5f, height * 0.5f, false);
  b.caps(p, -height * 0.5f, height * 0.5f);
  return b.m;
}

Mesh cylinder(float r, float height, size_t segments, glm::vec3 color) {
  Builder b;
  b.color = color;
  const auto p = circle(r, segments);
  // side rings also every height/4 so long shafts have interior vertices to cluster
  for (int k = 0; k < 4; ++k) b.extrudeSides(p, -height * 0.5f + height * k / 4.0f, -height * 0.5f + height * (k + 1) / 4.0f, true);
  b.caps(p, -height * 0.5f, height * 0.5f);
  return b.m;
}

Mesh gear(size_t teeth, float r_root, float r_tip, float thickness, float bore, size_t segments, glm::vec3 color) {
  Builder b;
  b.color = color;
  const auto p = gearProfile(teeth, r_root, r_tip);
  b.extrudeSides(p, -thickness * 0.5f, thickness * 0.5f, false);
  b.caps(p, -thickness * 0.5f, thickness * 0.5f);
  // a hub: a closed cylinder through the gear, standing out of both faces
  const auto hub = circle(bore, segments);
  b.extrudeSides(hub, -thickness * 0.9f, thickness * 0.9f, true);
  b.caps(hub, -thickness * 0.9f, thickness * 0.9f);
  return b.m;
}

Mesh pipe(float r_out, float r_in, float length, size_t segments, glm::vec3 color) {
  Builder b;
  b.color = color;
  const auto outer = circle(r_out, segments), inner = circle(r_in, segments);
  const float y0 = -length * 0.5f, y1 = length * 0.5f;
  for (int k = 0; k < 8; ++k) b.extrudeSides(outer, y0 + length * k / 8.0f, y0 + length * (k + 1) / 8.0f, true);
  // inner wall faces inwards: reversed profile, normals negated
  const size_t inner_first = b.m.positions.size();
  std::vector<glm::vec2> rev(inner.rbegin(), inner.rend());
  for (int k = 0; k < 8; ++k) b.extrudeSides(rev, y0 + length * k / 8.0f, y0 + length * (k + 1) / 8.0f, true);
  for (size_t v = inner_first; v < b.m.normals.size(); ++v) b.m.normals[v] = -b.m.normals[v];
  // end rings
  for (int end = 0; end < 2; ++end) {
    const float y = end ? y1 : y0;
    for (size_t i = 0; i < segments; ++i) {
      const size_t j = (i + 1) % segments;
      // this corner order faces -y; the top ring is turned round
      std::vector<glm::vec3> quad = {{outer[i].x, y, outer[i].y}, {outer[j].x, y, outer[j].y},
                                     {inner[j].x, y, inner[j].y}, {inner[i].x, y, inner[i].y}};
      if (end) std::swap(quad[1], quad[3]);
      b.polygon(quad);
    }
  }
  return b.m;
}

Mesh bolt(size_t segments, glm::vec3 color) {
  Builder b;
  b.color = color;
  const auto head = circle(0.09f, 6);
  b.extrudeSides(head, 0.0f, 0.06f, false);
  b.caps(head, 0.0f, 0.06f);
  const auto shank = circle(0.04f, segments / 2);
  b.extrudeSides(shank, -0.3f, 0.0f, true);
  std::vector<glm::vec3> tip;
  for (auto it = shank.rbegin(); it != shank.rend(); ++it) tip.push_back({it->x, -0.3f, it->y});
  b.starPolygon({0, -0.3f, 0}, tip, {0, -1, 0});
  // the shank's top (hidden under the head) closes it, so every part is a closed shell
  std::vector<glm::vec3> top;
  for (const glm::vec2& q : shank) top.push_back({q.x, 0.0f, q.y});
  b.starPolygon({0, 0.0f, 0}, top, {0, 1, 0});
  return b.m;
}

Mesh bracket(glm::vec3 color) {
  Mesh a = box({0.8f, 0.06f, 0.4f}, color), v = box({0.06f, 0.5f, 0.4f}, color);
  const uint32_t off = static_cast<uint32_t>(a.positions.size());
  for (auto& p : v.positions) p += glm::vec3(-0.37f, 0.28f, 0.0f);
  a.positions.insert(a.positions.end(), v.positions.begin(), v.positions.end());
  a.normals.insert(a.normals.end(), v.normals.begin(), v.normals.end());
  a.colors.insert(a.colors.end(), v.colors.begin(), v.colors.end());
  for (uint32_t i : v.triangles) a.triangles.push_back(i + off);
  // a rib: a thin triangular gusset between the two legs
  Mesh rib = prism(3, 0.2f, 0.01f, color);
  const uint32_t off2 = static_cast<uint32_t>(a.positions.size());
  const glm::mat4 t = glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(-0.25f, 0.15f, 0.0f)), kPi * 0.5f, glm::vec3(1, 0, 0));
  for (size_t i = 0; i < rib.positions.size(); ++i) {
    a.positions.push_back(glm::vec3(t * glm::vec4(rib.positions[i], 1.0f)));
    a.normals.push_back(glm::normalize(glm::mat3(t) * rib.normals[i]));
    a.colors.push_back(color);
  }
  for (uint32_t i : rib.triangles) a.triangles.push_back(i + off2);
  return a;
}

uint32_t hashMix(uint32_t x) {
  x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
  return x;
}

// Texture coordinates from the position alone: the projection along (1, 1, 1) onto its plane, so
// every face of the axis-aligned parts shows the texture alike (sheared, never degenerate), at
// `per_unit` texture repeats per object unit, v running down the parts as images do. Vertices at one
// position get one uv, so no UV seam is added: the parts' UV charts, and so their chains, stay what
// they were without texture coordinates. Round parts show a streak where their side turns parallel
// to the projection; fine for a demo.
void addProjectedUvs(Mesh& m, float per_unit) {
  const glm::vec3 e1 = glm::vec3(1.0f, 0.0f, -1.0f) / std::sqrt(2.0f);
  const glm::vec3 e2 = glm::vec3(1.0f, -2.0f, 1.0f) / std::sqrt(6.0f);
  m.uvs.resize(m.positions.size());
  for (size_t v = 0; v < m.positions.size(); ++v)
    m.uvs[v] = per_unit * glm::vec2(glm::dot(m.positions[v], e1), glm::dot(m.positions[v], e2));
}

// 3 x 5 pixel glyphs of the label's letters, rows top to bottom, bit 2 the left column
struct Glyph {
  char c;
  uint8_t rows[5];
};
constexpr Glyph kGlyphs[] = {{'S', {7, 4, 7, 1, 7}}, {'C', {7, 4, 4, 4, 7}}, {'E', {7, 4, 6, 4, 7}},
                             {'N', {7, 5, 5, 5, 5}}, {'L', {4, 4, 4, 4, 7}}, {'O', {7, 5, 5, 5, 7}},
                             {'D', {6, 5, 5, 5, 6}}};

ImageData rgbaImage(const std::string& name, int w, int h, std::vector<uint8_t> rgba) {
  ImageData img;
  img.name = name;
  img.mime_type = "image/png";
  img.width = w;
  img.height = h;
  img.rgba8 = std::move(rgba);
  // the encoded bytes too, as an imported image has them, so exporters can write the file's image
  auto append = [](void* context, void* data, int size) {
    auto* bytes = static_cast<std::vector<uint8_t>*>(context);
    bytes->insert(bytes->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
  };
  stbi_write_png_to_func(append, &img.encoded, w, h, 4, img.rgba8.data(), w * 4);
  return img;
}

// 64 x 64 texels: 8 x 8 blocks of white and light grey, so the part's vertex colour tints it
ImageData checkerImage() {
  std::vector<uint8_t> px;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const uint8_t v = ((x / 8 + y / 8) % 2) ? 255 : 150;
      px.insert(px.end(), {v, v, v, 255});
    }
  return rgbaImage("checker", 64, 64, std::move(px));
}

// 128 x 32 texels: "SCENELOD" in dark letters on a white plate with a dark border
ImageData labelImage() {
  const int w = 128, h = 32, scale = 3;
  std::vector<uint8_t> px(static_cast<size_t>(w) * h * 4, 255);
  auto dark = [&](int x, int y) {
    uint8_t* p = px.data() + (static_cast<size_t>(y) * w + x) * 4;
    p[0] = 30, p[1] = 30, p[2] = 40;
  };
  for (int x = 0; x < w; ++x) dark(x, 1), dark(x, h - 2);
  for (int y = 1; y < h - 1; ++y) dark(1, y), dark(w - 2, y);
  const std::string text = "SCENELOD";
  const int x0 = (w - static_cast<int>(text.size()) * 4 * scale + scale) / 2, y0 = (h - 5 * scale) / 2;
  for (size_t i = 0; i < text.size(); ++i)
    for (const Glyph& g : kGlyphs)
      if (g.c == text[i])
        for (int r = 0; r < 5 * scale; ++r)
          for (int c = 0; c < 3 * scale; ++c)
            if (g.rows[r / scale] & (4 >> (c / scale))) dark(x0 + static_cast<int>(i) * 4 * scale + c, y0 + r);
  return rgbaImage("label", w, h, std::move(px));
}

// mean linear colour of an image (MaterialData::average_texel_color)
glm::vec3 averageTexel(const ImageData& img) {
  glm::dvec3 sum(0.0);
  auto linear = [](uint8_t b) {
    const double c = b / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
  };
  for (size_t i = 0; i + 3 < img.rgba8.size(); i += 4)
    sum += glm::dvec3(linear(img.rgba8[i]), linear(img.rgba8[i + 1]), linear(img.rgba8[i + 2]));
  return glm::vec3(sum / std::max<double>(1.0, static_cast<double>(img.rgba8.size() / 4)));
}

}  // namespace

Mesh makeBlobMesh(int subdivisions) {
  // icosahedron
  const float t = (1.0f + std::sqrt(5.0f)) * 0.5f;
  std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<uint32_t> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                             3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return mid[key] = static_cast<uint32_t>(v.size() - 1);
    };
    std::vector<uint32_t> g;
    for (size_t i = 0; i < f.size(); i += 3) {
      const uint32_t a = f[i], b = f[i + 1], c = f[i + 2], ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      g.insert(g.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(g);
  }
  Mesh m;
  for (const glm::vec3& p : v) {
    // smooth bumps: a sum of a few low-frequency waves, like an organic surface
    const float d = 0.12f * std::sin(3.0f * p.x + 1.0f) * std::cos(2.0f * p.y) + 0.08f * std::sin(5.0f * p.z + 2.0f * p.x) +
                    0.15f * p.y * p.y;
    m.positions.push_back(p * (1.0f + d) * glm::vec3(1.0f, 0.8f, 0.9f));
  }
  m.triangles = f;
  computeVertexNormals(m);
  m.colors.assign(m.positions.size(), glm::vec3(0.7f, 0.55f, 0.4f));
  return m;
}

namespace {

bool readBunnyObj(const std::string& path, Mesh& out) {
  Mesh m;
  if (!readObj(path, m).ok() || m.triangles.empty()) return false;
  if (m.normals.empty()) computeVertexNormals(m);
  m.colors.assign(m.positions.size(), glm::vec3(0.75f, 0.7f, 0.65f));
  m.uvs.clear();
  out = std::move(m);
  return true;
}

}  // namespace

Error makeDemoScene(SceneData& out, const DemoSceneParams& p, DemoSceneInfo* info) {
  if (p.segments < 3) return {Status::kInvalidArgument, "demo scene: segments must be >= 3"};
  if (p.gearbox_count == 0) return {Status::kInvalidArgument, "demo scene: gearbox_count must be >= 1"};
  out = SceneData{};
  const size_t seg = p.segments;
  // two generated textures; the parts' colours stay in their vertex colours (COLOR_0), which tint
  // the white materials' textures
  out.images = {checkerImage(), labelImage()};
  out.textures = {TextureData{0, 10497, 10497}, TextureData{1, 10497, 10497}};
  auto material = [&](const char* name, int32_t texture) {
    MaterialData m;
    m.name = name;
    if (texture < 0) {
      out.materials.push_back(m);
      return static_cast<int32_t>(out.materials.size() - 1);
    }
    m.textured = true;
    m.base_color_texture = texture;
    m.average_texel_color = averageTexel(out.images[static_cast<size_t>(texture)]);
    // the label's texels are 4:1: one label per object unit across, four up
    if (texture == 1) m.base_color_transform.scale = glm::vec2(0.5f, 2.0f);
    out.materials.push_back(m);
    return static_cast<int32_t>(out.materials.size() - 1);
  };
  auto mesh = [&](const char* name, Mesh m, int32_t mat) {
    if (out.materials[static_cast<size_t>(mat)].textured && m.uvs.empty()) addProjectedUvs(m, 2.0f);
    MeshData d;
    d.name = name;
    d.mesh = std::move(m);
    d.primitive_materials = {mat};
    out.meshes.push_back(std::move(d));
    return static_cast<int32_t>(out.meshes.size() - 1);
  };
  const glm::vec3 steel(0.55f, 0.56f, 0.58f), brass(0.78f, 0.57f, 0.11f), paint(0.1f, 0.25f, 0.6f),
      copper(0.72f, 0.35f, 0.2f), alu(0.85f, 0.86f, 0.88f), dark(0.1f, 0.1f, 0.1f);
  const int32_t m_steel = material("steel", 0), m_brass = material("brass", 0), m_paint = material("paint", 1),
                m_alu = material("aluminium", 0), m_dark = material("rubber", 0);
  // The shafts, pipes and rods are extruded in bands whose seam rings repeat each vertex exactly:
  // with texture coordinates the clustering would weld those copies first (a mesh with attributes
  // is welded, #37) and their chains, and so the demo's selection, would change. They stay
  // untextured, coloured by their vertex colours alone.
  const int32_t m_plain = material("plain", -1);

  const int32_t base = mesh("base_plate", box({6.0f, 0.2f, 4.0f}, paint), m_paint);
  const int32_t gear_big = mesh("gear_24", gear(24, 0.5f, 0.6f, 0.12f, 0.12f, seg, brass), m_brass);
  const int32_t gear_small = mesh("gear_12", gear(12, 0.25f, 0.33f, 0.12f, 0.08f, seg, brass), m_brass);
  const int32_t shaft = mesh("shaft", cylinder(0.06f, 1.0f, seg, steel), m_plain);
  const int32_t boltm = mesh("bolt", bolt(seg, steel), m_steel);
  const int32_t brack = mesh("bracket", bracket(paint), m_paint);
  const int32_t pipem = mesh("pipe", pipe(0.15f, 0.12f, 2.5f, seg, copper), m_plain);
  const int32_t fin = mesh("fin", box({0.01f, 0.5f, 0.8f}, alu), m_alu);            // thin plate
  const int32_t rod = mesh("rod", cylinder(0.008f, 1.6f, 8, dark), m_plain);         // thin wire
  const int32_t hexm = mesh("hex_prism", prism(6, 0.2f, 0.3f, steel), m_steel);
  const int32_t trim = mesh("tri_prism", prism(3, 0.25f, 0.6f, paint), m_paint);

  DemoSceneInfo local_info;
  Mesh organic;
  if (p.bunny_count == 0) {
    local_info.note = "no bunny instances";
  } else if (!p.bunny_path.empty() && readBunnyObj(p.bunny_path, organic)) {
    local_info.bunny_loaded = true;
    local_info.note = "bunny instances use " + p.bunny_path;
  } else {
    organic = makeBlobMesh(5);
    local_info.note = p.bunny_path.empty() ? "bunny instances use a generated organic blob (no bunny path given)"
                                           : "could not read the bunny at " + p.bunny_path +
                                                 "; bunny instances use a generated organic blob instead";
  }
  const Aabb ob = computeBounds(organic);
  // about four checker repeats across the organic mesh, whatever its units
  if (!organic.positions.empty()) addProjectedUvs(organic, 4.0f / std::max(ob.diagonal(), 1e-6f));
  // no mesh without an instance: unused meshes would only surprise exporters and tables
  const int32_t bunny = p.bunny_count == 0 ? -1 : mesh(local_info.bunny_loaded ? "bunny" : "organic_blob", std::move(organic), m_dark);

  auto node = [&](int32_t parent, const std::string& name, const glm::mat4& local, int32_t mesh_index) {
    NodeData n;
    n.name = name;
    n.parent = parent;
    n.local = local;
    n.mesh = mesh_index;
    out.nodes.push_back(n);
    const int32_t i = static_cast<int32_t>(out.nodes.size() - 1);
    if (parent >= 0) out.nodes[parent].children.push_back(i);
    else out.roots.push_back(i);
    return i;
  };
  auto T = [](float x, float y, float z) { return glm::translate(glm::mat4(1.0f), glm::vec3(x, y, z)); };
  auto R = [](float deg, glm::vec3 axis) { return glm::rotate(glm::mat4(1.0f), glm::radians(deg), axis); };

  const int32_t root = node(-1, "demo", glm::mat4(1.0f), -1);
  node(root, "base", T(0, -0.1f, 0), base);
  for (size_t g = 0; g < p.gearbox_count; ++g) {
    const float x = -2.2f + 4.4f * float(g) / float(std::max<size_t>(p.gearbox_count - 1, 1));
    const uint32_t h = hashMix(uint32_t(g) + 17u);
    const int32_t box_node = node(root, "gearbox_" + std::to_string(g), T(x, 0.0f, -1.0f) * R(float(h % 30), {0, 1, 0}), -1);
    node(box_node, "bracket", T(0, 0.03f, 0), brack);
    const int32_t axle1 = node(box_node, "axle_a", T(-0.1f, 0.6f, 0) * R(90, {1, 0, 0}), -1);
    node(axle1, "shaft", glm::mat4(1.0f), shaft);
    node(axle1, "gear", T(0, 0.1f, 0) * R(float(h % 15), {0, 1, 0}), gear_big);
    const int32_t axle2 = node(box_node, "axle_b", T(-0.1f, 0.6f + 0.8f, 0) * R(90, {1, 0, 0}), -1);
    node(axle2, "shaft", glm::mat4(1.0f), shaft);
    node(axle2, "pinion", T(0, 0.1f, 0), gear_small);
    for (int b = 0; b < 4; ++b)
      node(box_node, "bolt_" + std::to_string(b), T(b < 2 ? 0.2f : 0.35f, 0.06f, b % 2 ? 0.12f : -0.12f), boltm);
  }
  const int32_t pipes = node(root, "pipe_rack", T(0, 0.6f, 1.2f), -1);
  for (int i = 0; i < 6; ++i) node(pipes, "pipe_" + std::to_string(i), T(-1.5f + 0.35f * i, 0.0f, 0.0f) * R(90, {0, 0, 1}) * R(0, {1, 0, 0}), pipem);
  const int32_t sink = node(root, "heat_sink", T(2.0f, 0.25f, 1.2f), -1);
  for (int i = 0; i < 12; ++i) node(sink, "fin_" + std::to_string(i), T(-0.3f + 0.05f * i, 0.0f, 0.0f), fin);
  const int32_t cage = node(root, "cage", T(-2.3f, 0.8f, 1.3f), -1);
  for (int i = 0; i < 8; ++i) {
    const float a = 45.0f * i;
    node(cage, "rod_" + std::to_string(i), R(a, {0, 1, 0}) * T(0.4f, 0.0f, 0.0f), rod);
  }
  const int32_t feet = node(root, "feet", glm::mat4(1.0f), -1);
  for (int i = 0; i < 4; ++i)
    node(feet, "foot_" + std::to_string(i), T(i % 2 ? 2.8f : -2.8f, -0.35f, i / 2 ? 1.8f : -1.8f), hexm);
  node(root, "wedge", T(0.0f, 0.3f, 0.2f) * R(90, {1, 0, 0}), trim);
  // bunnies: scaled so that their box diagonal is 0.8 units, standing on the plate
  const float scale = 0.8f / std::max(ob.diagonal(), 1e-6f);
  const int32_t zoo = p.bunny_count == 0 ? -1 : node(root, "bunnies", T(0.0f, 0.0f, 0.3f), -1);
  for (size_t b = 0; b < p.bunny_count; ++b) {
    const float x = -1.5f + 3.0f * float(b) / float(std::max<size_t>(p.bunny_count - 1, 1));
    const glm::mat4 place = T(x, -ob.min.y * scale, 0.0f) * R(float(hashMix(uint32_t(b)) % 360), {0, 1, 0}) *
                            glm::scale(glm::mat4(1.0f), glm::vec3(scale)) * T(-ob.center().x, 0.0f, -ob.center().z);
    node(zoo, "bunny_" + std::to_string(b), place, bunny);
  }
  if (info) *info = local_info;
  return validateSceneData(out, "demo scene");
}

}  // namespace scenelod::scene
