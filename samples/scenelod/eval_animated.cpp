// scenelod eval --animated: a skinned model's levels measured in the poses of its animations. The
// distances are the eval library's symmetric Hausdorff (metrics.h); the poses are glTF's linear
// blend skinning (scene/skin_pose.h), which ignores the skinned node's own transform.
#include "eval_animated.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "args.h"
#include "eval_support.h"
#include "scenelod/eval/metrics.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/scene/skin_pose.h"

namespace scenelod::tool {
namespace {

constexpr int kPoseTimes = 16;  // per animation, evenly spaced from its first key to its last

struct Pose {
  int32_t animation = scene::kRestPose;
  float time = 0.0f;
};

struct LevelResult {
  size_t level = 0;
  size_t triangles = 0;
  bool skinned = false;        // the level carries joints and weights (else it is not posed)
  double bind = 0.0;           // Hausdorff unposed, fraction of the original's bind-pose diagonal
  double posed = 0.0;          // worst Hausdorff over the poses, fraction of the rest-pose diagonal
  Pose worst;                  // the pose of `posed`
};

struct ObjectResult {
  int32_t node = -1, mesh = -1, skin = -1;
  std::string name;
  size_t pose_count = 0;
  std::vector<LevelResult> levels;
};

std::vector<Pose> evalPoses(const scene::SceneData& s) {
  std::vector<Pose> out;
  for (size_t a = 0; a < s.animations.size(); ++a) {
    float start, end;
    scene::animationTimeRange(s.animations[a], start, end);
    for (int i = 0; i < kPoseTimes; ++i)
      out.push_back({static_cast<int32_t>(a), start + (end - start) * float(i) / float(kPoseTimes - 1)});
  }
  if (out.empty()) out.push_back(Pose{});  // no animation: the rest pose alone
  return out;
}

Error poseAt(const scene::SceneData& s, int32_t skin, const Pose& pose, const Mesh& mesh, Mesh& out,
             const std::string& what) {
  std::vector<glm::mat4> locals, joints;
  scene::animatedLocals(s, pose.animation, pose.time, locals);
  const std::vector<glm::mat4> world = scene::worldTransforms(s, Span<const glm::mat4>(locals.data(), locals.size()));
  scene::skinMatrices(s, skin, Span<const glm::mat4>(world.data(), world.size()), joints);
  return scene::poseMesh(mesh, Span<const glm::mat4>(joints.data(), joints.size()), out, what);
}

// the level indices to measure: the arguments, or every simplified level
Error pickLevels(const std::vector<std::string>& args, size_t level_count, std::vector<size_t>& out) {
  out.clear();
  for (const std::string& a : args) {
    char* end = nullptr;
    const long k = std::strtol(a.c_str(), &end, 10);
    if (a.empty() || *end != '\0' || k < 1 || static_cast<size_t>(k) >= level_count)
      return {Status::kInvalidArgument, "LEVEL '" + a + "' is not a level index in [1, " +
                                            std::to_string(level_count - 1) + "] of the chain"};
    out.push_back(static_cast<size_t>(k));
  }
  if (args.empty())
    for (size_t k = 1; k < level_count; ++k) out.push_back(k);
  return {};
}

// the worst Hausdorff distance of each skinned level over the poses, in units of `diagonal`
Error measurePoses(const scene::SceneData& s, const ObjectResult& obj, const LodChain& chain,
                   const eval::DistanceParams& dp, double diagonal, std::vector<LevelResult>& levels) {
  Mesh original, level;
  for (const Pose& pose : evalPoses(s)) {
    const std::string when = pose.animation == scene::kRestPose
                                 ? std::string(" in the rest pose")
                                 : " at t = " + std::to_string(pose.time) + " of animation " + std::to_string(pose.animation);
    if (Error e = poseAt(s, obj.skin, pose, chain.levels[0].mesh, original, obj.name + when); !e.ok()) return e;
    for (LevelResult& r : levels) {
      if (!r.skinned) continue;
      const std::string what = obj.name + " level " + std::to_string(r.level) + when;
      if (Error e = poseAt(s, obj.skin, pose, chain.levels[r.level].mesh, level, what); !e.ok()) return e;
      eval::DistanceResult d;
      if (Error e = eval::measureSurfaceDistance(original, level, dp, d); !e.ok()) return {e.status, what + ": " + e.message};
      const double h = d.hausdorff * d.diagonal / diagonal;
      if (h >= r.posed) { r.posed = h; r.worst = pose; }
    }
  }
  return {};
}

Error evalObject(const scene::SceneData& s, const std::vector<std::string>& level_args, long level_count,
                 const eval::DistanceParams& dp, ObjectResult& obj) {
  const Mesh& mesh = s.meshes[obj.mesh].mesh;
  LodChain chain;
  ChainParams cp;
  cp.level_count = static_cast<size_t>(level_count);
  if (Error e = buildChain(mesh, cp, chain); !e.ok()) return {e.status, obj.name + ": " + e.message};
  std::vector<size_t> picked;
  if (Error e = pickLevels(level_args, chain.levelCount(), picked); !e.ok()) return e;
  for (size_t k : picked) {
    LevelResult r;
    r.level = k;
    const Mesh& lm = chain.levels[k].mesh;
    r.triangles = lm.triangleCount();
    r.skinned = lm.skinned();
    if (!lm.empty()) {
      eval::DistanceResult d;
      if (Error e = eval::measureSurfaceDistance(mesh, lm, dp, d); !e.ok())
        return {e.status, obj.name + " level " + std::to_string(k) + ": " + e.message};
      r.bind = d.hausdorff;
    } else {
      r.skinned = false;
    }
    obj.levels.push_back(r);
  }
  // posed distances in units of the original's rest-pose diagonal (world units, like the poses)
  Mesh rest;
  if (Error e = poseAt(s, obj.skin, Pose{}, mesh, rest, obj.name + " in the rest pose"); !e.ok()) return e;
  const double diagonal = computeBounds(rest).diagonal();
  if (!(diagonal > 0.0)) return {Status::kInvalidMesh, obj.name + ": the rest pose collapses to a point"};
  obj.pose_count = evalPoses(s).size();
  return measurePoses(s, obj, chain, dp, diagonal, obj.levels);
}

// worst posed over bind-pose Hausdorff; NaN (JSON null) for a level equal to the original unposed
double ratio(const LevelResult& r) { return r.bind > 0.0 ? r.posed / r.bind : NAN; }

std::string poseName(const scene::SceneData& s, const Pose& p) {
  if (p.animation == scene::kRestPose) return "rest pose";
  const std::string& name = s.animations[p.animation].name;
  char t[32];
  std::snprintf(t, sizeof t, " t=%.3f", p.time);
  return (name.empty() ? "animation " + std::to_string(p.animation) : name) + t;
}

void printJson(const std::string& path, const scene::SceneData& s, const std::vector<ObjectResult>& objects) {
  std::printf("{\"model\": %s, \"poses_per_animation\": %d, \"objects\": [", jsonString(path).c_str(), kPoseTimes);
  for (size_t o = 0; o < objects.size(); ++o) {
    const ObjectResult& obj = objects[o];
    std::printf("%s{\"node\": %d, \"mesh\": %d, \"skin\": %d, \"poses\": %zu, \"levels\": [", o ? ", " : "", obj.node,
                obj.mesh, obj.skin, obj.pose_count);
    for (size_t i = 0; i < obj.levels.size(); ++i) {
      const LevelResult& r = obj.levels[i];
      std::printf("%s{\"level\": %zu, \"triangles\": %zu, \"skinned\": %s, \"bind_hausdorff\": %s", i ? ", " : "",
                  r.level, r.triangles, r.skinned ? "true" : "false", jsonNumber(r.bind).c_str());
      if (r.skinned)
        std::printf(", \"posed_hausdorff\": %s, \"ratio\": %s, \"worst_pose\": %s", jsonNumber(r.posed).c_str(),
                    jsonNumber(ratio(r)).c_str(), jsonString(poseName(s, r.worst)).c_str());
      std::printf("}");
    }
    std::printf("]}");
  }
  std::printf("]}\n");
}

void printTable(const std::string& path, const scene::SceneData& s, const std::vector<ObjectResult>& objects) {
  for (const ObjectResult& obj : objects) {
    std::printf("%s: %s, %zu poses (%d per animation); Hausdorff in %% of the original's diagonal\n"
                "(bind: unposed; posed: worst over the poses, rest-pose diagonal)\n",
                path.c_str(), obj.name.c_str(), obj.pose_count, kPoseTimes);
    std::printf("%6s %10s %10s %12s %7s  %s\n", "level", "triangles", "bind", "worst posed", "ratio", "worst pose");
    for (const LevelResult& r : obj.levels) {
      if (!r.skinned) {
        std::printf("%6zu %10zu %9.4f%%  the level carries no skin: not posed\n", r.level, r.triangles, 100.0 * r.bind);
        continue;
      }
      std::printf("%6zu %10zu %9.4f%% %11.4f%% %7.2f  %s\n", r.level, r.triangles, 100.0 * r.bind, 100.0 * r.posed,
                  ratio(r), poseName(s, r.worst).c_str());
    }
  }
}

}  // namespace

int runAnimatedEval(const std::string& path, const std::vector<std::string>& level_args, long level_count,
                    long samples, bool json) {
  scene::SceneData s;
  if (Error e = scene::loadScene(path, s); !e.ok()) return runError("eval", e.message);
  if (Error e = scene::validateSkinning(s, path); !e.ok()) return runError("eval", e.message);
  std::vector<ObjectResult> objects;
  for (int32_t node : scene::objectNodes(s)) {
    if (s.nodes[node].skin < 0) continue;
    ObjectResult obj;
    obj.node = node;
    obj.mesh = s.nodes[node].mesh;
    obj.skin = s.nodes[node].skin;
    const std::string& mesh_name = s.meshes[obj.mesh].name;
    obj.name = "mesh " + std::to_string(obj.mesh) + (mesh_name.empty() ? "" : " '" + mesh_name + "'") +
               " (node " + std::to_string(node) + ", skin " + std::to_string(obj.skin) + ")";
    objects.push_back(obj);
  }
  if (objects.empty())
    return runError("eval", path + ": no mesh is drawn with a skin (" + std::to_string(s.skins.size()) + " skins, " +
                                std::to_string(s.animations.size()) + " animations read): nothing to pose");
  eval::DistanceParams dp;
  dp.area_sample_count = static_cast<size_t>(samples);
  for (ObjectResult& obj : objects)
    if (Error e = evalObject(s, level_args, level_count, dp, obj); !e.ok()) return runError("eval", path + ": " + e.message);
  if (json) {
    printJson(path, s, objects);
  } else {
    printTable(path, s, objects);
  }
  return 0;
}

}  // namespace scenelod::tool
