#pragma once
// glTF 2.0 (.gltf and .glb) import and export through tinygltf, and loading any supported scene file.
#include <string>
#include <vector>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

// Reads a .gltf or .glb file: every node with its local transform (matrix or TRS) and skin, the
// default scene's roots (scene 0 when none is named; every parentless node in order when there is
// no scene), meshes (all primitives of a mesh merged into one Mesh, triangle_groups = primitive
// index, primitive_materials = their materials: TRIANGLES, strips and fans as triangles; LINES,
// LINE_STRIP and LINE_LOOP as edges, thickness from a _THICKNESS vertex attribute; POINTS as
// points; indexed or not, any index and attribute component type, sparse accessors), with NORMAL,
// TEXCOORD_0 (uvs) and TEXCOORD_1.. (extra_uvs), TANGENT, COLOR_0 as read (linear RGB, no material
// colour in it: bakeMaterialColors in scene_data.h gives the old baked colours), JOINTS_0 and
// WEIGHTS_0 (normalised integers as floats); an attribute some primitives of a mesh lack is filled
// for them (normals from the faces, UV 0, white, tangents from the UV gradient, joint 0 weight 1).
// Also materials (base colour factor and texture, its texCoord and KHR_texture_transform), textures
// with their wrap modes, images (encoded bytes; RGBA8 for base colour images), skins (joints,
// inverse bind matrices; a mesh used by one skin gets joint_parents) and animations. Skinned meshes
// are read in their bind pose (POSITION as stored; the skinned node's own transform is ignored by
// worldTransforms, as glTF says); morph targets are ignored. Extensions that only change materials
// (KHR_texture_transform, KHR_materials_*) are accepted even when required; required extensions that
// change geometry (Draco, meshopt, GPU instancing) are refused. External buffer and image URIs must
// resolve inside the file's folder: absolute paths and '..' escapes are refused; a missing image is
// an error. Errors name the file and the problem (mesh, primitive and attribute; accessor, skin,
// animation channel, texture or image index). Never throws.
// Cost: reads the whole file, its buffers and images into memory; decodes each base colour image once.
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

// Writes a GLB with the node hierarchy and meshes (POSITION, NORMAL, TANGENT, COLOR_0, TEXCOORD_n;
// no skins, textures or animations: exportGltfLods keeps those of a glTF input); edges become LINES
// with a _THICKNESS attribute, points become POINTS. A mesh with colours gets no material; one
// without whose primitives share a material gets its base colour factor. When `chains` is given
// (one per mesh, or null entries), each mesh node is written with the MSFT_lod extension pointing
// at nodes of the coarser levels.
Error exportGlb(const std::string& path, const SceneData& scene,
                const std::vector<const LodChain*>* chains = nullptr);

// Writes the glTF file `input` again as `output` with LOD levels added and everything else kept:
// `output` is `input`'s own model (tinygltf), so materials, textures, samplers, images, skins,
// animations, cameras, lights, names, extras and extensions (unknown optional ones included) come
// through unchanged, mesh and node indices too; level 0 of every mesh is the input mesh itself.
// `chains[m]` (one per mesh of the file, as importGltf numbers them; null or one level for none)
// gives the levels: level l of mesh m becomes a mesh "<name>_LOD<l>" whose vertices are shared by
// one TRIANGLES primitive per triangle group the level still has (group g = source primitive g:
// its material and KHR_materials_variants mappings; when the level lacks the UV sets the material's
// textures read, or the tangents its normal map had, an untextured copy of the material appended
// to the file, base colour factor x the texture's mean from `scene`), thick edges and points as
// `thick_edges` says (below), one primitive per group,
// with every attribute the level mesh has (POSITION, NORMAL, TANGENT, COLOR_0, TEXCOORD_n,
// JOINTS_0 / WEIGHTS_0). Each node drawing such a mesh gets MSFT_lod ids of new parentless level
// nodes (as exportGlb writes them) and extras.MSFT_screencoverage; a level node of a skinned node
// has the same skin and no transform, or, when the level has no weights, no skin and the identity
// (bind pose; extras.scenelod.skin "dropped"). Levels never carry morph targets
// (extras.scenelod.morph_targets "dropped"). `notes` (optional) receives those two facts.
// The output is a GLB (every buffer and image in its binary chunk) or, for a .gltf name, a .gltf
// with <stem>.bin and images that were files beside it as <stem>_image<i>.<ext>. Every file is
// replaced atomically after everything succeeded, so `output` may be `input` for a GLB; a .gltf
// output that would replace a file the input reads is refused. Refused too: a required extension
// outside the material and texture ones, KHR_mesh_quantization and KHR_lights_punctual (named in
// the message), and an input that already has MSFT_lod. Never throws.
// `scene` is importGltf's reading of `input` (for the texture means).
// `thick_edges`: kPrisms (the default) writes each thick edge of a level as a 3-sided prism of
// circumradius half its thickness and each point as an octahedron of circumradius half the level's
// cell width, triangles in the edge's or point's material that any viewer draws (glTF viewers draw
// LINES one pixel wide and ignore _THICKNESS); hairline edges stay LINES. kLines keeps LINES with
// _THICKNESS and POINTS, for engines that draw them through scenelod's adapter.
enum class ThickEdges : uint8_t { kPrisms, kLines };
Error exportGltfLods(const std::string& input, const std::string& output, const SceneData& scene,
                     const std::vector<const LodChain*>& chains, std::vector<std::string>* notes = nullptr,
                     ThickEdges thick_edges = ThickEdges::kPrisms);

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
