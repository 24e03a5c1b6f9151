#include "scenelod/scene/scene.h"

#include <cmath>
#include <cstring>
#include <random>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scene_wide.h"  // private test hook (tests/CMakeLists.txt adds scene/src)

using namespace scenelod;
using namespace scenelod::scene;

namespace {

glm::mat4 randomAffine(std::mt19937& rng, bool shear) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(0.3f, 2.5f);
  Trs t;
  t.translation = {u(rng) * 5, u(rng) * 5, u(rng) * 5};
  t.rotation = glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng) + 0.01f));
  t.scale = {s(rng), s(rng), s(rng)};
  glm::mat4 m = composeTrs(t);
  if (shear) {
    glm::mat4 sh(1.0f);
    sh[1][0] = u(rng);
    sh[2][1] = u(rng);
    m = m * sh;
  }
  return m;
}

// world matrix by walking up the parents through the public API
glm::mat4 bruteWorld(const Scene& s, NodeHandle h) {
  glm::mat4 m(1.0f);
  while (h.slot != kInvalidSlot) {
    glm::mat4 local;
    EXPECT_TRUE(s.getLocal(h, local).ok());
    m = local * m;
    NodeHandle p;
    EXPECT_TRUE(s.getParent(h, p).ok());
    h = p;
  }
  return m;
}

void expectMatNear(const glm::mat4& a, const glm::mat4& b, float tol) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], tol * (1.0f + std::fabs(b[c][r])));
}

std::vector<glm::vec3> cloud(std::mt19937& rng, size_t n) {
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<glm::vec3> p(n);
  for (auto& v : p) v = {g(rng) * 2.0f + 1.0f, g(rng) * 0.5f, g(rng) - 3.0f};
  return p;
}

}  // namespace

TEST(Scene, WorldTransformsMatchBruteForceAfterMovesAndReparenting) {
  std::mt19937 rng(7);
  Scene s;
  s.setChainCount(1);
  std::vector<NodeHandle> nodes;
  for (int i = 0; i < 200; ++i) {
    NodeHandle parent;
    if (!nodes.empty() && rng() % 5 != 0) parent = nodes[rng() % nodes.size()];
    NodeHandle h;
    ASSERT_TRUE(s.addNode(parent, randomAffine(rng, i % 7 == 0), h).ok());
    nodes.push_back(h);
  }
  s.update();
  for (int round = 0; round < 30; ++round) {
    for (int k = 0; k < 20; ++k) ASSERT_TRUE(s.setLocal(nodes[rng() % nodes.size()], randomAffine(rng, false)).ok());
    for (int k = 0; k < 5; ++k) {
      const NodeHandle a = nodes[rng() % nodes.size()], b = nodes[rng() % nodes.size()];
      const Error e = s.reparent(a, rng() % 4 == 0 ? NodeHandle{} : b);
      // refused only when b is a or under a
      if (!e.ok()) {
        EXPECT_EQ(e.status, Status::kInvalidArgument);
        bool under = false;
        for (NodeHandle h = b; h.slot != kInvalidSlot;) {
          if (h == a) under = true;
          NodeHandle p;
          ASSERT_TRUE(s.getParent(h, p).ok());
          h = p;
        }
        EXPECT_TRUE(under) << e.message;
      }
    }
    s.update();
    // parents before children in the update order
    for (size_t i = 0; i < s.nodeCount(); ++i) {
      NodeHandle p;
      ASSERT_TRUE(s.getParent(s.nodeAt(i), p).ok());
      if (p.slot == kInvalidSlot) continue;
      bool before = false;
      for (size_t j = 0; j < i; ++j) before |= s.nodeAt(j) == p;
      ASSERT_TRUE(before) << "node at " << i << " comes before its parent";
    }
    for (NodeHandle h : nodes) {
      glm::mat4 w;
      ASSERT_TRUE(s.getWorld(h, w).ok());
      expectMatNear(w, bruteWorld(s, h), 1e-3f);
    }
  }
}

