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

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <stb_image.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "scenelod/lodcore/json_limits.h"
#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"
#include "gltf_model.h"

namespace scenelod::scene {

namespace {

// ---------------------------------------------------------------------------------------------
// file access: every external URI must resolve inside the glTF file's folder

struct LoadContext {
  std::string folder;       // realpath of the file's folder, no trailing slash
  std::string refused;      // message for the first refused URI
  std::vector<std::vector<uint8_t>> image_bytes;  // encoded bytes per image, as tinygltf read them
  std::vector<char> image_loaded;                 // whether tinygltf delivered image i's bytes
  std::vector<std::string> read_paths;            // external files read
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
  ctx.read_paths.push_back(path);
  return true;
}

bool fsWriteWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err = "the importer does not write files";
  return false;
}

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

// keeps every image's encoded bytes; decoding waits until the materials say which images need it
bool keepImageBytes(tinygltf::Image*, const int image_idx, std::string*, std::string*, int, int, const unsigned char* bytes,
                    int size, void* user) {
  LoadContext& ctx = *static_cast<LoadContext*>(user);
  if (image_idx < 0 || size < 0) return true;
  if (static_cast<size_t>(image_idx) >= ctx.image_bytes.size()) {
    ctx.image_bytes.resize(static_cast<size_t>(image_idx) + 1);
    ctx.image_loaded.resize(static_cast<size_t>(image_idx) + 1, 0);
  }
  ctx.image_bytes[static_cast<size_t>(image_idx)].assign(bytes, bytes + size);
  ctx.image_loaded[static_cast<size_t>(image_idx)] = 1;
  return true;
}


// decodes to RGBA8 (anything stb_image reads) and returns the linear mean RGB, or false when the
// bytes do not decode (the image then keeps no pixels)
bool decodeImage(ImageData& image, glm::vec3& mean) {
  int w = 0, h = 0, comp = 0;
  if (image.encoded.empty() || image.encoded.size() > static_cast<size_t>(INT_MAX)) return false;
  unsigned char* px = stbi_load_from_memory(image.encoded.data(), static_cast<int>(image.encoded.size()), &w, &h, &comp, 4);
  if (!px) return false;
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  image.width = w;
  image.height = h;
  image.rgba8.assign(px, px + 4 * n);
  stbi_image_free(px);
  static const std::array<float, 256> lut = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[static_cast<size_t>(i)] = srgbToLinear(static_cast<float>(i) / 255.0f);
    return t;
  }();
  double sum[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < n; ++i)
    for (size_t k = 0; k < 3; ++k) sum[k] += lut[image.rgba8[4 * i + k]];
  if (n > 0) mean = glm::vec3(float(sum[0] / double(n)), float(sum[1] / double(n)), float(sum[2] / double(n)));
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

// a unit vector perpendicular to unit `n`
glm::vec3 anyPerpendicular(const glm::vec3& n) {
  const glm::vec3 axis = std::fabs(n.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  const glm::vec3 t = glm::cross(n, axis);
  const float len = glm::length(t);
  return len > 0.0f ? t / len : glm::vec3(1.0f, 0.0f, 0.0f);
}

// tangents for the vertices without one (has[v] == 0): from the UV gradient of their triangles
// (Lengyel 2001), orthogonalised against the normal, w from the bitangent's side; without UVs or
// with degenerate ones, any unit vector perpendicular to the normal, w = +1
void fillTangents(Mesh& m, const std::vector<char>& has) {
  if (std::find(has.begin(), has.end(), 0) == has.end()) return;
  const size_t n = m.vertexCount();
  std::vector<glm::vec3> tan(n, glm::vec3(0.0f)), bit(n, glm::vec3(0.0f));
  if (!m.uvs.empty())
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      const uint32_t i0 = m.triangles[3 * t], i1 = m.triangles[3 * t + 1], i2 = m.triangles[3 * t + 2];
      const glm::vec3 e1 = m.positions[i1] - m.positions[i0], e2 = m.positions[i2] - m.positions[i0];
      const glm::vec2 d1 = m.uvs[i1] - m.uvs[i0], d2 = m.uvs[i2] - m.uvs[i0];
      const float r = d1.x * d2.y - d2.x * d1.y;
      if (!(std::fabs(r) > 1e-20f)) continue;
      const glm::vec3 tu = (e1 * d2.y - e2 * d1.y) / r, tv = (e2 * d1.x - e1 * d2.x) / r;
      for (uint32_t v : {i0, i1, i2}) tan[v] += tu, bit[v] += tv;
    }
  for (size_t v = 0; v < n; ++v) {
    if (has[v]) continue;
    const glm::vec3 nrm = m.normals.empty() || glm::length(m.normals[v]) == 0.0f ? glm::vec3(0.0f, 0.0f, 1.0f)
                                                                                  : glm::normalize(m.normals[v]);
    glm::vec3 t = tan[v] - nrm * glm::dot(nrm, tan[v]);
    const float len = glm::length(t);
    t = len > 1e-12f && std::isfinite(len) ? t / len : anyPerpendicular(nrm);
    m.tangents[v] = glm::vec4(t, glm::dot(glm::cross(nrm, t), bit[v]) < 0.0f ? -1.0f : 1.0f);
  }
}

bool numberField(const tinygltf::Value& obj, const char* key, float& out) {
  if (!obj.IsObject() || !obj.Has(key)) return false;
  const tinygltf::Value& v = obj.Get(key);
  if (!v.IsNumber()) return false;
  out = static_cast<float>(v.GetNumberAsDouble());
  return true;
}

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

