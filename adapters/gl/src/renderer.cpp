// OpenGL 3.3 core renderer of LOD chains, headless through EGL. Thick edges follow Low & Tan 1997
// §3.3: each edge is drawn as a camera-facing quad (wide lines are not in core profiles) shaded with
// the dynamic normal ((V1 - C) x (V2 - C)) x (V2 - V1), C the eye, as wide as the edge's thickness in
// world units and never thinner than one pixel.
#include "scenelod/gl/renderer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <tuple>
#include <unordered_map>
#include <glm/gtc/type_ptr.hpp>

namespace scenelod::gl {
namespace {

// Every program is compiled from "#version 330 core" and one of these sources. Geomorphs (Hoppe
// 1996): u_morph mixes each vertex toward its target in the next level (locations 4.. for
// triangles and points, 3 and 4 for edges); a level without targets has them aliased to its own
// attributes, so any factor leaves it unmoved.
const char kTriangleVs[] = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in vec3 a_color;
layout(location = 4) in vec3 a_pos_target;
layout(location = 5) in vec3 a_normal_target;
layout(location = 6) in vec2 a_uv_target;
layout(location = 7) in vec3 a_color_target;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform mat3 u_normal_matrix;
uniform float u_morph;
out vec3 v_normal;
out vec3 v_world;
out vec2 v_uv;
out vec3 v_color;
void main() {
  // (at factor 1 the targets themselves: mix may round a + 1 (b - a) away from b)
  bool at_target = u_morph >= 1.0;
  vec3 n = at_target ? a_normal_target : mix(a_normal, a_normal_target, u_morph);
  float n_len = length(n);
  n = n_len > 1e-20 ? n / n_len : at_target ? n : a_normal;
  vec4 w = u_model * vec4(at_target ? a_pos_target : mix(a_pos, a_pos_target, u_morph), 1.0);
  v_world = w.xyz;
  v_normal = u_normal_matrix * n;
  v_uv = at_target ? a_uv_target : mix(a_uv, a_uv_target, u_morph);
  v_color = at_target ? a_color_target : mix(a_color, a_color_target, u_morph);
  gl_Position = u_view_proj * w;
}
)";

// a_param: x = end (0 at V1, 1 at V2), y = side (-1 or +1), z = thickness (object space);
// a_t1, a_t2: the endpoints' morph targets
const char kEdgeVs[] = R"(
layout(location = 0) in vec3 a_v1;
layout(location = 1) in vec3 a_v2;
layout(location = 2) in vec4 a_param;
layout(location = 3) in vec3 a_t1;
layout(location = 4) in vec3 a_t2;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform vec3 u_eye;
uniform float u_scale;
uniform float u_pixel_factor;
uniform float u_pixel_const;
uniform float u_morph;
out vec3 v_normal;
out vec3 v_world;
out vec2 v_uv;
out vec3 v_color;
void main() {
  v_uv = vec2(0.0);
  v_color = vec3(1.0);
  bool at_target = u_morph >= 1.0;
  vec3 w1 = (u_model * vec4(at_target ? a_t1 : mix(a_v1, a_t1, u_morph), 1.0)).xyz;
  vec3 w2 = (u_model * vec4(at_target ? a_t2 : mix(a_v2, a_t2, u_morph), 1.0)).xyz;
  vec3 dir = w2 - w1;
  vec3 p = mix(w1, w2, a_param.x);
  vec3 to_p = p - u_eye;
  vec3 side = cross(dir, to_p);
  float side_len = length(side);
  side = side_len > 1e-30 ? side / side_len : vec3(0.0);
  float pixel = u_pixel_factor * length(to_p) + u_pixel_const;
  float width = max(a_param.z * u_scale, pixel);
  vec3 pos = p + side * (0.5 * width * a_param.y);
  v_normal = cross(cross(w1 - u_eye, w2 - u_eye), dir);
  v_world = pos;
  gl_Position = u_view_proj * vec4(pos, 1.0);
}
)";

const char kPointVs[] = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 4) in vec3 a_pos_target;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform vec3 u_eye;
uniform float u_point_size;
uniform float u_morph;
out vec3 v_normal;
out vec3 v_world;
out vec2 v_uv;
out vec3 v_color;
void main() {
  v_uv = vec2(0.0);
  v_color = vec3(1.0);
  vec4 w = u_model * vec4(u_morph >= 1.0 ? a_pos_target : mix(a_pos, a_pos_target, u_morph), 1.0);
  v_world = w.xyz;
  v_normal = u_eye - w.xyz;
  gl_PointSize = u_point_size;
  gl_Position = u_view_proj * w;
}
)";

// a headlight: the light sits at the eye; both sides of a surface are lit. With a shadow map, a
// directional light (u_light_dir, toward the light) adds most of the light where the map sees the
// surface (2x2 percentage-closer filtering by the depth comparison sampler). Screen-door dithering
// for cross-fades: with u_dither_on, a fragment is kept only when its pixel's 4x4 Bayer threshold
// t = (B(x mod 4, y mod 4) + 0.5) / 16 lies in [u_dither.x, u_dither.y): the new level of a fade
// keeps [0, fade), the previous one [fade, 2), so every pixel goes to exactly one of them.
const char kFs[] = R"(
in vec3 v_normal;
in vec3 v_world;
in vec2 v_uv;
in vec3 v_color;
uniform vec3 u_eye;
uniform vec3 u_color;
uniform int u_has_texture;
uniform sampler2D u_texture;
uniform mat3 u_uv_transform;
uniform int u_shadow_on;
uniform mat4 u_shadow_view_proj;
uniform vec3 u_light_dir;
uniform sampler2DShadow u_shadow_map;
uniform int u_dither_on;
uniform vec2 u_dither;
out vec4 o_color;
const int kBayer[16] = int[16](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);
void main() {
  if (u_dither_on != 0) {
    ivec2 q = ivec2(gl_FragCoord.xy) & 3;
    float t = (float(kBayer[q.y * 4 + q.x]) + 0.5) / 16.0;
    if (t < u_dither.x || t >= u_dither.y) discard;
  }
  float n_len = length(v_normal);
  vec3 to_eye = u_eye - v_world;
  float e_len = length(to_eye);
  float d = (n_len > 0.0 && e_len > 0.0) ? abs(dot(v_normal / n_len, to_eye / e_len)) : 1.0;
  vec3 base = u_color * v_color;
  if (u_has_texture != 0) base *= texture(u_texture, (u_uv_transform * vec3(v_uv, 1.0)).xy).rgb;
  if (u_shadow_on == 0) {
    o_color = vec4(base * (0.2 + 0.8 * d), 1.0);
    return;
  }
  vec4 s = u_shadow_view_proj * vec4(v_world, 1.0);
  vec3 p = s.xyz / s.w * 0.5 + 0.5;
  float lit = 1.0;
  if (all(greaterThanEqual(p, vec3(0.0))) && all(lessThanEqual(p, vec3(1.0)))) lit = texture(u_shadow_map, p);
  float l = n_len > 0.0 ? abs(dot(v_normal / n_len, u_light_dir)) : 1.0;
  o_color = vec4(base * (0.15 + 0.3 * d + 0.55 * l * lit), 1.0);
}
)";

