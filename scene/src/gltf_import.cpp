// glTF 2.0 import (.gltf and .glb) through tinygltf: nodes, transforms, meshes with every primitive
// merged into one Mesh, base colours baked per vertex, and MSFT_lod chains read back.
// Every accessor, buffer view and index is checked here before it is read; tinygltf only parses.
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <stb_image.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "scenelod/lodcore/json_limits.h"
#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::scene {

namespace {

// ---------------------------------------------------------------------------------------------
// file access: every external URI must resolve inside the glTF file's folder

struct LoadContext {
  std::string folder;       // realpath of the file's folder, no trailing slash
  std::string refused;      // message for the first refused URI
  std::vector<glm::vec3> image_average;  // linear mean colour per image
  std::vector<char> image_decoded;
};

bool readFileBytes(const std::string& path, std::vector<unsigned char>& out, std::string& err) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    err = std::strerror(errno);
    return false;
  }
  struct stat st;
  if (::fstat(::fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
    std::fclose(f);
    err = "not a regular file";
    return false;
  }
  std::fseek(f, 0, SEEK_END);
  const long size = std::ftell(f);
  std::rewind(f);
  if (size < 0) {
    std::fclose(f);
    err = "cannot tell the file size";
    return false;
  }
  out.resize(static_cast<size_t>(size));
  const size_t got = size > 0 ? std::fread(out.data(), 1, out.size(), f) : 0;
  std::fclose(f);
  if (got != out.size()) {
    err = "read error";
    return false;
  }
  return true;
}

bool hasDotDotSegment(const std::string& rel) {
  size_t start = 0;
  while (start <= rel.size()) {
    size_t end = rel.find_first_of("/\\", start);
    if (end == std::string::npos) end = rel.size();
    if (rel.compare(start, end - start, "..") == 0 && end - start == 2) return true;
    start = end + 1;
  }
  return false;
}

// checks a path tinygltf built as folder + "/" + uri; false (and a message) when it is refused
bool allowedPath(LoadContext& ctx, const std::string& joined) {
  const std::string prefix = ctx.folder + "/";
  if (joined.compare(0, prefix.size(), prefix) != 0) return false;  // tinygltf's "." fallback: never
  const std::string rel = joined.substr(prefix.size());
  const bool drive = rel.size() >= 3 && std::isalpha(static_cast<unsigned char>(rel[0])) && rel[1] == ':' &&
                     (rel[2] == '/' || rel[2] == '\\');
  if (!rel.empty() && (rel[0] == '/' || rel[0] == '\\' || drive)) {
    if (ctx.refused.empty())
      ctx.refused = "external URI '" + rel + "' is an absolute path; only files inside the glTF file's folder are read";
    return false;
  }
  if (hasDotDotSegment(rel)) {
    if (ctx.refused.empty())
      ctx.refused = "external URI '" + rel + "' escapes the glTF file's folder with '..'; only files inside it are read";
    return false;
  }
  char* real = ::realpath(joined.c_str(), nullptr);
  if (!real) return false;  // missing: tinygltf reports it
  const std::string r(real);
  std::free(real);
  if (r.compare(0, prefix.size(), prefix) != 0) {
    if (ctx.refused.empty())
      ctx.refused = "external URI '" + rel + "' resolves outside the glTF file's folder (through a link)";
    return false;
  }
  return true;
}

bool fsFileExists(const std::string& path, void* user) {
  LoadContext& ctx = *static_cast<LoadContext*>(user);
  if (!allowedPath(ctx, path)) return false;
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

std::string fsExpandFilePath(const std::string& path, void*) { return path; }

bool fsReadWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  LoadContext& ctx = *static_cast<LoadContext*>(user);
  if (!allowedPath(ctx, path)) {
    if (err) *err = "refused";
    return false;
  }
  std::string e;
  if (!readFileBytes(path, *out, e)) {
    if (err) *err = e;
    return false;
  }
  return true;
}

bool fsWriteWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err = "the importer does not write files";
  return false;
}

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

// decodes an image only to average its texels (sRGB -> linear first); the pixels are not kept
bool averageImage(tinygltf::Image* image, const int image_idx, std::string*, std::string* warn, int, int,
                  const unsigned char* bytes, int size, void* user) {
  LoadContext& ctx = *static_cast<LoadContext*>(user);
  if (image_idx < 0) return true;
  if (static_cast<size_t>(image_idx) >= ctx.image_average.size()) {
    ctx.image_average.resize(static_cast<size_t>(image_idx) + 1, glm::vec3(1.0f));
    ctx.image_decoded.resize(static_cast<size_t>(image_idx) + 1, 0);
  }
  int w = 0, h = 0, comp = 0;
  unsigned char* px = stbi_load_from_memory(bytes, size, &w, &h, &comp, 3);
  if (!px) {
    if (warn) *warn += "image " + std::to_string(image_idx) + " could not be decoded\n";
    return true;  // the material keeps a white average; geometry is unaffected
  }
  static const std::array<float, 256> lut = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[static_cast<size_t>(i)] = srgbToLinear(static_cast<float>(i) / 255.0f);
    return t;
  }();
  double sum[3] = {0.0, 0.0, 0.0};
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) sum[k] += lut[px[3 * i + static_cast<size_t>(k)]];
  stbi_image_free(px);
  if (n > 0)
    ctx.image_average[static_cast<size_t>(image_idx)] =
        glm::vec3(static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n), static_cast<float>(sum[2] / n));
  ctx.image_decoded[static_cast<size_t>(image_idx)] = 1;
  image->width = w;
  image->height = h;
  image->component = comp;
  image->bits = 8;
  return true;
}

// ---------------------------------------------------------------------------------------------
// GLB container checks (before tinygltf, so truncation gets a precise message)

