// A sketch of an OpenSceneGraph-style node graph (Group, MatrixTransform, LOD with one Geode child
// per level) mirrored into scenelod, without depending on OpenSceneGraph: the bridge walks the graph
// once, creates a scene node per transform and an object per LOD node, and after each selection
// switches each LOD node's active child, the way a cull callback would. docs/INTEGRATION.md shows
// the same pattern for a real engine.
#include <cstdio>
#include <memory>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "scenelod/lodcore/chain.h"
#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/scene.h"
#include "scenelod/selection/level_table.h"
#include "scenelod/selection/selector.h"

using namespace scenelod;

namespace osgish {

struct Node {
  virtual ~Node() = default;
  std::vector<std::shared_ptr<Node>> children;
};
struct MatrixTransform : Node {
  glm::mat4 matrix{1.0f};
};
struct Geode : Node {
  const Mesh* mesh = nullptr;  // the engine's drawable for one level
};
struct Lod : Node {           // like osg::LOD, but ranges come from scenelod, not from the artist
  uint32_t chain = 0;
  int active_child = 0;       // -1 = draw nothing
  scene::ObjectHandle mirror; // the scenelod object that stands for this node
};

}  // namespace osgish

// Walks the graph depth-first, mirroring transforms as scene nodes and LOD nodes as objects.
static void mirror(const std::shared_ptr<osgish::Node>& node, scene::NodeHandle parent, scene::Scene& s,
                   std::vector<osgish::Lod*>& lods) {
  scene::NodeHandle here = parent;
  if (auto* t = dynamic_cast<osgish::MatrixTransform*>(node.get())) s.addNode(parent, t->matrix, here);
  if (auto* lod = dynamic_cast<osgish::Lod*>(node.get())) {
    scene::ObjectDesc d;
    d.node = here;
    d.chain = lod->chain;
    s.addObject(d, lod->mirror);
    lods.push_back(lod);
  }
  for (const auto& c : node->children) mirror(c, here, s, lods);
}

static Mesh box(glm::vec3 half, int subdiv) {
  Mesh m;  // a subdivided box: 6 faces of subdiv x subdiv quads
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const float sign = (f % 2) ? 1.0f : -1.0f;
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (int i = 0; i <= subdiv; ++i)
      for (int j = 0; j <= subdiv; ++j) {
        glm::vec3 p;
        p[axis] = sign;
        p[(axis + 1) % 3] = -1.0f + 2.0f * i / subdiv;
        p[(axis + 2) % 3] = -1.0f + 2.0f * j / subdiv;
        m.positions.push_back(p * half);
      }
    for (int i = 0; i < subdiv; ++i)
      for (int j = 0; j < subdiv; ++j) {
        const uint32_t a = base + i * (subdiv + 1) + j, b = a + subdiv + 1;
        if (sign > 0) m.triangles.insert(m.triangles.end(), {a, b, a + 1, a + 1, b, b + 1});
        else m.triangles.insert(m.triangles.end(), {a, a + 1, b, a + 1, b + 1, b});
      }
  }
  return m;
}

int main() {
  // the engine's graph: a root group with 50 transforms, each holding a LOD node over a box's levels
  LodChain chain;
  ChainParams cp;
  cp.level_count = 5;
  if (Error e = buildChain(box(glm::vec3(1.0f, 0.5f, 2.0f), 16), cp, chain); !e.ok()) return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;
  auto root = std::make_shared<osgish::Node>();
  for (int i = 0; i < 50; ++i) {
    auto t = std::make_shared<osgish::MatrixTransform>();
    t->matrix = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, -4.0f * i));
    auto lod = std::make_shared<osgish::Lod>();
    for (const LodLevel& l : chain.levels) {
      auto g = std::make_shared<osgish::Geode>();
      g->mesh = &l.mesh;
      lod->children.push_back(g);
    }
    t->children.push_back(lod);
    root->children.push_back(t);
  }

  // mirror it once
  scene::Scene s;
  s.setChainCount(1);
  s.setChainSphere(0, scene::computeChainBounds(chain));
  std::vector<osgish::Lod*> lods;
  mirror(root, scene::NodeHandle{}, s, lods);
  s.update();
  selection::LevelTableData table;
  table.addChain(chain);

  selection::SelectorConfig cfg;
  cfg.max_object_count = s.objectCount();
  selection::SelectorContext* ctx = selection::createSelectorContext(cfg);
  std::vector<int8_t> levels(s.objectCount(), -1);
  selection::Camera cam;
  cam.eye = glm::vec3(0.0f, 2.0f, 6.0f);
  cam.target = glm::vec3(0.0f, 0.0f, -50.0f);
  selection::SelectionJob job;
  job.camera = &cam;
  job.params.mode = selection::SelectionMode::kDistance;
  job.levels = table.view();
  job.centers = s.worldCenters();
  job.radii = s.worldRadii();
  job.max_scales = s.maxScales();
  job.chains = s.chainIds();
  job.levels_out = Span<int8_t>(levels.data(), levels.size());
  job.context = ctx;
  if (!job.run()) return std::fprintf(stderr, "selection refused the frame\n"), 1;

  // apply: each LOD node draws the chosen child (the cull-callback step of a real graph)
  int switched = 0, previous = 0;
  bool monotonic = true;
  for (osgish::Lod* lod : lods) {
    size_t index = 0;
    s.objectIndex(lod->mirror, index);
    lod->active_child = levels[index];
    if (lod->active_child >= 0 && lod->active_child < previous) monotonic = false;  // farther is never finer
    if (lod->active_child >= 0) previous = lod->active_child;
    switched += lod->active_child > 0;
  }
  selection::destroySelectorContext(ctx);
  std::printf("osg_style: %zu LOD nodes mirrored, %d showing a simplified child, nearest shows child %d, farthest %d\n",
              lods.size(), switched, lods.front()->active_child, lods.back()->active_child);
  return monotonic && switched > 0 && lods.front()->active_child == 0 ? 0 : 1;
}