struct Program {
  GLuint id = 0;
  GLint model = -1, view_proj = -1, normal_matrix = -1, eye = -1, color = -1, scale = -1, pixel_factor = -1,
        pixel_const = -1, point_size = -1, shadow_on = -1, shadow_view_proj = -1, light_dir = -1, shadow_map = -1,
        has_texture = -1, texture = -1, uv_transform = -1, morph = -1, dither_on = -1, dither = -1;
};

// a run of one primitive kind's indices drawn with one material
struct Range {
  GLsizei first = 0, count = 0;  // in indices
  int32_t material = -1;         // -1: white (or the chain's colour when it has no materials)
};

struct LevelGpu {
  GLuint vbo = 0, tri_vao = 0, tri_ibo = 0, point_vao = 0, point_ibo = 0;
  GLuint edge_vao = 0, edge_vbo = 0, edge_ibo = 0;
  GLsizei tri_indices = 0, point_indices = 0, edge_indices = 0;
  std::vector<Range> tri_ranges, edge_ranges, point_ranges;
};

struct ChainGpu {
  std::vector<LevelGpu> levels;
  glm::vec3 color{0.8f};
  bool materials = false;  // drawn with materials (else the flat chain colour)
};

struct MaterialGpu {
  GLuint texture = 0;
  glm::vec3 factor{1.0f};
  glm::vec3 mean_texel{1.0f};  // for edges and points, which have no texture coordinates
  glm::mat3 uv_transform{1.0f};
};

// the order of `n` primitives sorted by their group (stable), and the runs of one group
std::vector<uint32_t> groupOrder(size_t n, const std::vector<uint32_t>& groups, const std::vector<int32_t>* materials,
                                 GLsizei per_primitive, std::vector<Range>& ranges) {
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  auto group = [&](uint32_t i) { return groups.empty() ? 0u : groups[i]; };
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return group(a) < group(b); });
  ranges.clear();
  for (size_t k = 0; k < n; ++k) {
    const uint32_t g = group(order[k]);
    const int32_t material = materials && g < materials->size() ? (*materials)[g] : -1;
    if (k == 0 || group(order[k - 1]) != g) ranges.push_back(Range{static_cast<GLsizei>(k) * per_primitive, 0, material});
    ranges.back().count += per_primitive;
  }
  return order;
}

Error compileShader(GLenum type, const char* source, const char* name, GLuint& out) {
  GLuint s = glCreateShader(type);
  const char* sources[2] = {"#version 330 core\n", source};
  glShaderSource(s, 2, sources, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetShaderInfoLog(s, sizeof(log) - 1, nullptr, log);
    glDeleteShader(s);
    return Error(Status::kUnsupported, std::string("GL renderer: shader ") + name + " does not compile: " + log);
  }
  out = s;
  return {};
}

Error linkProgram(const char* vs_source, const char* name, Program& out) {
  GLuint vs = 0, fs = 0;
  if (Error e = compileShader(GL_VERTEX_SHADER, vs_source, name, vs); !e.ok()) return e;
  if (Error e = compileShader(GL_FRAGMENT_SHADER, kFs, "fragment", fs); !e.ok()) {
    glDeleteShader(vs);
    return e;
  }
  GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetProgramInfoLog(p, sizeof(log) - 1, nullptr, log);
    glDeleteProgram(p);
    return Error(Status::kUnsupported, std::string("GL renderer: program ") + name + " does not link: " + log);
  }
  out.id = p;
  out.model = glGetUniformLocation(p, "u_model");
  out.view_proj = glGetUniformLocation(p, "u_view_proj");
  out.normal_matrix = glGetUniformLocation(p, "u_normal_matrix");
  out.eye = glGetUniformLocation(p, "u_eye");
  out.color = glGetUniformLocation(p, "u_color");
  out.scale = glGetUniformLocation(p, "u_scale");
  out.pixel_factor = glGetUniformLocation(p, "u_pixel_factor");
  out.pixel_const = glGetUniformLocation(p, "u_pixel_const");
  out.point_size = glGetUniformLocation(p, "u_point_size");
  out.shadow_on = glGetUniformLocation(p, "u_shadow_on");
  out.shadow_view_proj = glGetUniformLocation(p, "u_shadow_view_proj");
  out.light_dir = glGetUniformLocation(p, "u_light_dir");
  out.shadow_map = glGetUniformLocation(p, "u_shadow_map");
  out.has_texture = glGetUniformLocation(p, "u_has_texture");
  out.texture = glGetUniformLocation(p, "u_texture");
  out.uv_transform = glGetUniformLocation(p, "u_uv_transform");
  out.morph = glGetUniformLocation(p, "u_morph");
  out.dither_on = glGetUniformLocation(p, "u_dither_on");
  out.dither = glGetUniformLocation(p, "u_dither");
  glUseProgram(p);
  glUniform1i(out.shadow_map, 0);  // texture unit 0: the shadow map
  glUniform1i(out.texture, 1);     // texture unit 1: the material's base colour
  glUniform1i(out.shadow_on, 0);
  glUniform1i(out.has_texture, 0);
  glUniform1f(out.morph, 0.0f);
  glUniform1i(out.dither_on, 0);
  glUniform2f(out.dither, 0.0f, 2.0f);
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  glUniformMatrix3fv(out.uv_transform, 1, GL_FALSE, identity);
  glUseProgram(0);
  return {};
}

const char* eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    default: return "EGL error";
  }
}