  // images (encoded bytes kept), textures with their samplers' wrap modes
  Error readImagesAndTextures(SceneData& out) const {
    out.images.assign(model_.images.size(), ImageData{});
    for (size_t i = 0; i < model_.images.size(); ++i) {
      const tinygltf::Image& src = model_.images[i];
      ImageData& img = out.images[i];
      img.name = src.name;
      if (i < ctx_.image_loaded.size() && ctx_.image_loaded[i])
        img.encoded = ctx_.image_bytes[i];
      else if (!src.uri.empty())
        return fail(Status::kIoError, "image " + std::to_string(i) + ": cannot read '" + src.uri + "' (missing or unreadable)");
      img.mime_type = detail::imageMimeType(img.encoded, src.mimeType);
    }
    out.textures.assign(model_.textures.size(), TextureData{});
    for (size_t t = 0; t < model_.textures.size(); ++t) {
      const tinygltf::Texture& src = model_.textures[t];
      const std::string what = "texture " + std::to_string(t);
      if (src.source < -1 || src.source >= static_cast<int>(model_.images.size()))
        return fail(Status::kInvalidMesh, what + ": image " + std::to_string(src.source) + " out of range (the file has " +
                                              std::to_string(model_.images.size()) + ")");
      if (src.sampler < -1 || src.sampler >= static_cast<int>(model_.samplers.size()))
        return fail(Status::kInvalidMesh, what + ": sampler " + std::to_string(src.sampler) + " out of range (the file has " +
                                              std::to_string(model_.samplers.size()) + ")");
      TextureData& tex = out.textures[t];
      tex.image = src.source;
      if (src.sampler >= 0) {
        tex.wrap_s = model_.samplers[static_cast<size_t>(src.sampler)].wrapS;
        tex.wrap_t = model_.samplers[static_cast<size_t>(src.sampler)].wrapT;
      }
    }
    return {};
  }

  // KHR_texture_transform of a texture reference (identity without the extension)
  Error readTextureTransform(const tinygltf::ExtensionMap& ext, const std::string& what, TextureTransform& out) const {
    out = TextureTransform{};
    const auto it = ext.find("KHR_texture_transform");
    if (it == ext.end() || !it->second.IsObject()) return {};
    const tinygltf::Value& v = it->second;
    auto pair = [&](const char* key, glm::vec2& dst) {
      if (!v.Has(key) || !v.Get(key).IsArray() || v.Get(key).ArrayLen() != 2) return;
      for (int k = 0; k < 2; ++k)
        if (v.Get(key).Get(k).IsNumber()) dst[k] = static_cast<float>(v.Get(key).Get(k).GetNumberAsDouble());
    };
    pair("offset", out.offset);
    pair("scale", out.scale);
    numberField(v, "rotation", out.rotation);
    float texcoord = -1.0f;
    if (numberField(v, "texCoord", texcoord)) out.texcoord = static_cast<int32_t>(texcoord);
    if (!std::isfinite(out.offset.x) || !std::isfinite(out.offset.y) || !std::isfinite(out.scale.x) ||
        !std::isfinite(out.scale.y) || !std::isfinite(out.rotation) || out.texcoord < -1 || out.texcoord > 255)
      return fail(Status::kInvalidMesh, what + ": KHR_texture_transform has a non-finite value or a bad texCoord");
    return {};
  }

  // materials; the images their base colour textures use are decoded and averaged
  Error readMaterials(SceneData& out) {
    out.materials.clear();
    std::vector<char> decoded(out.images.size(), 0);
    std::vector<glm::vec3> mean(out.images.size(), glm::vec3(1.0f));
    for (size_t i = 0; i < model_.materials.size(); ++i) {
      const tinygltf::Material& src = model_.materials[i];
      const std::string what = "material " + std::to_string(i);
      MaterialData m;
      m.name = src.name;
      const auto& f = src.pbrMetallicRoughness.baseColorFactor;
      if (f.size() == 4) m.base_color = glm::vec4(float(f[0]), float(f[1]), float(f[2]), float(f[3]));
      const tinygltf::TextureInfo& info = src.pbrMetallicRoughness.baseColorTexture;
      if (info.index >= 0) {
        if (static_cast<size_t>(info.index) >= out.textures.size())
          return fail(Status::kInvalidMesh, what + ": texture " + std::to_string(info.index) + " out of range (the file has " +
                                                std::to_string(out.textures.size()) + ")");
        m.textured = true;
        m.base_color_texture = info.index;
        m.base_color_texcoord = static_cast<uint32_t>(std::max(info.texCoord, 0));
        if (Error e = readTextureTransform(info.extensions, what + " baseColorTexture", m.base_color_transform); !e.ok())
          return e;
        const int img = out.textures[static_cast<size_t>(info.index)].image;
        if (img >= 0 && !decoded[static_cast<size_t>(img)])
          decoded[static_cast<size_t>(img)] = decodeImage(out.images[static_cast<size_t>(img)], mean[static_cast<size_t>(img)]) ? 1 : 2;
        if (img >= 0) m.average_texel_color = mean[static_cast<size_t>(img)];
      }
      if (!std::isfinite(m.base_color.x) || !std::isfinite(m.base_color.y) || !std::isfinite(m.base_color.z))
        return fail(Status::kInvalidMesh, what + ": non-finite base colour factor");
      out.materials.push_back(m);
    }
    material_count_ = out.materials.size();
    return {};
  }