uint32_t readU32(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

Error checkGlbContainer(const std::string& path, const std::vector<unsigned char>& data) {
  const size_t n = data.size();
  if (n < 12) return {Status::kCorrupt, path + ": truncated GLB: " + std::to_string(n) + " bytes, the header alone needs 12"};
  if (std::memcmp(data.data(), "glTF", 4) != 0) return {Status::kParseError, path + ": not a GLB file (no 'glTF' magic)"};
  const uint32_t version = readU32(&data[4]), length = readU32(&data[8]);
  if (version != 2)
    return {Status::kUnsupported, path + ": GLB version " + std::to_string(version) + " (only glTF 2.0 is read)"};
  if (length > n)
    return {Status::kCorrupt, path + ": truncated GLB: the header says " + std::to_string(length) + " bytes, the file has " +
                                  std::to_string(n)};
  size_t off = 12;
  int chunk = 0;
  while (off < length) {
    if (length - off < 8)
      return {Status::kCorrupt, path + ": truncated GLB: chunk " + std::to_string(chunk) + " header is cut off"};
    const uint32_t chunk_len = readU32(&data[off]);
    if (chunk_len > length - off - 8)
      return {Status::kCorrupt, path + ": truncated GLB: chunk " + std::to_string(chunk) + " says " + std::to_string(chunk_len) +
                                    " bytes, only " + std::to_string(length - off - 8) + " remain"};
    off += 8 + static_cast<size_t>(chunk_len);
    ++chunk;
  }
  if (chunk == 0) return {Status::kCorrupt, path + ": GLB has no JSON chunk"};
  return {};
}

// ---------------------------------------------------------------------------------------------
// accessors

struct AccessorView {
  const unsigned char* data = nullptr;  // null: all zeros (no buffer view)
  size_t stride = 0;
  size_t count = 0;
  int component_type = 0;
  int component_count = 0;
  bool normalized = false;
};

int componentSize(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

// a stored integer as glTF reads it: normalised, signed types map to [-1, 1] (the most negative value
// clamped to -1) and unsigned ones to [0, 1]
template <class T>
double readInteger(const unsigned char* p, bool normalized) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  if (!normalized) return v;
  const double n = v / static_cast<double>(std::numeric_limits<T>::max());
  return std::is_signed<T>::value ? std::max(n, -1.0) : n;
}

double readComponent(const unsigned char* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return readInteger<int8_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return readInteger<uint8_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_SHORT: return readInteger<int16_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return readInteger<uint16_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_INT: return readInteger<int32_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return readInteger<uint32_t>(p, normalized);
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

// an accessor without a buffer view (zeros, maybe sparse) holds no data to bound its size: at most
// this many values (128 MiB as doubles), whatever its type
constexpr size_t kMaxUnbackedValues = size_t(1) << 24;

class GltfReader {
 public:
  GltfReader(const std::string& path, const tinygltf::Model& model, const LoadContext& ctx)
      : path_(path), model_(model), ctx_(ctx) {}

  Error fail(Status s, const std::string& what) const { return {s, path_ + ": " + what}; }

  // resolves a buffer view range; `what` names the user of the view
  Error viewBytes(int view_index, size_t offset, size_t stride, size_t count, size_t elem_size, const std::string& what,
                  const unsigned char*& out, size_t& out_stride) const {
    if (view_index < 0 || static_cast<size_t>(view_index) >= model_.bufferViews.size())
      return fail(Status::kInvalidMesh, what + ": buffer view " + std::to_string(view_index) + " out of range (the file has " +
                                            std::to_string(model_.bufferViews.size()) + ")");
    const tinygltf::BufferView& bv = model_.bufferViews[static_cast<size_t>(view_index)];
    if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= model_.buffers.size())
      return fail(Status::kInvalidMesh, "buffer view " + std::to_string(view_index) + ": buffer " + std::to_string(bv.buffer) +
                                            " out of range (the file has " + std::to_string(model_.buffers.size()) + ")");
    const tinygltf::Buffer& buf = model_.buffers[static_cast<size_t>(bv.buffer)];
    if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
      return fail(Status::kCorrupt, "buffer view " + std::to_string(view_index) + " (bytes " + std::to_string(bv.byteOffset) +
                                        " to " + std::to_string(bv.byteOffset + bv.byteLength) + ") is out of range of buffer " +
                                        std::to_string(bv.buffer) + " (" + std::to_string(buf.data.size()) +
                                        " bytes): truncated buffer?");
    out_stride = stride ? stride : (bv.byteStride ? bv.byteStride : elem_size);
    if (out_stride < elem_size)
      return fail(Status::kInvalidMesh, what + ": byte stride " + std::to_string(out_stride) + " of buffer view " +
                                            std::to_string(view_index) + " is smaller than the element (" +
                                            std::to_string(elem_size) + " bytes)");
    if (count > 0) {
      const size_t need = (count - 1) * out_stride + elem_size;
      if (offset > bv.byteLength || need > bv.byteLength - offset)
        return fail(Status::kInvalidMesh, what + " reads past the end of buffer view " + std::to_string(view_index) + " (needs " +
                                              std::to_string(offset + need) + " bytes, the view has " +
                                              std::to_string(bv.byteLength) + ")");
    }
    out = buf.data.data() + bv.byteOffset + offset;
    return {};
  }

  // reads accessor `index` as doubles, `component_count` per element, sparse values applied
  Error readAccessor(int index, const std::string& user, std::vector<double>& out, int& component_count,
                     int& component_type) const {
    const std::string what = user + ": accessor " + std::to_string(index);
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
      return fail(Status::kInvalidMesh, user + ": accessor " + std::to_string(index) + " out of range (the file has " +
                                            std::to_string(model_.accessors.size()) + " accessors)");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    const int csize = componentSize(a.componentType);
    if (csize == 0) return fail(Status::kParseError, what + " has unknown component type " + std::to_string(a.componentType));
    const int ccount = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    if (ccount <= 0) return fail(Status::kParseError, what + " has unknown type " + std::to_string(a.type));
    if (a.count > (size_t(1) << 31)) return fail(Status::kInvalidMesh, what + " has an implausible count " + std::to_string(a.count));
    component_count = ccount;
    component_type = a.componentType;
    const size_t elem = static_cast<size_t>(csize) * static_cast<size_t>(ccount);
    // the range check comes before any allocation, so a corrupt count cannot ask for gigabytes
    const unsigned char* p = nullptr;
    size_t stride = 0;
    if (a.bufferView >= 0) {
      if (Error e = viewBytes(a.bufferView, a.byteOffset, 0, a.count, elem, what, p, stride); !e.ok()) return e;
    } else if (a.count > kMaxUnbackedValues / static_cast<size_t>(ccount)) {
      return fail(Status::kInvalidMesh, what + " has no buffer view and an implausible count " + std::to_string(a.count));
    }
    out.assign(a.count * static_cast<size_t>(ccount), 0.0);
    if (p) {
      for (size_t i = 0; i < a.count; ++i)
        for (int k = 0; k < ccount; ++k)
          out[i * static_cast<size_t>(ccount) + static_cast<size_t>(k)] =
              readComponent(p + i * stride + static_cast<size_t>(k * csize), a.componentType, a.normalized);
    }
    if (a.sparse.isSparse) {
      const size_t n = static_cast<size_t>(std::max(a.sparse.count, 0));
      const int isize = componentSize(a.sparse.indices.componentType);
      if (isize == 0 || a.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
        return fail(Status::kParseError, what + " has sparse indices of unknown component type");
      const unsigned char* ip = nullptr;
      const unsigned char* vp = nullptr;
      size_t istride = 0, vstride = 0;
      if (Error e = viewBytes(a.sparse.indices.bufferView, static_cast<size_t>(std::max(a.sparse.indices.byteOffset, 0)),
                              static_cast<size_t>(isize), n, static_cast<size_t>(isize), what + " sparse indices", ip, istride); !e.ok())
        return e;
      if (Error e = viewBytes(a.sparse.values.bufferView, static_cast<size_t>(std::max(a.sparse.values.byteOffset, 0)), elem, n,
                              elem, what + " sparse values", vp, vstride); !e.ok())
        return e;
      for (size_t i = 0; i < n; ++i) {
        const double target = readComponent(ip + i * istride, a.sparse.indices.componentType, false);
        if (!(target >= 0.0) || target >= static_cast<double>(a.count))
          return fail(Status::kInvalidMesh, what + ": sparse index " + std::to_string(static_cast<long long>(target)) +
                                                " is not below the accessor count " + std::to_string(a.count));
        const size_t t = static_cast<size_t>(target);
        for (int k = 0; k < ccount; ++k)
          out[t * static_cast<size_t>(ccount) + static_cast<size_t>(k)] =
              readComponent(vp + i * vstride + static_cast<size_t>(k * csize), a.componentType, a.normalized);
      }
    }
    return {};
  }

  Error readVec(int index, const std::string& user, const char* semantic, int min_comps, int max_comps,
                std::vector<double>& out, int& comps) const {
    int ctype = 0;
    if (Error e = readAccessor(index, user + " " + semantic, out, comps, ctype); !e.ok()) return e;
    if (comps < min_comps || comps > max_comps)
      return fail(Status::kInvalidMesh, user + " " + semantic + ": accessor " + std::to_string(index) + " has " +
                                            std::to_string(comps) + " components per element, expected " +
                                            (min_comps == max_comps ? std::to_string(min_comps)
                                                                    : std::to_string(min_comps) + " to " + std::to_string(max_comps)));
    return {};
  }

  Error readIndices(int index, const std::string& user, std::vector<uint32_t>& out) const {
    std::vector<double> v;
    int comps = 0, ctype = 0;
    if (Error e = readAccessor(index, user + " indices", v, comps, ctype); !e.ok()) return e;
    if (comps != 1 || ctype == TINYGLTF_COMPONENT_TYPE_FLOAT)
      return fail(Status::kInvalidMesh, user + " indices: accessor " + std::to_string(index) +
                                            " must hold integer scalars");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    if (a.normalized) return fail(Status::kInvalidMesh, user + " indices: accessor " + std::to_string(index) + " is normalized");
    out.resize(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
      if (v[i] < 0.0) return fail(Status::kInvalidMesh, user + " indices: index " + std::to_string(i) + " is negative");
      out[i] = static_cast<uint32_t>(v[i]);
    }
    return {};
  }

  glm::vec3 materialColor(int material, bool& has_material) const {
    has_material = material >= 0;
    if (material < 0) return glm::vec3(1.0f);
    const MaterialData& m = materials_[static_cast<size_t>(material)];
    return glm::vec3(m.base_color) * (m.textured ? m.average_texel_color : glm::vec3(1.0f));
  }

  Error readMaterials(std::vector<MaterialData>& out) {
    out.clear();
    for (size_t i = 0; i < model_.materials.size(); ++i) {
      const tinygltf::Material& src = model_.materials[i];
      MaterialData m;
      m.name = src.name;
      const auto& f = src.pbrMetallicRoughness.baseColorFactor;
      if (f.size() == 4) m.base_color = glm::vec4(float(f[0]), float(f[1]), float(f[2]), float(f[3]));
      const int tex = src.pbrMetallicRoughness.baseColorTexture.index;
      if (tex >= 0) {
        if (static_cast<size_t>(tex) >= model_.textures.size())
          return fail(Status::kInvalidMesh, "material " + std::to_string(i) + ": texture " + std::to_string(tex) +
                                                " out of range (the file has " + std::to_string(model_.textures.size()) + ")");
        const int img = model_.textures[static_cast<size_t>(tex)].source;
        if (img >= static_cast<int>(model_.images.size()))
          return fail(Status::kInvalidMesh, "texture " + std::to_string(tex) + ": image " + std::to_string(img) + " out of range");
        m.textured = true;
        if (img >= 0 && static_cast<size_t>(img) < ctx_.image_decoded.size() && ctx_.image_decoded[static_cast<size_t>(img)])
          m.average_texel_color = ctx_.image_average[static_cast<size_t>(img)];
      }
      if (!std::isfinite(m.base_color.x) || !std::isfinite(m.base_color.y) || !std::isfinite(m.base_color.z))
        return fail(Status::kInvalidMesh, "material " + std::to_string(i) + ": non-finite base colour factor");
      out.push_back(m);
    }
    materials_ = out;
    return {};
  }

  // what readMesh gathers over a mesh's primitives before it sets the mesh's optional attributes
  struct MeshBuild {
    struct Vertices {
      uint32_t offset, count;
    };
    std::map<std::tuple<int, int, int, int, int>, Vertices> shared;  // attribute accessors + material -> vertices
    std::vector<char> has_normal;
    bool any_normal = false, any_uv = false, any_color = false, any_thickness = false;
    std::vector<glm::vec3> vertex_color;
    std::vector<float> edge_thickness;  // one per edge, from its own primitive's _THICKNESS
  };
  // a primitive's attribute accessors, -1 when absent
  struct Attributes {
    int position, normal, uv, color, thickness;
  };

  // appends the vertices of one primitive's attributes (POSITION, NORMAL, TEXCOORD_0, COLOR_0 times
  // the material colour) to `m`, from `base` on; `count` is their number
  Error readVertices(const tinygltf::Primitive& p, const Attributes& a, const std::string& what, const std::string& mesh_what,
                     Mesh& m, MeshBuild& b, uint32_t& base, uint32_t& count) const {
    std::vector<double> v;
    int comps = 0;
    if (Error e = readVec(a.position, what, "POSITION", 3, 3, v, comps); !e.ok()) return e;
    count = static_cast<uint32_t>(v.size() / 3);
    if (m.positions.size() + count > (size_t(1) << 31)) return fail(Status::kUnsupported, mesh_what + ": too many vertices");
    base = static_cast<uint32_t>(m.positions.size());
    for (uint32_t i = 0; i < count; ++i) {
      const glm::vec3 q{float(v[3 * i]), float(v[3 * i + 1]), float(v[3 * i + 2])};
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
        return fail(Status::kInvalidMesh, what + " POSITION: accessor " + std::to_string(a.position) + " element " +
                                              std::to_string(i) + " has a NaN or infinite coordinate");
      m.positions.push_back(q);
    }
    m.normals.resize(m.positions.size(), glm::vec3(0.0f));
    b.has_normal.resize(m.positions.size(), 0);
    if (a.normal >= 0) {
      if (Error e = readVec(a.normal, what, "NORMAL", 3, 3, v, comps); !e.ok()) return e;
      if (v.size() / 3 != count)
        return fail(Status::kInvalidMesh, what + ": NORMAL has " + std::to_string(v.size() / 3) + " elements, POSITION " +
                                              std::to_string(count));
      for (uint32_t i = 0; i < count; ++i) {
        const glm::vec3 n{float(v[3 * i]), float(v[3 * i + 1]), float(v[3 * i + 2])};
        if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
          return fail(Status::kInvalidMesh, what + " NORMAL: element " + std::to_string(i) + " is NaN or infinite");
        m.normals[base + i] = n;
        b.has_normal[base + i] = 1;
      }
      b.any_normal = true;
    }
    m.uvs.resize(m.positions.size(), glm::vec2(0.0f));
    if (a.uv >= 0) {
      if (Error e = readVec(a.uv, what, "TEXCOORD_0", 2, 2, v, comps); !e.ok()) return e;
      if (v.size() / 2 != count)
        return fail(Status::kInvalidMesh, what + ": TEXCOORD_0 has " + std::to_string(v.size() / 2) + " elements, POSITION " +
                                              std::to_string(count));
      for (uint32_t i = 0; i < count; ++i) m.uvs[base + i] = glm::vec2(float(v[2 * i]), float(v[2 * i + 1]));
      b.any_uv = true;
    }
    bool has_material = false;
    const glm::vec3 mat_color = materialColor(p.material, has_material);
    b.vertex_color.resize(m.positions.size(), mat_color);
    if (has_material) b.any_color = true;
    if (a.color >= 0) {
      if (Error e = readVec(a.color, what, "COLOR_0", 3, 4, v, comps); !e.ok()) return e;
      if (v.size() / static_cast<size_t>(comps) != count)
        return fail(Status::kInvalidMesh, what + ": COLOR_0 has " + std::to_string(v.size() / static_cast<size_t>(comps)) +
                                              " elements, POSITION " + std::to_string(count));
      for (uint32_t i = 0; i < count; ++i) {
        const size_t o = static_cast<size_t>(i) * static_cast<size_t>(comps);
        b.vertex_color[base + i] = mat_color * glm::vec3(float(v[o]), float(v[o + 1]), float(v[o + 2]));
      }
      b.any_color = true;
    }
    return {};
  }

  // a primitive's indices (0 .. count - 1 when it has none), each checked against its vertex count
  Error readPrimitiveIndices(const tinygltf::Primitive& p, uint32_t count, const std::string& what,
                             std::vector<uint32_t>& idx) const {
    if (p.indices < 0) {
      idx.resize(count);
      for (uint32_t i = 0; i < count; ++i) idx[i] = i;
      return {};
    }
    if (Error e = readIndices(p.indices, what, idx); !e.ok()) return e;
    for (size_t i = 0; i < idx.size(); ++i)
      if (idx[i] >= count)
        return fail(Status::kInvalidMesh, what + ": index " + std::to_string(i) + " is " + std::to_string(idx[i]) +
                                              ", not below the vertex count " + std::to_string(count));
    return {};
  }

  // appends a primitive's triangles (strips and fans as triangles), edges or points to `m`;
  // `thickness` is per vertex of the primitive when it has a _THICKNESS attribute (`has_thickness`)
  Error addPrimitive(int mode, const std::vector<uint32_t>& idx, uint32_t base, const std::vector<double>& thickness,
                     bool has_thickness, const std::string& what, Mesh& m, MeshBuild& b) const {
    // per-vertex thickness to per-edge: the mean of the two ends (equal for files we write)
    auto addEdge = [&](uint32_t i, uint32_t j) {
      m.edges.insert(m.edges.end(), {base + i, base + j});
      b.edge_thickness.push_back(thickness.empty() ? 0.0f : static_cast<float>(0.5 * (thickness[i] + thickness[j])));
    };
    const size_t n = idx.size();
    switch (mode) {
      case TINYGLTF_MODE_TRIANGLES:
        if (n % 3 != 0)
          return fail(Status::kInvalidMesh, what + ": TRIANGLES with " + std::to_string(n) + " indices (not a multiple of 3)");
        for (uint32_t i : idx) m.triangles.push_back(base + i);
        break;
      case TINYGLTF_MODE_TRIANGLE_STRIP:
        // triangle i is (i, i+1, i+2) for even i and (i, i+2, i+1) for odd i (glTF 2.0 §3.7.2.1)
        for (size_t i = 0; i + 2 < n; ++i) {
          const bool odd = i % 2 == 1;
          m.triangles.insert(m.triangles.end(), {base + idx[i], base + idx[odd ? i + 2 : i + 1], base + idx[odd ? i + 1 : i + 2]});
        }
        break;
      case TINYGLTF_MODE_TRIANGLE_FAN:
        for (size_t i = 1; i + 1 < n; ++i) m.triangles.insert(m.triangles.end(), {base + idx[i], base + idx[i + 1], base + idx[0]});
        break;
      case TINYGLTF_MODE_LINE:
        if (n % 2 != 0)
          return fail(Status::kInvalidMesh, what + ": LINES with " + std::to_string(n) + " indices (not a multiple of 2)");
        for (size_t i = 0; i < n; i += 2) addEdge(idx[i], idx[i + 1]);
        b.any_thickness |= has_thickness;
        break;
      case TINYGLTF_MODE_LINE_STRIP:
      case TINYGLTF_MODE_LINE_LOOP:
        for (size_t i = 0; i + 1 < n; ++i) addEdge(idx[i], idx[i + 1]);
        if (mode == TINYGLTF_MODE_LINE_LOOP && n > 2) addEdge(idx[n - 1], idx[0]);
        b.any_thickness |= has_thickness;
        break;
      case TINYGLTF_MODE_POINTS:
        for (uint32_t i : idx) m.points.push_back(base + i);
        break;
      default: break;
    }
    return {};
  }

  Error readMesh(size_t mesh_index, MeshData& out) const {
    const tinygltf::Mesh& src = model_.meshes[mesh_index];
    out = MeshData{};
    out.name = src.name;
    Mesh& m = out.mesh;
    const std::string mesh_what = "mesh " + std::to_string(mesh_index) + (src.name.empty() ? "" : " '" + src.name + "'");
    MeshBuild b;
    for (size_t pi = 0; pi < src.primitives.size(); ++pi) {
      const tinygltf::Primitive& p = src.primitives[pi];
      const std::string what = mesh_what + " primitive " + std::to_string(pi);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      if (mode > TINYGLTF_MODE_TRIANGLE_FAN)
        return fail(Status::kUnsupported, what + ": unsupported primitive mode " + std::to_string(mode));
      if (p.material >= static_cast<int>(materials_.size()))
        return fail(Status::kInvalidMesh, what + ": material " + std::to_string(p.material) + " out of range (the file has " +
                                              std::to_string(materials_.size()) + ")");
      if (p.extensions.count("KHR_draco_mesh_compression"))
        return fail(Status::kUnsupported, what + ": Draco-compressed primitives (KHR_draco_mesh_compression) are not supported");
      auto attr = [&](const char* name) {
        auto it = p.attributes.find(name);
        return it == p.attributes.end() ? -1 : it->second;
      };
      const Attributes a{attr("POSITION"), attr("NORMAL"), attr("TEXCOORD_0"), attr("COLOR_0"), attr("_THICKNESS")};
      if (a.position < 0) return fail(Status::kInvalidMesh, what + " has no POSITION attribute");
      out.primitive_materials.push_back(p.material);

      const auto key = std::make_tuple(a.position, a.normal, a.uv, a.color, p.material);
      uint32_t base = 0, count = 0;
      auto found = b.shared.find(key);
      if (found != b.shared.end()) {
        base = found->second.offset;
        count = found->second.count;
      } else {
        if (Error e = readVertices(p, a, what, mesh_what, m, b, base, count); !e.ok()) return e;
        b.shared.emplace(key, MeshBuild::Vertices{base, count});
      }
      std::vector<double> thickness;  // per vertex of this primitive, when it has _THICKNESS
      if (a.thickness >= 0) {
        int comps = 0;
        if (Error e = readVec(a.thickness, what, "_THICKNESS", 1, 1, thickness, comps); !e.ok()) return e;
        if (thickness.size() != count)
          return fail(Status::kInvalidMesh, what + ": _THICKNESS has " + std::to_string(thickness.size()) + " elements, POSITION " +
                                                std::to_string(count));
        for (uint32_t i = 0; i < count; ++i) {
          if (!std::isfinite(thickness[i]) || thickness[i] < 0.0)
            return fail(Status::kInvalidMesh, what + " _THICKNESS: element " + std::to_string(i) + " is negative or not finite");
        }
      }
      std::vector<uint32_t> idx;
      if (Error e = readPrimitiveIndices(p, count, what, idx); !e.ok()) return e;
      if (Error e = addPrimitive(mode, idx, base, thickness, a.thickness >= 0, what, m, b); !e.ok()) return e;
    }
    if (b.any_thickness) m.edge_thickness = std::move(b.edge_thickness);
    if (!b.any_uv) m.uvs.clear();
    if (b.any_color) m.colors = std::move(b.vertex_color);
    if (!b.any_normal) {
      m.normals.clear();
    } else if (std::find(b.has_normal.begin(), b.has_normal.end(), 0) != b.has_normal.end()) {
      // primitives without NORMAL next to ones with: area-weighted normals for the missing ones
      Mesh tmp;
      tmp.positions = m.positions;
      tmp.triangles = m.triangles;
      computeVertexNormals(tmp);
      for (size_t i = 0; i < b.has_normal.size(); ++i)
        if (!b.has_normal[i]) m.normals[i] = tmp.normals[i];
    }
    return {};
  }

  Error readNodes(SceneData& out) const {
    const size_t n = model_.nodes.size();
    out.nodes.assign(n, NodeData{});
    for (size_t i = 0; i < n; ++i) {
      const tinygltf::Node& src = model_.nodes[i];
      NodeData& node = out.nodes[i];
      const std::string what = "node " + std::to_string(i);
      node.name = src.name;
      if (src.mesh >= static_cast<int>(model_.meshes.size()))
        return fail(Status::kInvalidMesh, what + ": mesh " + std::to_string(src.mesh) + " out of range (the file has " +
                                              std::to_string(model_.meshes.size()) + ")");
      node.mesh = src.mesh < 0 ? -1 : src.mesh;
      if (src.matrix.size() == 16) {
        float v[16];
        for (int k = 0; k < 16; ++k) v[k] = static_cast<float>(src.matrix[static_cast<size_t>(k)]);
        node.local = glm::make_mat4(v);  // glTF matrices are column-major, as glm's
      } else {
        glm::mat4 t(1.0f);
        if (src.translation.size() == 3)
          t = glm::translate(t, glm::vec3(float(src.translation[0]), float(src.translation[1]), float(src.translation[2])));
        if (src.rotation.size() == 4)
          t = t * glm::mat4_cast(glm::quat(float(src.rotation[3]), float(src.rotation[0]), float(src.rotation[1]),
                                           float(src.rotation[2])));
        if (src.scale.size() == 3) t = glm::scale(t, glm::vec3(float(src.scale[0]), float(src.scale[1]), float(src.scale[2])));
        node.local = t;
      }
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
          if (!std::isfinite(node.local[c][r]))
            return fail(Status::kInvalidMesh, what + " has a NaN or infinite transform");
      for (int c : src.children) {
        if (c < 0 || static_cast<size_t>(c) >= n)
          return fail(Status::kInvalidMesh, what + ": child " + std::to_string(c) + " out of range (the file has " +
                                                std::to_string(n) + " nodes)");
        if (out.nodes[static_cast<size_t>(c)].parent >= 0)
          return fail(Status::kInvalidMesh, "node " + std::to_string(c) + " is a child of both node " +
                                                std::to_string(out.nodes[static_cast<size_t>(c)].parent) + " and node " +
                                                std::to_string(i));
        out.nodes[static_cast<size_t>(c)].parent = static_cast<int32_t>(i);
        node.children.push_back(c);
      }
    }
    // roots: the default scene (scene 0 when none is named); all parentless nodes when there is no scene
    out.roots.clear();
    if (!model_.scenes.empty()) {
      const int s = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (static_cast<size_t>(s) >= model_.scenes.size())
        return fail(Status::kInvalidMesh, "default scene " + std::to_string(s) + " out of range");
      for (int r : model_.scenes[static_cast<size_t>(s)].nodes) {
        if (r < 0 || static_cast<size_t>(r) >= n)
          return fail(Status::kInvalidMesh, "scene " + std::to_string(s) + ": node " + std::to_string(r) + " out of range");
        if (out.nodes[static_cast<size_t>(r)].parent >= 0)
          return fail(Status::kInvalidMesh, "scene " + std::to_string(s) + ": root node " + std::to_string(r) + " has a parent");
        out.roots.push_back(r);
      }
    } else {
      for (size_t i = 0; i < n; ++i)
        if (out.nodes[i].parent < 0) out.roots.push_back(static_cast<int32_t>(i));
    }
    return {};
  }

 private:
  std::string path_;
  const tinygltf::Model& model_;
  const LoadContext& ctx_;
  std::vector<MaterialData> materials_;
};

// ---------------------------------------------------------------------------------------------
// hostile JSON, checked before tinygltf sees it: tinygltf recurses once per nesting level (20,000
// levels overflow the stack) and narrows sizes into int or converts doubles into size_t, so that
// 2^32 + 1 reads as 1 and 1e300 as 0. Each size and offset scenelod reads must be a whole number
// in range.

// the JSON text of a .gltf, or the first chunk of a checked GLB
std::pair<const char*, size_t> gltfJsonText(const std::vector<unsigned char>& data, bool binary) {
  const char* text = reinterpret_cast<const char*>(data.data());
  if (!binary) return {text, data.size()};
  return {text + 20, std::min<size_t>(readU32(&data[12]), data.size() - 20)};
}

Error checkGltfJson(const std::string& path, const std::vector<unsigned char>& data, bool binary) {
  const auto [text, size] = gltfJsonText(data, binary);
  if (jsonNestingDepth(text, size) > kMaxJsonNesting)
    return {Status::kParseError, path + ": JSON nested deeper than " + std::to_string(kMaxJsonNesting) + " levels"};
  const nlohmann::json j = nlohmann::json::parse(text, text + size, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return {};  // tinygltf reports malformed JSON in its words
  // (array, key, smallest value): the members tinygltf narrows
  struct Field {
    const char* array;
    const char* key;
    int64_t lo;
  };
  const Field fields[] = {{"accessors", "count", 1},       {"accessors", "byteOffset", 0}, {"bufferViews", "byteOffset", 0},
                          {"bufferViews", "byteLength", 1}, {"bufferViews", "byteStride", 4}, {"buffers", "byteLength", 1}};
  const int64_t kMaxSize = (int64_t(1) << 32) - 1;  // GLB and tinygltf sizes are 32-bit
  for (const Field& f : fields) {
    const auto list = j.find(f.array);
    if (list == j.end() || !list->is_array()) continue;
    for (size_t i = 0; i < list->size(); ++i) {
      const nlohmann::json& element = (*list)[i];
      if (!element.is_object()) continue;
      const auto v = element.find(f.key);
      int64_t n = 0;
      if (v != element.end() && !jsonWholeNumber(*v, f.lo, kMaxSize, n))
        return {Status::kParseError, path + ": " + std::string(f.array).substr(0, std::strlen(f.array) - 1) + " " +
                                         std::to_string(i) + ": \"" + f.key + "\" must be a whole number from " +
                                         std::to_string(f.lo) + " to 2^32 - 1"};
    }
  }
  const auto accessors = j.find("accessors");
  if (accessors == j.end() || !accessors->is_array()) return {};
  for (size_t i = 0; i < accessors->size(); ++i) {
    const nlohmann::json& a = (*accessors)[i];
    if (!a.is_object() || !a.contains("sparse")) continue;
    const nlohmann::json& sp = a["sparse"];
    int64_t count = 0, n = 0, total = 0;
    const std::string where = path + ": accessor " + std::to_string(i) + ": sparse ";
    if (!sp.is_object() || !sp.contains("count") || !jsonWholeNumber(sp["count"], 1, kMaxSize, count))
      return {Status::kParseError, where + "\"count\" must be a whole number from 1 to 2^32 - 1"};
    if (a.contains("count") && jsonWholeNumber(a["count"], 1, kMaxSize, total) && count > total)
      return {Status::kParseError, where + "\"count\" " + std::to_string(count) + " exceeds the accessor's count " +
                                       std::to_string(total)};
    for (const char* part : {"indices", "values"})
      if (sp.contains(part) && sp[part].is_object() && sp[part].contains("byteOffset") &&
          !jsonWholeNumber(sp[part]["byteOffset"], 0, kMaxSize, n))
        return {Status::kParseError, where + part + " \"byteOffset\" must be a whole number from 0 to 2^32 - 1"};
  }
  return {};
}

// extensions that change the geometry we would read: refused when required
const char* const kGeometryExtensions[] = {"KHR_draco_mesh_compression", "EXT_meshopt_compression", "EXT_mesh_gpu_instancing",
                                           "KHR_meshopt_compression"};

Error loadModel(const std::string& path, tinygltf::Model& model, LoadContext& ctx) {
  std::vector<unsigned char> data;
  std::string err;
  if (!readFileBytes(path, data, err)) return {Status::kIoError, path + ": cannot open file (" + err + ")"};
  const std::string ext = lowerExtension(path);
  const bool binary = data.size() >= 4 && std::memcmp(data.data(), "glTF", 4) == 0;
  if (ext == ".glb" || binary)
    if (Error e = checkGlbContainer(path, data); !e.ok()) return e;
  if (data.size() > UINT_MAX) return {Status::kUnsupported, path + ": file larger than 4 GiB"};
  if (Error e = checkGltfJson(path, data, binary); !e.ok()) return e;

  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  char* real = ::realpath(dir.c_str(), nullptr);
  if (!real) return {Status::kIoError, path + ": cannot resolve the file's folder"};
  ctx.folder = real;
  std::free(real);
  if (ctx.folder == "/") ctx.folder.clear();  // then prefix "/" matches anything: the root folder holds it all

  tinygltf::TinyGLTF loader;
  tinygltf::FsCallbacks fs{};
  fs.FileExists = &fsFileExists;
  fs.ExpandFilePath = &fsExpandFilePath;
  fs.ReadWholeFile = &fsReadWholeFile;
  fs.WriteWholeFile = &fsWriteWholeFile;
  fs.user_data = &ctx;
  loader.SetFsCallbacks(fs);
  loader.SetImageLoader(&averageImage, &ctx);
  std::string warn;
  err.clear();
  const std::string base = ctx.folder.empty() ? "/" : ctx.folder;
  bool ok;
  if (binary)
    ok = loader.LoadBinaryFromMemory(&model, &err, &warn, data.data(), static_cast<unsigned int>(data.size()), base);
  else
    ok = loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(data.data()),
                                    static_cast<unsigned int>(data.size()), base);
  if (!ctx.refused.empty()) return {Status::kInvalidArgument, path + ": " + ctx.refused};
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    for (char& c : err)
      if (c == '\n') c = ';';
    const bool size_problem = err.find("size mismatch") != std::string::npos || err.find("byteLength") != std::string::npos;
    const bool bad_reference = err.find("out of bounds") != std::string::npos;
    if (size_problem) return {Status::kCorrupt, path + ": truncated or wrong-size buffer: " + err};
    if (bad_reference) return {Status::kInvalidMesh, path + ": invalid reference: " + err};
    return {Status::kParseError, path + ": cannot parse glTF: " + err};
  }
  for (const std::string& req : model.extensionsRequired)
    for (const char* g : kGeometryExtensions)
      if (req == g)
        return {Status::kUnsupported, path + ": requires extension " + req +
                                          ", which changes the geometry and is not supported (only uncompressed, "
                                          "non-instanced geometry is read)"};
  return {};
}

Error readScene(const std::string& path, const tinygltf::Model& model, const LoadContext& ctx, SceneData& out) {
  GltfReader reader(path, model, ctx);
  SceneData s;
  if (Error e = reader.readMaterials(s.materials); !e.ok()) return e;
  s.meshes.resize(model.meshes.size());
  for (size_t m = 0; m < model.meshes.size(); ++m)
    if (Error e = reader.readMesh(m, s.meshes[m]); !e.ok()) return e;
  if (Error e = reader.readNodes(s); !e.ok()) return e;
  if (Error e = validateSceneData(s, path); !e.ok()) return e;
  out = std::move(s);
  return {};
}

bool numberField(const tinygltf::Value& obj, const char* key, float& out) {
  if (!obj.IsObject() || !obj.Has(key)) return false;
  const tinygltf::Value& v = obj.Get(key);
  if (!v.IsNumber()) return false;
  out = static_cast<float>(v.GetNumberAsDouble());
  return true;
}

void readLevelExtras(const tinygltf::Node& node, LodLevel& level) {
  if (!node.extras.IsObject() || !node.extras.Has("scenelod")) return;
  const tinygltf::Value& s = node.extras.Get("scenelod");
  numberField(s, "cell_width", level.cell_width);
  numberField(s, "max_error", level.max_error);
  if (s.IsObject() && s.Has("method") && s.Get("method").IsString()) {
    const std::string name = s.Get("method").Get<std::string>();
    for (int k = 0; k <= static_cast<int>(LodMethod::kScrooge); ++k)
      if (name == lodMethodName(static_cast<LodMethod>(k))) level.method = static_cast<LodMethod>(k);
  }
}

// runs `read`, turning what tinygltf and the standard library may throw into errors naming the file
template <class Read>
Error withoutExceptions(const std::string& path, Read read) {
  try {
    return read();
  } catch (const std::bad_alloc&) {
    return {Status::kOutOfMemory, path + ": out of memory while reading"};
  } catch (const std::exception& e) {
    return {Status::kParseError, path + ": cannot parse glTF: " + e.what()};
  } catch (...) {
    return {Status::kParseError, path + ": cannot parse glTF (unknown exception)"};
  }
}

}  // namespace

