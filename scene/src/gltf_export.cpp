// GLB export through tinygltf: node hierarchy, meshes (TRIANGLES, LINES with _THICKNESS, POINTS),
// vertex colours, and LOD chains as MSFT_lod with MSFT_screencoverage (docs/IO.md).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <utility>

#include <glm/geometric.hpp>
#include <tiny_gltf.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"

#include "scenelod/lodcore/atomic_file.h"
#include "gltf_model.h"

namespace scenelod::scene {

namespace {

// unit vectors as glTF readers require (within 1e-6 they are kept bit for bit); zero ones become
// `fallback`
std::vector<glm::vec3> unitVectors(std::vector<glm::vec3> v, const glm::vec3& fallback = glm::vec3(0.0f, 0.0f, 1.0f)) {
  for (glm::vec3& n : v) {
    const float len = glm::length(n);
    if (!(std::fabs(len - 1.0f) <= 1e-6f)) n = len > 0.0f && std::isfinite(len) ? n / len : fallback;
  }
  return v;
}

std::vector<glm::vec4> unitTangents(const std::vector<glm::vec4>& v) {
  std::vector<glm::vec3> xyz(v.size());
  for (size_t i = 0; i < v.size(); ++i) xyz[i] = glm::vec3(v[i]);
  xyz = unitVectors(std::move(xyz), glm::vec3(1.0f, 0.0f, 0.0f));
  std::vector<glm::vec4> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = glm::vec4(xyz[i], v[i].w);
  return out;
}

// skin weights summing to 1 (within 1e-6 they are kept bit for bit)
std::vector<glm::vec4> unitSums(const std::vector<glm::vec4>& w) {
  std::vector<glm::vec4> out(w);
  for (glm::vec4& x : out) {
    const float sum = x.x + x.y + x.z + x.w;
    if (!(std::fabs(sum - 1.0f) <= 1e-6f) && sum > 0.0f) x /= sum;
  }
  return out;
}

class GlbWriter {
 public:
  tinygltf::Model model;

  GlbWriter() {
    model.asset.version = "2.0";
    model.asset.generator = "scenelod";
    model.buffers.emplace_back();
  }

  // appends raw bytes as a new buffer view (4-byte aligned); returns its index
  int addView(const void* data, size_t bytes, int target) {
    std::vector<unsigned char>& buf = model.buffers[0].data;
    while (buf.size() % 4 != 0) buf.push_back(0);
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteOffset = buf.size();
    bv.byteLength = bytes;
    bv.target = target;
    const unsigned char* p = static_cast<const unsigned char*>(data);
    buf.insert(buf.end(), p, p + bytes);
    model.bufferViews.push_back(bv);
    return static_cast<int>(model.bufferViews.size() - 1);
  }

  int addFloatAccessor(const float* data, size_t count, int type, int comps, bool minmax) {
    tinygltf::Accessor a;
    a.bufferView = addView(data, count * static_cast<size_t>(comps) * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    a.byteOffset = 0;
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = count;
    a.type = type;
    if (minmax && count > 0) {
      a.minValues.assign(static_cast<size_t>(comps), 0.0);
      a.maxValues.assign(static_cast<size_t>(comps), 0.0);
      for (int k = 0; k < comps; ++k) a.minValues[static_cast<size_t>(k)] = a.maxValues[static_cast<size_t>(k)] = data[k];
      for (size_t i = 0; i < count; ++i)
        for (int k = 0; k < comps; ++k) {
          const double v = data[i * static_cast<size_t>(comps) + static_cast<size_t>(k)];
          a.minValues[static_cast<size_t>(k)] = std::min(a.minValues[static_cast<size_t>(k)], v);
          a.maxValues[static_cast<size_t>(k)] = std::max(a.maxValues[static_cast<size_t>(k)], v);
        }
    }
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size() - 1);
  }

  int addIndexAccessor(const std::vector<uint32_t>& idx) {
    tinygltf::Accessor a;
    a.bufferView = addView(idx.data(), idx.size() * sizeof(uint32_t), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    a.byteOffset = 0;
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    a.count = idx.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size() - 1);
  }

  struct VertexSet {
    std::map<std::string, int> attributes;
  };

  // appends a float attribute, gathered through `source` (the original vertex of each new vertex)
  // when given; returns its accessor
  template <class T>
  int addAttribute(const std::vector<T>& attr, const std::vector<uint32_t>* source, int type, int comps) {
    std::vector<T> gathered;
    if (source) {
      gathered.reserve(source->size());
      for (uint32_t v : *source) gathered.push_back(attr[v]);
    }
    const std::vector<T>& data = source ? gathered : attr;
    return addFloatAccessor(&data[0][0], data.size(), type, comps, false);
  }

  int addJoints(const std::vector<glm::u16vec4>& joints, const std::vector<uint32_t>* source) {
    std::vector<glm::u16vec4> data;
    if (source) {
      for (uint32_t v : *source) data.push_back(joints[v]);
    } else {
      data = joints;
    }
    tinygltf::Accessor a;
    a.bufferView = addView(data.data(), data.size() * sizeof(glm::u16vec4), TINYGLTF_TARGET_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    a.count = data.size();
    a.type = TINYGLTF_TYPE_VEC4;
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size() - 1);
  }

  // every attribute the mesh has: POSITION, NORMAL and TANGENT (unit length, as readers require),
  // COLOR_0, TEXCOORD_n, and JOINTS_0 / WEIGHTS_0 (weights summing to 1) when write_skin is set
  VertexSet addVertices(const Mesh& m, const std::vector<glm::vec3>& positions, const std::vector<uint32_t>* source) {
    VertexSet vs;
    vs.attributes["POSITION"] = addFloatAccessor(&positions[0].x, positions.size(), TINYGLTF_TYPE_VEC3, 3, true);
    if (!m.normals.empty()) vs.attributes["NORMAL"] = addAttribute(unitVectors(m.normals), source, TINYGLTF_TYPE_VEC3, 3);
    if (!m.tangents.empty()) vs.attributes["TANGENT"] = addAttribute(unitTangents(m.tangents), source, TINYGLTF_TYPE_VEC4, 4);
    if (!m.colors.empty()) vs.attributes["COLOR_0"] = addAttribute(m.colors, source, TINYGLTF_TYPE_VEC3, 3);
    if (!m.uvs.empty()) vs.attributes["TEXCOORD_0"] = addAttribute(m.uvs, source, TINYGLTF_TYPE_VEC2, 2);
    for (size_t set = 0; set < m.extra_uvs.size(); ++set)
      vs.attributes["TEXCOORD_" + std::to_string(set + 1)] = addAttribute(m.extra_uvs[set], source, TINYGLTF_TYPE_VEC2, 2);
    if (write_skin && m.skinned()) {
      vs.attributes["JOINTS_0"] = addJoints(m.joints, source);
      vs.attributes["WEIGHTS_0"] = addAttribute(unitSums(m.weights), source, TINYGLTF_TYPE_VEC4, 4);
    }
    return vs;
  }