TEST(Scene, WorldSpheresContainTransformedVerticesUnderNonUniformScaleAndShear) {
  std::mt19937 rng(11);
  const std::vector<glm::vec3> pts = cloud(rng, 500);
  Scene s;
  s.setChainCount(1);
  ASSERT_TRUE(s.setChainSphere(0, minimalSphere(Span<const glm::vec3>(pts.data(), pts.size()))).ok());
  std::vector<NodeHandle> nodes;
  std::vector<ObjectHandle> objects;
  for (int i = 0; i < 40; ++i) {
    NodeHandle h;
    ASSERT_TRUE(s.addNode(nodes.empty() || i % 3 == 0 ? NodeHandle{} : nodes[rng() % nodes.size()],
                          randomAffine(rng, i % 2 == 0), h).ok());
    nodes.push_back(h);
    ObjectHandle o;
    ASSERT_TRUE(s.addObject(ObjectDesc{h, 0, 1.0f, false, uint64_t(i)}, o).ok());
    objects.push_back(o);
  }
  for (int round = 0; round < 5; ++round) {
    for (int k = 0; k < 10; ++k) ASSERT_TRUE(s.setLocal(nodes[rng() % nodes.size()], randomAffine(rng, true)).ok());
    s.reparent(nodes[rng() % 20 + 20], nodes[rng() % 20]);  // may be refused (would form a cycle)
    s.update();
    for (ObjectHandle o : objects) {
      size_t k;
      ASSERT_TRUE(s.objectIndex(o, k).ok());
      ObjectDesc d;
      ASSERT_TRUE(s.getObject(o, d).ok());
      const glm::mat4 w = bruteWorld(s, d.node);
      const glm::vec3 c = s.worldCenters()[k];
      const float r = s.worldRadii()[k];
      EXPECT_EQ(s.userData()[k], d.user_data);
      float worst = 0.0f;
      for (const glm::vec3& p : pts) worst = std::max(worst, glm::length(glm::vec3(w * glm::vec4(p, 1.0f)) - c));
      EXPECT_LE(worst, r * (1.0f + 1e-4f)) << "object " << k;
    }
  }
}

TEST(Scene, MaxScaleBoundIsExactWithoutShearAndAnUpperBoundWithIt) {
  Trs t;
  t.rotation = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3)));
  t.scale = {0.5f, 3.0f, 1.5f};
  EXPECT_NEAR(maxScaleBound(composeTrs(t)), 3.0f, 1e-5f);
  // a shear whose spectral norm (golden ratio) exceeds its largest column norm (sqrt 2)
  glm::mat4 sh(1.0f);
  sh[1][0] = 1.0f;
  const float golden = (1.0f + std::sqrt(5.0f)) * 0.5f;
  EXPECT_GE(maxScaleBound(sh), golden);
  // and the unit vector it stretches most really gets stretched by that much
  // (the top right singular vector (1, golden) / |.|), so the bound must exceed the largest column norm
  const glm::vec3 v = glm::normalize(glm::vec3(1.0f, golden, 0.0f));
  const float stretch = glm::length(glm::vec3(sh * glm::vec4(v, 0.0f)));
  EXPECT_NEAR(stretch, golden, 1e-5f);
  EXPECT_GT(stretch, std::sqrt(2.0f));
  EXPECT_GE(maxScaleBound(sh), stretch);
}

TEST(Scene, StaleHandlesAreRefused) {
  Scene s;
  s.setChainCount(2);
  NodeHandle root, child;
  ASSERT_TRUE(s.addNode({}, glm::mat4(1.0f), root).ok());
  ASSERT_TRUE(s.addNode(root, glm::mat4(1.0f), child).ok());
  ObjectHandle a, b;
  ASSERT_TRUE(s.addObject(ObjectDesc{child, 1}, a).ok());
  ASSERT_TRUE(s.addObject(ObjectDesc{root, 0}, b).ok());
  EXPECT_EQ(s.addObject(ObjectDesc{root, 2}, b).status, Status::kInvalidArgument);  // chain out of range
  ASSERT_TRUE(s.removeNode(root).ok());  // takes the child and both objects
  EXPECT_EQ(s.nodeCount(), 0u);
  EXPECT_EQ(s.objectCount(), 0u);
  glm::mat4 m;
  EXPECT_EQ(s.setLocal(child, glm::mat4(1.0f)).status, Status::kNotFound);
  EXPECT_EQ(s.getWorld(root, m).status, Status::kNotFound);
  EXPECT_EQ(s.removeObject(a).status, Status::kNotFound);
  EXPECT_EQ(s.setImportance(b, 2.0f).status, Status::kNotFound);
  EXPECT_EQ(s.reparent(child, {}).status, Status::kNotFound);
  EXPECT_EQ(s.addNode(root, glm::mat4(1.0f), child).status, Status::kNotFound);
  // the slots are reused with new generations: the old handles stay stale
  NodeHandle again;
  ASSERT_TRUE(s.addNode({}, glm::mat4(2.0f), again).ok());
  EXPECT_EQ(again.slot == root.slot || again.slot == child.slot, true);
  EXPECT_FALSE(s.isValid(root));
  EXPECT_FALSE(s.isValid(child));
  EXPECT_TRUE(s.isValid(again));
  ObjectHandle c;
  ASSERT_TRUE(s.addObject(ObjectDesc{again, 0}, c).ok());
  EXPECT_FALSE(s.isValid(a));
  EXPECT_FALSE(s.isValid(b));
  ObjectDesc desc;
  EXPECT_EQ(s.getObject(a, desc).status, Status::kNotFound);
  EXPECT_EQ(NodeHandle{}.slot, kInvalidSlot);
  EXPECT_EQ(s.setLocal(NodeHandle{}, glm::mat4(1.0f)).status, Status::kNotFound);
}