// A distinct colour per chain (golden-ratio hue steps), so levels of different meshes are told apart.
// For every target position, the normal of the vertex of `next` at exactly that position (its own
// normal, or the area-weighted one the upload computes when it has none); `own[v]` where no vertex
// of `next` sits there.
void nextLevelNormals(const Mesh& next, const std::vector<glm::vec3>& targets, const std::vector<glm::vec3>& own,
                      std::vector<glm::vec3>& out) {
  Mesh computed;
  const std::vector<glm::vec3>* normals = &next.normals;
  if (next.normals.size() != next.positions.size()) {
    computed.positions = next.positions;
    computed.triangles = next.triangles;
    computeVertexNormals(computed);
    normals = &computed.normals;
  }
  auto key = [](const glm::vec3& p) {
    uint32_t b[3];
    std::memcpy(b, &p, 12);
    return std::make_tuple(b[0], b[1], b[2]);
  };
  std::vector<std::pair<std::tuple<uint32_t, uint32_t, uint32_t>, uint32_t>> sorted(next.positions.size());
  for (size_t i = 0; i < next.positions.size(); ++i) sorted[i] = {key(next.positions[i]), static_cast<uint32_t>(i)};
  std::sort(sorted.begin(), sorted.end());
  out.resize(targets.size());
  for (size_t v = 0; v < targets.size(); ++v) {
    const auto k = key(targets[v]);
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(k, 0u));
    out[v] = it != sorted.end() && it->first == k ? (*normals)[it->second] : own[v];
  }
}

glm::vec3 chainColor(size_t chain) {
  const float h = std::fmod(0.13f + 0.618034f * static_cast<float>(chain), 1.0f) * 6.0f;
  const float s = 0.45f, v = 0.9f;
  const int i = static_cast<int>(h);
  const float f = h - static_cast<float>(i);
  const float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (i % 6) {
    case 0: return {v, t, p};
    case 1: return {q, v, p};
    case 2: return {p, v, t};
    case 3: return {p, q, v};
    case 4: return {t, p, v};
    default: return {v, p, q};
  }
}

}  // namespace

struct Renderer::Impl {
  RendererConfig config;
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface pbuffer = EGL_NO_SURFACE;
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;  // made on the first frame with a shadow camera
  Program tri, edge, point;
  std::vector<ChainGpu> chains;
  std::vector<MaterialGpu> materials;
  size_t gpu_bytes = 0;
  bool ready = false;
  std::string description;

  void releaseMaterials() {
    for (MaterialGpu& mat : materials) glDeleteTextures(1, &mat.texture);
    materials.clear();
  }

  void releaseChains() {
    for (ChainGpu& c : chains)
      for (LevelGpu& l : c.levels) {
        GLuint bufs[5] = {l.vbo, l.tri_ibo, l.point_ibo, l.edge_vbo, l.edge_ibo};
        glDeleteBuffers(5, bufs);
        GLuint vaos[3] = {l.tri_vao, l.point_vao, l.edge_vao};
        glDeleteVertexArrays(3, vaos);
      }
    chains.clear();
    gpu_bytes = 0;
  }

  ~Impl() {
    if (ready) {
      releaseChains();
      releaseMaterials();
      glDeleteProgram(tri.id);
      glDeleteProgram(edge.id);
      glDeleteProgram(point.id);
      glDeleteFramebuffers(1, &fbo);
      glDeleteFramebuffers(1, &shadow_fbo);
      glDeleteTextures(1, &shadow_tex);
      glDeleteRenderbuffers(1, &color_rb);
      glDeleteRenderbuffers(1, &depth_rb);
    }
    if (display != EGL_NO_DISPLAY) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
      if (pbuffer != EGL_NO_SURFACE) eglDestroySurface(display, pbuffer);
      eglTerminate(display);
    }
  }

  // the depth texture and framebuffer of the shadow pass; false when the framebuffer is incomplete
  bool makeShadowMap() {
    if (shadow_fbo) return true;
    const GLsizei n = static_cast<GLsizei>(config.shadow_map_px);
    glGenTextures(1, &shadow_tex);
    glBindTexture(GL_TEXTURE_2D, shadow_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, n, n, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    const bool ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE && glGetError() == GL_NO_ERROR;
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    return ok;
  }

  Error startEgl() {
    const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    auto get_platform_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_platform_display && client_ext && std::strstr(client_ext, "EGL_MESA_platform_surfaceless"))
      display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY) display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (display == EGL_NO_DISPLAY) return Error(Status::kUnsupported, "EGL: no display (neither surfaceless nor default)");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
      const EGLint err = eglGetError();
      display = EGL_NO_DISPLAY;
      return Error(Status::kUnsupported, std::string("EGL: eglInitialize failed: ") + eglErrorName(err));
    }
    if (!eglBindAPI(EGL_OPENGL_API)) return Error(Status::kUnsupported, "EGL: the display has no desktop OpenGL API");
    const EGLint pbuffer_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                      EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
    const EGLint any_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig cfg = nullptr;
    EGLint n = 0;
    bool has_pbuffer = eglChooseConfig(display, pbuffer_attribs, &cfg, 1, &n) && n > 0;
    if (!has_pbuffer && !(eglChooseConfig(display, any_attribs, &cfg, 1, &n) && n > 0))
      return Error(Status::kUnsupported, "EGL: no config renders desktop OpenGL");
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    context = eglCreateContext(display, cfg, EGL_NO_CONTEXT, ctx_attribs);
    if (context == EGL_NO_CONTEXT)
      return Error(Status::kUnsupported,
                   std::string("EGL: cannot create an OpenGL 3.3 core context: ") + eglErrorName(eglGetError()));
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
      // without EGL_KHR_surfaceless_context: a 1x1 pbuffer (we render into our own FBO anyway)
      const EGLint pb_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      if (has_pbuffer) pbuffer = eglCreatePbufferSurface(display, cfg, pb_attribs);
      if (pbuffer == EGL_NO_SURFACE || !eglMakeCurrent(display, pbuffer, pbuffer, context))
        return Error(Status::kUnsupported,
                     std::string("EGL: cannot make the context current: ") + eglErrorName(eglGetError()));
    }
    return {};
  }
};

void fitDepthPlanes(selection::Camera& camera, const Sphere& bounds, float min_near) {
  const float r = std::max(bounds.radius, 1e-6f);
  const glm::vec3 view = camera.target - camera.eye;
  const float len = glm::length(view);
  const float depth = len > 0.0f ? glm::dot(bounds.center - camera.eye, view / len) : 0.0f;
  camera.near_plane = std::max({1e-6f, min_near * r, 0.99f * (depth - r)});
  camera.far_plane = std::max(camera.near_plane * 1.01f + 1e-6f, 1.01f * (depth + r));
}

Renderer::Renderer() = default;
Renderer::~Renderer() = default;

