#pragma once
// The runtime scene graph an engine mirrors its objects into: nodes with parent links and local
// transforms, world transforms kept current with dirty flags in one parent-before-child pass, and
// objects (a node + a shared LOD chain + importance + user data) whose world bounding spheres are
// stored as flat arrays that selection reads as spans.
//
// Handles are (slot, generation) pairs: removing a node or object bumps its slot's generation, so an
// old handle is refused with Status::kNotFound instead of touching a reused slot.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

constexpr uint32_t kInvalidSlot = 0xffffffffu;

struct NodeHandle {
  uint32_t slot = kInvalidSlot;
  uint32_t generation = 0;
  bool operator==(const NodeHandle& o) const { return slot == o.slot && generation == o.generation; }
  bool operator!=(const NodeHandle& o) const { return !(*this == o); }
};

struct ObjectHandle {
  uint32_t slot = kInvalidSlot;
  uint32_t generation = 0;
  bool operator==(const ObjectHandle& o) const { return slot == o.slot && generation == o.generation; }
  bool operator!=(const ObjectHandle& o) const { return !(*this == o); }
};

// Translation, rotation, scale; composes to T * R * S as in glTF.
struct Trs {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // w, x, y, z
  glm::vec3 scale{1.0f};
};

glm::mat4 composeTrs(const Trs& trs);

// Largest factor by which the linear part (upper 3x3) of `m` can stretch a vector, bounded from
// above: sqrt of the largest Gershgorin row sum of the Gram matrix G = A^T A (G_ij = column_i .
// column_j). For matrices without shear (any T * R * S) G is diagonal and the bound is exact, the
// largest column norm; under shear it stays an upper bound of the spectral norm (the largest column
// norm alone would not be). Cost: 6 dot products and a square root.
float maxScaleBound(const glm::mat4& m);

// A sphere moved by an affine matrix: centre transformed, radius times maxScaleBound(m). The result
// contains the image of every point of the input sphere (conservative under non-uniform scale and
// shear).
Sphere transformSphere(const Sphere& s, const glm::mat4& m);

struct ObjectDesc {
  NodeHandle node;
  uint32_t chain = 0;       // chain id, shared by every instance of one mesh; < chainCount()
  float importance = 1.0f;  // selection's benefit weight, >= 0
  bool must_draw = false;   // never culled by selection
  uint64_t user_data = 0;   // the engine's own id, returned untouched
};

class Scene {
 public:
  Scene() = default;

  // Builds the runtime scene from raw data: every node (same parents and local transforms; node i of
  // `data` is nodeHandle(i)) and one object per node with a mesh, numbered as objectNodes() does
  // (object k has dense index k until objects are removed). Chain ids are mesh indices; each
  // chain's object-space sphere starts as the minimal sphere of its mesh, or for a mesh drawn with a
  // skin the sphere over its animations (bounding_sphere.h, animatedMeshSphere). World transforms
  // and spheres are current on return. Errors: validateSceneData's and validateSkinning's
  // (skin_pose.h). Allocates.
  static Error fromSceneData(const SceneData& data, Scene& out, const std::string& what = "scene");

  // ---- chains: their object-space bounding spheres, indexed by chain id ----
  // Sets the number of chains (new ones get an empty sphere). Allocates.
  void setChainCount(size_t chain_count);
  size_t chainCount() const { return chain_spheres_.size(); }
  // Sets chain `chain`'s object-space sphere (it must contain every level of the chain); every
  // object using it gets a new world sphere at the next update(). Errors: chain out of range.
  Error setChainSphere(uint32_t chain, const Sphere& sphere);
  Span<const Sphere> chainSpheres() const { return {chain_spheres_.data(), chain_spheres_.size()}; }

