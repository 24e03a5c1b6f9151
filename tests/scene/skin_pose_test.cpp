#include "scenelod/scene/skin_pose.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <gtest/gtest.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/scene.h"
#include "test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

using Interp = AnimationData::Interpolation;
using Path = AnimationData::Path;

constexpr float kPi = 3.14159265358979f;

// glTF stores quaternions as x, y, z, w
glm::vec4 quatValue(float angle, const glm::vec3& axis) {
  const glm::quat q = glm::angleAxis(angle, axis);
  return glm::vec4(q.x, q.y, q.z, q.w);
}

AnimationData::Sampler sampler(std::vector<float> times, std::vector<glm::vec4> values, Interp interp = Interp::kLinear) {
  AnimationData::Sampler s;
  s.times = std::move(times);
  s.values = std::move(values);
  s.interpolation = interp;
  return s;
}

// a square tube along x with rings at `xs`: rings before the elbow (x = 1) follow joint 0 (the
// upper arm), rings after it joint 1 (the forearm), a ring at the elbow both
Mesh tubeMesh(const std::vector<float>& xs) {
  Mesh m;
  const float h = 0.1f;
  const glm::vec2 corners[4] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
  for (float x : xs)
    for (const glm::vec2& c : corners) {
      m.positions.push_back(glm::vec3(x, c.x, c.y));
      m.normals.push_back(glm::normalize(glm::vec3(0.0f, c.x, c.y)));
      m.joints.push_back(x < 1.0f ? glm::u16vec4(0) : x == 1.0f ? glm::u16vec4(0, 1, 0, 0) : glm::u16vec4(1, 0, 0, 0));
      m.weights.push_back(x == 1.0f ? glm::vec4(0.5f, 0.5f, 0.0f, 0.0f) : glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
    }
  m.joint_parents = {-1, 0};
  for (uint32_t r = 0; r + 1 < xs.size(); ++r)
    for (uint32_t c = 0; c < 4; ++c) {
      const uint32_t a = 4 * r + c, b = 4 * r + (c + 1) % 4;
      m.triangles.insert(m.triangles.end(), {a, b, b + 4, a, b + 4, a + 4});
    }
  return m;
}

Mesh armMesh() { return tubeMesh({0.0f, 0.5f, 1.0f, 1.5f, 2.0f}); }

// root (0) -> upper joint (1) -> forearm joint (2) at x = 1; the arm's mesh node (3) under the root,
// moved away: glTF ignores its transform when skinning. Animation 0 "bend" turns the elbow 90
// degrees about z in 1 s while the shoulder rises 1 unit in 2 s (LINEAR); animation 1 "wave" swings
// the upper arm on a cubic spline and steps the elbow.
SceneData armScene() {
  SceneData s;
  s.nodes.resize(4);
  s.nodes[0].name = "root";
  s.nodes[0].children = {1, 3};
  s.nodes[1].name = "upper";
  s.nodes[1].parent = 0;
  s.nodes[1].children = {2};
  s.nodes[2].name = "forearm";
  s.nodes[2].parent = 1;
  s.nodes[2].local = glm::translate(glm::mat4(1.0f), glm::vec3(1.0f, 0.0f, 0.0f));
  s.nodes[3].name = "arm";
  s.nodes[3].parent = 0;
  s.nodes[3].local = glm::translate(glm::mat4(1.0f), glm::vec3(5.0f, 5.0f, 5.0f));
  s.nodes[3].mesh = 0;
  s.nodes[3].skin = 0;
  s.roots = {0};
  MeshData md;
  md.name = "arm";
  md.mesh = armMesh();
  md.primitive_materials = {-1};
  s.meshes.push_back(md);
  SkinData skin;
  skin.joints = {1, 2};
  skin.inverse_bind = {glm::mat4(1.0f), glm::translate(glm::mat4(1.0f), glm::vec3(-1.0f, 0.0f, 0.0f))};
  s.skins.push_back(skin);

  AnimationData bend;
  bend.name = "bend";
  bend.samplers.push_back(sampler({0.0f, 1.0f}, {quatValue(0.0f, {0, 0, 1}), quatValue(0.5f * kPi, {0, 0, 1})}));
  bend.samplers.push_back(sampler({0.0f, 2.0f}, {glm::vec4(0.0f), glm::vec4(0.0f, 1.0f, 0.0f, 0.0f)}));
  bend.channels = {{2, Path::kRotation, 0}, {1, Path::kTranslation, 1}};
  s.animations.push_back(bend);

  AnimationData wave;
  wave.name = "wave";
  const glm::vec4 zero(0.0f), spin(0.0f, 0.0f, 0.6f, 0.0f);
  wave.samplers.push_back(sampler({0.0f, 0.5f, 1.5f},
                                  {zero, quatValue(0.0f, {0, 0, 1}), spin, -spin, quatValue(1.2f, {0, 0, 1}), zero,
                                   zero, quatValue(-0.8f, {0, 1, 0}), zero},
                                  Interp::kCubicSpline));
  wave.samplers.push_back(sampler({0.0f, 0.7f}, {quatValue(0.3f, {0, 1, 0}), quatValue(1.4f, {1, 0, 0})}, Interp::kStep));
  wave.channels = {{1, Path::kRotation, 0}, {2, Path::kRotation, 1}};
  s.animations.push_back(wave);
  return s;
}

// mesh of node `node` posed at time t of `animation`, world space
Mesh posed(const SceneData& s, int32_t node, int32_t animation, float t, const Mesh& mesh) {
  std::vector<glm::mat4> locals, joints;
  animatedLocals(s, animation, t, locals);
  const std::vector<glm::mat4> world = worldTransforms(s, Span<const glm::mat4>(locals.data(), locals.size()));
  skinMatrices(s, s.nodes[node].skin, Span<const glm::mat4>(world.data(), world.size()), joints);
  Mesh out;
  const Error e = poseMesh(mesh, Span<const glm::mat4>(joints.data(), joints.size()), out, "test mesh");
  EXPECT_TRUE(e.ok()) << e.message;
  return out;
}

// the runtime scene of `s` with chain sphere `chain_sphere` for the mesh of node `node`, driven as
// an engine drives it: every node's local transform set to the pose, then update()
class PosedScene {
 public:
  PosedScene(const SceneData& s, int32_t node, const Sphere& chain_sphere) : s_(s) {
    const Error e = Scene::fromSceneData(s, scene_, "test");
    EXPECT_TRUE(e.ok()) << e.message;
    EXPECT_TRUE(scene_.setChainSphere(static_cast<uint32_t>(s.nodes[node].mesh), chain_sphere).ok());
    const std::vector<int32_t> objects = objectNodes(s);
    object_ = static_cast<size_t>(std::find(objects.begin(), objects.end(), node) - objects.begin());
  }

  // the object's world sphere at time t of `animation`
  Sphere sphereAt(int32_t animation, float t) {
    std::vector<glm::mat4> locals;
    animatedLocals(s_, animation, t, locals);
    for (size_t i = 0; i < locals.size(); ++i) EXPECT_TRUE(scene_.setLocal(NodeHandle{uint32_t(i), 0}, locals[i]).ok());
    scene_.update();
    return Sphere{scene_.worldCenters()[object_], scene_.worldRadii()[object_]};
  }

 private:
  const SceneData& s_;
  Scene scene_;
  size_t object_ = 0;
};

// node `node`'s own frame at a pose (the product of its ancestors' locals and its own)
glm::mat4 frameAt(const SceneData& s, int32_t node, int32_t animation, float t) {
  std::vector<glm::mat4> locals;
  animatedLocals(s, animation, t, locals);
  return nodeFrame(s, Span<const glm::mat4>(locals.data(), locals.size()), node);
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// the largest distance by which a posed vertex of node `node` leaves the sphere its scene object
// gets, over `count` random times of every animation (a little before and after each) and the rest
// pose, relative to the sphere's radius; <= 0 when every vertex is inside
float worstEscape(const SceneData& s, int32_t node, const Mesh& mesh, const Sphere& chain_sphere, int count) {
  std::mt19937 rng(7);
  float worst = -1.0f;
  PosedScene scene(s, node, chain_sphere);
  auto check = [&](int32_t a, float t) {
    const Sphere w = scene.sphereAt(a, t);
    for (const glm::vec3& p : posed(s, node, a, t, mesh).positions)
      worst = std::max(worst, (glm::length(p - w.center) - w.radius) / w.radius);
  };
  check(kRestPose, 0.0f);
  for (size_t a = 0; a < s.animations.size(); ++a) {
    float start, end;
    animationTimeRange(s.animations[a], start, end);
    std::uniform_real_distribution<float> time(start - 0.1f, end + 0.1f);
    for (int i = 0; i < count; ++i) check(static_cast<int32_t>(a), time(rng));
  }
  return worst;
}

// the minimal sphere of every posed vertex of node `node`, in its frame, at `count` evenly spaced
// times of every animation and in the rest pose
Sphere sampledPoseSphere(const SceneData& s, int32_t node, const Mesh& mesh, int count) {
  std::vector<glm::vec3> all;
  auto add = [&](int32_t a, float t) {
    const glm::mat4 to_node = glm::inverse(frameAt(s, node, a, t));
    for (const glm::vec3& p : posed(s, node, a, t, mesh).positions) all.push_back(glm::vec3(to_node * glm::vec4(p, 1.0f)));
  };
  add(kRestPose, 0.0f);
  for (size_t a = 0; a < s.animations.size(); ++a) {
    float start, end;
    animationTimeRange(s.animations[a], start, end);
    for (int i = 0; i < count; ++i) add(static_cast<int32_t>(a), start + (end - start) * float(i) / float(count - 1));
  }
  return minimalSphere(Span<const glm::vec3>(all.data(), all.size()));
}

template <class Edit>
std::string skinningError(Edit edit) {
  SceneData s = armScene();
  edit(s);
  return validateSkinning(s, "arm.gltf").message;
}

}  // namespace

TEST(SkinPose, LinearSamplesLerpAndClampOutsideTheKeys) {
  const auto s = sampler({0.0f, 2.0f}, {glm::vec4(0.0f), glm::vec4(2.0f, 4.0f, 0.0f, 0.0f)});
  expectNear(glm::vec3(sampleAnimation(s, 0.5f, false)), {0.5f, 1.0f, 0.0f});
  expectNear(glm::vec3(sampleAnimation(s, -1.0f, false)), {0.0f, 0.0f, 0.0f});
  expectNear(glm::vec3(sampleAnimation(s, 3.0f, false)), {2.0f, 4.0f, 0.0f});
}

TEST(SkinPose, StepHoldsThePreviousKey) {
  const auto s = sampler({0.0f, 2.0f}, {glm::vec4(1.0f), glm::vec4(3.0f)}, Interp::kStep);
  EXPECT_FLOAT_EQ(sampleAnimation(s, 1.99f, false).x, 1.0f);
  EXPECT_FLOAT_EQ(sampleAnimation(s, 2.0f, false).x, 3.0f);
}

TEST(SkinPose, CubicSplineIsTheSpecsHermiteWithTangentsScaledByTheInterval) {
  // v0 = 0, out-tangent 0.5; v1 = 1, in-tangent 0; interval 2 s. At u = 1/2 the Hermite bases are
  // 1/2, 1/8, 1/2, -1/8: 0.125 * 0.5 * 2 + 0.5 * 1 = 0.625
  const glm::vec4 z(0.0f);
  const auto s = sampler({0.0f, 2.0f}, {z, z, glm::vec4(0.5f), z, glm::vec4(1.0f), z}, Interp::kCubicSpline);
  EXPECT_NEAR(sampleAnimation(s, 1.0f, false).x, 0.625f, 1e-6f);
  EXPECT_NEAR(sampleAnimation(s, 0.0f, false).x, 0.0f, 1e-6f);
  EXPECT_NEAR(sampleAnimation(s, 2.0f, false).x, 1.0f, 1e-6f);
}

TEST(SkinPose, RotationsSlerpAlongTheShorterArc) {
  const glm::vec4 q90 = quatValue(0.5f * kPi, {0, 0, 1});
  const glm::vec4 q45 = quatValue(0.25f * kPi, {0, 0, 1});
  for (const glm::vec4& end : {q90, -q90}) {
    const auto s = sampler({0.0f, 1.0f}, {quatValue(0.0f, {0, 0, 1}), end});
    const glm::vec4 q = sampleAnimation(s, 0.5f, true);
    EXPECT_NEAR(std::fabs(glm::dot(q, q45)), 1.0f, 1e-6f);
  }
  // one third of the way is 30 degrees: a slerp, not a normalised lerp (which gives about 33.7)
  const glm::vec4 q = sampleAnimation(sampler({0.0f, 1.0f}, {quatValue(0.0f, {0, 0, 1}), q90}), 1.0f / 3.0f, true);
  EXPECT_NEAR(2.0f * std::acos(q.w), kPi / 6.0f, 1e-5f);
}

TEST(SkinPose, DecomposeTrsInvertsCompose) {
  Trs trs;
  trs.translation = {1.0f, -2.0f, 3.0f};
  trs.rotation = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)));
  trs.scale = {-2.0f, 0.5f, 3.0f};
  const glm::mat4 m = composeTrs(trs);
  const glm::mat4 back = composeTrs(decomposeTrs(m));
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(back[c][r], m[c][r], 1e-5f) << c << "," << r;
}