TEST(Scene, SwapRemoveKeepsOtherHandlesAndData) {
  Scene s;
  s.setChainCount(3);
  NodeHandle n;
  ASSERT_TRUE(s.addNode({}, glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)), n).ok());
  std::vector<ObjectHandle> objs(3);
  for (uint32_t i = 0; i < 3; ++i) ASSERT_TRUE(s.addObject(ObjectDesc{n, i, float(i), i == 2, 100u + i}, objs[i]).ok());
  ASSERT_TRUE(s.removeObject(objs[0]).ok());
  s.update();
  for (uint32_t i = 1; i < 3; ++i) {
    size_t k;
    ASSERT_TRUE(s.objectIndex(objs[i], k).ok());
    EXPECT_EQ(s.chainIds()[k], i);
    EXPECT_EQ(s.userData()[k], 100u + i);
    EXPECT_EQ(s.importances()[k], float(i));
    EXPECT_EQ(s.mustDraw()[k], i == 2 ? 1 : 0);
    EXPECT_EQ(s.objectAt(k), objs[i]);
  }
}

TEST(Scene, FromSceneDataNumbersObjectsLikeObjectNodes) {
  SceneData d;
  d.meshes.resize(2);
  d.meshes[0].mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  d.meshes[0].mesh.triangles = {0, 1, 2};
  d.meshes[1].mesh.positions = {{0, 0, 0}, {0, 0, 4}, {0, 3, 0}};
  d.meshes[1].mesh.triangles = {0, 1, 2};
  d.nodes.resize(4);
  d.nodes[0].children = {2, 1};
  d.nodes[1].parent = 0; d.nodes[1].mesh = 0;
  d.nodes[2].parent = 0; d.nodes[2].mesh = 1; d.nodes[2].children = {3};
  d.nodes[2].local = glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
  d.nodes[3].parent = 2; d.nodes[3].mesh = 0;
  d.nodes[3].local = glm::translate(glm::mat4(1.0f), glm::vec3(10, 0, 0));
  d.roots = {0};
  Scene s;
  ASSERT_TRUE(Scene::fromSceneData(d, s).ok());
  const std::vector<int32_t> expect = objectNodes(d);
  ASSERT_EQ(s.objectCount(), expect.size());
  const std::vector<glm::mat4> world = worldTransforms(d);
  for (size_t k = 0; k < expect.size(); ++k) {
    ObjectDesc od;
    ASSERT_TRUE(s.getObject(s.objectAt(k), od).ok());
    EXPECT_EQ(od.node.slot, uint32_t(expect[k]));
    EXPECT_EQ(s.chainIds()[k], uint32_t(d.nodes[expect[k]].mesh));
    glm::mat4 w;
    ASSERT_TRUE(s.getWorld(od.node, w).ok());
    expectMatNear(w, world[expect[k]], 1e-6f);
  }
  // object 1 is node 3: mesh 0 scaled by 2 around (20, 0, 0); its minimal sphere has radius sqrt(2)/2
  EXPECT_NEAR(s.worldRadii()[1], std::sqrt(2.0f), 1e-5f);
  EXPECT_NEAR(s.worldCenters()[1].x, 21.0f, 1e-5f);
}