  // ---- nodes ----
  // Adds a node under `parent` (a null NodeHandle{} for a root) with a local matrix. The node goes
  // after its parent in the update order. Errors: stale parent. Amortised O(1).
  Error addNode(NodeHandle parent, const glm::mat4& local, NodeHandle& out);
  // Removes a node, all its descendants and every object on them (their handles become stale).
  // Errors: stale handle. O(nodes + objects).
  Error removeNode(NodeHandle node);
  // Moves `node` (with its subtree) under `new_parent` (null for a root), keeping its local
  // transform. Errors: stale handle, or new_parent is the node itself or one of its descendants.
  // Reorders the update order so parents stay first: O(nodes) worst case.
  Error reparent(NodeHandle node, NodeHandle new_parent);
  // Set a node's local transform and mark it dirty. Errors: stale handle. O(1), no allocation.
  // Transforms are affine: only the upper 3x4 part (linear part and translation) is stored, the
  // last row reads back as (0, 0, 0, 1).
  Error setLocal(NodeHandle node, const glm::mat4& local);
  Error setLocal(NodeHandle node, const Trs& trs);
  // Sets the local transforms of many nodes in one call: nodes[i] gets locals[i], as setLocal would
  // (an engine handing over a frame's poses). `locals` may be strided (e.g. a member of the engine's
  // own per-node structs).
  // Errors: the counts differ (nothing set); a stale handle nodes[i] (the nodes before i are set, the
  // rest are not; the message names i). O(count), no allocation.
  Error setLocals(Span<const NodeHandle> nodes, StridedSpan<const glm::mat4> locals);
  Error getLocal(NodeHandle node, glm::mat4& out) const;
  // World transform from the current local transforms (affine, last row (0, 0, 0, 1)); the same bits
  // update() uses for the node's spheres. Nodes without children keep no world transform: theirs is
  // their parent's times their local, computed here. Errors: stale handle.
  // Cost: O(1) when no node before this one in the update order changed since the last update(),
  // else one product per ancestor down from the nearest unchanged one.
  Error getWorld(NodeHandle node, glm::mat4& out) const;
  Error getParent(NodeHandle node, NodeHandle& out) const;  // null handle for a root
  bool isValid(NodeHandle node) const;
  size_t nodeCount() const { return order_.size(); }
  // Handle of the node at position `i` of the update order (parents before children), i < nodeCount().
  NodeHandle nodeAt(size_t i) const;

  // ---- objects ----
  // Adds an object. Errors: stale node, chain out of range, importance negative or not finite.
  // Its world sphere is current after the next update(). Amortised O(1).
  Error addObject(const ObjectDesc& desc, ObjectHandle& out);
  // Removes an object; the last object takes its dense index (swap-remove). Errors: stale handle. O(1).
  Error removeObject(ObjectHandle object);
  // Moves an object to another node. Errors: stale handles. O(1).
  Error setObjectNode(ObjectHandle object, NodeHandle node);
  Error setObjectChain(ObjectHandle object, uint32_t chain);
  Error setImportance(ObjectHandle object, float importance);
  Error setMustDraw(ObjectHandle object, bool must_draw);
  Error setUserData(ObjectHandle object, uint64_t user_data);
  Error getObject(ObjectHandle object, ObjectDesc& out) const;
  // Dense index of a live object (its position in the span accessors below). Errors: stale handle.
  Error objectIndex(ObjectHandle object, size_t& out) const;
  ObjectHandle objectAt(size_t dense_index) const;  // dense_index < objectCount()
  bool isValid(ObjectHandle object) const;
  size_t objectCount() const { return object_chain_.size(); }

  // Recomputes world transforms of dirty nodes and their descendants in one linear pass in
  // parent-before-child order (stored only for nodes with children), with the world spheres of the
  // objects on each recomputed node; then the spheres of objects whose chain, chain sphere or node
  // changed. Returns the number of objects whose sphere was recomputed.
  // Cost: O(nodes after the first dirty one + objects on moved nodes), plus O(objects) when an
  // object itself was edited since the last update; O(1) when nothing changed. Spheres are computed
  // eight at a time (AVX2 when the CPU has it, chosen at load time; same bits either way). No
  // allocation, no locks; single-threaded.
  size_t update();