TEST(SkinPose, TheElbowBendsTheForearmAndTheMeshNodeIsIgnored) {
  const SceneData s = armScene();
  ASSERT_TRUE(validateSkinning(s, "arm").ok()) << validateSkinning(s, "arm").message;
  const Mesh& mesh = s.meshes[0].mesh;
  // at t = 1 the elbow has turned 90 degrees about z and the shoulder has risen 0.5
  const Mesh p = posed(s, 3, 0, 1.0f, mesh);
  const glm::vec3 lift(0.0f, 0.5f, 0.0f);
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 q = mesh.positions[v];
    if (q.x < 0.75f) {
      expectNear(p.positions[v], q + lift);  // upper arm: only lifted
    } else if (q.x > 1.25f) {
      expectNear(p.positions[v], glm::vec3(1.0f - q.y, q.x - 1.0f, q.z) + lift);  // forearm: turned about the elbow
      expectNear(p.normals[v], glm::vec3(-mesh.normals[v].y, mesh.normals[v].x, mesh.normals[v].z));
    } else {
      // the elbow ring blends both: half way between the unturned and the turned point
      expectNear(p.positions[v], 0.5f * (q + glm::vec3(1.0f - q.y, q.x - 1.0f, q.z)) + lift);
    }
  }
  // the rest pose is the bind pose: every joint at its inverse bind matrix's inverse
  const Mesh rest = posed(s, 3, kRestPose, 0.0f, mesh);
  for (size_t v = 0; v < mesh.vertexCount(); ++v) expectNear(rest.positions[v], mesh.positions[v]);
}