TEST(Scene, UpdateOnlyRecomputesMovedObjects) {
  Scene s;
  s.setChainCount(1);
  NodeHandle a, b, c;
  ASSERT_TRUE(s.addNode({}, glm::mat4(1.0f), a).ok());
  ASSERT_TRUE(s.addNode(a, glm::mat4(1.0f), b).ok());
  ASSERT_TRUE(s.addNode({}, glm::mat4(1.0f), c).ok());
  ObjectHandle o;
  ASSERT_TRUE(s.addObject(ObjectDesc{b}, o).ok());
  ASSERT_TRUE(s.addObject(ObjectDesc{c}, o).ok());
  EXPECT_EQ(s.update(), 2u);
  EXPECT_EQ(s.update(), 0u);
  ASSERT_TRUE(s.setLocal(a, glm::translate(glm::mat4(1.0f), glm::vec3(1, 0, 0))).ok());
  EXPECT_EQ(s.update(), 1u);  // only the object under a's child
  EXPECT_FLOAT_EQ(s.worldCenters()[0].x, 1.0f);
  EXPECT_FLOAT_EQ(s.worldCenters()[1].x, 0.0f);
}

TEST(Scene, RandomEditsKeepWorldSpheresAndHandlesConsistent) {
  std::mt19937 rng(23);
  Scene s;
  s.setChainCount(3);
  for (uint32_t c = 0; c < 3; ++c) ASSERT_TRUE(s.setChainSphere(c, Sphere{{0.5f * c, 0.0f, -0.25f}, 1.0f + c}).ok());
  std::vector<NodeHandle> live_nodes, dead_nodes;
  std::vector<ObjectHandle> live_objects, dead_objects;
  auto pick = [&](auto& v) { return v[rng() % v.size()]; };
  for (int step = 0; step < 600; ++step) {
    const int op = int(rng() % 10);
    if (op < 3 || live_nodes.size() < 3) {
      NodeHandle h;
      ASSERT_TRUE(s.addNode(live_nodes.empty() || rng() % 4 == 0 ? NodeHandle{} : pick(live_nodes), randomAffine(rng, rng() % 3 == 0), h).ok());
      live_nodes.push_back(h);
      ObjectHandle o;
      ASSERT_TRUE(s.addObject(ObjectDesc{h, uint32_t(rng() % 3), 1.0f, false, uint64_t(step)}, o).ok());
      live_objects.push_back(o);
    } else if (op == 3) {
      ASSERT_TRUE(s.setLocal(pick(live_nodes), randomAffine(rng, true)).ok());
    } else if (op == 4) {
      s.reparent(pick(live_nodes), rng() % 3 == 0 ? NodeHandle{} : pick(live_nodes));  // cycles are refused
    } else if (op == 5 && !live_objects.empty()) {
      const size_t i = rng() % live_objects.size();
      ASSERT_TRUE(s.removeObject(live_objects[i]).ok());
      dead_objects.push_back(live_objects[i]);
      live_objects.erase(live_objects.begin() + i);
    } else if (op == 6) {
      ASSERT_TRUE(s.removeNode(pick(live_nodes)).ok());
      // the subtree and its objects went with it
      std::vector<NodeHandle> keep;
      for (NodeHandle h : live_nodes) (s.isValid(h) ? keep : dead_nodes).push_back(h);
      live_nodes.swap(keep);
      std::vector<ObjectHandle> keep_objects;
      for (ObjectHandle h : live_objects) (s.isValid(h) ? keep_objects : dead_objects).push_back(h);
      live_objects.swap(keep_objects);
    } else if (op == 7 && !live_objects.empty()) {
      ASSERT_TRUE(s.setObjectNode(pick(live_objects), pick(live_nodes)).ok());
    } else {
      s.update();
    }
    if (step % 50 != 49) continue;
    s.update();
    ASSERT_EQ(s.nodeCount(), live_nodes.size());
    ASSERT_EQ(s.objectCount(), live_objects.size());
    for (ObjectHandle o : live_objects) {
      ObjectDesc d;
      ASSERT_TRUE(s.getObject(o, d).ok());
      size_t k;
      ASSERT_TRUE(s.objectIndex(o, k).ok());
      const glm::mat4 w = bruteWorld(s, d.node);
      const Sphere expect = transformSphere(s.chainSpheres()[d.chain], w);
      EXPECT_NEAR(glm::length(s.worldCenters()[k] - expect.center), 0.0f, 1e-3f * (1.0f + glm::length(expect.center)));
      EXPECT_NEAR(s.worldRadii()[k], expect.radius, 1e-4f * expect.radius);
    }
    for (NodeHandle h : dead_nodes) EXPECT_EQ(s.setLocal(h, glm::mat4(1.0f)).status, Status::kNotFound);
    for (ObjectHandle h : dead_objects) EXPECT_EQ(s.setImportance(h, 1.0f).status, Status::kNotFound);
  }
}