  bool write_skin = false;  // JOINTS_0 and WEIGHTS_0 are written only beside their skin

  // edges with a thickness: glTF has per-vertex attributes only, so when every vertex's edges agree
  // on their thickness the lines share the mesh's vertices, otherwise each edge gets two of its own
  tinygltf::Primitive addThickLines(const Mesh& m, const VertexSet& shared) {
    tinygltf::Primitive p;
    std::vector<float> vertex_thickness(m.vertexCount(), -1.0f);
    bool consistent = true;
    for (size_t e = 0; e < m.edgeCount() && consistent; ++e)
      for (int k = 0; k < 2; ++k) {
        float& t = vertex_thickness[m.edges[2 * e + static_cast<size_t>(k)]];
        if (t >= 0.0f && t != m.edge_thickness[e]) consistent = false;
        t = m.edge_thickness[e];
      }
    if (consistent) {
      for (float& t : vertex_thickness) t = std::max(t, 0.0f);
      p.attributes = shared.attributes;
      p.attributes["_THICKNESS"] =
          addFloatAccessor(vertex_thickness.data(), vertex_thickness.size(), TINYGLTF_TYPE_SCALAR, 1, false);
      p.indices = addIndexAccessor(m.edges);
      return p;
    }
    std::vector<glm::vec3> pos;
    std::vector<float> thick;
    std::vector<uint32_t> idx;
    for (size_t e = 0; e < m.edgeCount(); ++e)
      for (int k = 0; k < 2; ++k) {
        pos.push_back(m.positions[m.edges[2 * e + static_cast<size_t>(k)]]);
        thick.push_back(m.edge_thickness[e]);
        idx.push_back(static_cast<uint32_t>(idx.size()));
      }
    const VertexSet own = addVertices(m, pos, &m.edges);
    p.attributes = own.attributes;
    p.attributes["_THICKNESS"] = addFloatAccessor(thick.data(), thick.size(), TINYGLTF_TYPE_SCALAR, 1, false);
    p.indices = addIndexAccessor(idx);
    return p;
  }

  // writes a mesh; returns its index
  int addMesh(const Mesh& m, const std::string& name, int material) {
    tinygltf::Mesh out;
    out.name = name;
    const VertexSet shared = addVertices(m, m.positions, nullptr);
    const auto add = [&](tinygltf::Primitive p, int mode) {
      p.mode = mode;
      p.material = material;
      out.primitives.push_back(std::move(p));
    };
    // a primitive over the mesh's own vertices
    const auto sharing = [&](const std::vector<uint32_t>& indices) {
      tinygltf::Primitive p;
      p.attributes = shared.attributes;
      p.indices = addIndexAccessor(indices);
      return p;
    };
    if (!m.triangles.empty()) add(sharing(m.triangles), TINYGLTF_MODE_TRIANGLES);
    if (!m.edges.empty())
      add(m.edge_thickness.empty() ? sharing(m.edges) : addThickLines(m, shared), TINYGLTF_MODE_LINE);
    if (!m.points.empty()) add(sharing(m.points), TINYGLTF_MODE_POINTS);
    model.meshes.push_back(out);
    return static_cast<int>(model.meshes.size() - 1);
  }
};

bool isIdentity(const glm::mat4& m) { return m == glm::mat4(1.0f); }

void setMatrix(tinygltf::Node& node, const glm::mat4& m) {
  if (isIdentity(m)) return;
  node.matrix.resize(16);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) node.matrix[static_cast<size_t>(c * 4 + r)] = m[c][r];
}

tinygltf::Value levelExtras(const LodLevel& level) {
  tinygltf::Value::Object o;
  o["cell_width"] = tinygltf::Value(static_cast<double>(level.cell_width));
  o["max_error"] = tinygltf::Value(static_cast<double>(level.max_error));
  o["method"] = tinygltf::Value(std::string(lodMethodName(level.method)));
  return tinygltf::Value(o);
}

// the minimal bounding sphere of level 0's vertices, whatever bounds the caller stored
float sphereRadius(const LodLevel& level) {
  return minimalSphere(Span<const glm::vec3>(level.mesh.positions.data(), level.mesh.positions.size())).radius;
}

// MSFT_screencoverage of a chain: value i is where level i + 1 becomes accurate enough, 0 for the
// last level (docs/IO.md)
tinygltf::Value coverageValues(const LodChain& c) {
  tinygltf::Value::Array coverage;
  const float r = sphereRadius(c.levels[0]);
  for (size_t l = 0; l < c.levelCount(); ++l) {
    const double next = l + 1 < c.levelCount() ? c.levels[l + 1].cell_width : 0.0;
    coverage.emplace_back(next > 0.0 ? 2.0 * r * kCoverageCellPixels / (next * kCoverageViewportPx) : 0.0);
  }
  return tinygltf::Value(coverage);
}

// levels 1.. of the chain of mesh m: not empty, valid, cell widths strictly increasing
Error checkChainLevels(const std::string& path, const LodChain& c, size_t m) {
  for (size_t l = 1; l < c.levelCount(); ++l) {
    const std::string what = path + ": chain of mesh " + std::to_string(m) + " level " + std::to_string(l);
    if (c.levels[l].mesh.empty()) return {Status::kInvalidArgument, what + " is empty"};
    if (!(c.levels[l].cell_width > c.levels[l - 1].cell_width))
      return {Status::kInvalidArgument, what + ": cell widths must strictly increase"};
    if (Error e = validateMesh(c.levels[l].mesh, what); !e.ok()) return e;
  }
  return {};
}

}  // namespace