TEST(SkinPose, NodesWithoutChannelsKeepTheirLocalMatrix) {
  const SceneData s = armScene();
  std::vector<glm::mat4> locals;
  animatedLocals(s, 0, 0.5f, locals);
  ASSERT_EQ(locals.size(), s.nodes.size());
  EXPECT_EQ(locals[3], s.nodes[3].local);
  EXPECT_EQ(locals[0], s.nodes[0].local);
  // the forearm keeps its rest translation under its rotation channel
  expectNear(glm::vec3(locals[2][3]), {1.0f, 0.0f, 0.0f});
}

TEST(SkinPose, MirroredJointsKeepNormalsOutward) {
  const Mesh mesh = armMesh();
  const glm::mat4 mirror = glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, -1.0f, 1.0f));
  const glm::mat4 joints[2] = {mirror, mirror};
  Mesh p;
  ASSERT_TRUE(poseMesh(mesh, Span<const glm::mat4>(joints, 2), p, "mirror").ok());
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    // the normal points away from the axis both before and after the mirror
    const glm::vec3 radial(0.0f, p.positions[v].y, p.positions[v].z);
    EXPECT_GT(glm::dot(p.normals[v], radial), 0.0f) << v;
  }
}

TEST(SkinPose, BadSkinsAndAnimationsAreRefusedWithTheirNames) {
  EXPECT_NE(skinningError([](SceneData& s) { s.meshes[0].mesh.joints[7][1] = 2; s.meshes[0].mesh.weights[7][1] = 0.5f; })
                .find("mesh 0 'arm': vertex 7 uses joint 2 but skin 0 has 2 joints"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.skins[0].inverse_bind.pop_back(); }).find("skin 0 has 1 inverse bind"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.skins[0].joints[1] = 9; }).find("joint 1 is node 9 of 4"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.animations[1].samplers[0].values.pop_back(); })
                .find("animation 1 'wave' sampler 0 has 8 values for 3 keys (needs 9)"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.animations[0].samplers[1].times = {1.0f, 1.0f}; })
                .find("animation 0 'bend' sampler 1: key times are not strictly increasing at key 1"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.animations[0].samplers[0].values[1].x = NAN; })
                .find("sampler 0: value 1 is not finite"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.animations[0].channels[1].node = 4; })
                .find("animation 0 'bend' channel 1 targets node 4 of 4"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.animations[0].channels[0].sampler = 2; }).find("uses sampler 2 of 2"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.animations[0].samplers[0].values[0] = glm::vec4(0.0f); })
                .find("channel 0: rotation key 0 is a zero quaternion"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.meshes[0].mesh.joints.clear(); s.meshes[0].mesh.weights.clear(); })
                .find("mesh 0 'arm' is drawn with skin 0 by arm.gltf node 3 'arm' but has no joints"),
            std::string::npos);
  EXPECT_NE(skinningError([](SceneData& s) { s.nodes[3].skin = 1; }).find("node 3 'arm' uses skin 1 of 1"),
            std::string::npos);

  // the runtime scene and the LOD build refuse them too
  SceneData bad = armScene();
  bad.skins[0].inverse_bind.clear();
  Scene scene;
  EXPECT_EQ(Scene::fromSceneData(bad, scene, "arm.gltf").status, Status::kInvalidArgument);
  SceneLods lods;
  EXPECT_EQ(buildLods(bad, LodBuildParams{}, lods, nullptr, "arm.gltf").status, Status::kInvalidArgument);

  // posing a mesh without a skin, or with joints the matrices do not have, says so
  Mesh out, plain = armMesh();
  plain.joints.clear();
  const glm::mat4 one(1.0f);
  EXPECT_NE(poseMesh(plain, Span<const glm::mat4>(&one, 1), out, "level 3").message.find("level 3: cannot pose"),
            std::string::npos);
  EXPECT_NE(poseMesh(armMesh(), Span<const glm::mat4>(&one, 1), out, "level 3").message.find("uses joint 1 but the skin has 1"),
            std::string::npos);
}

