#pragma once
// glTF 2.0 (.gltf and .glb) import and export through tinygltf, and loading any supported scene file.
#include <string>
#include <vector>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

// Reads a .gltf or .glb file: every node with its local transform (matrix or TRS), the default
// scene's roots (scene 0 when none is named; every parentless node in order when there is no scene),
// meshes (all primitives of a mesh merged into one Mesh: TRIANGLES, strips and fans as triangles;
// LINES, LINE_STRIP and LINE_LOOP as edges, thickness from a _THICKNESS vertex attribute; POINTS as
// points; indexed or not, any index and attribute component type, sparse accessors), materials.
// Vertex colours are baked as linear RGB = base colour factor x COLOR_0 x the average texel of the
// base colour texture (sRGB texels made linear before averaging); a mesh gets colours when any of
// its primitives has a material or COLOR_0. Skinned meshes are read in their bind pose (POSITION as
// stored; joints, morph targets and animations are ignored). Extensions that only change materials
// (KHR_texture_transform, KHR_materials_*) are accepted even when required; required extensions that
// change geometry (Draco, meshopt, GPU instancing) are refused. External buffer and image URIs must
// resolve inside the file's folder: absolute paths and '..' escapes are refused.
// Errors name the file and the problem (mesh/primitive/accessor index). Never throws.
// Cost: reads the whole file and its buffers into memory; decodes each base colour image once.
Error importGltf(const std::string& path, SceneData& out);

// Like importGltf, and reads MSFT_lod chains back: `chains[m]` is the chain of mesh m of `out`.
// Level nodes (the MSFT_lod ids) and meshes used only by them are removed from `out`, so a file
// written by exportGlb with chains comes back as the scene and chains that were written. A level's
// cell width, error and method come from its node's extras.scenelod; without them the cell width
// follows from MSFT_screencoverage (see kCoverageCellPixels). A mesh without MSFT_lod gets a
// one-level chain (its own mesh). Level bounds are recomputed (computeChainBounds).
Error importGltfLods(const std::string& path, SceneData& out, std::vector<LodChain>& chains);

// MSFT_screencoverage as written and read here (docs/IO.md): coverage = projected bounding-sphere
// diameter / viewport height. Level k (cell width w_k) is accurate enough while one cell projects to
// at most kCoverageCellPixels pixels on a kCoverageViewportPx-pixel-high viewport, that is while
// coverage <= 2 r X / (w_k H) with r the radius of the minimal sphere of level 0's vertices (the
// field of view cancels).
// The value stored for level i is that bound for level i + 1 (where level i stops being needed);
// the last level's value is 0 (it is drawn down to any size).
constexpr float kCoverageCellPixels = 1.0f;
constexpr float kCoverageViewportPx = 1080.0f;

// Reads OBJ (one root node holding one mesh, both named after the file), .gltf or .glb, chosen by the
// extension (case-insensitive); other extensions are refused.
Error loadScene(const std::string& path, SceneData& out);

// The extension of the file name in `path`, dot included, in lower case ("dir/Box.GLB" -> ".glb"),
// or "" when the name has none: what loadScene chooses by.
std::string lowerExtension(const std::string& path);

// Writes a GLB with the node hierarchy and meshes; edges become LINES with a _THICKNESS attribute,
// points become POINTS. When `chains` is given (one per mesh, or null entries), each mesh node is
// written with the MSFT_lod extension pointing at nodes of the coarser levels.
Error exportGlb(const std::string& path, const SceneData& scene,
                const std::vector<const LodChain*>* chains = nullptr);

// Merges every object of the scene (one copy per node instance) into one world-space mesh, as used
// to simplify or measure a whole model: positions by the world transform (worldTransforms: skinned
// mesh nodes in their bind pose), normals by its inverse transpose (renormalised), tangents by its
// linear part (renormalised; w kept, flipped under a mirroring transform), triangle and face
// winding reversed under a mirroring transform, edge thickness scaled by the cube root of the
// transform's determinant. UV sets, colours (as the meshes hold them: bakeMaterialColors first for
// material colours) and tangents are carried; attributes missing on some objects are filled
// (normals 0, colours white, UVs 0, tangents (1,0,0,+1)). Joints and weights are dropped (each
// object's joints index its own skin). triangle_groups holds each triangle's MATERIAL index into
// scene.materials (kNoMaterial for none), so a renderer can shade the result with the scene's
// materials; it is empty when the scene has no materials (an OBJ). Triangles become 3-corner faces when another object has polygon faces.
// Cost: allocates the result, linear in the drawn size.
Mesh flattenScene(const SceneData& scene);

}  // namespace scenelod::scene