Error exportGlb(const std::string& path, const SceneData& scene, const std::vector<const LodChain*>* chains) {
  if (Error e = validateSceneData(scene, path); !e.ok()) return e;
  if (chains && chains->size() != scene.meshes.size())
    return {Status::kInvalidArgument, path + ": " + std::to_string(chains->size()) + " chains for " +
                                          std::to_string(scene.meshes.size()) + " meshes"};
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (scene.meshes[m].mesh.empty())
      return {Status::kInvalidArgument, path + ": mesh " + std::to_string(m) + " has no triangles, edges or points (glTF needs a primitive)"};
  auto chainOf = [&](size_t m) -> const LodChain* {
    if (!chains) return nullptr;
    const LodChain* c = (*chains)[m];
    return c && c->levelCount() >= 2 ? c : nullptr;
  };
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (const LodChain* c = chainOf(m))
      if (Error e = checkChainLevels(path, *c, m); !e.ok()) return e;
  try {
    GlbWriter w;
    // one material per mesh when the mesh has no baked colours and its primitives share one material;
    // baked colours go to COLOR_0 without a material, so an import gets the same colours back
    std::vector<int> material_of_material(scene.materials.size(), -1);
    auto materialFor = [&](const MeshData& md) -> int {
      if (!md.mesh.colors.empty() || md.primitive_materials.empty()) return -1;
      const int32_t mat = md.primitive_materials[0];
      for (int32_t other : md.primitive_materials)
        if (other != mat) return -1;
      if (mat < 0) return -1;
      int& out = material_of_material[static_cast<size_t>(mat)];
      if (out < 0) {
        const MaterialData& src = scene.materials[static_cast<size_t>(mat)];
        tinygltf::Material gm;
        gm.name = src.name;
        gm.pbrMetallicRoughness.baseColorFactor = {src.base_color.r, src.base_color.g, src.base_color.b, src.base_color.a};
        w.model.materials.push_back(gm);
        out = static_cast<int>(w.model.materials.size() - 1);
      }
      return out;
    };
    std::vector<int> mesh_index(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m)
      mesh_index[m] = w.addMesh(scene.meshes[m].mesh, scene.meshes[m].name, materialFor(scene.meshes[m]));
    // level meshes, shared by every instance of their mesh
    std::vector<std::vector<int>> level_meshes(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
      const LodChain* c = chainOf(m);
      if (!c) continue;
      const int mat = materialFor(scene.meshes[m]);
      for (size_t l = 1; l < c->levelCount(); ++l)
        level_meshes[m].push_back(
            w.addMesh(c->levels[l].mesh, scene.meshes[m].name + "_LOD" + std::to_string(l), c->levels[l].mesh.colors.empty() ? mat : -1));
    }
    for (const NodeData& src : scene.nodes) {
      tinygltf::Node node;
      node.name = src.name;
      setMatrix(node, src.local);
      node.children.assign(src.children.begin(), src.children.end());
      node.mesh = src.mesh >= 0 ? mesh_index[static_cast<size_t>(src.mesh)] : -1;
      w.model.nodes.push_back(node);
    }
    bool any_lod = false;
    for (size_t i = 0; i < scene.nodes.size(); ++i) {
      const int32_t m = scene.nodes[i].mesh;
      if (m < 0) continue;
      const LodChain* c = chainOf(static_cast<size_t>(m));
      if (!c) continue;
      any_lod = true;
      tinygltf::Value::Array ids;
      for (size_t l = 1; l < c->levelCount(); ++l) {
        tinygltf::Node level;
        level.name = (scene.nodes[i].name.empty() ? "node" + std::to_string(i) : scene.nodes[i].name) + "_LOD" + std::to_string(l);
        setMatrix(level, scene.nodes[i].local);
        level.mesh = level_meshes[static_cast<size_t>(m)][l - 1];
        tinygltf::Value::Object extras;
        extras["scenelod"] = levelExtras(c->levels[l]);
        level.extras = tinygltf::Value(extras);
        w.model.nodes.push_back(level);
        ids.emplace_back(static_cast<int>(w.model.nodes.size() - 1));
      }
      tinygltf::Node& node = w.model.nodes[i];
      tinygltf::Value::Object lod;
      lod["ids"] = tinygltf::Value(ids);
      node.extensions["MSFT_lod"] = tinygltf::Value(lod);
      tinygltf::Value::Object extras;
      extras["MSFT_screencoverage"] = coverageValues(*c);
      extras["scenelod"] = levelExtras(c->levels[0]);
      node.extras = tinygltf::Value(extras);
    }
    if (any_lod) w.model.extensionsUsed.push_back("MSFT_lod");
    tinygltf::Scene sc;
    sc.nodes.assign(scene.roots.begin(), scene.roots.end());
    w.model.scenes.push_back(sc);
    w.model.defaultScene = 0;
    if (w.model.buffers[0].data.empty()) w.model.buffers.clear();

    std::ostringstream glb;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&w.model, glb, false, true))
      return {Status::kIoError, path + ": cannot serialise the GLB"};
    const std::string bytes = glb.str();
    if (Error e = writeFileAtomic(path, bytes.data(), bytes.size()); !e.ok()) return e;
  } catch (const std::bad_alloc&) {
    return {Status::kOutOfMemory, path + ": out of memory while writing"};
  } catch (const std::exception& e) {
    return {Status::kIoError, path + ": cannot write GLB: " + e.what()};
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// pass-through export: the input file's model kept, LOD levels appended

namespace {

// required extensions whose meaning survives appending levels: material and texture ones (levels
// use the same materials), quantised attributes (level 0 keeps its own; levels are floats)
bool keepableRequiredExtension(const std::string& ext) {
  return ext == "KHR_texture_transform" || ext == "KHR_mesh_quantization" || ext == "KHR_texture_basisu" ||
         ext == "EXT_texture_webp" || ext == "EXT_texture_avif" || ext == "KHR_lights_punctual" ||
         ext.rfind("KHR_materials_", 0) == 0;
}

// every buffer's bytes appended to buffer 0 (4-byte aligned), buffer views moved with them: a GLB
// has one binary chunk, and a .gltf output one .bin
void mergeBuffers(tinygltf::Model& m) {
  if (m.buffers.empty()) m.buffers.emplace_back();
  std::vector<size_t> base(m.buffers.size(), 0);
  std::vector<unsigned char>& data = m.buffers[0].data;
  for (size_t b = 1; b < m.buffers.size(); ++b) {
    while (data.size() % 4 != 0) data.push_back(0);
    base[b] = data.size();
    data.insert(data.end(), m.buffers[b].data.begin(), m.buffers[b].data.end());
  }
  m.buffers.resize(1);
  m.buffers[0].uri.clear();
  for (tinygltf::BufferView& bv : m.bufferViews) {
    if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= base.size()) continue;
    bv.byteOffset += base[static_cast<size_t>(bv.buffer)];
    bv.buffer = 0;
  }
}

std::string extensionOfMime(const std::string& mime) {
  if (mime == "image/png") return ".png";
  if (mime == "image/jpeg") return ".jpg";
  if (mime == "image/ktx2") return ".ktx2";
  if (mime == "image/webp") return ".webp";
  return ".bin";
}

std::string mimeOfUri(const std::string& uri) {
  const std::string ext = lowerExtension(uri);
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".ktx2") return "image/ktx2";
  if (ext == ".webp") return "image/webp";
  return "application/octet-stream";
}

