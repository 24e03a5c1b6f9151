#pragma once
// Helpers shared by the eval, render and bench subcommands: loading a model as one world-space mesh
// and writing JSON strings.
#include <cstdio>
#include <string>

#include <sys/stat.h>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

// Loads OBJ, glTF or GLB (scene::loadScene), saying plainly when the path is missing or a folder.
inline Error loadSceneFile(const std::string& path, scene::SceneData& out) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return {Status::kIoError, path + ": no such file"};
  if (S_ISDIR(st.st_mode)) return {Status::kIoError, path + ": is a folder, not a model file"};
  return scene::loadScene(path, out);
}

// Loads OBJ, glTF or GLB and flattens every object into one world-space mesh (scene::flattenScene),
// material colours baked into the vertex colours (scene::bakeMaterialColors).
inline Error loadFlatMesh(const std::string& path, Mesh& out) {
  scene::SceneData scene;
  if (Error e = loadSceneFile(path, scene); !e.ok()) return e;
  scene::bakeMaterialColors(scene);  // the renderer shades by vertex colour
  out = scene::flattenScene(scene);
  return validateMesh(out, path);
}

// `s` as a JSON string literal, quotes included.
inline std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// a number for JSON: finite values with 6 significant digits, null otherwise
inline std::string jsonNumber(double v) {
  if (!(v == v) || v > 1e300 || v < -1e300) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace scenelod::tool