Error Renderer::init(const RendererConfig& config, bool* unavailable) {
  if (unavailable) *unavailable = false;
  if (config.width_px < 1 || config.height_px < 1 || config.width_px > 8192 || config.height_px > 8192)
    return Error(Status::kInvalidArgument, "GL renderer: size must be 1..8192 pixels per side");
  if (config.shadow_map_px < 16 || config.shadow_map_px > 8192)
    return Error(Status::kInvalidArgument, "GL renderer: the shadow map must be 16..8192 texels per side");
  impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  m.config = config;
  if (Error e = m.startEgl(); !e.ok()) {
    if (unavailable) *unavailable = true;
    impl_.reset();
    return e;
  }
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  m.description = std::string("OpenGL ") + (version ? version : "?") + ", " + (renderer ? renderer : "?");

  glGenRenderbuffers(1, &m.color_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, m.color_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, config.width_px, config.height_px);
  glGenRenderbuffers(1, &m.depth_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, m.depth_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, config.width_px, config.height_px);
  glGenFramebuffers(1, &m.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m.color_rb);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m.depth_rb);
  m.ready = true;  // from here on the destructor releases GL objects
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    impl_.reset();
    return Error(Status::kUnsupported, "GL renderer: the RGBA8 + depth24 framebuffer is incomplete");
  }
  for (auto [src, name, prog] : {std::make_tuple(kTriangleVs, "triangles", &m.tri),
                                 std::make_tuple(kEdgeVs, "edges", &m.edge), std::make_tuple(kPointVs, "points", &m.point)})
    if (Error e = linkProgram(src, name, *prog); !e.ok()) {
      impl_.reset();
      return e;
    }
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glViewport(0, 0, config.width_px, config.height_px);
  if (glGetError() != GL_NO_ERROR) {
    impl_.reset();
    return Error(Status::kUnsupported, "GL renderer: a GL error while setting up the context");
  }
  return {};
}

std::string Renderer::description() const { return impl_ ? impl_->description : std::string(); }
size_t Renderer::chainCount() const { return impl_ ? impl_->chains.size() : 0; }
size_t Renderer::gpuBytes() const { return impl_ ? impl_->gpu_bytes : 0; }

Error Renderer::uploadMaterials(Span<const MaterialDesc> materials) {
  if (!impl_) return Error(Status::kInvalidArgument, "GL renderer: uploadMaterials before init");
  Impl& m = *impl_;
  m.releaseMaterials();
  auto wrapOk = [](int32_t w) { return w == GL_REPEAT || w == GL_CLAMP_TO_EDGE || w == GL_MIRRORED_REPEAT; };
  for (size_t i = 0; i < materials.count; ++i) {
    const MaterialDesc& d = materials[i];
    const std::string what = "GL renderer: material " + std::to_string(i);
    MaterialGpu g;
    g.factor = glm::vec3(d.base_color[0], d.base_color[1], d.base_color[2]);
    g.uv_transform = glm::make_mat3(d.uv_transform);
    if (d.rgba8) {
      if (d.width < 1 || d.height < 1 || d.width > 16384 || d.height > 16384)
        return Error(Status::kInvalidArgument, what + ": texture of " + std::to_string(d.width) + "x" + std::to_string(d.height) + " texels");
      if (!wrapOk(d.wrap_s) || !wrapOk(d.wrap_t)) return Error(Status::kInvalidArgument, what + ": unknown wrap mode");
      glm::dvec3 sum(0.0);
      const size_t texels = static_cast<size_t>(d.width) * static_cast<size_t>(d.height);
      for (size_t t = 0; t < texels; ++t) sum += glm::dvec3(d.rgba8[4 * t], d.rgba8[4 * t + 1], d.rgba8[4 * t + 2]);
      g.mean_texel = glm::vec3(sum / (255.0 * static_cast<double>(texels)));
      glGenTextures(1, &g.texture);
      glBindTexture(GL_TEXTURE_2D, g.texture);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      // rows top first, as glTF's v: v = 0 is the first row, which GL calls t = 0
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, d.width, d.height, 0, GL_RGBA, GL_UNSIGNED_BYTE, d.rgba8);
      glGenerateMipmap(GL_TEXTURE_2D);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, d.wrap_s);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, d.wrap_t);
      glBindTexture(GL_TEXTURE_2D, 0);
      m.gpu_bytes += texels * 4 * 4 / 3;
    }
    m.materials.push_back(g);
    if (glGetError() != GL_NO_ERROR) return Error(Status::kOutOfMemory, what + ": a GL error uploading its texture");
  }
  return {};
}