// images outside the buffer: into it (GLB, or data URIs in a .gltf), or a file of their own beside a
// .gltf output (`files`: path and bytes to write)
void placeImages(GlbWriter& w, const std::vector<std::vector<uint8_t>>& bytes, bool glb, const std::string& out_prefix,
                 std::vector<std::pair<std::string, const std::vector<uint8_t>*>>& files) {
  for (size_t i = 0; i < w.model.images.size(); ++i) {
    tinygltf::Image& img = w.model.images[i];
    if (img.bufferView >= 0) continue;
    const std::string mime = detail::imageMimeType(bytes[i], img.mimeType.empty() ? mimeOfUri(img.uri) : img.mimeType);
    if (glb || img.uri.empty()) {
      img.bufferView = w.addView(bytes[i].data(), bytes[i].size(), 0);
      img.mimeType = mime;
      img.uri.clear();
    } else {
      const std::string name = out_prefix + "_image" + std::to_string(i) + extensionOfMime(mime);
      img.uri = name.substr(name.find_last_of('/') + 1);
      files.emplace_back(name, &bytes[i]);
    }
  }
}

// the texture coordinate sets a texture reference reads: its texCoord, or KHR_texture_transform's
int texCoordOf(int texcoord, const tinygltf::ExtensionMap& ext) {
  const auto t = ext.find("KHR_texture_transform");
  if (t != ext.end() && t->second.IsObject() && t->second.Has("texCoord") && t->second.Get("texCoord").IsNumber())
    return t->second.Get("texCoord").GetNumberAsInt();
  return texcoord;
}

// the largest texCoord + 1 of the texture references inside an extension's value ({"index": ...})
int texCoordSetsIn(const tinygltf::Value& v) {
  int sets = 0;
  if (v.IsObject()) {
    if (v.Has("index") && v.Get("index").IsNumber()) {
      int tc = v.Has("texCoord") && v.Get("texCoord").IsNumber() ? v.Get("texCoord").GetNumberAsInt() : 0;
      if (v.Has("extensions") && v.Get("extensions").IsObject() && v.Get("extensions").Has("KHR_texture_transform")) {
        const tinygltf::Value& t = v.Get("extensions").Get("KHR_texture_transform");
        if (t.IsObject() && t.Has("texCoord") && t.Get("texCoord").IsNumber()) tc = t.Get("texCoord").GetNumberAsInt();
      }
      sets = tc + 1;
    }
    for (const std::string& key : v.Keys()) sets = std::max(sets, texCoordSetsIn(v.Get(key)));
  } else if (v.IsArray()) {
    for (size_t i = 0; i < v.ArrayLen(); ++i) sets = std::max(sets, texCoordSetsIn(v.Get(static_cast<int>(i))));
  }
  return sets;
}

// how many TEXCOORD sets a material's textures need
int texCoordSetsNeeded(const tinygltf::Material& m) {
  int sets = 0;
  auto use = [&](int index, int texcoord, const tinygltf::ExtensionMap& ext) {
    if (index >= 0) sets = std::max(sets, texCoordOf(texcoord, ext) + 1);
  };
  const auto& pbr = m.pbrMetallicRoughness;
  use(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, pbr.baseColorTexture.extensions);
  use(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord, pbr.metallicRoughnessTexture.extensions);
  use(m.normalTexture.index, m.normalTexture.texCoord, m.normalTexture.extensions);
  use(m.occlusionTexture.index, m.occlusionTexture.texCoord, m.occlusionTexture.extensions);
  use(m.emissiveTexture.index, m.emissiveTexture.texCoord, m.emissiveTexture.extensions);
  for (const auto& [name, value] : m.extensions) sets = std::max(sets, texCoordSetsIn(value));
  return sets;
}

// Materials for level primitives that cannot use their source material's textures (too few UV
// sets, or a normal map without the tangents the source had): an untextured copy, its base colour
// factor times the base colour texture's mean (what SCROOGE draws far levels with), emission off
// where a texture drove it, material extensions dropped. Made once per source material.
class FallbackMaterials {
 public:
  FallbackMaterials(tinygltf::Model& model, const SceneData& scene) : model_(model), scene_(scene) {}