Error importGltf(const std::string& path, SceneData& out) {
  return withoutExceptions(path, [&]() -> Error {
    tinygltf::Model model;
    LoadContext ctx;
    if (Error e = loadModel(path, model, ctx); !e.ok()) return e;
    return readScene(path, model, ctx, out);
  });
}

Error importGltfLods(const std::string& path, SceneData& out, std::vector<LodChain>& chains) {
  return withoutExceptions(path, [&]() -> Error {
    tinygltf::Model model;
    LoadContext ctx;
    if (Error e = loadModel(path, model, ctx); !e.ok()) return e;
    SceneData raw;
    if (Error e = readScene(path, model, ctx, raw); !e.ok()) return e;

    const size_t n = raw.nodes.size();
    std::vector<char> is_level(n, 0);
    std::vector<std::vector<int>> lod_ids(n);
    for (size_t i = 0; i < n; ++i) {
      auto it = model.nodes[i].extensions.find("MSFT_lod");
      if (it == model.nodes[i].extensions.end()) continue;
      const tinygltf::Value& ext = it->second;
      if (!ext.IsObject() || !ext.Has("ids") || !ext.Get("ids").IsArray())
        return {Status::kParseError, path + ": node " + std::to_string(i) + ": MSFT_lod without an 'ids' array"};
      if (raw.nodes[i].mesh < 0)
        return {Status::kUnsupported, path + ": node " + std::to_string(i) + ": MSFT_lod on a node without a mesh"};
      const tinygltf::Value& ids = ext.Get("ids");
      for (size_t k = 0; k < ids.ArrayLen(); ++k) {
        const tinygltf::Value& v = ids.Get(static_cast<int>(k));
        const int id = v.IsNumber() ? v.GetNumberAsInt() : -1;
        if (id < 0 || static_cast<size_t>(id) >= n || static_cast<size_t>(id) == i)
          return {Status::kInvalidMesh, path + ": node " + std::to_string(i) + ": MSFT_lod id " + std::to_string(id) + " out of range"};
        const NodeData& lvl = raw.nodes[static_cast<size_t>(id)];
        if (lvl.mesh < 0 || lvl.parent >= 0 || !lvl.children.empty())
          return {Status::kUnsupported, path + ": node " + std::to_string(id) +
                                            ": an MSFT_lod level must be a parentless, childless node with a mesh"};
        is_level[static_cast<size_t>(id)] = 1;
        lod_ids[i].push_back(id);
      }
    }
    for (size_t i = 0; i < n; ++i)
      if (is_level[i] && !lod_ids[i].empty())
        return {Status::kUnsupported, path + ": node " + std::to_string(i) + " is an MSFT_lod level with levels of its own"};

    // keep every mesh used by a kept node or by no node; drop meshes only level nodes use
    std::vector<char> used_by_kept(raw.meshes.size(), 0), used_by_level(raw.meshes.size(), 0);
    for (size_t i = 0; i < n; ++i)
      if (raw.nodes[i].mesh >= 0) (is_level[i] ? used_by_level : used_by_kept)[static_cast<size_t>(raw.nodes[i].mesh)] = 1;
    std::vector<int32_t> mesh_map(raw.meshes.size(), -1), node_map(n, -1);
    SceneData s;
    s.materials = raw.materials;
    for (size_t m = 0; m < raw.meshes.size(); ++m)
      if (used_by_kept[m] || !used_by_level[m]) {
        mesh_map[m] = static_cast<int32_t>(s.meshes.size());
        s.meshes.push_back(raw.meshes[m]);
      }
    for (size_t i = 0; i < n; ++i)
      if (!is_level[i]) node_map[i] = static_cast<int32_t>(s.nodes.size()), s.nodes.push_back(raw.nodes[i]);
    for (NodeData& node : s.nodes) {
      if (node.parent >= 0) node.parent = node_map[static_cast<size_t>(node.parent)];
      for (int32_t& c : node.children) c = node_map[static_cast<size_t>(c)];
      if (node.mesh >= 0) node.mesh = mesh_map[static_cast<size_t>(node.mesh)];
    }
    for (int32_t r : raw.roots)
      if (!is_level[static_cast<size_t>(r)]) s.roots.push_back(node_map[static_cast<size_t>(r)]);

    std::vector<LodChain> c(s.meshes.size());
    std::vector<char> defined(s.meshes.size(), 0);
    for (size_t i = 0; i < n; ++i) {
      if (is_level[i] || raw.nodes[i].mesh < 0) continue;
      const size_t m = static_cast<size_t>(mesh_map[static_cast<size_t>(raw.nodes[i].mesh)]);
      if (defined[m] || lod_ids[i].empty()) continue;  // the first node with MSFT_lod defines the chain
      defined[m] = 1;
      LodLevel l0;
      l0.mesh = s.meshes[m].mesh;
      readLevelExtras(model.nodes[i], l0);
      l0.bounds = minimalSphere(Span<const glm::vec3>(l0.mesh.positions.data(), l0.mesh.positions.size()));
      c[m].levels.push_back(std::move(l0));
      // without our extras, a level's cell width follows from MSFT_screencoverage (docs/IO.md)
      std::vector<float> coverage;
      if (model.nodes[i].extras.IsObject() && model.nodes[i].extras.Has("MSFT_screencoverage")) {
        const tinygltf::Value& cv = model.nodes[i].extras.Get("MSFT_screencoverage");
        for (size_t k = 0; k < cv.ArrayLen(); ++k)
          coverage.push_back(cv.Get(static_cast<int>(k)).IsNumber() ? float(cv.Get(static_cast<int>(k)).GetNumberAsDouble()) : 0.0f);
      }
      for (size_t k = 0; k < lod_ids[i].size(); ++k) {
        const tinygltf::Node& ln = model.nodes[static_cast<size_t>(lod_ids[i][k])];
        LodLevel level;
        level.mesh = raw.meshes[static_cast<size_t>(ln.mesh)].mesh;
        level.method = LodMethod::kUniform;
        if (k < coverage.size() && coverage[k] > 0.0f)
          level.cell_width = 2.0f * c[m].levels[0].bounds.radius * kCoverageCellPixels / (coverage[k] * kCoverageViewportPx);
        readLevelExtras(ln, level);
        c[m].levels.push_back(std::move(level));
      }
      computeChainBounds(c[m]);
    }
    for (size_t m = 0; m < c.size(); ++m)
      if (!defined[m]) {
        LodLevel l0;
        l0.mesh = s.meshes[m].mesh;
        c[m].levels.push_back(std::move(l0));
        computeChainBounds(c[m]);
      }
    if (Error e = validateSceneData(s, path); !e.ok()) return e;
    out = std::move(s);
    chains = std::move(c);
    return {};
  });
}

}  // namespace scenelod::scene