TEST(SkinPose, AnimatedSpheresHoldEveryPosedVertexBetweenTheSamples) {
  const SceneData s = armScene();
  Scene scene;
  const Error e = Scene::fromSceneData(s, scene, "arm");
  ASSERT_TRUE(e.ok()) << e.message;
  const Sphere chain = scene.chainSpheres()[0];
  const Mesh& mesh = s.meshes[0].mesh;
  // float rounding of posed vertices is far below 1e-6 of the radius
  EXPECT_LE(worstEscape(s, 3, mesh, chain, 2000), 1e-6f);
  // the test can fail: the bind-pose sphere misses the bent and waving arm
  const Sphere bind = minimalSphere(Span<const glm::vec3>(mesh.positions.data(), mesh.positions.size()));
  EXPECT_GT(worstEscape(s, 3, mesh, bind, 200), 0.1f);
  // the object's world sphere is the node's transform of it (the scene follows the node)
  expectNear(scene.worldCenters()[0], chain.center + glm::vec3(5.0f));

  // the character moved by the common ancestor, its mesh node turned and scaled on its own
  SceneData moved = s;
  moved.nodes[0].local = glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(-3.0f, 2.0f, 7.0f)), 0.5f, glm::vec3(1, 0, 0));
  moved.nodes[3].local = glm::scale(glm::rotate(moved.nodes[3].local, 1.5f, glm::vec3(0, 1, 0)), glm::vec3(2.0f));
  Scene moved_scene;
  ASSERT_TRUE(Scene::fromSceneData(moved, moved_scene, "arm").ok());
  EXPECT_LE(worstEscape(moved, 3, mesh, moved_scene.chainSpheres()[0], 500), 1e-6f);
}

