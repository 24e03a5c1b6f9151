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
#include <glm/gtc/type_ptr.hpp>

namespace scenelod::gl {
namespace {

const char kTriangleVs[] = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform mat3 u_normal_matrix;
out vec3 v_normal;
out vec3 v_world;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_world = w.xyz;
  v_normal = u_normal_matrix * a_normal;
  gl_Position = u_view_proj * w;
}
)";

// a_param: x = end (0 at V1, 1 at V2), y = side (-1 or +1), z = thickness (object space)
const char kEdgeVs[] = R"(#version 330 core
layout(location = 0) in vec3 a_v1;
layout(location = 1) in vec3 a_v2;
layout(location = 2) in vec4 a_param;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform vec3 u_eye;
uniform float u_scale;
uniform float u_pixel_factor;
uniform float u_pixel_const;
out vec3 v_normal;
out vec3 v_world;
void main() {
  vec3 w1 = (u_model * vec4(a_v1, 1.0)).xyz;
  vec3 w2 = (u_model * vec4(a_v2, 1.0)).xyz;
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

const char kPointVs[] = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform vec3 u_eye;
uniform float u_point_size;
out vec3 v_normal;
out vec3 v_world;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_world = w.xyz;
  v_normal = u_eye - w.xyz;
  gl_PointSize = u_point_size;
  gl_Position = u_view_proj * w;
}
)";

// a headlight: the light sits at the eye; both sides of a surface are lit. With a shadow map, a
// directional light (u_light_dir, toward the light) adds most of the light where the map sees the
// surface (2x2 percentage-closer filtering by the depth comparison sampler)
const char kFs[] = R"(#version 330 core
in vec3 v_normal;
in vec3 v_world;
uniform vec3 u_eye;
uniform vec3 u_color;
uniform int u_shadow_on;
uniform mat4 u_shadow_view_proj;
uniform vec3 u_light_dir;
uniform sampler2DShadow u_shadow_map;
out vec4 o_color;
void main() {
  float n_len = length(v_normal);
  vec3 to_eye = u_eye - v_world;
  float e_len = length(to_eye);
  float d = (n_len > 0.0 && e_len > 0.0) ? abs(dot(v_normal / n_len, to_eye / e_len)) : 1.0;
  if (u_shadow_on == 0) {
    o_color = vec4(u_color * (0.2 + 0.8 * d), 1.0);
    return;
  }
  vec4 s = u_shadow_view_proj * vec4(v_world, 1.0);
  vec3 p = s.xyz / s.w * 0.5 + 0.5;
  float lit = 1.0;
  if (all(greaterThanEqual(p, vec3(0.0))) && all(lessThanEqual(p, vec3(1.0)))) lit = texture(u_shadow_map, p);
  float l = n_len > 0.0 ? abs(dot(v_normal / n_len, u_light_dir)) : 1.0;
  o_color = vec4(u_color * (0.15 + 0.3 * d + 0.55 * l * lit), 1.0);
}
)";

struct Program {
  GLuint id = 0;
  GLint model = -1, view_proj = -1, normal_matrix = -1, eye = -1, color = -1, scale = -1, pixel_factor = -1,
        pixel_const = -1, point_size = -1, shadow_on = -1, shadow_view_proj = -1, light_dir = -1, shadow_map = -1;
};

struct LevelGpu {
  GLuint vbo = 0, tri_vao = 0, tri_ibo = 0, point_vao = 0, point_ibo = 0;
  GLuint edge_vao = 0, edge_vbo = 0, edge_ibo = 0;
  GLsizei tri_indices = 0, point_indices = 0, edge_indices = 0;
};

struct ChainGpu {
  std::vector<LevelGpu> levels;
  glm::vec3 color{0.8f};
};

Error compileShader(GLenum type, const char* source, const char* name, GLuint& out) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
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
  glUseProgram(p);
  glUniform1i(out.shadow_map, 0);  // texture unit 0
  glUniform1i(out.shadow_on, 0);
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
  size_t gpu_bytes = 0;
  bool ready = false;
  std::string description;

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