  // what readMesh gathers over a mesh's primitives before it sets the mesh's optional attributes;
  // the per-vertex arrays grow with the positions, holding defaults where a primitive lacks one
  struct MeshBuild {
    struct Vertices {
      uint32_t offset, count, joint_end;
    };
    std::map<std::vector<int>, Vertices> shared;  // attribute accessors + material -> vertices
    std::vector<char> has_normal, has_tangent;
    bool any_normal = false, any_color = false, any_tangent = false, any_skin = false, any_thickness = false;
    std::vector<std::vector<glm::vec2>> uvs;  // one array per TEXCOORD set
    std::vector<glm::vec3> colors;
    std::vector<glm::vec4> tangents;
    std::vector<glm::u16vec4> joints;
    std::vector<glm::vec4> weights;
    std::vector<float> edge_thickness;  // one per edge, from its own primitive's _THICKNESS
  };
  // a primitive's attribute accessors, -1 when absent
  struct Attributes {
    int position = -1, normal = -1, tangent = -1, color = -1, joints = -1, weights = -1, thickness = -1;
    std::vector<int> uv;  // TEXCOORD_0, TEXCOORD_1, ... up to the first missing set

    std::vector<int> key(int material) const {
      std::vector<int> k{position, normal, tangent, color, joints, weights, material};
      k.insert(k.end(), uv.begin(), uv.end());
      return k;
    }
  };