Error Renderer::uploadChains(const std::vector<LodChain>& chains, const std::vector<std::vector<int32_t>>& group_materials) {
  if (!impl_) return Error(Status::kInvalidArgument, "GL renderer: uploadChains before init");
  Impl& m = *impl_;
  m.releaseChains();
  for (size_t c = 0; c < group_materials.size() && c < chains.size(); ++c)
    for (int32_t mat : group_materials[c])
      if (mat < -1 || mat >= static_cast<int32_t>(m.materials.size()))
        return Error(Status::kInvalidArgument, "GL renderer: chain " + std::to_string(c) + ": material " + std::to_string(mat) +
                                                   " but " + std::to_string(m.materials.size()) + " were uploaded");
  constexpr size_t kOwn = 11;  // floats per vertex: position, normal, uv, colour (then the same for the morph target)
  std::vector<float> vertex_data, edge_data;
  std::vector<uint32_t> indices;
  for (size_t c = 0; c < chains.size(); ++c) {
    ChainGpu gpu;
    gpu.color = chainColor(c);
    gpu.materials = c < group_materials.size();
    const std::vector<int32_t>* mats = gpu.materials ? &group_materials[c] : nullptr;
    for (size_t l = 0; l < chains[c].levels.size(); ++l) {
      const Mesh& src = chains[c].levels[l].mesh;
      const LevelMorph& morph = chains[c].levels[l].morph;
      const std::string what = "chain " + std::to_string(c) + " level " + std::to_string(l);
      if (Error e = validateMesh(src, what); !e.ok()) return Error(e.status, "GL renderer: " + e.message);
      const size_t nv = src.positions.size();
      for (auto [size, name] : {std::make_pair(morph.positions.size(), "positions"), std::make_pair(morph.normals.size(), "normals"),
                                std::make_pair(morph.uvs.size(), "texture coordinates"), std::make_pair(morph.colors.size(), "colours")})
        if (size != 0 && size != nv)
          return Error(Status::kInvalidArgument, "GL renderer: " + what + ": " + std::to_string(size) + " morph target " + name +
                                                     " for " + std::to_string(nv) + " vertices");
      Mesh normals_mesh;
      const std::vector<glm::vec3>* normals = &src.normals;
      if (src.normals.size() != nv) {
        normals_mesh.positions = src.positions;
        normals_mesh.triangles = src.triangles;
        computeVertexNormals(normals_mesh);
        normals = &normals_mesh.normals;
      }
      const bool uvs = src.uvs.size() == nv;
      const bool colors = gpu.materials && src.colors.size() == nv;
      const bool morphs = !morph.positions.empty();
      // a level without normals has no normal targets: each vertex takes the normal this upload
      // computes for the next-level vertex at its target position, so that level k at factor 1 is
      // shaded as level k + 1 is drawn
      std::vector<glm::vec3> target_normals;
      if (morphs && morph.normals.empty() && src.normals.size() != nv && l + 1 < chains[c].levels.size())
        nextLevelNormals(chains[c].levels[l + 1].mesh, morph.positions, *normals, target_normals);
      const size_t stride = morphs ? 2 * kOwn : kOwn;
      // triangle corners drawn at factor 1 by a next-level vertex other than their vertex's target
      // (a crease of the next level through the vertex) get a copy of the vertex with that target
      std::vector<uint32_t> corners = src.triangles;
      std::vector<uint32_t> match;  // per triangle: the next level's triangle it becomes
      std::vector<std::pair<uint32_t, uint32_t>> copies;  // (vertex, next-level vertex)
      Mesh next_normals_mesh;
      const Mesh* next = morphs && l + 1 < chains[c].levels.size() ? &chains[c].levels[l + 1].mesh : nullptr;
      const std::vector<glm::vec3>* next_normals = next ? &next->normals : nullptr;
      if (next && next->normals.size() != next->positions.size()) {
        next_normals_mesh.positions = next->positions;
        next_normals_mesh.triangles = next->triangles;
        computeVertexNormals(next_normals_mesh);
        next_normals = &next_normals_mesh.normals;
      }
      if (next && validateMesh(*next, what).ok()) {
        const std::vector<uint32_t> at = morphCornerVertices(chains[c].levels[l], *next, &match);
        const bool next_uvs = uvs && !morph.uvs.empty() && next->uvs.size() == next->positions.size();
        const bool next_colors = colors && !morph.colors.empty() && next->colors.size() == next->positions.size();
        std::unordered_map<uint64_t, uint32_t> made;  // (vertex << 32 | next vertex) -> copy
        for (size_t i = 0; i < corners.size(); ++i) {
          const uint32_t u = corners[i], w = at[i];
          if (w == UINT32_MAX) continue;
          const glm::vec3 n = !morph.normals.empty() ? morph.normals[u] : !target_normals.empty() ? target_normals[u] : (*normals)[u];
          const bool same = n == (*next_normals)[w] && (!next_uvs || morph.uvs[u] == next->uvs[w]) &&
                            (!next_colors || morph.colors[u] == next->colors[w]);
          if (same) continue;
          const auto [it, added] = made.emplace(uint64_t(u) << 32 | w, static_cast<uint32_t>(nv + copies.size()));
          if (added) copies.push_back({u, w});
          corners[i] = it->second;
        }
        // each matched triangle's corners rotated to start where its match starts (the same
        // triangle given from another first corner may round its edges and attributes otherwise)
        for (size_t t = 0; t < match.size(); ++t) {
          if (match[t] == UINT32_MAX) continue;
          const uint32_t first = next->triangles[3 * size_t(match[t])];
          for (int r = 1; r < 3; ++r)
            if (at[3 * t + r] == first && at[3 * t + (r + 1) % 3] == next->triangles[3 * size_t(match[t]) + 1]) {
              std::rotate(corners.begin() + 3 * t, corners.begin() + 3 * t + r, corners.begin() + 3 * t + 3);
              break;
            }
        }
      }
      LevelGpu lg;
      vertex_data.assign((nv + copies.size()) * stride, 1.0f);
      for (size_t v = 0; v < nv; ++v) {
        float* d = &vertex_data[v * stride];
        std::memcpy(d, &src.positions[v], 12);
        std::memcpy(d + 3, &(*normals)[v], 12);
        d[6] = uvs ? src.uvs[v].x : 0.0f;
        d[7] = uvs ? src.uvs[v].y : 0.0f;
        if (colors) std::memcpy(d + 8, &src.colors[v], 12);
        if (!morphs) continue;
        float* t = d + kOwn;  // the target: the vertex's own value where the level has none
        std::memcpy(t, d, kOwn * 4);
        std::memcpy(t, &morph.positions[v], 12);
        if (!morph.normals.empty()) std::memcpy(t + 3, &morph.normals[v], 12);
        else if (!target_normals.empty()) std::memcpy(t + 3, &target_normals[v], 12);
        if (uvs && !morph.uvs.empty()) std::memcpy(t + 6, &morph.uvs[v], 8);
        if (colors && !morph.colors.empty()) std::memcpy(t + 8, &morph.colors[v], 12);
      }
      for (size_t i = 0; i < copies.size(); ++i) {
        const auto [u, w] = copies[i];
        float* d = &vertex_data[(nv + i) * stride];
        std::memcpy(d, &vertex_data[u * stride], stride * 4);
        float* t = d + kOwn;
        std::memcpy(t + 3, &(*next_normals)[w], 12);
        if (uvs && !morph.uvs.empty() && next->uvs.size() == next->positions.size()) std::memcpy(t + 6, &next->uvs[w], 8);
        if (colors && !morph.colors.empty() && next->colors.size() == next->positions.size()) std::memcpy(t + 8, &next->colors[w], 12);
      }
      glGenBuffers(1, &lg.vbo);
      glBindBuffer(GL_ARRAY_BUFFER, lg.vbo);
      glBufferData(GL_ARRAY_BUFFER, vertex_data.size() * 4, vertex_data.data(), GL_STATIC_DRAW);
      m.gpu_bytes += vertex_data.size() * 4;
      // attributes 0..3 the vertex's own, 4..7 its target (the own ones again without morph data)
      auto vertexArray = [&](GLuint& vao, bool all_attributes) {
        glGenVertexArrays(1, &vao);
        glBindVertexArray(vao);
        glBindBuffer(GL_ARRAY_BUFFER, lg.vbo);
        const GLsizei bytes = static_cast<GLsizei>(stride * 4);
        const uintptr_t target = morphs ? kOwn * 4 : 0;
        const GLint sizes[4] = {3, 3, 2, 3};
        const uintptr_t offsets[4] = {0, 12, 24, 32};
        for (GLuint a = 0; a < 4; ++a) {
          if (a > 0 && !all_attributes) break;
          glEnableVertexAttribArray(a);
          glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, bytes, reinterpret_cast<void*>(offsets[a]));
          glEnableVertexAttribArray(a + 4);
          glVertexAttribPointer(a + 4, sizes[a], GL_FLOAT, GL_FALSE, bytes, reinterpret_cast<void*>(offsets[a] + target));
        }
      };
      auto indexBuffer = [&](GLuint& ibo, const std::vector<uint32_t>& data) {
        glGenBuffers(1, &ibo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, data.size() * 4, data.data(), GL_STATIC_DRAW);
        m.gpu_bytes += data.size() * 4;
      };
      if (!src.triangles.empty()) {
        std::vector<uint32_t> order = groupOrder(src.triangleCount(), src.triangle_groups, mats, 3, lg.tri_ranges);
        // within a group, in the order of the next level's triangles they become (then the rest):
        // coinciding surfaces at factor 1 win their depth ties as in the next level
        if (!match.empty())
          for (const Range& r : lg.tri_ranges)
            std::stable_sort(order.begin() + r.first / 3, order.begin() + (r.first + r.count) / 3,
                             [&](uint32_t a, uint32_t b) { return match[a] < match[b]; });
        indices.clear();
        for (uint32_t t : order) indices.insert(indices.end(), corners.begin() + 3 * t, corners.begin() + 3 * t + 3);
        vertexArray(lg.tri_vao, true);
        indexBuffer(lg.tri_ibo, indices);
        lg.tri_indices = static_cast<GLsizei>(indices.size());
      }
      if (!src.points.empty()) {
        const std::vector<uint32_t> order = groupOrder(src.pointCount(), src.point_groups, mats, 1, lg.point_ranges);
        indices.clear();
        for (uint32_t p : order) indices.push_back(src.points[p]);
        vertexArray(lg.point_vao, false);
        indexBuffer(lg.point_ibo, indices);
        lg.point_indices = static_cast<GLsizei>(indices.size());
      }
      const size_t edge_count = src.edgeCount();
      if (edge_count) {
        // four vertices per edge: (V1, V2, end, side, thickness, 0, T1, T2) with T the endpoints'
        // morph targets (V again without morph data), two triangles
        constexpr size_t kEdgeFloats = 16;
        const std::vector<uint32_t> order = groupOrder(edge_count, src.edge_groups, mats, 6, lg.edge_ranges);
        edge_data.resize(edge_count * 4 * kEdgeFloats);
        indices.resize(edge_count * 6);
        for (size_t k = 0; k < edge_count; ++k) {
          const size_t e = order[k];
          const uint32_t ia = src.edges[2 * e], ib = src.edges[2 * e + 1];
          const glm::vec3& a = src.positions[ia];
          const glm::vec3& b = src.positions[ib];
          const glm::vec3& ta = morphs ? morph.positions[ia] : a;
          const glm::vec3& tb = morphs ? morph.positions[ib] : b;
          const float thickness = src.edgeThickness(e);
          for (int q = 0; q < 4; ++q) {
            float* d = &edge_data[(k * 4 + q) * kEdgeFloats];
            std::memcpy(d, &a, 12);
            std::memcpy(d + 3, &b, 12);
            d[6] = (q == 1 || q == 2) ? 1.0f : 0.0f;  // end
            d[7] = (q < 2) ? -1.0f : 1.0f;            // side
            d[8] = thickness;
            d[9] = 0.0f;
            std::memcpy(d + 10, &ta, 12);
            std::memcpy(d + 13, &tb, 12);
          }
          const uint32_t base = static_cast<uint32_t>(k * 4);
          const uint32_t quad[6] = {base, base + 1, base + 2, base, base + 2, base + 3};
          std::memcpy(&indices[k * 6], quad, sizeof(quad));
        }
        glGenVertexArrays(1, &lg.edge_vao);
        glBindVertexArray(lg.edge_vao);
        glGenBuffers(1, &lg.edge_vbo);
        glBindBuffer(GL_ARRAY_BUFFER, lg.edge_vbo);
        glBufferData(GL_ARRAY_BUFFER, edge_data.size() * 4, edge_data.data(), GL_STATIC_DRAW);
        const GLsizei edge_bytes = kEdgeFloats * 4;
        const GLint sizes[5] = {3, 3, 4, 3, 3};
        const uintptr_t offsets[5] = {0, 12, 24, 40, 52};
        for (GLuint a = 0; a < 5; ++a) {
          glEnableVertexAttribArray(a);
          glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, edge_bytes, reinterpret_cast<void*>(offsets[a]));
        }
        indexBuffer(lg.edge_ibo, indices);
        lg.edge_indices = static_cast<GLsizei>(indices.size());
        m.gpu_bytes += edge_data.size() * 4;
      }
      glBindVertexArray(0);
      gpu.levels.push_back(std::move(lg));
      if (glGetError() != GL_NO_ERROR) {
        m.chains.push_back(std::move(gpu));
        return Error(Status::kOutOfMemory, "GL renderer: a GL error uploading " + what);
      }
    }
    m.chains.push_back(std::move(gpu));
  }
  return {};
}

