#pragma once
// Posing skinned meshes as glTF 2.0 does (§3.7.3 skins, §3.11 animations): node transforms sampled
// from an animation at a time, composed over the hierarchy, then every vertex moved by the
// weighted blend of its joints' matrices world(joint) x inverse_bind. A skinned node's own
// transform is ignored (the joints place the mesh). The offline side uses this to measure posed
// levels (`scenelod eval --animated`) and to precompute bounding spheres that follow the
// animations (bounding_sphere.h, animatedMeshSphere); engines pose their own meshes.
//
// Typical use:
//   if (Error e = validateSkinning(scene, "fox.glb"); !e.ok()) ...
//   std::vector<glm::mat4> locals, joints;
//   animatedLocals(scene, 0, 0.5f, locals);              // animation 0 at t = 0.5 s
//   std::vector<glm::mat4> world = worldTransforms(scene, Span<const glm::mat4>(locals));
//   skinMatrices(scene, scene.nodes[node].skin, world, joints);
//   poseMesh(mesh, joints, posed, "fox mesh 0");         // posed positions in world space
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

// The rest pose: no animation, every node at NodeData::local.
constexpr int32_t kRestPose = -1;

// Checks what posing reads: every skin's joints name nodes and have one inverse bind matrix each
// (finite); every animation sampler has increasing finite key times and as many values as keys
// (three per key for cubic splines); every channel names a node and a sampler in range. Every mesh
// drawn with a skin uses joints below that skin's joint count. `what` names the source in
// messages, which name the skin, animation, sampler, channel or mesh.
// Cost: one pass over skins, animations and skinned meshes' joints.
Error validateSkinning(const SceneData& scene, const std::string& what);

// The first and last key time over the samplers of `animation` (0, 0 when it has no keys).
void animationTimeRange(const AnimationData& animation, float& start, float& end);

// Samples one animation sampler at time `t` (clamped to its keys): LINEAR lerps, or slerps along
// the shorter arc when `rotation` is set; STEP holds the previous key; CUBICSPLINE evaluates the
// Hermite spline of the glTF spec (values: in-tangent, value, out-tangent per key). Rotations come
// out normalised. Precondition: the sampler passed validateSkinning and has at least one key.
glm::vec4 sampleAnimation(const AnimationData::Sampler& sampler, float t, bool rotation);

// The local transform of every node at time `t` of animation `animation` (kRestPose for none):
// nodes driven by a translation, rotation or scale channel get T x R x S from their rest
// decomposition (NodeData::local split into translation, rotation, scale) with the driven parts
// replaced; every other node keeps NodeData::local. Morph-weight channels are ignored.
// Preconditions: validateSkinning passed; `animation` is kRestPose or in range. `out` is resized.
void animatedLocals(const SceneData& scene, int32_t animation, float t, std::vector<glm::mat4>& out);

// Splits an affine matrix into translation, rotation and scale (a negative determinant gives a
// negative x scale). Exact, up to rounding, for matrices composed as T x R x S.
Trs decomposeTrs(const glm::mat4& m);

// Node `node`'s world transform from the given local transforms (one per node): the product of the
// locals from its root down. This is the frame the runtime Scene moves an object's sphere by, also
// for a skinned mesh node, whose posed vertices ignore it (and which worldTransforms may report as
// the identity). Cost: O(depth of the node).
glm::mat4 nodeFrame(const SceneData& scene, Span<const glm::mat4> locals, int32_t node);

// The skinning matrix of every joint of skin `skin`: world(joint_i) x inverse_bind_i.
// Preconditions: validateSkinning passed, `skin` in range, `world` one per node. `out` is resized.
void skinMatrices(const SceneData& scene, int32_t skin, Span<const glm::mat4> world, std::vector<glm::mat4>& out);

// A copy of `mesh` with every vertex skinned: position = sum_i w_i M_i p / sum_i w_i with M_i the
// skinning matrix of joints[v][i]; normals by the blended matrix's inverse transpose, tangents' xyz
// by the blended matrix (both renormalised). Works on an original or on any level that carries
// joints and weights.
// Errors: kInvalidMesh naming `what` when the mesh has no joints or weights, or a vertex uses a
// joint with nonzero weight at or above the matrix count. Cost: O(vertices); allocates `out`.
Error poseMesh(const Mesh& mesh, Span<const glm::mat4> skin_matrices, Mesh& out, const std::string& what);

}  // namespace scenelod::scene