TEST(SkinPose, ChordSpheresCoverNearHalfTurnsBetweenTwoSamples) {
  // a ring 2 before the elbow stays; a ring 1 after it swings from -85 to +85 degrees in one key
  // interval, sampled at its two ends only
  SceneData s = armScene();
  s.meshes[0].mesh = tubeMesh({-1.0f, 2.0f});
  s.animations.resize(1);
  s.animations[0].samplers[0] = sampler({0.0f, 1.0f}, {quatValue(-85.0f / 180.0f * kPi, {0, 0, 1}),
                                                       quatValue(85.0f / 180.0f * kPi, {0, 0, 1})});
  s.animations[0].samplers[1] = sampler({0.0f, 1.0f}, {glm::vec4(0.0f), glm::vec4(0.0f)});
  const Mesh& mesh = s.meshes[0].mesh;
  const Mesh* levels[] = {&mesh};
  Sphere chain;
  ASSERT_TRUE(animatedMeshSphere(s, 0, Span<const Mesh* const>(levels, 1), chain, "arm", 1).ok());
  EXPECT_LE(worstEscape(s, 3, mesh, chain, 2000), 1e-6f);
  // the sphere of the two end poses alone misses the swing's middle by about a third
  std::vector<glm::vec3> ends;
  for (float t : {0.0f, 1.0f})
    for (const glm::vec3& p : posed(s, 3, 0, t, mesh).positions) ends.push_back(p - glm::vec3(5.0f));
  const Sphere end_only = minimalSphere(Span<const glm::vec3>(ends.data(), ends.size()));
  EXPECT_GT(worstEscape(s, 3, mesh, end_only, 200), 0.2f);
}