  int materialFor(int material, const Mesh& level, bool source_had_tangents) {
    if (material < 0 || static_cast<size_t>(material) >= model_.materials.size()) return material;
    const tinygltf::Material& src = model_.materials[static_cast<size_t>(material)];
    const int sets = level.uvs.empty() ? 0 : 1 + static_cast<int>(level.extra_uvs.size());
    const bool lost_tangents = src.normalTexture.index >= 0 && source_had_tangents && level.tangents.empty();
    if (texCoordSetsNeeded(src) <= sets && !lost_tangents) return material;
    auto found = made_.find(material);
    if (found != made_.end()) return found->second;
    tinygltf::Material m = src;
    m.name = (src.name.empty() ? "material" + std::to_string(material) : src.name) + "_untextured";
    glm::vec3 mean(1.0f);
    if (static_cast<size_t>(material) < scene_.materials.size() && scene_.materials[static_cast<size_t>(material)].textured)
      mean = scene_.materials[static_cast<size_t>(material)].average_texel_color;
    std::vector<double>& f = m.pbrMetallicRoughness.baseColorFactor;
    if (f.size() != 4) f = {1.0, 1.0, 1.0, 1.0};
    for (int k = 0; k < 3; ++k) f[static_cast<size_t>(k)] *= mean[k];
    if (m.emissiveTexture.index >= 0) m.emissiveFactor = {0.0, 0.0, 0.0};
    m.pbrMetallicRoughness.baseColorTexture = tinygltf::TextureInfo();
    m.pbrMetallicRoughness.metallicRoughnessTexture = tinygltf::TextureInfo();
    m.normalTexture = tinygltf::NormalTextureInfo();
    m.occlusionTexture = tinygltf::OcclusionTextureInfo();
    m.emissiveTexture = tinygltf::TextureInfo();
    m.extensions.clear();
    model_.materials.push_back(std::move(m));
    return made_[material] = static_cast<int>(model_.materials.size() - 1);
  }

  // a primitive's KHR_materials_variants with each mapping's material replaced as materialFor does
  tinygltf::Value variantsFor(const tinygltf::Value& ext, const Mesh& level, bool source_had_tangents) {
    if (!ext.IsObject() || !ext.Has("mappings") || !ext.Get("mappings").IsArray()) return ext;
    tinygltf::Value::Object out = ext.Get<tinygltf::Value::Object>();
    tinygltf::Value::Array mappings = ext.Get("mappings").Get<tinygltf::Value::Array>();
    for (tinygltf::Value& mapping : mappings) {
      if (!mapping.IsObject() || !mapping.Has("material") || !mapping.Get("material").IsNumber()) continue;
      tinygltf::Value::Object o = mapping.Get<tinygltf::Value::Object>();
      o["material"] = tinygltf::Value(materialFor(mapping.Get("material").GetNumberAsInt(), level, source_had_tangents));
      mapping = tinygltf::Value(o);
    }
    out["mappings"] = tinygltf::Value(mappings);
    return tinygltf::Value(out);
  }

 private:
  tinygltf::Model& model_;
  const SceneData& scene_;
  std::map<int, int> made_;
};

// one level's mesh: its vertices shared by one TRIANGLES primitive per triangle group still
// present (the source primitive's material and KHR_materials_variants mappings), LINES and POINTS
// one per edge and point group, with that group's source primitive's material
int addLevelMesh(GlbWriter& w, FallbackMaterials& fallback, const Mesh& level, const tinygltf::Mesh& src,
                 const std::string& name) {
  tinygltf::Mesh out;
  out.name = name;
  w.write_skin = level.skinned();  // for the thick lines' own vertices too
  const GlbWriter::VertexSet shared = w.addVertices(level, level.positions, nullptr);
  std::map<uint32_t, std::vector<uint32_t>> by_group;
  for (size_t t = 0; t < level.triangleCount(); ++t)
    by_group[level.triangleGroup(t)].insert(by_group[level.triangleGroup(t)].end(), level.triangles.begin() + 3 * t,
                                            level.triangles.begin() + 3 * t + 3);
  auto source = [&](uint32_t g) -> const tinygltf::Primitive* {
    if (g < src.primitives.size()) return &src.primitives[g];
    return src.primitives.empty() ? nullptr : &src.primitives[0];
  };
  auto add = [&](tinygltf::Primitive p, int mode, uint32_t group) {
    p.mode = mode;
    // the source primitive (group) this one draws, so that importGltfLods gives chains whose
    // groups index level 0's primitives (materials can repeat, and untextured copies differ)
    tinygltf::Value::Object ours, extras;
    ours["group"] = tinygltf::Value(static_cast<int>(group));
    extras["scenelod"] = tinygltf::Value(ours);
    p.extras = tinygltf::Value(extras);
    if (const tinygltf::Primitive* sp = source(group)) {
      const bool tangents = sp->attributes.count("TANGENT") > 0;
      p.material = fallback.materialFor(sp->material, level, tangents);
      const auto variants = sp->extensions.find("KHR_materials_variants");
      if (variants != sp->extensions.end())
        p.extensions[variants->first] = fallback.variantsFor(variants->second, level, tangents);
    }
    out.primitives.push_back(std::move(p));
  };
  auto sharing = [&](const std::vector<uint32_t>& indices) {
    tinygltf::Primitive p;
    p.attributes = shared.attributes;
    p.indices = w.addIndexAccessor(indices);
    return p;
  };
  for (const auto& [group, indices] : by_group) add(sharing(indices), TINYGLTF_MODE_TRIANGLES, group);
  // thick edges and points in their own group's material (a thin part collapsed into edges keeps
  // its material): one LINES and one POINTS primitive per group present
  std::map<uint32_t, std::vector<size_t>> edges_by_group;
  for (size_t e = 0; e < level.edgeCount(); ++e) edges_by_group[level.edgeGroup(e)].push_back(e);
  for (const auto& [group, list] : edges_by_group) {
    if (edges_by_group.size() == 1) {
      add(level.edge_thickness.empty() ? sharing(level.edges) : w.addThickLines(level, shared), TINYGLTF_MODE_LINE, group);
      continue;
    }
    Mesh part = level;  // (levels with edges in several groups are rare and their edges few)
    part.edges.clear(), part.edge_thickness.clear(), part.edge_groups.clear();
    for (size_t e : list) {
      part.edges.insert(part.edges.end(), {level.edges[2 * e], level.edges[2 * e + 1]});
      if (!level.edge_thickness.empty()) part.edge_thickness.push_back(level.edge_thickness[e]);
    }
    add(part.edge_thickness.empty() ? sharing(part.edges) : w.addThickLines(part, shared), TINYGLTF_MODE_LINE, group);
  }
  std::map<uint32_t, std::vector<uint32_t>> points_by_group;
  for (size_t i = 0; i < level.pointCount(); ++i) points_by_group[level.pointGroup(i)].push_back(level.points[i]);
  for (const auto& [group, indices] : points_by_group) add(sharing(indices), TINYGLTF_MODE_POINTS, group);
  w.write_skin = false;
  w.model.meshes.push_back(std::move(out));
  return static_cast<int>(w.model.meshes.size() - 1);
}

