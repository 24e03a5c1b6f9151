// Loading any supported scene file by extension, and flattening a scene into one world-space mesh.
#include <cctype>
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

Mesh flattenScene(const SceneData& scene) {
  Mesh out;
  const std::vector<int32_t> objects = objectNodes(scene);
  const std::vector<glm::mat4> world = worldTransforms(scene);
  bool any_normals = false, any_colors = false, any_uvs = false, any_faces = false, any_thick = false;
  for (int32_t node : objects) {
    const Mesh& m = scene.meshes[static_cast<size_t>(scene.nodes[static_cast<size_t>(node)].mesh)].mesh;
    any_normals |= !m.normals.empty();
    any_colors |= !m.colors.empty();
    any_uvs |= !m.uvs.empty();
    any_faces |= m.faceCount() > 0;
    any_thick |= !m.edge_thickness.empty();
  }
  if (any_faces) out.face_offsets.push_back(0);
  for (int32_t node : objects) {
    const Mesh& m = scene.meshes[static_cast<size_t>(scene.nodes[static_cast<size_t>(node)].mesh)].mesh;
    const glm::mat4& w = world[static_cast<size_t>(node)];
    const glm::mat3 linear(w);
    const float det = glm::determinant(linear);
    const glm::mat3 normal_matrix = det != 0.0f ? glm::transpose(glm::inverse(linear)) : linear;
    const bool mirrored = det < 0.0f;  // a mirroring transform flips the winding back to counter-clockwise
    const float thickness_scale = std::cbrt(std::fabs(det));
    const uint32_t base = static_cast<uint32_t>(out.positions.size());
    for (const glm::vec3& p : m.positions) out.positions.push_back(glm::vec3(w * glm::vec4(p, 1.0f)));
    if (any_normals) {
      for (size_t i = 0; i < m.positions.size(); ++i) {
        glm::vec3 n = m.normals.empty() ? glm::vec3(0.0f) : normal_matrix * m.normals[i];
        const float len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
        out.normals.push_back(len > 0.0f ? n / len : n);
      }
    }
    if (any_colors) {
      if (m.colors.empty()) out.colors.insert(out.colors.end(), m.positions.size(), glm::vec3(1.0f));
      else out.colors.insert(out.colors.end(), m.colors.begin(), m.colors.end());
    }
    if (any_uvs) {
      if (m.uvs.empty()) out.uvs.insert(out.uvs.end(), m.positions.size(), glm::vec2(0.0f));
      else out.uvs.insert(out.uvs.end(), m.uvs.begin(), m.uvs.end());
    }
    for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
      const uint32_t a = m.triangles[t], b = m.triangles[t + 1], c = m.triangles[t + 2];
      out.triangles.insert(out.triangles.end(), {base + a, base + (mirrored ? c : b), base + (mirrored ? b : c)});
    }
    if (any_faces) {
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
    if (any_thick)
      for (size_t e = 0; e < m.edgeCount(); ++e) out.edge_thickness.push_back(m.edgeThickness(e) * thickness_scale);
    for (uint32_t p : m.points) out.points.push_back(base + p);
  }
  return out;
}

}  // namespace scenelod::scene