  // reads vertex attribute `semantic`: min_c..max_c components, `count` elements, all finite
  Error readAttribute(int accessor, const std::string& what, const std::string& semantic, int min_c, int max_c,
                      uint32_t count, std::vector<double>& v, int& comps) const {
    if (Error e = readVec(accessor, what, semantic.c_str(), min_c, max_c, v, comps); !e.ok()) return e;
    const size_t n = v.size() / static_cast<size_t>(comps);
    if (n != count)
      return fail(Status::kInvalidMesh, what + ": " + semantic + " has " + std::to_string(n) + " elements, POSITION " +
                                            std::to_string(count));
    for (size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        return fail(Status::kInvalidMesh, what + " " + semantic + ": element " + std::to_string(i / static_cast<size_t>(comps)) +
                                              " is NaN or infinite");
    return {};
  }

  // appends the vertices of one primitive's POSITION, NORMAL, TEXCOORD_n and COLOR_0 to `m` and
  // `b`, from `base` on; `count` is their number
  Error readVertices(const Attributes& a, const std::string& what, const std::string& mesh_what, Mesh& m, MeshBuild& b,
                     uint32_t& base, uint32_t& count) const {
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
    const size_t n = m.positions.size();
    m.normals.resize(n, glm::vec3(0.0f));
    b.has_normal.resize(n, 0);
    b.has_tangent.resize(n, 0);
    b.colors.resize(n, glm::vec3(1.0f));
    b.tangents.resize(n, glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
    b.joints.resize(n, glm::u16vec4(0));
    b.weights.resize(n, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
    if (b.uvs.size() < a.uv.size()) b.uvs.resize(a.uv.size());
    for (std::vector<glm::vec2>& set : b.uvs) set.resize(n, glm::vec2(0.0f));
    if (a.normal >= 0) {
      if (Error e = readAttribute(a.normal, what, "NORMAL", 3, 3, count, v, comps); !e.ok()) return e;
      for (uint32_t i = 0; i < count; ++i) {
        m.normals[base + i] = glm::vec3(float(v[3 * i]), float(v[3 * i + 1]), float(v[3 * i + 2]));
        b.has_normal[base + i] = 1;
      }
      b.any_normal = true;
    }
    for (size_t set = 0; set < a.uv.size(); ++set) {
      if (Error e = readAttribute(a.uv[set], what, "TEXCOORD_" + std::to_string(set), 2, 2, count, v, comps); !e.ok()) return e;
      for (uint32_t i = 0; i < count; ++i) b.uvs[set][base + i] = glm::vec2(float(v[2 * i]), float(v[2 * i + 1]));
    }
    if (a.color >= 0) {
      if (Error e = readAttribute(a.color, what, "COLOR_0", 3, 4, count, v, comps); !e.ok()) return e;
      for (uint32_t i = 0; i < count; ++i) {
        const size_t o = static_cast<size_t>(i) * static_cast<size_t>(comps);
        b.colors[base + i] = glm::vec3(float(v[o]), float(v[o + 1]), float(v[o + 2]));
      }
      b.any_color = true;
    }
    return {};
  }

  // reads one primitive's TANGENT, JOINTS_0 and WEIGHTS_0 into `b` at `base`; `joint_end` is one
  // more than the largest joint index the primitive uses (0 without JOINTS_0)
  Error readTangentsAndSkin(const Attributes& a, const std::string& what, uint32_t base, uint32_t count, MeshBuild& b,
                            uint32_t& joint_end) const {
    std::vector<double> v;
    int comps = 0;
    joint_end = 0;
    if (a.tangent >= 0) {
      if (Error e = readAttribute(a.tangent, what, "TANGENT", 4, 4, count, v, comps); !e.ok()) return e;
      for (uint32_t i = 0; i < count; ++i) {
        // w is +1 or -1 in the spec; a file's rounding is snapped to the sign
        b.tangents[base + i] = glm::vec4(float(v[4 * i]), float(v[4 * i + 1]), float(v[4 * i + 2]), v[4 * i + 3] < 0.0 ? -1.0f : 1.0f);
        b.has_tangent[base + i] = 1;
      }
      b.any_tangent = true;
    }
    if ((a.joints >= 0) != (a.weights >= 0))
      return fail(Status::kInvalidMesh, what + (a.joints >= 0 ? ": JOINTS_0 without WEIGHTS_0" : ": WEIGHTS_0 without JOINTS_0"));
    if (a.joints < 0) return {};
    if (Error e = readAttribute(a.joints, what, "JOINTS_0", 4, 4, count, v, comps); !e.ok()) return e;
    const tinygltf::Accessor& ja = model_.accessors[static_cast<size_t>(a.joints)];
    if ((ja.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ja.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) ||
        ja.normalized)
      return fail(Status::kInvalidMesh, what + " JOINTS_0: accessor " + std::to_string(a.joints) +
                                            " must hold unsigned bytes or shorts, not normalized");
    for (uint32_t i = 0; i < count; ++i)
      for (int c = 0; c < 4; ++c) {
        const double j = v[4 * i + static_cast<size_t>(c)];
        b.joints[base + i][c] = static_cast<uint16_t>(j);
        joint_end = std::max(joint_end, static_cast<uint32_t>(j) + 1);
      }
    if (Error e = readAttribute(a.weights, what, "WEIGHTS_0", 4, 4, count, v, comps); !e.ok()) return e;
    for (uint32_t i = 0; i < count; ++i) {
      const glm::vec4 w(float(v[4 * i]), float(v[4 * i + 1]), float(v[4 * i + 2]), float(v[4 * i + 3]));
      if (w.x < 0.0f || w.y < 0.0f || w.z < 0.0f || w.w < 0.0f || !(w.x + w.y + w.z + w.w > 0.0f))
        return fail(Status::kInvalidMesh, what + " WEIGHTS_0: element " + std::to_string(i) +
                                              " has a negative weight or weights summing to 0");
      b.weights[base + i] = w;
    }
    b.any_skin = true;
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

  // a primitive's attribute accessors by semantic
  static Attributes primitiveAttributes(const tinygltf::Primitive& p) {
    auto attr = [&](const std::string& name) {
      auto it = p.attributes.find(name);
      return it == p.attributes.end() ? -1 : it->second;
    };
    Attributes a;
    a.position = attr("POSITION");
    a.normal = attr("NORMAL");
    a.tangent = attr("TANGENT");
    a.color = attr("COLOR_0");
    a.joints = attr("JOINTS_0");
    a.weights = attr("WEIGHTS_0");
    a.thickness = attr("_THICKNESS");
    for (int set = 0; attr("TEXCOORD_" + std::to_string(set)) >= 0; ++set) a.uv.push_back(attr("TEXCOORD_" + std::to_string(set)));
    return a;
  }

  // a primitive's _THICKNESS per vertex (empty without it)
  Error readThickness(const Attributes& a, const std::string& what, uint32_t count, std::vector<double>& thickness) const {
    thickness.clear();
    if (a.thickness < 0) return {};
    int comps = 0;
    if (Error e = readVec(a.thickness, what, "_THICKNESS", 1, 1, thickness, comps); !e.ok()) return e;
    if (thickness.size() != count)
      return fail(Status::kInvalidMesh, what + ": _THICKNESS has " + std::to_string(thickness.size()) + " elements, POSITION " +
                                            std::to_string(count));
    for (uint32_t i = 0; i < count; ++i)
      if (!std::isfinite(thickness[i]) || thickness[i] < 0.0)
        return fail(Status::kInvalidMesh, what + " _THICKNESS: element " + std::to_string(i) + " is negative or not finite");
    return {};
  }

  // sets the mesh's optional attributes from what its primitives had; a primitive lacking one
  // that others have gets normals computed from the faces, tangents from its UVs (fillTangents),
  // UV 0, colour white, and joint 0 with weight 1
  static void finishMesh(MeshBuild& b, Mesh& m) {
    if (b.any_thickness) m.edge_thickness = std::move(b.edge_thickness);
    if (!b.uvs.empty()) {
      m.uvs = std::move(b.uvs[0]);
      m.extra_uvs.assign(std::make_move_iterator(b.uvs.begin() + 1), std::make_move_iterator(b.uvs.end()));
    } else {
      m.uvs.clear();
    }
    if (b.any_color) m.colors = std::move(b.colors);
    if (!b.any_normal) {
      m.normals.clear();
    } else if (std::find(b.has_normal.begin(), b.has_normal.end(), 0) != b.has_normal.end()) {
      Mesh tmp;
      tmp.positions = m.positions;
      tmp.triangles = m.triangles;
      computeVertexNormals(tmp);
      for (size_t i = 0; i < b.has_normal.size(); ++i)
        if (!b.has_normal[i]) m.normals[i] = tmp.normals[i];
    }
    if (b.any_tangent) {
      m.tangents = std::move(b.tangents);
      fillTangents(m, b.has_tangent);
    }
    if (b.any_skin) {
      m.joints = std::move(b.joints);
      m.weights = std::move(b.weights);
    }
    // one primitive: no groups (the convention for "all in group 0")
    for (std::vector<uint32_t>* groups : {&m.triangle_groups, &m.edge_groups, &m.point_groups})
      if (std::all_of(groups->begin(), groups->end(), [](uint32_t g) { return g == 0; })) groups->clear();
  }

  // `joint_end[p]`: one more than the largest joint primitive p uses (0 without JOINTS_0)
  Error readMesh(size_t mesh_index, MeshData& out, std::vector<uint32_t>& joint_end) const {
    const tinygltf::Mesh& src = model_.meshes[mesh_index];
    out = MeshData{};
    out.name = src.name;
    joint_end.clear();
    Mesh& m = out.mesh;
    const std::string mesh_what = "mesh " + std::to_string(mesh_index) + (src.name.empty() ? "" : " '" + src.name + "'");
    MeshBuild b;
    for (size_t pi = 0; pi < src.primitives.size(); ++pi) {
      const tinygltf::Primitive& p = src.primitives[pi];
      const std::string what = mesh_what + " primitive " + std::to_string(pi);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      if (mode > TINYGLTF_MODE_TRIANGLE_FAN)
        return fail(Status::kUnsupported, what + ": unsupported primitive mode " + std::to_string(mode));
      if (p.material >= static_cast<int>(material_count_))
        return fail(Status::kInvalidMesh, what + ": material " + std::to_string(p.material) + " out of range (the file has " +
                                              std::to_string(material_count_) + ")");
      if (p.extensions.count("KHR_draco_mesh_compression"))
        return fail(Status::kUnsupported, what + ": Draco-compressed primitives (KHR_draco_mesh_compression) are not supported");
      const Attributes a = primitiveAttributes(p);
      if (a.position < 0) return fail(Status::kInvalidMesh, what + " has no POSITION attribute");
      out.primitive_materials.push_back(p.material);

      const std::vector<int> key = a.key(p.material);
      MeshBuild::Vertices vs{0, 0, 0};
      auto found = b.shared.find(key);
      if (found != b.shared.end()) {
        vs = found->second;
      } else {
        if (Error e = readVertices(a, what, mesh_what, m, b, vs.offset, vs.count); !e.ok()) return e;
        if (Error e = readTangentsAndSkin(a, what, vs.offset, vs.count, b, vs.joint_end); !e.ok()) return e;
        b.shared.emplace(key, vs);
      }
      joint_end.push_back(vs.joint_end);
      std::vector<double> thickness;
      if (Error e = readThickness(a, what, vs.count, thickness); !e.ok()) return e;
      std::vector<uint32_t> idx;
      if (Error e = readPrimitiveIndices(p, vs.count, what, idx); !e.ok()) return e;
      if (Error e = addPrimitive(mode, idx, vs.offset, thickness, a.thickness >= 0, what, m, b); !e.ok()) return e;
      m.triangle_groups.resize(m.triangleCount(), static_cast<uint32_t>(pi));
      m.edge_groups.resize(m.edgeCount(), static_cast<uint32_t>(pi));
      m.point_groups.resize(m.pointCount(), static_cast<uint32_t>(pi));
    }
    finishMesh(b, m);
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
      if (src.skin >= static_cast<int>(model_.skins.size()))
        return fail(Status::kInvalidMesh, what + ": skin " + std::to_string(src.skin) + " out of range (the file has " +
                                              std::to_string(model_.skins.size()) + ")");
      node.skin = src.skin < 0 ? -1 : src.skin;
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

  // skins: joints must be nodes; inverse bind matrices MAT4 floats, at least one per joint
  Error readSkins(SceneData& out) const {
    out.skins.assign(model_.skins.size(), SkinData{});
    for (size_t k = 0; k < model_.skins.size(); ++k) {
      const tinygltf::Skin& src = model_.skins[k];
      SkinData& skin = out.skins[k];
      const std::string what = "skin " + std::to_string(k);
      skin.name = src.name;
      for (int j : src.joints) {
        if (j < 0 || static_cast<size_t>(j) >= model_.nodes.size())
          return fail(Status::kInvalidMesh, what + ": joint " + std::to_string(j) + " is not a node (the file has " +
                                                std::to_string(model_.nodes.size()) + ")");
        skin.joints.push_back(j);
      }
      if (src.skeleton < -1 || src.skeleton >= static_cast<int>(model_.nodes.size()))
        return fail(Status::kInvalidMesh, what + ": skeleton node " + std::to_string(src.skeleton) + " out of range");
      skin.skeleton = src.skeleton;
      skin.inverse_bind.assign(skin.joints.size(), glm::mat4(1.0f));
      if (src.inverseBindMatrices < 0) continue;
      std::vector<double> v;
      int comps = 0;
      if (Error e = readVec(src.inverseBindMatrices, what, "inverseBindMatrices", 16, 16, v, comps); !e.ok()) return e;
      if (v.size() / 16 < skin.joints.size())
        return fail(Status::kInvalidMesh, what + ": " + std::to_string(v.size() / 16) + " inverse bind matrices for " +
                                              std::to_string(skin.joints.size()) + " joints");
      for (size_t j = 0; j < skin.joints.size(); ++j)
        for (int c = 0; c < 16; ++c) {
          const double x = v[16 * j + static_cast<size_t>(c)];
          if (!std::isfinite(x)) return fail(Status::kInvalidMesh, what + ": inverse bind matrix " + std::to_string(j) + " is not finite");
          skin.inverse_bind[j][c / 4][c % 4] = static_cast<float>(x);  // column-major, as glm
        }
    }
    return {};
  }

  // one animation sampler: increasing finite key times, values (1, 3 or 4 components) per key
  Error readSampler(const tinygltf::AnimationSampler& src, const std::string& what, AnimationData::Sampler& out,
                    int& comps) const {
    std::vector<double> v;
    if (Error e = readVec(src.input, what, "input", 1, 1, v, comps); !e.ok()) return e;
    for (size_t i = 0; i < v.size(); ++i) {
      if (!std::isfinite(v[i]) || (i > 0 && v[i] < v[i - 1]))
        return fail(Status::kInvalidMesh, what + " input: key time " + std::to_string(i) + " is not finite or decreases");
      out.times.push_back(static_cast<float>(v[i]));
    }
    if (src.interpolation == "STEP") out.interpolation = AnimationData::Interpolation::kStep;
    else if (src.interpolation == "CUBICSPLINE") out.interpolation = AnimationData::Interpolation::kCubicSpline;
    else if (src.interpolation.empty() || src.interpolation == "LINEAR") out.interpolation = AnimationData::Interpolation::kLinear;
    else return fail(Status::kInvalidMesh, what + ": unknown interpolation '" + src.interpolation + "'");
    if (Error e = readVec(src.output, what, "output", 1, 4, v, comps); !e.ok()) return e;
    const size_t per_key = out.interpolation == AnimationData::Interpolation::kCubicSpline ? 3 : 1;
    const size_t values = v.size() / static_cast<size_t>(comps);
    if (comps == 2 || values % std::max<size_t>(out.times.size() * per_key, 1) != 0 || (comps > 1 && values != out.times.size() * per_key))
      return fail(Status::kInvalidMesh, what + ": " + std::to_string(values) + " output values of " + std::to_string(comps) +
                                            " components for " + std::to_string(out.times.size()) + " keys");
    out.values.assign(values, glm::vec4(0.0f));
    for (size_t i = 0; i < values; ++i)
      for (int c = 0; c < comps; ++c) {
        const double x = v[i * static_cast<size_t>(comps) + static_cast<size_t>(c)];
        if (!std::isfinite(x)) return fail(Status::kInvalidMesh, what + " output: value " + std::to_string(i) + " is not finite");
        out.values[i][c] = static_cast<float>(x);
      }
    return {};
  }

  // animations; channels with a path scenelod does not model (KHR_animation_pointer) are skipped
  Error readAnimations(SceneData& out) const {
    out.animations.assign(model_.animations.size(), AnimationData{});
    for (size_t k = 0; k < model_.animations.size(); ++k) {
      const tinygltf::Animation& src = model_.animations[k];
      AnimationData& anim = out.animations[k];
      anim.name = src.name;
      std::vector<int> comps(src.samplers.size(), 0);
      anim.samplers.resize(src.samplers.size());
      for (size_t i = 0; i < src.samplers.size(); ++i)
        if (Error e = readSampler(src.samplers[i], "animation " + std::to_string(k) + " sampler " + std::to_string(i),
                                  anim.samplers[i], comps[i]); !e.ok())
          return e;
      for (size_t c = 0; c < src.channels.size(); ++c) {
        const tinygltf::AnimationChannel& ch = src.channels[c];
        const std::string what = "animation " + std::to_string(k) + " channel " + std::to_string(c);
        static const std::pair<const char*, std::pair<AnimationData::Path, int>> kPaths[] = {
            {"translation", {AnimationData::Path::kTranslation, 3}},
            {"rotation", {AnimationData::Path::kRotation, 4}},
            {"scale", {AnimationData::Path::kScale, 3}},
            {"weights", {AnimationData::Path::kWeights, 1}}};
        const auto path = std::find_if(std::begin(kPaths), std::end(kPaths),
                                       [&](const auto& p) { return ch.target_path == p.first; });
        if (path == std::end(kPaths) || ch.target_node < 0) continue;
        if (static_cast<size_t>(ch.target_node) >= model_.nodes.size())
          return fail(Status::kInvalidMesh, what + " targets node " + std::to_string(ch.target_node) + ", which does not exist (the file has " +
                                                std::to_string(model_.nodes.size()) + " nodes)");
        if (ch.sampler < 0 || static_cast<size_t>(ch.sampler) >= src.samplers.size())
          return fail(Status::kInvalidMesh, what + ": sampler " + std::to_string(ch.sampler) + " out of range");
        if (comps[static_cast<size_t>(ch.sampler)] != path->second.second)
          return fail(Status::kInvalidMesh, what + ": '" + ch.target_path + "' needs " + std::to_string(path->second.second) +
                                                " components, sampler " + std::to_string(ch.sampler) + " has " +
                                                std::to_string(comps[static_cast<size_t>(ch.sampler)]));
        anim.channels.push_back({ch.target_node, path->second.first, ch.sampler});
      }
    }
    return {};
  }

 private:
  std::string path_;
  const tinygltf::Model& model_;
  const LoadContext& ctx_;
  size_t material_count_ = 0;
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
  loader.SetImageLoader(&keepImageBytes, &ctx);
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

// each skinned node's mesh uses joints its skin has, named by primitive; a mesh used by exactly one
// skin gets that skin's hierarchy as joint_parents
Error checkSkinnedMeshes(const std::string& path, const std::vector<std::vector<uint32_t>>& joint_end, SceneData& s) {
  std::vector<int32_t> skin_of(s.meshes.size(), -1);  // -2: used by several skins
  for (size_t i = 0; i < s.nodes.size(); ++i) {
    const NodeData& node = s.nodes[i];
    if (node.mesh < 0 || node.skin < 0) continue;
    const size_t m = static_cast<size_t>(node.mesh);
    const size_t count = s.skins[static_cast<size_t>(node.skin)].joints.size();
    for (size_t p = 0; p < joint_end[m].size(); ++p)
      if (joint_end[m][p] > count)
        return {Status::kInvalidMesh, path + ": mesh " + std::to_string(m) + (s.meshes[m].name.empty() ? "" : " '" + s.meshes[m].name + "'") +
                                          " primitive " + std::to_string(p) + " JOINTS_0: joint " + std::to_string(joint_end[m][p] - 1) +
                                          " is not below the " + std::to_string(count) + " joints of skin " +
                                          std::to_string(node.skin) + " (node " + std::to_string(i) + ")"};
    skin_of[m] = skin_of[m] == -1 || skin_of[m] == node.skin ? node.skin : -2;
  }
  std::vector<int32_t> joint_index(s.nodes.size(), -1);
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    if (skin_of[m] < 0 || !s.meshes[m].mesh.skinned()) continue;
    const SkinData& skin = s.skins[static_cast<size_t>(skin_of[m])];
    std::fill(joint_index.begin(), joint_index.end(), -1);
    for (size_t j = 0; j < skin.joints.size(); ++j) joint_index[static_cast<size_t>(skin.joints[j])] = static_cast<int32_t>(j);
    std::vector<int32_t>& parents = s.meshes[m].mesh.joint_parents;
    parents.assign(skin.joints.size(), -1);
    for (size_t j = 0; j < skin.joints.size(); ++j) {
      // the nearest ancestor that is a joint of the same skin; bounded, as the hierarchy is only
      // checked for cycles afterwards
      int32_t a = s.nodes[static_cast<size_t>(skin.joints[j])].parent;
      for (size_t steps = 0; a >= 0 && joint_index[static_cast<size_t>(a)] < 0 && steps < s.nodes.size(); ++steps)
        a = s.nodes[static_cast<size_t>(a)].parent;
      parents[j] = a >= 0 && joint_index[static_cast<size_t>(a)] >= 0 ? joint_index[static_cast<size_t>(a)] : -1;
    }
  }
  return {};
}

Error readScene(const std::string& path, const tinygltf::Model& model, const LoadContext& ctx, SceneData& out) {
  GltfReader reader(path, model, ctx);
  SceneData s;
  if (Error e = reader.readImagesAndTextures(s); !e.ok()) return e;
  if (Error e = reader.readMaterials(s); !e.ok()) return e;
  s.meshes.resize(model.meshes.size());
  std::vector<std::vector<uint32_t>> joint_end(model.meshes.size());
  for (size_t m = 0; m < model.meshes.size(); ++m)
    if (Error e = reader.readMesh(m, s.meshes[m], joint_end[m]); !e.ok()) return e;
  if (Error e = reader.readNodes(s); !e.ok()) return e;
  if (Error e = reader.readSkins(s); !e.ok()) return e;
  if (Error e = reader.readAnimations(s); !e.ok()) return e;
  if (Error e = checkSkinnedMeshes(path, joint_end, s); !e.ok()) return e;
  if (Error e = validateSceneData(s, path); !e.ok()) return e;
  out = std::move(s);
  return {};
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

// skins and animations of `raw` for the scene without its MSFT_lod level nodes (node_map: -1 for a
// level node); a level node cannot be a joint, and channels animating one are dropped
Error remapSkinsAndAnimations(const std::string& path, const SceneData& raw, const std::vector<int32_t>& node_map, SceneData& s) {
  s.skins = raw.skins;
  for (size_t k = 0; k < s.skins.size(); ++k) {
    for (int32_t& j : s.skins[k].joints) {
      if (node_map[static_cast<size_t>(j)] < 0)
        return {Status::kUnsupported, path + ": skin " + std::to_string(k) + ": joint node " + std::to_string(j) + " is an MSFT_lod level"};
      j = node_map[static_cast<size_t>(j)];
    }
    if (s.skins[k].skeleton >= 0) s.skins[k].skeleton = node_map[static_cast<size_t>(s.skins[k].skeleton)];
  }
  s.animations = raw.animations;
  for (AnimationData& a : s.animations) {
    std::vector<AnimationData::Channel> kept;
    for (AnimationData::Channel c : a.channels)
      if (node_map[static_cast<size_t>(c.node)] >= 0) c.node = node_map[static_cast<size_t>(c.node)], kept.push_back(c);
    a.channels = std::move(kept);
  }
  return {};
}

// A level mesh's groups are its own primitives; a chain's groups are level 0's primitives. Each
// level primitive names its source group in extras.scenelod.group (as exportGltfLods writes);
// without it, the first level-0 primitive with the same material; otherwise the group is kept.
void levelGroupsAsSourceGroups(const tinygltf::Mesh& gm, const MeshData& level_data, const MeshData& original, Mesh& level) {
  std::vector<uint32_t> to_source(gm.primitives.size());
  for (size_t p = 0; p < gm.primitives.size(); ++p) {
    to_source[p] = static_cast<uint32_t>(p);
    const tinygltf::Value& ex = gm.primitives[p].extras;
    if (ex.IsObject() && ex.Has("scenelod") && ex.Get("scenelod").Has("group") && ex.Get("scenelod").Get("group").IsInt()) {
      const int g = ex.Get("scenelod").Get("group").GetNumberAsInt();
      if (g >= 0 && (original.primitive_materials.empty() || static_cast<size_t>(g) < original.primitive_materials.size())) {
        to_source[p] = static_cast<uint32_t>(g);
        continue;
      }
    }
    const int32_t mat = p < level_data.primitive_materials.size() ? level_data.primitive_materials[p] : -1;
    const auto it = std::find(original.primitive_materials.begin(), original.primitive_materials.end(), mat);
    if (it != original.primitive_materials.end()) to_source[p] = static_cast<uint32_t>(it - original.primitive_materials.begin());
  }
  auto remap = [&](std::vector<uint32_t>& groups) {
    for (uint32_t& g : groups)
      if (g < to_source.size()) g = to_source[g];
  };
  remap(level.triangle_groups);
  remap(level.edge_groups);
  remap(level.point_groups);
  // a level drawn by one primitive of group 0 needs no group arrays
  auto allZero = [](const std::vector<uint32_t>& v) { return std::all_of(v.begin(), v.end(), [](uint32_t g) { return g == 0; }); };
  if (allZero(level.triangle_groups) && allZero(level.edge_groups) && allZero(level.point_groups)) {
    level.triangle_groups.clear();
    level.edge_groups.clear();
    level.point_groups.clear();
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

namespace detail {

std::string imageMimeType(const std::vector<uint8_t>& bytes, const std::string& declared) {
  static const unsigned char kPng[] = {0x89, 'P', 'N', 'G'};
  if (bytes.size() >= 4 && std::memcmp(bytes.data(), kPng, 4) == 0) return "image/png";
  if (bytes.size() >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff) return "image/jpeg";
  return declared;
}

Error loadGltfFile(const std::string& path, GltfFile& out) {
  return withoutExceptions(path, [&]() -> Error {
    LoadContext ctx;
    if (Error e = loadModel(path, out.model, ctx); !e.ok()) return e;
    out.image_bytes = std::move(ctx.image_bytes);
    out.image_bytes.resize(out.model.images.size());
    out.read_paths = std::move(ctx.read_paths);
    out.read_paths.insert(out.read_paths.begin(), path);
    return {};
  });
}

}  // namespace detail

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
    s.materials = std::move(raw.materials);
    s.textures = std::move(raw.textures);
    s.images = std::move(raw.images);
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
    if (Error e = remapSkinsAndAnimations(path, raw, node_map, s); !e.ok()) return e;

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
        levelGroupsAsSourceGroups(model.meshes[static_cast<size_t>(ln.mesh)], raw.meshes[static_cast<size_t>(ln.mesh)],
                                  s.meshes[m], level.mesh);
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
