// GLB export through tinygltf: node hierarchy, meshes (TRIANGLES, LINES with _THICKNESS, POINTS),
// vertex colours, and LOD chains as MSFT_lod with MSFT_screencoverage (docs/IO.md).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <map>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <utility>

#include <tiny_gltf.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"

#include "scenelod/lodcore/atomic_file.h"

namespace scenelod::scene {

namespace {

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

  VertexSet addVertices(const Mesh& m, const std::vector<glm::vec3>& positions, const std::vector<uint32_t>* source) {
    // source: for a separate vertex set, the original vertex of each new vertex
    VertexSet vs;
    auto gather3 = [&](const std::vector<glm::vec3>& attr) {
      std::vector<glm::vec3> out;
      if (!source) return attr;
      out.reserve(source->size());
      for (uint32_t v : *source) out.push_back(attr[v]);
      return out;
    };
    vs.attributes["POSITION"] = addFloatAccessor(&positions[0].x, positions.size(), TINYGLTF_TYPE_VEC3, 3, true);
    if (!m.normals.empty()) {
      const std::vector<glm::vec3> n = gather3(m.normals);
      vs.attributes["NORMAL"] = addFloatAccessor(&n[0].x, n.size(), TINYGLTF_TYPE_VEC3, 3, false);
    }
    if (!m.colors.empty()) {
      const std::vector<glm::vec3> c = gather3(m.colors);
      vs.attributes["COLOR_0"] = addFloatAccessor(&c[0].x, c.size(), TINYGLTF_TYPE_VEC3, 3, false);
    }
    if (!m.uvs.empty()) {
      std::vector<glm::vec2> t;
      if (source) {
        for (uint32_t v : *source) t.push_back(m.uvs[v]);
      } else {
        t = m.uvs;
      }
      vs.attributes["TEXCOORD_0"] = addFloatAccessor(&t[0].x, t.size(), TINYGLTF_TYPE_VEC2, 2, false);
    }
    return vs;
  }

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
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const LodChain* c = chainOf(m);
    if (!c) continue;
    for (size_t l = 1; l < c->levelCount(); ++l) {
      const std::string what = path + ": chain of mesh " + std::to_string(m) + " level " + std::to_string(l);
      if (c->levels[l].mesh.empty()) return {Status::kInvalidArgument, what + " is empty"};
      if (!(c->levels[l].cell_width > c->levels[l - 1].cell_width))
        return {Status::kInvalidArgument, what + ": cell widths must strictly increase"};
      if (Error e = validateMesh(c->levels[l].mesh, what); !e.ok()) return e;
    }
  }
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
      tinygltf::Value::Array ids, coverage;
      const float r = sphereRadius(c->levels[0]);
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
      // coverage value of level i: where level i + 1 becomes accurate enough; 0 for the last level
      for (size_t l = 0; l < c->levelCount(); ++l) {
        const double next = l + 1 < c->levelCount() ? c->levels[l + 1].cell_width : 0.0;
        coverage.emplace_back(next > 0.0 ? 2.0 * r * kCoverageCellPixels / (next * kCoverageViewportPx) : 0.0);
      }
      tinygltf::Node& node = w.model.nodes[i];
      tinygltf::Value::Object lod;
      lod["ids"] = tinygltf::Value(ids);
      node.extensions["MSFT_lod"] = tinygltf::Value(lod);
      tinygltf::Value::Object extras;
      extras["MSFT_screencoverage"] = tinygltf::Value(coverage);
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

}  // namespace scenelod::scene