bool hasMorphTargets(const tinygltf::Mesh& m) {
  for (const tinygltf::Primitive& p : m.primitives)
    if (!p.targets.empty()) return true;
  return false;
}

// a level node of node i: the level mesh, the node's skin when the level is skinned (no transform:
// glTF ignores a skinned node's own), otherwise the node's local transform; a skinned node's level
// without weights is drawn unskinned in the bind pose (identity)
tinygltf::Node levelNode(const tinygltf::Model& m, size_t i, int mesh, const LodLevel& level, size_t l, bool morph_dropped,
                         std::vector<std::string>* notes) {
  const tinygltf::Node& src = m.nodes[i];
  tinygltf::Node node;
  node.name = (src.name.empty() ? "node" + std::to_string(i) : src.name) + "_LOD" + std::to_string(l);
  node.mesh = mesh;
  tinygltf::Value::Object scenelod = levelExtras(level).Get<tinygltf::Value::Object>();
  if (src.skin >= 0 && level.mesh.skinned()) {
    node.skin = src.skin;
  } else if (src.skin < 0) {
    node.matrix = src.matrix;
    node.translation = src.translation;
    node.rotation = src.rotation;
    node.scale = src.scale;
  } else {
    scenelod["skin"] = tinygltf::Value(std::string("dropped"));
    if (notes && l == 1) notes->push_back("node " + std::to_string(i) + ": levels without skin weights are drawn unskinned");
  }
  if (morph_dropped) {
    scenelod["morph_targets"] = tinygltf::Value(std::string("dropped"));
    if (notes && l == 1) notes->push_back("node " + std::to_string(i) + ": morph targets stay on level 0; levels have none");
  }
  tinygltf::Value::Object extras;
  extras["scenelod"] = tinygltf::Value(scenelod);
  node.extras = tinygltf::Value(extras);
  return node;
}

// a copy of vertex `from` of `m` (every attribute) at `p` with normal `n`, appended to `m`
uint32_t copyVertex(Mesh& m, uint32_t from, const glm::vec3& p, const glm::vec3& n) {
  auto copy = [from](auto& v) {
    if (!v.empty()) v.push_back(v[from]);
  };
  m.positions.push_back(p);
  if (!m.normals.empty()) m.normals.push_back(n);
  copy(m.colors), copy(m.uvs), copy(m.tangents), copy(m.joints), copy(m.weights);
  for (std::vector<glm::vec2>& set : m.extra_uvs) copy(set);
  return static_cast<uint32_t>(m.positions.size() - 1);
}

// Thick edges and points as triangles any viewer draws (glTF viewers draw LINES one pixel wide and
// ignore _THICKNESS): each edge of thickness t > 0 a 3-sided prism of circumradius t / 2 along it
// (6 vertices, 8 triangles), each point an octahedron of circumradius half the level's cell width
// (6 vertices, 8 triangles), in the edge's or point's group, their vertices copies of its own
// (texture coordinates, colour, skin) with radial normals. Hairline edges (thickness 0) stay edges.
// Returns the triangles added.
size_t thickPrimitivesAsTriangles(Mesh& m, float cell_width) {
  const size_t before = m.triangleCount();
  if (m.triangle_groups.empty()) m.triangle_groups.assign(before, 0u);
  if (m.normals.empty() && !m.positions.empty()) m.normals.assign(m.positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  auto addTriangle = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t group) {
    m.triangles.insert(m.triangles.end(), {a, b, c});
    m.triangle_groups.push_back(group);
  };
  std::vector<uint32_t> edges;
  std::vector<float> thickness;
  std::vector<uint32_t> edge_groups;
  const size_t edge_count = m.edgeCount();
  for (size_t e = 0; e < edge_count; ++e) {
    const uint32_t ia = m.edges[2 * e], ib = m.edges[2 * e + 1];
    const float r = 0.5f * m.edgeThickness(e);
    const glm::vec3 a = m.positions[ia], b = m.positions[ib];
    const float len = glm::length(b - a);
    if (!(r > 0.0f) || !(len > 0.0f)) {  // hairlines (and zero-length edges) stay edges
      edges.insert(edges.end(), {ia, ib});
      thickness.push_back(m.edgeThickness(e));
      edge_groups.push_back(m.edgeGroup(e));
      continue;
    }
    const glm::vec3 d = (b - a) / len;
    const glm::vec3 helper = std::fabs(d.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 u = glm::normalize(glm::cross(d, helper)), v = glm::cross(d, u);
    uint32_t ra[3], rb[3];
    for (int k = 0; k < 3; ++k) {
      const float angle = 2.0943951f * float(k);
      const glm::vec3 radial = std::cos(angle) * u + std::sin(angle) * v;
      ra[k] = copyVertex(m, ia, a + r * radial, radial);
      rb[k] = copyVertex(m, ib, m.positions[ib] + r * radial, radial);
    }
    const uint32_t g = m.edgeGroup(e);
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3;
      addTriangle(ra[k], ra[k1], rb[k1], g);
      addTriangle(ra[k], rb[k1], rb[k], g);
    }
    addTriangle(ra[0], ra[2], ra[1], g);
    addTriangle(rb[0], rb[1], rb[2], g);
  }
  const float pr = 0.5f * cell_width;
  std::vector<uint32_t> points, point_groups;
  for (size_t i = 0; i < m.pointCount(); ++i) {
    if (!(pr > 0.0f)) {
      points.push_back(m.points[i]);
      point_groups.push_back(m.pointGroup(i));
      continue;
    }
    static const glm::vec3 kAxes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    uint32_t c[6];
    for (int k = 0; k < 6; ++k) c[k] = copyVertex(m, m.points[i], m.positions[m.points[i]] + pr * kAxes[k], kAxes[k]);
    const uint32_t g = m.pointGroup(i);
    // the eight faces (+-x, +-y, +-z), each wound counter-clockwise seen from outside
    for (int sx = 0; sx < 2; ++sx)
      for (int sy = 0; sy < 2; ++sy)
        for (int sz = 0; sz < 2; ++sz) {
          const uint32_t x = c[sx], y = c[2 + sy], z = c[4 + sz];
          if ((sx + sy + sz) % 2 == 0) addTriangle(x, y, z, g);
          else addTriangle(x, z, y, g);
        }
  }
  m.edges.swap(edges);
  m.edge_thickness.swap(thickness);
  m.edge_groups.swap(edge_groups);
  m.points.swap(points);
  m.point_groups.swap(point_groups);
  if (std::all_of(m.edge_thickness.begin(), m.edge_thickness.end(), [](float t) { return t == 0.0f; }))
    m.edge_thickness.clear();
  return m.triangleCount() - before;
}