TEST(Scene, UpdateCountsFollowEditsAndBothSpherePassesGiveTheSameBits) {
  std::mt19937 rng(5);
  Scene s;
  s.setChainCount(2);
  ASSERT_TRUE(s.setChainSphere(0, Sphere{{0.3f, -0.2f, 0.1f}, 1.5f}).ok());
  ASSERT_TRUE(s.setChainSphere(1, Sphere{{-1.0f, 0.5f, 2.0f}, 0.25f}).ok());
  NodeHandle r, a, b, c;
  ASSERT_TRUE(s.addNode({}, randomAffine(rng, false), r).ok());
  ASSERT_TRUE(s.addNode(r, randomAffine(rng, true), a).ok());
  ASSERT_TRUE(s.addNode(r, randomAffine(rng, false), b).ok());
  ASSERT_TRUE(s.addNode(a, randomAffine(rng, true), c).ok());
  ObjectHandle on_a0, on_a1, on_b, on_c;
  ASSERT_TRUE(s.addObject(ObjectDesc{a, 0}, on_a0).ok());
  ASSERT_TRUE(s.addObject(ObjectDesc{a, 1}, on_a1).ok());
  ASSERT_TRUE(s.addObject(ObjectDesc{b, 1}, on_b).ok());
  ASSERT_TRUE(s.addObject(ObjectDesc{c, 0}, on_c).ok());
  EXPECT_EQ(s.update(), 4u);
  EXPECT_EQ(s.update(), 0u);
  ASSERT_TRUE(s.setLocal(a, randomAffine(rng, true)).ok());
  EXPECT_EQ(s.update(), 3u);  // both objects on a and the one on its child c
  ASSERT_TRUE(s.setObjectChain(on_b, 0).ok());
  EXPECT_EQ(s.update(), 1u);
  ASSERT_TRUE(s.setObjectNode(on_a1, b).ok());
  EXPECT_EQ(s.update(), 1u);
  ASSERT_TRUE(s.setLocal(b, randomAffine(rng, false)).ok());
  EXPECT_EQ(s.update(), 2u);  // on_b and on_a1, now on b
  ASSERT_TRUE(s.removeObject(on_a0).ok());  // swap-remove: another object takes its index
  ASSERT_TRUE(s.setLocal(a, randomAffine(rng, false)).ok());
  EXPECT_EQ(s.update(), 1u);  // only on_c is left under a
  ASSERT_TRUE(s.removeNode(c).ok());
  EXPECT_EQ(s.update(), 0u);
  ASSERT_TRUE(s.setLocal(r, randomAffine(rng, true)).ok());
  EXPECT_EQ(s.update(), 2u);
  // spheres from the node pass (above) and from the object pass (every chain marked dirty, nothing
  // moved) are the same bits
  std::vector<glm::vec3> centres(s.worldCenters().begin(), s.worldCenters().end());
  std::vector<float> radii(s.worldRadii().begin(), s.worldRadii().end());
  std::vector<float> scales(s.maxScales().begin(), s.maxScales().end());
  s.setChainCount(2);
  EXPECT_EQ(s.update(), 2u);
  for (size_t k = 0; k < s.objectCount(); ++k) {
    EXPECT_EQ(std::memcmp(&centres[k], &s.worldCenters()[k], sizeof(glm::vec3)), 0) << k;
    EXPECT_EQ(std::memcmp(&radii[k], &s.worldRadii()[k], sizeof(float)), 0) << k;
    EXPECT_EQ(std::memcmp(&scales[k], &s.maxScales()[k], sizeof(float)), 0) << k;
  }
}

