// The runtime scene alone (scenelod::scene_graph): a two-node scene mirrored into a Scene, then
// written as a LOD pack in memory, read back and mirrored again; prints objects and world radii.
#include <cstdio>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include <scenelod/scene/bounding_sphere.h>
#include <scenelod/scene/pack.h>
#include <scenelod/scene/scene.h>

namespace sc = scenelod::scene;

namespace {
void print(const char* tag, const sc::Scene& s) {
  std::printf("%s: objects=%zu radii", tag, s.objectCount());
  for (float r : s.worldRadii()) std::printf(" %.3f", r);
  std::printf("\n");
}
}  // namespace

int main() {
  sc::SceneData data;
  sc::MeshData quad;
  quad.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.mesh.triangles = {0, 1, 2, 0, 2, 3};
  data.meshes.push_back(quad);
  sc::NodeData root, child;
  root.mesh = 0;
  root.children = {1};
  root.local = glm::translate(glm::mat4(1.0f), glm::vec3(5, 0, 0));
  child.parent = 0;
  child.mesh = 0;
  child.local = glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
  data.nodes = {root, child};
  data.roots = {0};

  sc::Scene scene;
  if (!sc::Scene::fromSceneData(data, scene).ok()) return 1;
  scene.update();
  print("scene", scene);

  std::vector<scenelod::LodChain> chains(1);
  chains[0].levels.resize(1);
  chains[0].levels[0].mesh = quad.mesh;
  const std::vector<scenelod::Sphere> spheres = {sc::computeChainBounds(chains[0])};
  std::vector<uint8_t> bytes;
  sc::Pack pack;
  sc::Scene back;
  if (!sc::writePackBytes(bytes, data, chains, spheres).ok()) return 2;
  if (!sc::Pack::fromBytes(bytes.data(), bytes.size(), pack, "memory").ok() || !pack.toScene(back).ok()) return 3;
  back.update();
  print("pack", back);
  return 0;
}
