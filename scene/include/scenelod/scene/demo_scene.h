#pragma once
// The built-in default scene: a CAD-like assembly of simple polyhedra (boxes, cylinders, prisms,
// gears, pipes, brackets, bolts; thin fins and rods that collapse into thick edges) of the kind
// Low & Tan 1997 target, plus several instances of the Stanford bunny. Meshes are shared between
// instances. Deterministic: the same parameters give the same scene, byte for byte.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

struct DemoSceneParams {
  std::string bunny_path = "/usr/share/glmark2/models/bunny.obj";  // empty = always the generated blob
  size_t gearbox_count = 4;    // sub-assemblies of gears, shafts, bolts and a bracket
  size_t bunny_count = 4;      // instances of the bunny mesh
  size_t segments = 48;        // tessellation of round parts (cylinders, pipes), >= 3
};

struct DemoSceneInfo {
  bool bunny_loaded = false;   // false: the bunny file was unreadable and a generated blob stands in
  std::string note;            // says which, for the tool to print
};

// Fills `out` with the demo scene. When the bunny file cannot be read, a generated organic mesh
// (a displaced icosphere, ~20k triangles) takes its place and `info.note` says so; that is not an
// error. Errors: segments < 3 or gearbox_count == 0. Allocates.
Error makeDemoScene(SceneData& out, const DemoSceneParams& params = {}, DemoSceneInfo* info = nullptr);

// The organic stand-in: an icosphere subdivided `subdivisions` times (20 * 4^s triangles), radius
// about 1, displaced by smooth deterministic bumps; smooth normals.
Mesh makeBlobMesh(int subdivisions = 5);

}  // namespace scenelod::scene