// appends every chain's level meshes (shared by the mesh's instances) and level nodes, and
// MSFT_lod with the coverage values on every node that draws a mesh with levels
void addLodLevels(GlbWriter& w, const SceneData& scene, const std::vector<const LodChain*>& chains,
                  ThickEdges thick_edges, std::vector<std::string>* notes) {
  const size_t mesh_count = w.model.meshes.size(), node_count = w.model.nodes.size();
  FallbackMaterials fallback(w.model, scene);
  std::vector<std::vector<int>> level_meshes(mesh_count);
  struct PrismCount {
    size_t meshes = 0, edges = 0, points = 0, triangles = 0;
  };
  std::vector<PrismCount> prisms;  // per level, summed over meshes, for the notes
  for (size_t m = 0; m < mesh_count; ++m) {
    const LodChain* c = chains[m];
    if (!c || c->levelCount() < 2) continue;
    const tinygltf::Mesh src = w.model.meshes[m];
    const std::string base = src.name.empty() ? "mesh" + std::to_string(m) : src.name;
    for (size_t l = 1; l < c->levelCount(); ++l) {
      const LodLevel& level = c->levels[l];
      const std::string name = base + "_LOD" + std::to_string(l);
      if (thick_edges == ThickEdges::kLines || (level.mesh.edges.empty() && level.mesh.points.empty())) {
        level_meshes[m].push_back(addLevelMesh(w, fallback, level.mesh, src, name));
        continue;
      }
      Mesh drawn = level.mesh;
      if (prisms.size() < l + 1) prisms.resize(l + 1);
      prisms[l].meshes += 1;
      prisms[l].edges += drawn.edgeCount();
      prisms[l].points += drawn.pointCount();
      prisms[l].triangles += thickPrimitivesAsTriangles(drawn, level.cell_width);
      level_meshes[m].push_back(addLevelMesh(w, fallback, drawn, src, name));
    }
  }
  for (size_t l = 0; notes && l < prisms.size(); ++l) {
    const PrismCount& p = prisms[l];
    if (p.triangles == 0) continue;
    notes->push_back("level " + std::to_string(l) + ": " + std::to_string(p.edges) + " thick edge(s) and " +
                     std::to_string(p.points) + " point(s) in " + std::to_string(p.meshes) + " mesh(es) drawn as " +
                     std::to_string(p.triangles) + " triangles (--thick-edges lines keeps LINES and POINTS)");
  }
  bool any = false;
  for (size_t i = 0; i < node_count; ++i) {
    const int mesh = w.model.nodes[i].mesh;
    if (mesh < 0 || level_meshes[static_cast<size_t>(mesh)].empty()) continue;
    const LodChain& c = *chains[static_cast<size_t>(mesh)];
    const bool morph = hasMorphTargets(w.model.meshes[static_cast<size_t>(mesh)]);
    tinygltf::Value::Array ids;
    for (size_t l = 1; l < c.levelCount(); ++l) {
      w.model.nodes.push_back(levelNode(w.model, i, level_meshes[static_cast<size_t>(mesh)][l - 1], c.levels[l], l, morph, notes));
      ids.emplace_back(static_cast<int>(w.model.nodes.size() - 1));
    }
    tinygltf::Node& node = w.model.nodes[i];
    tinygltf::Value::Object lod;
    lod["ids"] = tinygltf::Value(ids);
    node.extensions["MSFT_lod"] = tinygltf::Value(lod);
    tinygltf::Value::Object extras = node.extras.IsObject() ? node.extras.Get<tinygltf::Value::Object>() : tinygltf::Value::Object{};
    extras["MSFT_screencoverage"] = coverageValues(c);
    extras["scenelod"] = levelExtras(c.levels[0]);
    node.extras = tinygltf::Value(extras);
    any = true;
  }
  auto& used = w.model.extensionsUsed;
  if (any && std::find(used.begin(), used.end(), "MSFT_lod") == used.end()) used.push_back("MSFT_lod");
}

bool keepImageUri(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) { return false; }

// the real path of `path`'s folder joined with its file name (the file need not exist)
std::string resolvedPath(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  char* real = ::realpath(dir.c_str(), nullptr);
  if (!real) return path;
  std::string out = std::string(real) + "/" + path.substr(slash == std::string::npos ? 0 : slash + 1);
  std::free(real);
  return out;
}

// checks the input can be kept as it is with levels added
Error checkPassThrough(const std::string& input, const std::string& output, const tinygltf::Model& model,
                       const std::vector<const LodChain*>& chains) {
  for (const std::string& req : model.extensionsRequired)
    if (!keepableRequiredExtension(req))
      return {Status::kUnsupported, input + ": requires extension " + req +
                                        ", which scenelod cannot keep correct with LOD levels added; nothing written to " + output};
  if (chains.size() != model.meshes.size())
    return {Status::kInvalidArgument, output + ": " + std::to_string(chains.size()) + " chains for the " +
                                          std::to_string(model.meshes.size()) + " meshes of " + input};
  for (size_t i = 0; i < model.nodes.size(); ++i)
    if (model.nodes[i].extensions.count("MSFT_lod"))
      return {Status::kUnsupported, input + ": node " + std::to_string(i) +
                                        " already has MSFT_lod levels; build levels from a file without them"};
  for (size_t m = 0; m < chains.size(); ++m)
    if (chains[m] && chains[m]->levelCount() >= 2)
      if (Error e = checkChainLevels(output, *chains[m], m); !e.ok()) return e;
  return {};
}