Error Renderer::uploadChains(const std::vector<LodChain>& chains) {
  if (!impl_) return Error(Status::kInvalidArgument, "GL renderer: uploadChains before init");
  Impl& m = *impl_;
  m.releaseChains();
  std::vector<float> vertex_data, edge_data;
  std::vector<uint32_t> edge_indices;
  for (size_t c = 0; c < chains.size(); ++c) {
    ChainGpu gpu;
    gpu.color = chainColor(c);
    for (size_t l = 0; l < chains[c].levels.size(); ++l) {
      const Mesh& src = chains[c].levels[l].mesh;
      const std::string what = "chain " + std::to_string(c) + " level " + std::to_string(l);
      if (Error e = validateMesh(src, what); !e.ok()) return Error(e.status, "GL renderer: " + e.message);
      Mesh normals_mesh;
      const std::vector<glm::vec3>* normals = &src.normals;
      if (src.normals.size() != src.positions.size()) {
        normals_mesh.positions = src.positions;
        normals_mesh.triangles = src.triangles;
        computeVertexNormals(normals_mesh);
        normals = &normals_mesh.normals;
      }
      LevelGpu lg;
      vertex_data.resize(src.positions.size() * 6);
      for (size_t v = 0; v < src.positions.size(); ++v) {
        std::memcpy(&vertex_data[v * 6], &src.positions[v], 12);
        std::memcpy(&vertex_data[v * 6 + 3], &(*normals)[v], 12);
      }
      glGenBuffers(1, &lg.vbo);
      glBindBuffer(GL_ARRAY_BUFFER, lg.vbo);
      glBufferData(GL_ARRAY_BUFFER, vertex_data.size() * 4, vertex_data.data(), GL_STATIC_DRAW);
      m.gpu_bytes += vertex_data.size() * 4;
      if (!src.triangles.empty()) {
        glGenVertexArrays(1, &lg.tri_vao);
        glBindVertexArray(lg.tri_vao);
        glBindBuffer(GL_ARRAY_BUFFER, lg.vbo);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 24, reinterpret_cast<void*>(0));
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 24, reinterpret_cast<void*>(12));
        glGenBuffers(1, &lg.tri_ibo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, lg.tri_ibo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, src.triangles.size() * 4, src.triangles.data(), GL_STATIC_DRAW);
        lg.tri_indices = static_cast<GLsizei>(src.triangles.size());
        m.gpu_bytes += src.triangles.size() * 4;
      }
      if (!src.points.empty()) {
        glGenVertexArrays(1, &lg.point_vao);
        glBindVertexArray(lg.point_vao);
        glBindBuffer(GL_ARRAY_BUFFER, lg.vbo);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 24, reinterpret_cast<void*>(0));
        glGenBuffers(1, &lg.point_ibo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, lg.point_ibo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, src.points.size() * 4, src.points.data(), GL_STATIC_DRAW);
        lg.point_indices = static_cast<GLsizei>(src.points.size());
        m.gpu_bytes += src.points.size() * 4;
      }
      const size_t edge_count = src.edgeCount();
      if (edge_count) {
        // four vertices per edge: (V1, V2, end, side, thickness), two triangles
        edge_data.resize(edge_count * 4 * 10);
        edge_indices.resize(edge_count * 6);
        for (size_t e = 0; e < edge_count; ++e) {
          const glm::vec3& a = src.positions[src.edges[2 * e]];
          const glm::vec3& b = src.positions[src.edges[2 * e + 1]];
          const float thickness = src.edgeThickness(e);
          for (int k = 0; k < 4; ++k) {
            float* d = &edge_data[(e * 4 + k) * 10];
            std::memcpy(d, &a, 12);
            std::memcpy(d + 3, &b, 12);
            d[6] = (k == 1 || k == 2) ? 1.0f : 0.0f;  // end
            d[7] = (k < 2) ? -1.0f : 1.0f;            // side
            d[8] = thickness;
            d[9] = 0.0f;
          }
          const uint32_t base = static_cast<uint32_t>(e * 4);
          const uint32_t quad[6] = {base, base + 1, base + 2, base, base + 2, base + 3};
          std::memcpy(&edge_indices[e * 6], quad, sizeof(quad));
        }
        glGenVertexArrays(1, &lg.edge_vao);
        glBindVertexArray(lg.edge_vao);
        glGenBuffers(1, &lg.edge_vbo);
        glBindBuffer(GL_ARRAY_BUFFER, lg.edge_vbo);
        glBufferData(GL_ARRAY_BUFFER, edge_data.size() * 4, edge_data.data(), GL_STATIC_DRAW);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 40, reinterpret_cast<void*>(0));
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 40, reinterpret_cast<void*>(12));
        glEnableVertexAttribArray(2);
        glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 40, reinterpret_cast<void*>(24));
        glGenBuffers(1, &lg.edge_ibo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, lg.edge_ibo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, edge_indices.size() * 4, edge_indices.data(), GL_STATIC_DRAW);
        lg.edge_indices = static_cast<GLsizei>(edge_indices.size());
        m.gpu_bytes += edge_data.size() * 4 + edge_indices.size() * 4;
      }
      glBindVertexArray(0);
      gpu.levels.push_back(lg);
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