namespace {

glm::mat4 viewProjection(const selection::Camera& cam, float aspect) {
  glm::mat4 proj;
  if (cam.projection == selection::Projection::kOrthographic) {
    const float h = 0.5f * cam.ortho_height, w = h * aspect;
    proj = glm::ortho(-w, w, -h, h, cam.near_plane, cam.far_plane);
  } else {
    proj = glm::perspective(cam.fov_y_rad, aspect, cam.near_plane, cam.far_plane);
  }
  return proj * glm::lookAt(cam.eye, cam.target, cam.up);
}

// What one pass drew: all of it, and the part drawn by fading objects' previous levels.
struct PassCounters {
  uint64_t triangles = 0, edges = 0, points = 0;
  uint32_t draw_calls = 0;
  uint32_t fading_objects = 0;
  uint64_t fade_triangles = 0, fade_edges = 0, fade_points = 0;
  uint32_t fade_draw_calls = 0;
};

// the uniforms of one range's material: the chain's colour when the chain has no materials, white
// for a range without one; edges and points (no texture coordinates) take the texture's mean
void setMaterial(const Program& p, const ChainGpu& chain, const std::vector<MaterialGpu>& materials, int32_t material,
                 bool textured) {
  glm::vec3 color = chain.materials ? glm::vec3(1.0f) : chain.color;
  const MaterialGpu* mat = chain.materials && material >= 0 && static_cast<size_t>(material) < materials.size()
                               ? &materials[static_cast<size_t>(material)]
                               : nullptr;
  const bool texture = mat && mat->texture && textured;
  if (mat) color = mat->factor * (mat->texture && !textured ? mat->mean_texel : glm::vec3(1.0f));
  glUniform3fv(p.color, 1, glm::value_ptr(color));
  glUniform1i(p.has_texture, texture ? 1 : 0);
  if (texture) {
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, mat->texture);
    glUniformMatrix3fv(p.uv_transform, 1, GL_FALSE, glm::value_ptr(mat->uv_transform));
  }
}

