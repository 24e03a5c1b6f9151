#include "scenelod/scene/bounding_sphere.h"

#include <cmath>
#include <random>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

void expectContains(const Sphere& s, const std::vector<glm::vec3>& pts) {
  for (size_t i = 0; i < pts.size(); ++i) ASSERT_LE(glm::length(pts[i] - s.center), s.radius) << "point " << i;
}

Span<const glm::vec3> span(const std::vector<glm::vec3>& v) { return {v.data(), v.size()}; }

}  // namespace

TEST(BoundingSphere, MinimalSphereOfKnownConfigurations) {
  // a regular tetrahedron: circumsphere radius sqrt(3/8) * edge
  const std::vector<glm::vec3> tet = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  Sphere s = minimalSphere(span(tet));
  EXPECT_NEAR(s.radius, std::sqrt(3.0f), 1e-5f);
  EXPECT_NEAR(glm::length(s.center), 0.0f, 1e-5f);
  // an obtuse triangle: the minimal sphere is the one on its longest side, not the circumsphere
  const std::vector<glm::vec3> obtuse = {{-1, 0, 0}, {1, 0, 0}, {0, 0.2f, 0}};
  s = minimalSphere(span(obtuse));
  EXPECT_NEAR(s.radius, 1.0f, 1e-5f);
  // points on a sphere plus interior points
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  std::vector<glm::vec3> ball;
  for (int i = 0; i < 2000; ++i) {
    glm::vec3 v(g(rng), g(rng), g(rng));
    v = glm::normalize(v) * (i % 2 ? 2.0f : 1.0f) + glm::vec3(5, -1, 3);
    ball.push_back(v);
  }
  s = minimalSphere(span(ball));
  EXPECT_NEAR(s.radius, 2.0f, 1e-3f);
  expectContains(s, ball);
}

TEST(BoundingSphere, MinimalIsNoLargerThanRitterAndBothContainEveryPoint) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<glm::vec3> pts(50 + trial * 37);
    const glm::vec3 stretch(1.0f + trial, 1.0f, 0.2f + 0.1f * trial);
    for (auto& p : pts) p = glm::vec3(u(rng), u(rng), u(rng)) * stretch;
    const Sphere r = ritterSphere(span(pts)), m = minimalSphere(span(pts));
    expectContains(r, pts);
    expectContains(m, pts);
    EXPECT_LE(m.radius, r.radius * (1.0f + 1e-6f)) << "trial " << trial;
    // minimality: some point lies on the minimal sphere's surface
    float far = 0.0f;
    for (auto& p : pts) far = std::max(far, glm::length(p - m.center));
    EXPECT_NEAR(far, m.radius, 1e-5f * m.radius);
  }
}

TEST(BoundingSphere, DegenerateInputs) {
  EXPECT_EQ(minimalSphere({}).radius, 0.0f);
  EXPECT_EQ(ritterSphere({}).radius, 0.0f);
  const std::vector<glm::vec3> same(10, glm::vec3(1, 2, 3));
  const Sphere s = minimalSphere(span(same));
  EXPECT_LT(s.radius, 1e-6f);
  expectContains(s, same);
  // collinear and coplanar points (affinely dependent support sets)
  std::vector<glm::vec3> line, plane;
  for (int i = 0; i < 100; ++i) line.push_back({float(i), 2.0f * i, 0.0f});
  for (int i = 0; i < 100; ++i) plane.push_back({float(i % 10), float(i / 10), 1.0f});
  const Sphere l = minimalSphere(span(line)), p = minimalSphere(span(plane));
  expectContains(l, line);
  expectContains(p, plane);
  EXPECT_NEAR(l.radius, 0.5f * std::sqrt(99.0f * 99.0f * 5.0f), 1e-3f);
  EXPECT_NEAR(p.radius, 0.5f * std::sqrt(81.0f + 81.0f), 1e-4f);
}

TEST(BoundingSphere, ChainBoundsContainEveryLevel) {
  LodChain chain;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int l = 0; l < 4; ++l) {
    LodLevel level;
    for (int i = 0; i < 300 / (l + 1); ++i) level.mesh.positions.push_back({u(rng) + l * 0.3f, u(rng), u(rng) * (l + 1)});
    chain.levels.push_back(level);
  }
  const Sphere all = computeChainBounds(chain);
  for (const LodLevel& l : chain.levels) {
    expectContains(l.bounds, l.mesh.positions);
    expectContains(all, l.mesh.positions);
  }
}

TEST(BoundingSphere, MergeContainsBoth) {
  const Sphere a{{0, 0, 0}, 1.0f}, b{{3, 0, 0}, 0.5f};
  const Sphere m = mergeSpheres(a, b);
  EXPECT_NEAR(m.radius, 2.25f, 1e-6f);
  EXPECT_LE(glm::length(a.center - m.center) + a.radius, m.radius);
  EXPECT_LE(glm::length(b.center - m.center) + b.radius, m.radius);
  EXPECT_EQ(mergeSpheres(a, Sphere{{0.1f, 0, 0}, 0.2f}).radius, 1.0f);
}

TEST(BoundingSphere, BunnyMinimalTighterThanRitter) {
  SCENELOD_REQUIRE_BUNNY();
  std::vector<glm::vec3> pts;
  {
    FILE* f = std::fopen(scenelod::test::bunnyPath().c_str(), "r");
    ASSERT_NE(f, nullptr);
    char line[512];
    while (std::fgets(line, sizeof line, f)) {
      glm::vec3 v;
      if (line[0] == 'v' && line[1] == ' ' && std::sscanf(line + 2, "%f %f %f", &v.x, &v.y, &v.z) == 3) pts.push_back(v);
    }
    std::fclose(f);
  }
  ASSERT_EQ(pts.size(), 34835u);
  const Sphere r = ritterSphere(span(pts)), m = minimalSphere(span(pts));
  expectContains(r, pts);
  expectContains(m, pts);
  EXPECT_LT(m.radius, r.radius);
}