TEST(SkinPose, AnimatedSpheresAreNotMuchLooserThanThePosesThemselves) {
  const SceneData s = armScene();
  Scene scene;
  ASSERT_TRUE(Scene::fromSceneData(s, scene, "arm").ok());
  const Sphere tight = sampledPoseSphere(s, 3, s.meshes[0].mesh, 400);
  const float ratio = scene.chainSpheres()[0].radius / tight.radius;
  std::printf("arm: animated sphere radius %.4f, minimal sphere of the sampled poses %.4f (x%.3f)\n",
              scene.chainSpheres()[0].radius, tight.radius, ratio);
  EXPECT_GE(ratio, 1.0f);
  EXPECT_LE(ratio, 1.5f);
}

TEST(SkinPose, BuildLodsGivesSkinnedChainsAnimatedSpheres) {
  const SceneData s = armScene();
  Scene scene;
  ASSERT_TRUE(Scene::fromSceneData(s, scene, "arm").ok());
  SceneLods lods;
  LodBuildParams p;
  p.chain.level_count = 3;
  const Error e = buildLods(s, p, lods, &scene, "arm");
  ASSERT_TRUE(e.ok()) << e.message;
  const Sphere chain = lods.chain_spheres[0];
  EXPECT_EQ(scene.chainSpheres()[0].radius, chain.radius);
  for (const LodLevel& level : lods.chains[0].levels) {
    // a level carrying the skin is posed; one without is drawn as stored
    if (level.mesh.skinned()) {
      EXPECT_LE(worstEscape(s, 3, level.mesh, chain, 300), 1e-6f);
    } else {
      for (const glm::vec3& q : level.mesh.positions) EXPECT_LE(glm::length(q - chain.center), chain.radius);
    }
  }
}