// One pass over the objects: each one's level of `levels` under the camera's matrices, counted in
// `r`. A depth-only pass draws each primitive kind of a level in one call; the colour pass one call
// per material range. The colour pass (`fades`) also draws the cross-fades: the new level keeps
// the pixels whose dither threshold is below the fade, the previous level (unmorphed) the rest.
// The depth pass morphs a level only where it is the object's level in `in.levels`.
void drawObjects(const Program& tri, const Program& edge, const Program& point, const std::vector<ChainGpu>& chains,
                 const std::vector<MaterialGpu>& materials, const FrameInput& in, Span<const int8_t> levels,
                 const selection::Camera& cam, const glm::mat4& view_proj, uint32_t height_px, float point_size,
                 bool depth_only, PassCounters& r) {
  // one pixel in world units at distance d: factor * d + constant (the target's height)
  const float tan_half = std::tan(0.5f * cam.fov_y_rad);
  const float pixel_factor =
      cam.projection == selection::Projection::kPerspective ? 2.0f * tan_half / static_cast<float>(height_px) : 0.0f;
  const float pixel_const =
      cam.projection == selection::Projection::kOrthographic ? cam.ortho_height / static_cast<float>(height_px) : 0.0f;
  for (const Program* p : {&tri, &edge, &point}) {
    glUseProgram(p->id);
    glUniformMatrix4fv(p->view_proj, 1, GL_FALSE, glm::value_ptr(view_proj));
    if (p->eye >= 0) glUniform3fv(p->eye, 1, glm::value_ptr(cam.eye));
    glUniform1i(p->has_texture, 0);
    glUniform1i(p->dither_on, 0);
  }
  glUseProgram(edge.id);
  glUniform1f(edge.pixel_factor, pixel_factor);
  glUniform1f(edge.pixel_const, pixel_const);
  glUseProgram(point.id);
  glUniform1f(point.point_size, point_size);
  bool dithering = false;  // u_dither_on of the three programs
  // each range of `ranges` (or the whole `count` indices in a depth pass) as `mode` primitives
  auto drawRanges = [&](const Program& p, const ChainGpu& chain, const std::vector<Range>& ranges, GLsizei count, GLenum mode,
                        bool textured, uint32_t& draw_calls) {
    if (depth_only) {
      glDrawElements(mode, count, GL_UNSIGNED_INT, nullptr);
      ++draw_calls;
      return;
    }
    for (const Range& range : ranges) {
      setMaterial(p, chain, materials, range.material, textured);
      glDrawElements(mode, range.count, GL_UNSIGNED_INT, reinterpret_cast<void*>(static_cast<uintptr_t>(range.first) * 4));
      ++draw_calls;
    }
  };
  // object o's `level` at morph factor `factor`, its fragments kept where the dither threshold lies
  // in [lo, hi) when `dither`; counted in r's totals and, for a previous level, its fade counters
  auto drawLevel = [&](size_t o, const ChainGpu& chain, const LevelGpu& lg, float factor, bool dither, float lo, float hi,
                       bool previous) {
    if (dither || dithering)
      for (const Program* p : {&tri, &edge, &point}) {
        glUseProgram(p->id);
        glUniform1i(p->dither_on, dither ? 1 : 0);
        if (dither) glUniform2f(p->dither, lo, hi);
      }
    dithering = dither;
    uint32_t calls = 0;
    const glm::mat4& model = in.object_world[o];
    if (lg.tri_indices) {
      const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(model));
      glUseProgram(tri.id);
      glUniformMatrix4fv(tri.model, 1, GL_FALSE, glm::value_ptr(model));
      glUniformMatrix3fv(tri.normal_matrix, 1, GL_FALSE, glm::value_ptr(normal_matrix));
      glUniform1f(tri.morph, factor);
      glBindVertexArray(lg.tri_vao);
      drawRanges(tri, chain, lg.tri_ranges, lg.tri_indices, GL_TRIANGLES, true, calls);
      r.triangles += static_cast<uint64_t>(lg.tri_indices) / 3;
      if (previous) r.fade_triangles += static_cast<uint64_t>(lg.tri_indices) / 3;
    }
    if (lg.edge_indices) {
      const float scale = std::max({glm::length(glm::vec3(model[0])), glm::length(glm::vec3(model[1])),
                                    glm::length(glm::vec3(model[2]))});
      glUseProgram(edge.id);
      glUniformMatrix4fv(edge.model, 1, GL_FALSE, glm::value_ptr(model));
      glUniform1f(edge.scale, scale);
      glUniform1f(edge.morph, factor);
      glBindVertexArray(lg.edge_vao);
      drawRanges(edge, chain, lg.edge_ranges, lg.edge_indices, GL_TRIANGLES, false, calls);
      r.edges += static_cast<uint64_t>(lg.edge_indices) / 6;
      if (previous) r.fade_edges += static_cast<uint64_t>(lg.edge_indices) / 6;
    }
    if (lg.point_indices) {
      glUseProgram(point.id);
      glUniformMatrix4fv(point.model, 1, GL_FALSE, glm::value_ptr(model));
      glUniform1f(point.morph, factor);
      glBindVertexArray(lg.point_vao);
      drawRanges(point, chain, lg.point_ranges, lg.point_indices, GL_POINTS, false, calls);
      r.points += static_cast<uint64_t>(lg.point_indices);
      if (previous) r.fade_points += static_cast<uint64_t>(lg.point_indices);
    }
    r.draw_calls += calls;
    if (previous) r.fade_draw_calls += calls;
  };
  // the chain and level `level` of object o, or null when it draws nothing
  auto find = [&](size_t o, int level, const ChainGpu*& chain) -> const LevelGpu* {
    const uint32_t c = in.object_chain[o];
    if (level < 0 || c >= chains.size() || static_cast<size_t>(level) >= chains[c].levels.size()) return nullptr;
    chain = &chains[c];
    return &chain->levels[static_cast<size_t>(level)];
  };
  for (size_t o = 0; o < levels.count; ++o) {
    const int level = levels[o];
    float factor = in.morph.count ? in.morph[o] : 0.0f;
    if (depth_only && (level != in.levels[o])) factor = 0.0f;
    const float fade = depth_only || !in.fade.count ? 1.0f : in.fade[o];
    const int previous = in.previous_levels.count ? in.previous_levels[o] : -1;
    const ChainGpu* chain = nullptr;
    const LevelGpu* lg = find(o, level, chain);
    if (fade >= 1.0f || previous == level) {  // no fade
      if (lg) drawLevel(o, *chain, *lg, factor, false, 0.0f, 2.0f, false);
      continue;
    }
    ++r.fading_objects;
    if (lg && fade > 0.0f) drawLevel(o, *chain, *lg, factor, true, 0.0f, fade, false);
    const ChainGpu* previous_chain = nullptr;
    if (const LevelGpu* pg = find(o, previous, previous_chain)) drawLevel(o, *previous_chain, *pg, 0.0f, true, fade, 2.0f, true);
  }
  glBindVertexArray(0);
}

}  // namespace

