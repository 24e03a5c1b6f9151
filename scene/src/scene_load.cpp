// Loading any supported scene file by extension, and flattening a scene into one world-space mesh.
#include <cctype>
#include <algorithm>
#include <cmath>

#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::scene {

namespace {

std::string fileStem(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace

std::string lowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

Error loadScene(const std::string& path, SceneData& out) {
  const std::string ext = lowerExtension(path);
  if (ext == ".gltf" || ext == ".glb") return importGltf(path, out);
  if (ext == ".obj") {
    SceneData s;
    MeshData mesh;
    mesh.name = fileStem(path);
    if (Error e = readObj(path, mesh.mesh); !e.ok()) return e;
    s.meshes.push_back(std::move(mesh));
    NodeData node;
    node.name = fileStem(path);
    node.mesh = 0;
    s.nodes.push_back(std::move(node));
    s.roots.push_back(0);
    out = std::move(s);
    return {};
  }
  return {Status::kUnsupported, path + ": unknown file type '" + ext + "' (expected .obj, .gltf or .glb)"};
}

namespace {

// which optional attributes any drawn object has: the flattened mesh has them for every vertex
struct FlatAttributes {
  bool normals = false, colors = false, uvs = false, tangents = false, faces = false, thick = false;
  size_t extra_uv_sets = 0;
};

// appends object `m`'s vertex attributes transformed by `w` (positions, normals by the inverse
// transpose, tangents by the linear part with w flipped under mirroring), filling missing ones
void appendVertices(const Mesh& m, const glm::mat4& w, const FlatAttributes& any, Mesh& out) {
  const glm::mat3 linear(w);
  const float det = glm::determinant(linear);
  const glm::mat3 normal_matrix = det != 0.0f ? glm::transpose(glm::inverse(linear)) : linear;
  const size_t n = m.positions.size();
  auto unit = [](glm::vec3 v) {
    const float len = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return len > 0.0f ? v / len : v;
  };
  for (const glm::vec3& p : m.positions) out.positions.push_back(glm::vec3(w * glm::vec4(p, 1.0f)));
  if (any.normals)
    for (size_t i = 0; i < n; ++i) out.normals.push_back(m.normals.empty() ? glm::vec3(0.0f) : unit(normal_matrix * m.normals[i]));
  if (any.colors) {
    if (m.colors.empty()) out.colors.insert(out.colors.end(), n, glm::vec3(1.0f));
    else out.colors.insert(out.colors.end(), m.colors.begin(), m.colors.end());
  }
  if (any.uvs) {
    if (m.uvs.empty()) out.uvs.insert(out.uvs.end(), n, glm::vec2(0.0f));
    else out.uvs.insert(out.uvs.end(), m.uvs.begin(), m.uvs.end());
  }
  for (size_t set = 0; set < any.extra_uv_sets; ++set) {
    std::vector<glm::vec2>& dst = out.extra_uvs[set];
    if (set < m.extra_uvs.size()) dst.insert(dst.end(), m.extra_uvs[set].begin(), m.extra_uvs[set].end());
    else dst.insert(dst.end(), n, glm::vec2(0.0f));
  }
  if (any.tangents) {
    const float sign = det < 0.0f ? -1.0f : 1.0f;
    for (size_t i = 0; i < n; ++i) {
      const glm::vec3 t = m.tangents.empty() ? glm::vec3(0.0f) : unit(linear * glm::vec3(m.tangents[i]));
      out.tangents.push_back(t == glm::vec3(0.0f) ? glm::vec4(1.0f, 0.0f, 0.0f, 1.0f) : glm::vec4(t, sign * m.tangents[i].w));
    }
  }
}

}  // namespace

Mesh flattenScene(const SceneData& scene) {
  Mesh out;
  const std::vector<int32_t> objects = objectNodes(scene);
  const std::vector<glm::mat4> world = worldTransforms(scene);
  FlatAttributes any;
  for (int32_t node : objects) {
    const Mesh& m = scene.meshes[static_cast<size_t>(scene.nodes[static_cast<size_t>(node)].mesh)].mesh;
    any.normals |= !m.normals.empty();
    any.colors |= !m.colors.empty();
    any.uvs |= !m.uvs.empty();
    any.extra_uv_sets = std::max(any.extra_uv_sets, m.extra_uvs.size());
    any.tangents |= !m.tangents.empty();
    any.faces |= m.faceCount() > 0;
    any.thick |= !m.edge_thickness.empty();
  }
  out.extra_uvs.resize(any.extra_uv_sets);
  if (any.faces) out.face_offsets.push_back(0);
  for (int32_t node : objects) {
    const MeshData& md = scene.meshes[static_cast<size_t>(scene.nodes[static_cast<size_t>(node)].mesh)];
    const Mesh& m = md.mesh;
    const glm::mat4& w = world[static_cast<size_t>(node)];
    const float det = glm::determinant(glm::mat3(w));
    const bool mirrored = det < 0.0f;  // a mirroring transform flips the winding back to counter-clockwise
    const float thickness_scale = std::cbrt(std::fabs(det));
    const uint32_t base = static_cast<uint32_t>(out.positions.size());
    appendVertices(m, w, any, out);
    // each primitive's group becomes its material's index
    auto material = [&](uint32_t group) {
      const int32_t mat = group < md.primitive_materials.size() ? md.primitive_materials[group] : -1;
      return mat >= 0 ? static_cast<uint32_t>(mat) : kNoMaterial;
    };
    for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
      const uint32_t a = m.triangles[t], b = m.triangles[t + 1], c = m.triangles[t + 2];
      out.triangles.insert(out.triangles.end(), {base + a, base + (mirrored ? c : b), base + (mirrored ? b : c)});
      if (!scene.materials.empty()) out.triangle_groups.push_back(material(m.triangleGroup(t / 3)));
    }
    if (any.faces) {
      auto addFace = [&](const uint32_t* corners, size_t k) {
        for (size_t i = 0; i < k; ++i) out.face_corners.push_back(base + corners[mirrored ? k - 1 - i : i]);
        out.face_offsets.push_back(static_cast<uint32_t>(out.face_corners.size()));
      };
      if (m.faceCount() > 0) {
        for (size_t f = 0; f < m.faceCount(); ++f)
          addFace(m.face_corners.data() + m.face_offsets[f], m.face_offsets[f + 1] - m.face_offsets[f]);
      } else {
        for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) addFace(m.triangles.data() + t, 3);
      }
    }
    for (uint32_t e : m.edges) out.edges.push_back(base + e);
    if (any.thick)
      for (size_t e = 0; e < m.edgeCount(); ++e) out.edge_thickness.push_back(m.edgeThickness(e) * thickness_scale);
    for (uint32_t p : m.points) out.points.push_back(base + p);
    if (!scene.materials.empty()) {
      for (size_t e = 0; e < m.edgeCount(); ++e) out.edge_groups.push_back(material(m.edgeGroup(e)));
      for (size_t i = 0; i < m.pointCount(); ++i) out.point_groups.push_back(material(m.pointGroup(i)));
    }
  }
  return out;
}

}  // namespace scenelod::scene