TEST(SkinPose, AMeshAlsoDrawnWithoutASkinKeepsItsStoredVerticesInItsSphere) {
  SceneData s = armScene();
  const Mesh& mesh = s.meshes[0].mesh;
  Scene skinned_only;
  ASSERT_TRUE(Scene::fromSceneData(s, skinned_only, "arm").ok());
  // the posed arm lies far from the mesh node's origin, where the stored vertices are
  bool stored_outside = false;
  for (const glm::vec3& q : mesh.positions)
    stored_outside |= glm::length(q - skinned_only.chainSpheres()[0].center) > skinned_only.chainSpheres()[0].radius;
  EXPECT_TRUE(stored_outside);
  // a second, unskinned node drawing the same mesh draws the stored vertices
  s.nodes.push_back(NodeData{});
  s.nodes[4].mesh = 0;
  s.roots.push_back(4);
  Scene both;
  ASSERT_TRUE(Scene::fromSceneData(s, both, "arm").ok());
  const Sphere chain = both.chainSpheres()[0];
  for (const glm::vec3& q : mesh.positions) EXPECT_LE(glm::length(q - chain.center), chain.radius);
  EXPECT_LE(worstEscape(s, 3, mesh, chain, 300), 1e-6f);
}

TEST(SkinPose, SharedModelsAnimatedSpheresHoldEveryPose) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  for (const char* name : {"Fox/Fox.glb", "BrainStem/BrainStem.glb"}) {
    const std::string path = test::sharedModelsDir() + "/" + name;
    SceneData s;
    const Error e = loadScene(path, s);
    ASSERT_TRUE(e.ok()) << e.message;
    if (s.skins.empty() || s.animations.empty())
      GTEST_SKIP() << path << ": the glTF importer does not read skins and animations yet";
    Scene scene;
    const Error se = Scene::fromSceneData(s, scene, path);
    ASSERT_TRUE(se.ok()) << se.message;
    for (int32_t node : objectNodes(s)) {
      if (s.nodes[node].skin < 0) continue;
      const int32_t m = s.nodes[node].mesh;
      const Sphere chain = scene.chainSpheres()[m];
      const Mesh& mesh = s.meshes[m].mesh;
      const float escape = worstEscape(s, node, mesh, chain, 40);
      EXPECT_LE(escape, 1e-5f) << path << " node " << node;
      // today's bind-pose sphere lets posed vertices out
      const Sphere bind = minimalSphere(Span<const glm::vec3>(mesh.positions.data(), mesh.positions.size()));
      const float bind_escape = worstEscape(s, node, mesh, bind, 40);
      EXPECT_GT(bind_escape, 0.0f) << path;
      const float ratio = chain.radius / sampledPoseSphere(s, node, mesh, 40).radius;
      std::printf("%s node %d: animated sphere radius %g (x%.3f the minimal sphere of the sampled poses), worst "
                  "escape %.4f of it; the bind-pose sphere lets vertices %.1f %% of its radius out\n",
                  name, node, chain.radius, ratio, escape, 100.0 * bind_escape);
      EXPECT_LE(ratio, 1.5f) << path;
    }
  }
}