namespace {

// a scene with every shape the sphere batches meet: roots and inner nodes with objects (stored
// worlds), leaves under shared and under different parents, several objects per node, and object
// indices out of node order after swap-removes
struct MixedScene {
  Scene s;
  std::vector<NodeHandle> nodes;
  std::vector<ObjectHandle> objects;
};

void buildMixed(MixedScene& m, std::mt19937& rng, int node_count) {
  m.s.setChainCount(3);
  for (uint32_t c = 0; c < 3; ++c) ASSERT_TRUE(m.s.setChainSphere(c, Sphere{{0.3f * c, -0.1f, 0.2f * c}, 0.5f + c}).ok());
  for (int i = 0; i < node_count; ++i) {
    NodeHandle parent;
    if (!m.nodes.empty() && rng() % 4 != 0) parent = m.nodes[rng() % m.nodes.size()];
    NodeHandle h;
    ASSERT_TRUE(m.s.addNode(parent, randomAffine(rng, i % 5 == 0), h).ok());
    m.nodes.push_back(h);
    for (int k = int(rng() % 3); k > 0; --k) {
      ObjectHandle o;
      ASSERT_TRUE(m.s.addObject(ObjectDesc{h, uint32_t(rng() % 3)}, o).ok());
      m.objects.push_back(o);
    }
  }
  for (int k = 0; k < 10; ++k) {
    const size_t i = rng() % m.objects.size();
    ASSERT_TRUE(m.s.removeObject(m.objects[i]).ok());
    m.objects.erase(m.objects.begin() + static_cast<std::ptrdiff_t>(i));
  }
}

struct SphereBits {
  std::vector<glm::vec3> centres;
  std::vector<float> radii, scales;
};

SphereBits sphereBits(const Scene& s) {
  return {std::vector<glm::vec3>(s.worldCenters().begin(), s.worldCenters().end()),
          std::vector<float>(s.worldRadii().begin(), s.worldRadii().end()),
          std::vector<float>(s.maxScales().begin(), s.maxScales().end())};
}

void expectSameBits(const SphereBits& a, const SphereBits& b) {
  ASSERT_EQ(a.centres.size(), b.centres.size());
  for (size_t k = 0; k < a.centres.size(); ++k) {
    EXPECT_EQ(std::memcmp(&a.centres[k], &b.centres[k], sizeof(glm::vec3)), 0) << k;
    EXPECT_EQ(std::memcmp(&a.radii[k], &b.radii[k], sizeof(float)), 0) << k;
    EXPECT_EQ(std::memcmp(&a.scales[k], &b.scales[k], sizeof(float)), 0) << k;
  }
}

}  // namespace

TEST(Scene, WideAndNarrowSphereCodeGiveTheSameBits) {
  // the same scene and edits twice, once per sphere code; the node pass and the object pass both
  std::mt19937 rng_a(31), rng_b(31);
  MixedScene a, b;
  buildMixed(a, rng_a, 300);
  const bool was_wide = detail::useWideSpheres(false);
  buildMixed(b, rng_b, 300);
  b.s.update();
  detail::useWideSpheres(true);
  a.s.update();
  expectSameBits(sphereBits(a.s), sphereBits(b.s));
  for (int round = 0; round < 4; ++round) {
    for (int k = 0; k < 60; ++k) {
      const size_t i = rng_a() % a.nodes.size();
      rng_b();
      const glm::mat4 local = randomAffine(rng_a, k % 3 == 0);
      randomAffine(rng_b, k % 3 == 0);
      ASSERT_TRUE(a.s.setLocal(a.nodes[i], local).ok());
      ASSERT_TRUE(b.s.setLocal(b.nodes[i], local).ok());
    }
    if (round == 2) {
      a.s.setChainCount(3);
      b.s.setChainCount(3);
    }
    detail::useWideSpheres(false);
    const size_t nb = b.s.update();
    detail::useWideSpheres(true);
    EXPECT_EQ(a.s.update(), nb);
    expectSameBits(sphereBits(a.s), sphereBits(b.s));
  }
  detail::useWideSpheres(was_wide);
}

