#pragma once
// Skin weights in clustering levels (docs/CLUSTERING.md, "Attributes"): the split of clusters whose
// vertices follow unrelated bones, and each cluster's joint weights.
#include <cstdint>
#include <vector>

#include <glm/ext/vector_uint4_sized.hpp>
#include <glm/vec4.hpp>

#include "cluster_internal.h"

namespace scenelod::detail {

// Each cluster's vertices as a list: cluster c's are members[offset[c] .. offset[c + 1]), in
// increasing index. Cost: O(V), a counting sort.
void clusterMembers(const Assignment& a, std::vector<uint32_t>& offset, std::vector<uint32_t>& members);

// Splits every cluster of `a` whose vertices' dominant joints (the joint of the largest weight)
// differ: the centre's joint keeps its members, the others form one new cluster per dominant
// joint, centred on its heaviest vertex. Parent and child joints are kept apart too: merged, an arm
// hanging along the torso took blended weights and left the body halfway when it moved (BrainStem's
// worst posed Hausdorff 4.4x its bind-pose one at level 1, 1.0x apart). Does nothing for a mesh
// without a skin. Run before synthesis.
void splitSkinClusters(const PreparedMesh& p, Assignment& a);

// Per cluster: the sum of each joint's weights over its vertices, the four largest kept (ties: the
// lower joint) and renormalised to sum 1, unused slots joint 0 weight 0. Empty skin: all zero.
void clusterSkinWeights(const Mesh& m, const Assignment& a, std::vector<glm::u16vec4>& joints,
                        std::vector<glm::vec4>& weights);

}  // namespace scenelod::detail