  // ---- hot per-object data, dense arrays indexed by object dense index (valid after update()) ----
  Span<const glm::vec3> worldCenters() const { return {world_center_.data(), world_center_.size()}; }
  Span<const float> worldRadii() const { return {world_radius_.data(), world_radius_.size()}; }
  Span<const float> maxScales() const { return {max_scale_.data(), max_scale_.size()}; }
  Span<const uint32_t> chainIds() const { return {object_chain_.data(), object_chain_.size()}; }
  Span<const float> importances() const { return {importance_.data(), importance_.size()}; }
  Span<const uint8_t> mustDraw() const { return {must_draw_.data(), must_draw_.size()}; }
  Span<const uint64_t> userData() const { return {user_data_.data(), user_data_.size()}; }

 private:
  // an affine transform as the first three rows of its 4x4 matrix, row r = (m[0][r], m[1][r],
  // m[2][r], translation[r]): a row-major 3x4 block, 16-byte aligned
  struct alignas(16) Affine {
    float row[3][4];
  };
  static constexpr size_t kNoneDirty = ~size_t(0);

  bool nodeLive(NodeHandle h) const;
  bool objectLive(ObjectHandle h) const;
  void rebuildParentIndices();  // also refreshes object_node_dense_
  void linkObject(uint32_t k);    // pushes object k onto its node's object list
  void unlinkObject(uint32_t k);  // takes object k off its node's object list
  void markNodeDirty(size_t i) {
    node_dirty_[i] = 1;
    if (i < dirty_from_) dirty_from_ = i;
  }
  Affine currentWorld(size_t i) const;  // from the current locals, update()'s bits
  void addChild(size_t parent);          // a node that gets its first child stores its world from now on
  void countChildren();

  // node slots (stable, indexed by handle slot)
  std::vector<uint32_t> node_generation_;  // 4 B: bumped on removal
  std::vector<uint32_t> node_dense_;       // 4 B: position in the order, kInvalidSlot when free
  std::vector<uint32_t> node_free_;        // free slots
  // nodes in update order (parents before children), indexed by dense position
  std::vector<uint32_t> order_;            // 4 B: slot of the node at this position
  std::vector<int32_t> parent_dense_;      // 4 B: parent's position, -1 for a root (hot: update pass)
  std::vector<uint8_t> node_dirty_;        // 1 B: local changed since the last update (hot)
  std::vector<Affine> local_;              // 48 B (hot: update pass)
  // 48 B, kept current only for nodes with children (their children's products read it); a leaf's
  // row is stale, its world is made in registers when its spheres are (update pass)
  std::vector<Affine> world_;
  std::vector<uint32_t> child_count_;      // 4 B: children of the node (update pass: store world or not)
  std::vector<int32_t> node_first_object_; // 4 B: first object on the node, -1 none (update pass)
  size_t dirty_from_ = kNoneDirty;         // no node before this position is dirty

  // object slots
  std::vector<uint32_t> object_generation_;
  std::vector<uint32_t> object_dense_;     // kInvalidSlot when free
  std::vector<uint32_t> object_free_;
  // objects, dense. hot, read by the sphere pass and by selection:
  std::vector<glm::vec3> world_center_;    // 12 B: world sphere centre
  std::vector<float> world_radius_;        // 4 B: world sphere radius
  std::vector<float> max_scale_;           // 4 B: maxScaleBound of the node's world matrix
  std::vector<uint32_t> object_chain_;     // 4 B: chain id
  std::vector<uint32_t> object_node_dense_; // 4 B: the node's position in the update order (sphere pass)
  std::vector<uint8_t> object_dirty_;      // 1 B: sphere must be recomputed
  std::vector<int32_t> object_next_;       // 4 B: next object on the same node, -1 end (update pass)
  // read by selection:
  std::vector<float> importance_;          // 4 B
  std::vector<uint8_t> must_draw_;         // 1 B
  // cold:
  std::vector<uint64_t> user_data_;        // 8 B: engine id
  std::vector<uint32_t> object_slot_;      // 4 B: slot of the object at this dense index
  std::vector<uint32_t> object_node_slot_; // 4 B: node slot (handles; refreshes object_node_dense_)

  std::vector<Sphere> chain_spheres_;      // object space, per chain id
  bool all_objects_dirty_ = false;
  bool some_objects_dirty_ = false;        // some object_dirty_ flag may be set
};

}  // namespace scenelod::scene