// a GLB container: the JSON chunk (padded with spaces) and the binary chunk (padded with zeros)
std::string glbContainer(const std::string& json, const std::vector<unsigned char>& bin) {
  auto u32 = [](std::string& out, size_t v) {
    const uint32_t x = static_cast<uint32_t>(v);
    out.append(reinterpret_cast<const char*>(&x), 4);
  };
  const size_t json_len = (json.size() + 3) / 4 * 4, bin_len = (bin.size() + 3) / 4 * 4;
  std::string out = "glTF";
  u32(out, 2);
  u32(out, 12 + 8 + json_len + (bin.empty() ? 0 : 8 + bin_len));
  u32(out, json_len);
  u32(out, 0x4E4F534Au);  // "JSON"
  out += json;
  out.append(json_len - json.size(), ' ');
  if (!bin.empty()) {
    u32(out, bin_len);
    u32(out, 0x004E4942u);  // "BIN\0"
    out.append(reinterpret_cast<const char*>(bin.data()), bin.size());
    out.append(bin_len - bin.size(), '\0');
  }
  return out;
}

// serialises the model around buffer 0's bytes `bin` (moved out of the model): a GLB, or the JSON
// of a .gltf whose buffer 0 is the file `bin_name`. tinygltf writes a perspective camera without
// zfar (an infinite projection) as zfar 0: `infinite[c]` restores it.
std::string serialise(tinygltf::Model& model, const std::vector<unsigned char>& bin, bool glb, const std::string& bin_name,
                      const std::vector<char>& infinite) {
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(&keepImageUri, nullptr);
  std::ostringstream out;
  if (!writer.WriteGltfSceneToStream(&model, out, false, false)) return {};
  nlohmann::json j = nlohmann::json::parse(out.str());
  if (!bin.empty()) {
    nlohmann::json& b = j["buffers"][0];
    b["byteLength"] = bin.size();
    if (glb) b.erase("uri");
    else b["uri"] = bin_name;
  } else if (j.contains("buffers")) {
    j.erase("buffers");
  }
  for (size_t c = 0; c < infinite.size() && j.contains("cameras"); ++c)
    if (infinite[c] && j["cameras"][c].contains("perspective")) j["cameras"][c]["perspective"].erase("zfar");
  return glb ? glbContainer(j.dump(), bin) : j.dump(2);
}

// perspective cameras without zfar, as the file has them (tinygltf reads them as zfar 0)
std::vector<char> infiniteCameras(const tinygltf::Model& m) {
  std::vector<char> out(m.cameras.size(), 0);
  for (size_t c = 0; c < m.cameras.size(); ++c) out[c] = m.cameras[c].type == "perspective" && m.cameras[c].perspective.zfar == 0.0;
  return out;
}

}  // namespace

Error exportGltfLods(const std::string& input, const std::string& output, const SceneData& scene,
                     const std::vector<const LodChain*>& chains, std::vector<std::string>* notes,
                     ThickEdges thick_edges) {
  const std::string ext = lowerExtension(output);
  if (ext != ".glb" && ext != ".gltf")
    return {Status::kInvalidArgument, output + ": the output must end in .glb or .gltf"};
  const bool glb = ext == ".glb";
  try {
    detail::GltfFile file;
    if (Error e = detail::loadGltfFile(input, file); !e.ok()) return e;
    if (Error e = checkPassThrough(input, output, file.model, chains); !e.ok()) return e;
    for (size_t i = 0; i < file.model.images.size(); ++i)
      if (file.image_bytes[i].empty() && file.model.images[i].bufferView < 0)
        return {Status::kIoError, input + ": image " + std::to_string(i) + ": cannot read '" + file.model.images[i].uri + "'"};
    const std::string prefix = output.substr(0, output.size() - ext.size());
    const std::string bin_path = prefix + ".bin";
    std::vector<std::pair<std::string, const std::vector<uint8_t>*>> files;
    GlbWriter w;
    w.model = std::move(file.model);
    mergeBuffers(w.model);
    placeImages(w, file.image_bytes, glb, prefix, files);
    addLodLevels(w, scene, chains, thick_edges, notes);
    // a .gltf output writes several files: none of them may replace a file the input is read from
    if (!glb) {
      std::vector<std::string> written{output, bin_path};
      for (const auto& f : files) written.push_back(f.first);
      for (const std::string& path : written)
        for (const std::string& read : file.read_paths)
          if (resolvedPath(path) == resolvedPath(read))
            return {Status::kInvalidArgument, output + ": would overwrite " + read + ", which " + input +
                                                  " is read from; write the .gltf elsewhere or write a .glb"};
    }
    std::vector<unsigned char> bin;
    bin.swap(w.model.buffers[0].data);
    const std::string text =
        serialise(w.model, bin, glb, bin_path.substr(bin_path.find_last_of('/') + 1), infiniteCameras(w.model));
    if (text.empty()) return {Status::kIoError, output + ": cannot serialise the glTF"};
    for (const auto& f : files)
      if (Error e = writeFileAtomic(f.first, f.second->data(), f.second->size()); !e.ok()) return e;
    if (!glb && !bin.empty())
      if (Error e = writeFileAtomic(bin_path, bin.data(), bin.size()); !e.ok()) return e;
    return writeFileAtomic(output, text.data(), text.size());
  } catch (const std::bad_alloc&) {
    return {Status::kOutOfMemory, output + ": out of memory while writing"};
  } catch (const std::exception& e) {
    return {Status::kIoError, output + ": cannot write glTF: " + e.what()};
  }
}

}  // namespace scenelod::scene
