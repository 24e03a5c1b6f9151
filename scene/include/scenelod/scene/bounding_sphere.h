#pragma once
// Bounding spheres of point sets and LOD chains: Ritter's fast approximate sphere and the minimal
// enclosing sphere (Welzl's algorithm in Gärtner's move-to-front form), and the spheres of skinned
// meshes over their animations.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

// Ritter 1990 ("An efficient bounding sphere", Graphics Gems): the sphere through the two far-apart
// points found from an extreme point, grown point by point. Contains every point; typically 5-20 %
// larger than minimal. An empty input gives a zero sphere. Cost: 3 passes, no allocation.
Sphere ritterSphere(Span<const glm::vec3> points);

// The smallest sphere containing every point (Welzl 1991, move-to-front as in Gärtner 1999), in
// double precision, then grown by a few ulps so that every float point is inside when tested in
// float. Deterministic (fixed shuffle seed). An empty input gives a zero sphere.
// Cost: expected O(n); allocates O(n) scratch.
Sphere minimalSphere(Span<const glm::vec3> points);

// Smallest radius r such that every point is within r of `center` (rounded up): the radius a sphere
// at `center` needs to contain the points. Cost: one pass.
float coveringRadius(Span<const glm::vec3> points, const glm::vec3& center);

// Sets every level's `bounds` to the minimal sphere of that level's vertices and returns one
// object-space sphere containing every level (the minimal sphere of all levels' vertices).
// Cost: O(total vertices); allocates scratch.
Sphere computeChainBounds(LodChain& chain);

// The sphere containing both spheres (smallest such). Cost: O(1).
Sphere mergeSpheres(const Sphere& a, const Sphere& b);

// A sphere containing every given sphere: the minimal sphere of their six axis extreme points,
// its radius then grown until it covers each whole sphere. An empty input gives a zero sphere.
// Cost: O(n); allocates O(n) scratch.
Sphere sphereOfSpheres(Span<const Sphere> spheres);

// One flag per mesh of `scene`: 1 when some node draws it with a skin, so that its bounding sphere
// must follow the skin's animations (animatedMeshSphere). Cost: one pass over the nodes.
std::vector<uint8_t> meshesDrawnWithSkin(const SceneData& scene);

// Key interval subdivisions animatedMeshSphere samples by default.
constexpr uint32_t kAnimatedSphereStepsPerKey = 4;

// A sphere in the frame of the nodes that draw mesh `mesh` with a skin, containing `levels` (the
// mesh and its LOD levels) skinned in the rest pose and all through every animation of the scene,
// for every such node: the chain sphere of a skinned mesh. Levels without joints cannot be posed
// and are drawn as stored, so the sphere holds their vertices unposed, as it holds every level's
// when some node draws the mesh without a skin. The engine moves the node
// and its skeleton together (through their common ancestors), so the scene's sphere, the node's
// world transform x this sphere, follows the character wherever it goes.
//
// Method: per-joint spheres. A skinned vertex is a convex combination sum_i w_i M_i v of its
// joints' images, so it lies in any sphere holding the image of the bind-space sphere of every
// vertex each joint moves (the joint sphere, over all levels). The joint spheres are posed
// (transformSphere, conservative under scale) at every key time of each animation and at
// `steps_per_key` - 1 times between consecutive keys. Between two samples a joint sphere's centre
// moves along some path from one to the other; the step is covered by the sphere centred at the
// middle of the chord with radius chord / 2 + the larger posed radius: by Thales' theorem it holds every arc of up to 180
// degrees through both ends, which covers straight moves (translation, scale) and a slerped
// rotation about a fixed pivot of up to 180 degrees per step; composed rotations of parent and
// child joints stay inside while each step turns them little, which the subdivisions ensure.
// The result is sphereOfSpheres of all step spheres. Cheaper than posing every vertex (joints x
// samples instead of vertices x samples) and conservative between samples, at the price of some
// slack where one joint moves vertices far apart.
// Preconditions: validateSkinning(scene) passed; `mesh` in range; steps_per_key >= 1.
// Errors: kInvalidMesh naming `what` when a level's vertex uses a joint at or above the skin's
// joint count. Cost: O(level vertices + skinned nodes drawing the mesh x samples x (nodes +
// joints)); allocates.
Error animatedMeshSphere(const SceneData& scene, int32_t mesh, Span<const Mesh* const> levels, Sphere& out,
                         const std::string& what, uint32_t steps_per_key = kAnimatedSphereStepsPerKey);

}  // namespace scenelod::scene