TEST(Scene, LeafWorldsAreRightOnRequestAndWhenALeafGetsChildren) {
  std::mt19937 rng(41);
  Scene s;
  s.setChainCount(1);
  NodeHandle root, leaf, other, deep;
  ASSERT_TRUE(s.addNode({}, randomAffine(rng, false), root).ok());
  ASSERT_TRUE(s.addNode(root, randomAffine(rng, true), leaf).ok());
  ASSERT_TRUE(s.addNode({}, randomAffine(rng, false), other).ok());
  ObjectHandle on_leaf;
  ASSERT_TRUE(s.addObject(ObjectDesc{leaf, 0}, on_leaf).ok());
  s.update();
  glm::mat4 w;
  ASSERT_TRUE(s.getWorld(leaf, w).ok());
  expectMatNear(w, bruteWorld(s, leaf), 1e-5f);
  // getWorld follows the current locals, before update() too
  ASSERT_TRUE(s.setLocal(root, randomAffine(rng, false)).ok());
  ASSERT_TRUE(s.getWorld(leaf, w).ok());
  expectMatNear(w, bruteWorld(s, leaf), 1e-5f);
  s.update();
  glm::mat4 after;
  ASSERT_TRUE(s.getWorld(leaf, after).ok());
  EXPECT_EQ(std::memcmp(&w, &after, sizeof w), 0);  // the same bits update() used
  // a child under the former leaf (added later in the order): the leaf's world must now be kept
  ASSERT_TRUE(s.addNode(leaf, randomAffine(rng, false), deep).ok());
  ObjectHandle on_deep;
  ASSERT_TRUE(s.addObject(ObjectDesc{deep, 0}, on_deep).ok());
  s.update();
  for (NodeHandle h : {root, leaf, other, deep}) {
    ASSERT_TRUE(s.getWorld(h, w).ok());
    expectMatNear(w, bruteWorld(s, h), 1e-5f);
  }
  // reparent a node that comes earlier under a later leaf (the subtree moves after it), then a node
  // under an earlier leaf (nothing moves); both were leaves with a parent
  NodeHandle late;
  ASSERT_TRUE(s.addNode(other, randomAffine(rng, true), late).ok());
  s.update();
  ASSERT_TRUE(s.reparent(deep, late).ok());
  s.update();
  ASSERT_TRUE(s.getWorld(deep, w).ok());
  expectMatNear(w, bruteWorld(s, deep), 1e-5f);
  ASSERT_TRUE(s.setLocal(root, randomAffine(rng, false)).ok());  // leaf lost deep: its world row goes stale
  s.update();
  ASSERT_TRUE(s.reparent(late, leaf).ok());
  s.update();
  for (NodeHandle h : {root, leaf, other, deep, late}) {
    ASSERT_TRUE(s.getWorld(h, w).ok());
    expectMatNear(w, bruteWorld(s, h), 1e-5f);
  }
  for (ObjectHandle o : {on_leaf, on_deep}) {
    ObjectDesc d;
    ASSERT_TRUE(s.getObject(o, d).ok());
    size_t k;
    ASSERT_TRUE(s.objectIndex(o, k).ok());
    const Sphere expect = transformSphere(s.chainSpheres()[0], bruteWorld(s, d.node));
    EXPECT_NEAR(glm::length(s.worldCenters()[k] - expect.center), 0.0f, 1e-4f * (1.0f + glm::length(expect.center)));
    EXPECT_NEAR(s.worldRadii()[k], expect.radius, 1e-4f * expect.radius);
  }
  // a parent that lost its children is a leaf again; a new child brings its world back
  ASSERT_TRUE(s.removeNode(deep).ok());
  ASSERT_TRUE(s.setLocal(late, randomAffine(rng, false)).ok());
  s.update();
  ASSERT_TRUE(s.addNode(late, randomAffine(rng, false), deep).ok());
  s.update();
  ASSERT_TRUE(s.getWorld(deep, w).ok());
  expectMatNear(w, bruteWorld(s, deep), 1e-5f);
}