// One pass over the objects: each one's level of `levels` under the camera's matrices, counted in
// `triangles`, `edges`, `points`, `draw_calls`.
struct PassCounters {
  uint64_t triangles = 0, edges = 0, points = 0;
  uint32_t draw_calls = 0;
};

void drawObjects(const Program& tri, const Program& edge, const Program& point, const std::vector<ChainGpu>& chains,
                 const FrameInput& in, Span<const int8_t> levels, const selection::Camera& cam, const glm::mat4& view_proj,
                 uint32_t height_px, float point_size, PassCounters& r) {
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
  }
  glUseProgram(edge.id);
  glUniform1f(edge.pixel_factor, pixel_factor);
  glUniform1f(edge.pixel_const, pixel_const);
  glUseProgram(point.id);
  glUniform1f(point.point_size, point_size);
  for (size_t o = 0; o < levels.count; ++o) {
    const int level = levels[o];
    const uint32_t chain = in.object_chain[o];
    if (level < 0 || chain >= chains.size() || static_cast<size_t>(level) >= chains[chain].levels.size()) continue;
    const LevelGpu& lg = chains[chain].levels[static_cast<size_t>(level)];
    const glm::vec3& color = chains[chain].color;
    const glm::mat4& model = in.object_world[o];
    if (lg.tri_indices) {
      const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(model));
      glUseProgram(tri.id);
      glUniformMatrix4fv(tri.model, 1, GL_FALSE, glm::value_ptr(model));
      glUniformMatrix3fv(tri.normal_matrix, 1, GL_FALSE, glm::value_ptr(normal_matrix));
      glUniform3fv(tri.color, 1, glm::value_ptr(color));
      glBindVertexArray(lg.tri_vao);
      glDrawElements(GL_TRIANGLES, lg.tri_indices, GL_UNSIGNED_INT, nullptr);
      r.triangles += static_cast<uint64_t>(lg.tri_indices) / 3;
      ++r.draw_calls;
    }
    if (lg.edge_indices) {
      const float scale = std::max({glm::length(glm::vec3(model[0])), glm::length(glm::vec3(model[1])),
                                    glm::length(glm::vec3(model[2]))});
      glUseProgram(edge.id);
      glUniformMatrix4fv(edge.model, 1, GL_FALSE, glm::value_ptr(model));
      glUniform1f(edge.scale, scale);
      glUniform3fv(edge.color, 1, glm::value_ptr(color));
      glBindVertexArray(lg.edge_vao);
      glDrawElements(GL_TRIANGLES, lg.edge_indices, GL_UNSIGNED_INT, nullptr);
      r.edges += static_cast<uint64_t>(lg.edge_indices) / 6;
      ++r.draw_calls;
    }
    if (lg.point_indices) {
      glUseProgram(point.id);
      glUniformMatrix4fv(point.model, 1, GL_FALSE, glm::value_ptr(model));
      glUniform3fv(point.color, 1, glm::value_ptr(color));
      glBindVertexArray(lg.point_vao);
      glDrawElements(GL_POINTS, lg.point_indices, GL_UNSIGNED_INT, nullptr);
      r.points += static_cast<uint64_t>(lg.point_indices);
      ++r.draw_calls;
    }
  }
  glBindVertexArray(0);
}

}  // namespace

bool Renderer::drawFrame(const FrameInput& in, FrameResult* result) {
  if (!impl_ || !in.camera || in.object_world.count != in.levels.count || in.object_chain.count != in.levels.count)
    return false;
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
    drawObjects(m.tri, m.edge, m.point, m.chains, in, in.shadow_levels, light, shadow_view_proj, m.config.shadow_map_px,
                m.config.point_size_px, sc);
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
  drawObjects(m.tri, m.edge, m.point, m.chains, in, in.levels, cam, viewProjection(cam, aspect), m.config.height_px,
              m.config.point_size_px, pc);
  glFinish();
  const auto t1 = std::chrono::steady_clock::now();
  r.triangles = pc.triangles;
  r.edges = pc.edges;
  r.points = pc.points;
  r.draw_calls = pc.draw_calls;
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