namespace {

// every value in [0, 1] (NaN is not)
bool unitInterval(Span<const float> values) {
  for (size_t i = 0; i < values.count; ++i)
    if (!(values[i] >= 0.0f && values[i] <= 1.0f)) return false;
  return true;
}

}  // namespace

bool Renderer::drawFrame(const FrameInput& in, FrameResult* result) {
  if (!impl_ || !in.camera || in.object_world.count != in.levels.count || in.object_chain.count != in.levels.count)
    return false;
  const size_t n = in.levels.count;
  for (size_t count : {in.morph.count, in.previous_levels.count, in.fade.count})
    if (count != 0 && count != n) return false;
  if (!unitInterval(in.morph) || !unitInterval(in.fade)) return false;
  const bool shadows = in.shadow_camera != nullptr;
  if (shadows && (in.shadow_levels.count != in.levels.count || in.shadow_camera->projection != selection::Projection::kOrthographic))
    return false;
  Impl& m = *impl_;
  if (shadows && !m.makeShadowMap()) return false;
  const selection::Camera& cam = *in.camera;
  const auto t0 = std::chrono::steady_clock::now();
  FrameResult r;
  glm::mat4 shadow_view_proj(1.0f);
  if (shadows) {
    // depth only, from the light; the offset keeps lit surfaces from shadowing themselves
    const selection::Camera& light = *in.shadow_camera;
    shadow_view_proj = viewProjection(light, 1.0f);
    glBindFramebuffer(GL_FRAMEBUFFER, m.shadow_fbo);
    glViewport(0, 0, static_cast<GLsizei>(m.config.shadow_map_px), static_cast<GLsizei>(m.config.shadow_map_px));
    glClear(GL_DEPTH_BUFFER_BIT);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 4.0f);
    for (const Program* p : {&m.tri, &m.edge, &m.point}) {
      glUseProgram(p->id);
      glUniform1i(p->shadow_on, 0);
    }
    PassCounters sc;
    drawObjects(m.tri, m.edge, m.point, m.chains, m.materials, in, in.shadow_levels, light, shadow_view_proj,
                m.config.shadow_map_px, m.config.point_size_px, true, sc);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glViewport(0, 0, static_cast<GLsizei>(m.config.width_px), static_cast<GLsizei>(m.config.height_px));
    r.shadow_triangles = sc.triangles;
    r.shadow_draw_calls = sc.draw_calls;
  }
  const glm::vec3 light_dir = shadows ? glm::normalize(in.shadow_camera->eye - in.shadow_camera->target) : glm::vec3(0.0f, 0.0f, 1.0f);
  for (const Program* p : {&m.tri, &m.edge, &m.point}) {
    glUseProgram(p->id);
    glUniform1i(p->shadow_on, shadows ? 1 : 0);
    glUniformMatrix4fv(p->shadow_view_proj, 1, GL_FALSE, glm::value_ptr(shadow_view_proj));
    glUniform3fv(p->light_dir, 1, glm::value_ptr(light_dir));
  }
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, shadows ? m.shadow_tex : 0);

  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  glClearColor(m.config.background[0], m.config.background[1], m.config.background[2], 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const float aspect = static_cast<float>(m.config.width_px) / static_cast<float>(m.config.height_px);
  PassCounters pc;
  drawObjects(m.tri, m.edge, m.point, m.chains, m.materials, in, in.levels, cam, viewProjection(cam, aspect),
              m.config.height_px, m.config.point_size_px, false, pc);
  glFinish();
  const auto t1 = std::chrono::steady_clock::now();
  r.triangles = pc.triangles;
  r.edges = pc.edges;
  r.points = pc.points;
  r.draw_calls = pc.draw_calls;
  r.fading_objects = pc.fading_objects;
  r.fade_triangles = pc.fade_triangles;
  r.fade_edges = pc.fade_edges;
  r.fade_points = pc.fade_points;
  r.fade_draw_calls = pc.fade_draw_calls;
  r.measured_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  if (result) *result = r;
  return true;
}

Error Renderer::readPixels(eval::Image& out) {
  if (!impl_) return Error(Status::kInvalidArgument, "GL renderer: readPixels before init");
  Impl& m = *impl_;
  const int w = static_cast<int>(m.config.width_px), h = static_cast<int>(m.config.height_px);
  std::vector<uint8_t> rgba(static_cast<size_t>(w) * h * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  if (glGetError() != GL_NO_ERROR) return Error(Status::kUnsupported, "GL renderer: glReadPixels failed");
  out = eval::Image(w, h, 0);
  for (int y = 0; y < h; ++y)  // GL rows go bottom to top
    for (int x = 0; x < w; ++x) {
      const uint8_t* s = &rgba[(static_cast<size_t>(h - 1 - y) * w + x) * 4];
      uint8_t* d = out.pixel(x, y);
      d[0] = s[0];
      d[1] = s[1];
      d[2] = s[2];
    }
  return {};
}

}  // namespace scenelod::gl