TEST(Scene, GetWorldOfADeepPathWithChangedAncestors) {
  // a chain longer than getWorld's 32-node chunks, with changed locals above the queried node
  std::mt19937 rng(43);
  Scene s;
  std::vector<NodeHandle> chain;
  for (int i = 0; i < 100; ++i) {
    NodeHandle h;
    Trs t;
    t.translation = {0.1f, 0.0f, 0.05f};
    t.rotation = glm::angleAxis(0.05f * float(i % 7), glm::vec3(0.0f, 1.0f, 0.0f));
    ASSERT_TRUE(s.addNode(chain.empty() ? NodeHandle{} : chain.back(), composeTrs(t), h).ok());
    chain.push_back(h);
  }
  glm::mat4 before_update;
  ASSERT_TRUE(s.getWorld(chain.back(), before_update).ok());  // nothing updated yet: the whole path
  s.update();
  glm::mat4 w;
  ASSERT_TRUE(s.getWorld(chain.back(), w).ok());
  EXPECT_EQ(std::memcmp(&w, &before_update, sizeof w), 0);
  ASSERT_TRUE(s.setLocal(chain[3], randomAffine(rng, false)).ok());
  glm::mat4 pending;
  ASSERT_TRUE(s.getWorld(chain.back(), pending).ok());
  expectMatNear(pending, bruteWorld(s, chain.back()), 1e-3f);
  s.update();
  ASSERT_TRUE(s.getWorld(chain.back(), w).ok());
  EXPECT_EQ(std::memcmp(&w, &pending, sizeof w), 0);
}

TEST(Scene, SetLocalsMatchesSetLocalAndNamesAStaleHandle) {
  std::mt19937 rng(47);
  MixedScene a, b;
  std::mt19937 rng_a(53), rng_b(53);
  buildMixed(a, rng_a, 120);
  buildMixed(b, rng_b, 120);
  a.s.update();
  b.s.update();
  std::vector<NodeHandle> picked;
  std::vector<glm::mat4> locals;
  for (int k = 0; k < 50; ++k) {
    picked.push_back(a.nodes[rng() % a.nodes.size()]);  // same slots in both scenes
    locals.push_back(randomAffine(rng, k % 4 == 0));
  }
  ASSERT_TRUE(a.s.setLocals(Span<const NodeHandle>(picked.data(), picked.size()),
                            Span<const glm::mat4>(locals.data(), locals.size())).ok());
  for (size_t k = 0; k < picked.size(); ++k) ASSERT_TRUE(b.s.setLocal(picked[k], locals[k]).ok());
  EXPECT_EQ(a.s.update(), b.s.update());
  expectSameBits(sphereBits(a.s), sphereBits(b.s));
  // strided: the matrices inside the caller's own structs
  struct Pose {
    int id;
    glm::mat4 local;
  };
  std::vector<Pose> poses;
  for (size_t k = 0; k < 3; ++k) poses.push_back(Pose{int(k), randomAffine(rng, false)});
  ASSERT_TRUE(a.s.setLocals(Span<const NodeHandle>(picked.data(), 3),
                            StridedSpan<const glm::mat4>(&poses[0].local, 3, sizeof(Pose))).ok());
  glm::mat4 got;
  ASSERT_TRUE(a.s.getLocal(picked[2], got).ok());
  expectMatNear(got, poses[2].local, 0.0f);
  // errors: counts differ (nothing set); a stale handle (the ones before it are set)
  EXPECT_EQ(a.s.setLocals(Span<const NodeHandle>(picked.data(), 2), Span<const glm::mat4>(locals.data(), 3)).status,
            Status::kInvalidArgument);
  NodeHandle doomed;
  ASSERT_TRUE(a.s.addNode({}, glm::mat4(1.0f), doomed).ok());
  ASSERT_TRUE(a.s.removeNode(doomed).ok());
  std::vector<NodeHandle> with_stale = {a.nodes[0], doomed, a.nodes[1]};
  const glm::mat4 moved = glm::translate(glm::mat4(1.0f), glm::vec3(7.0f, 8.0f, 9.0f));
  std::vector<glm::mat4> three(3, moved);
  glm::mat4 before1;
  ASSERT_TRUE(a.s.getLocal(a.nodes[1], before1).ok());
  const Error e = a.s.setLocals(Span<const NodeHandle>(with_stale.data(), 3), Span<const glm::mat4>(three.data(), 3));
  EXPECT_EQ(e.status, Status::kNotFound);
  EXPECT_NE(e.message.find("node 1"), std::string::npos) << e.message;
  ASSERT_TRUE(a.s.getLocal(a.nodes[0], got).ok());
  expectMatNear(got, moved, 0.0f);
  ASSERT_TRUE(a.s.getLocal(a.nodes[1], got).ok());
  expectMatNear(got, before1, 0.0f);
  a.s.update();
  ASSERT_TRUE(a.s.getWorld(a.nodes[0], got).ok());
  expectMatNear(got, bruteWorld(a.s, a.nodes[0]), 1e-4f);
}
