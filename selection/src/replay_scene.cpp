// Scenes for replays: validation, world spheres, moves, built-in synthetic scenes, level-scene JSON.
#include "scenelod/selection/replay_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <iterator>
#include <nlohmann/json.hpp>

#include "scenelod/lodcore/json_limits.h"
#include "scenelod/lodcore/atomic_file.h"

#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/pack.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::selection {

namespace {

using json = nlohmann::json;

bool finiteMat(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

glm::mat4 trs(const glm::vec3& t, const glm::quat& q, float s) {
  return glm::translate(glm::mat4(1.0f), t) * glm::mat4_cast(q) * glm::scale(glm::mat4(1.0f), glm::vec3(s));
}

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

// chain with `levels` levels: counts shrink by `ratio` per level from `triangles`, widths double
uint32_t addSyntheticChain(ReplayScene& s, std::mt19937& rng, size_t levels, uint32_t triangles, float radius,
                           const std::string& name) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> w(levels);
  std::vector<uint32_t> t(levels), v(levels), lp(levels);
  const float w1 = radius * (0.01f + 0.01f * u(rng));
  uint32_t tri = triangles;
  for (size_t k = 0; k < levels; ++k) {
    w[k] = k == 0 ? 0.0f : w1 * std::pow(2.0f, static_cast<float>(k - 1));
    t[k] = tri;
    v[k] = tri / 2 + 2;
    lp[k] = k < 2 ? 0 : static_cast<uint32_t>(10 + 40 * u(rng));
    tri = std::max<uint32_t>(6, static_cast<uint32_t>(static_cast<float>(tri) * (0.3f + 0.2f * u(rng))));
  }
  const uint32_t id = s.table.addChain(Span<const float>(w.data(), w.size()), Span<const uint32_t>(t.data(), t.size()),
                                       Span<const uint32_t>(v.data(), v.size()), Span<const uint32_t>(lp.data(), lp.size()));
  Sphere b;
  b.radius = radius;
  s.chain_bounds.push_back(b);
  s.chain_names.push_back(name);
  return id;
}

void addObject(ReplayScene& s, int32_t parent, const glm::mat4& local, uint32_t chain, float importance, bool must) {
  s.node_parent.push_back(parent);
  s.node_local.push_back(local);
  s.object_node.push_back(static_cast<int32_t>(s.node_parent.size() - 1));
  s.object_chain.push_back(chain);
  s.importance.push_back(importance);
  s.must_draw.push_back(must ? 1 : 0);
}

}  // namespace

Error validateReplayScene(const ReplayScene& s, const std::string& what) {
  const size_t nodes = s.node_parent.size(), objects = s.object_node.size(), chains = s.table.chainCount();
  if (s.node_local.size() != nodes) return Error(Status::kInvalidArgument, what + ": node transform count differs from node count");
  if (s.object_chain.size() != objects || s.importance.size() != objects || s.must_draw.size() != objects)
    return Error(Status::kInvalidArgument, what + ": per-object arrays differ in length");
  if (s.chain_bounds.size() != chains) return Error(Status::kInvalidArgument, what + ": one bounding sphere per chain needed");
  for (size_t n = 0; n < nodes; ++n) {
    if (s.node_parent[n] < -1 || s.node_parent[n] >= static_cast<int32_t>(nodes))
      return Error(Status::kInvalidArgument, what + ": node " + std::to_string(n) + " has a parent out of range");
    if (!finiteMat(s.node_local[n])) return Error(Status::kInvalidArgument, what + ": node " + std::to_string(n) + " has a non-finite transform");
    // a cycle shows as a walk longer than the node count
    int32_t p = s.node_parent[n];
    size_t steps = 0;
    while (p >= 0 && steps <= nodes) {
      p = s.node_parent[static_cast<size_t>(p)];
      ++steps;
    }
    if (steps > nodes) return Error(Status::kInvalidArgument, what + ": node " + std::to_string(n) + " is in a parent cycle");
  }
  for (size_t o = 0; o < objects; ++o) {
    if (s.object_node[o] < 0 || s.object_node[o] >= static_cast<int32_t>(nodes))
      return Error(Status::kInvalidArgument, what + ": object " + std::to_string(o) + " has a node out of range");
    if (s.object_chain[o] >= chains)
      return Error(Status::kInvalidArgument, what + ": object " + std::to_string(o) + " has a chain out of range");
    if (!(s.importance[o] >= 0.0f) || !std::isfinite(s.importance[o]))
      return Error(Status::kInvalidArgument, what + ": object " + std::to_string(o) + " has a negative or non-finite importance");
  }
  for (size_t c = 0; c < chains; ++c) {
    const Sphere& b = s.chain_bounds[c];
    if (!(b.radius >= 0.0f) || !std::isfinite(b.radius) || !std::isfinite(b.center.x) || !std::isfinite(b.center.y) ||
        !std::isfinite(b.center.z))
      return Error(Status::kInvalidArgument, what + ": chain " + std::to_string(c) + " has an invalid bounding sphere");
    const uint32_t b0 = s.table.chain_level_offset[c], e0 = s.table.chain_level_offset[c + 1];
    if (e0 - b0 > 64) return Error(Status::kInvalidArgument, what + ": chain " + std::to_string(c) + " has more than 64 levels");
    for (uint32_t r = b0; r < e0; ++r) {
      const float w = s.table.cell_width[r];
      if (!(w >= 0.0f) || !std::isfinite(w) || (r > b0 && w < s.table.cell_width[r - 1]))
        return Error(Status::kInvalidArgument, what + ": chain " + std::to_string(c) +
                                                   " has cell widths that are negative, not finite or decreasing");
    }
  }
  return Error();
}

void computeObjectWorlds(const ReplayScene& s, std::vector<glm::mat4>& worlds) {
  const size_t nodes = s.node_parent.size();
  std::vector<glm::mat4> world(nodes);
  std::vector<char> done(nodes, 0);
  std::vector<size_t> stack;
  for (size_t n = 0; n < nodes; ++n) {
    size_t m = n;
    while (!done[m]) {
      stack.push_back(m);
      if (s.node_parent[m] < 0) break;
      m = static_cast<size_t>(s.node_parent[m]);
    }
    while (!stack.empty()) {
      const size_t k = stack.back();
      stack.pop_back();
      world[k] = s.node_parent[k] < 0 ? s.node_local[k] : world[static_cast<size_t>(s.node_parent[k])] * s.node_local[k];
      done[k] = 1;
    }
  }
  worlds.resize(s.objectCount());
  for (size_t o = 0; o < worlds.size(); ++o) worlds[o] = world[static_cast<size_t>(s.object_node[o])];
}

void computeWorldSpheres(const ReplayScene& s, std::vector<glm::vec3>& centers, std::vector<float>& radii,
                         std::vector<float>& max_scales) {
  std::vector<glm::mat4> world;
  computeObjectWorlds(s, world);
  const size_t objects = s.objectCount();
  centers.resize(objects);
  radii.resize(objects);
  max_scales.resize(objects);
  for (size_t o = 0; o < objects; ++o) {
    const glm::mat4& m = world[o];
    const Sphere& b = s.chain_bounds[s.object_chain[o]];
    const float sx = glm::length(glm::vec3(m[0])), sy = glm::length(glm::vec3(m[1])), sz = glm::length(glm::vec3(m[2]));
    const float scale = std::max(sx, std::max(sy, sz));
    centers[o] = glm::vec3(m * glm::vec4(b.center, 1.0f));
    radii[o] = b.radius * scale;
    max_scales[o] = scale > 0.0f ? scale : 1.0f;
  }
}

Error applyMoves(ReplayScene& s, const std::vector<ReplayMove>& moves, const std::string& what) {
  for (const ReplayMove& m : moves) {
    if (m.object >= s.objectCount())
      return Error(Status::kInvalidArgument, what + ": a move names object " + std::to_string(m.object) + " but the scene has " +
                                                 std::to_string(s.objectCount()) + " objects");
    s.node_local[static_cast<size_t>(s.object_node[m.object])] = trs(m.translation, glm::normalize(m.rotation), m.scale);
  }
  return Error();
}

Error makeBuiltinScene(const std::string& name, ReplayScene& s) {
  s = ReplayScene();
  s.name = name;
  const std::string key = name.rfind("builtin:", 0) == 0 ? name.substr(8) : name;
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  if (key == "small") {
    for (int c = 0; c < 4; ++c) addSyntheticChain(s, rng, 6, 4000 + 3000 * c, 1.0f + 0.5f * c, "small" + std::to_string(c));
    // a parent node carrying objects 0..3, so a move of an ancestor is visible through the hierarchy
    s.node_parent.push_back(-1);
    s.node_local.push_back(glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, -10.0f)));
    for (int i = 0; i < 40; ++i) {
      const int32_t parent = i < 4 ? 0 : -1;
      const glm::vec3 p = i < 4 ? glm::vec3(-3.0f + 2.0f * i, 0.0f, 0.0f)
                                : glm::vec3((u(rng) - 0.5f) * 60.0f, (u(rng) - 0.5f) * 6.0f, -5.0f - 60.0f * u(rng));
      addObject(s, parent, glm::translate(glm::mat4(1.0f), p), static_cast<uint32_t>(i % 4), 0.5f + u(rng), i == 5);
    }
  } else if (key == "city") {
    const char* kinds[] = {"tower", "block", "house", "dome", "tree", "car"};
    for (int c = 0; c < 6; ++c) addSyntheticChain(s, rng, 8, 6000 + 9000 * c, 2.0f + c, kinds[c]);
    for (int z = 0; z < 24; ++z)
      for (int x = 0; x < 24; ++x) {
        const glm::vec3 p((x - 11.5f) * 12.0f, 0.0f, (z - 11.5f) * 12.0f);
        const float scale = 0.6f + 0.8f * u(rng);
        const glm::mat4 m = glm::translate(glm::mat4(1.0f), p) *
                            glm::rotate(glm::mat4(1.0f), 6.2831853f * u(rng), glm::vec3(0, 1, 0)) *
                            glm::scale(glm::mat4(1.0f), glm::vec3(scale));
        addObject(s, -1, m, static_cast<uint32_t>(rng() % 6), 0.5f + u(rng), false);
      }
    for (int i = 0; i < 2; ++i)  // instruments: small, must-draw
      addObject(s, -1, glm::translate(glm::mat4(1.0f), glm::vec3(-1.0f + 2.0f * i, 1.0f, 0.0f)) * glm::scale(glm::mat4(1.0f), glm::vec3(0.1f)),
                5, 2.0f, true);
  } else if (key == "field") {
    for (int c = 0; c < 10; ++c) addSyntheticChain(s, rng, 8, 2000 + 7000 * c, 1.0f + 0.3f * c, "field" + std::to_string(c));
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 p((u(rng) - 0.5f) * 400.0f, 0.0f, (u(rng) - 0.5f) * 400.0f);
      addObject(s, -1, glm::translate(glm::mat4(1.0f), p) * glm::scale(glm::mat4(1.0f), glm::vec3(0.5f + 1.5f * u(rng))),
                static_cast<uint32_t>(rng() % 10), 0.5f + u(rng), false);
    }
  } else {
    return Error(Status::kNotFound, "unknown built-in scene '" + name + "' (known: builtin:small, builtin:city, builtin:field)");
  }
  return validateReplayScene(s, name);
}

Error replaySceneFromSceneData(const scene::SceneData& d, const std::vector<LodChain>& chains, const std::string& what,
                               ReplayScene& s, const std::vector<Sphere>* chain_spheres) {
  s = ReplayScene();
  s.name = what;
  if (chains.size() != d.meshes.size())
    return Error(Status::kInvalidArgument, what + ": " + std::to_string(chains.size()) + " chains for " +
                                               std::to_string(d.meshes.size()) + " meshes");
  for (size_t m = 0; m < chains.size(); ++m) {
    if (chains[m].levelCount() > 64) return Error(Status::kInvalidArgument, what + ": mesh " + std::to_string(m) + " has more than 64 levels");
    s.table.addChain(chains[m]);
    // a sphere containing every level: the union of the level spheres around level 0's centre
    Sphere b;
    if (!chains[m].empty()) {
      b.center = chains[m].levels[0].bounds.center;
      for (const LodLevel& l : chains[m].levels) {
        float r = glm::length(l.bounds.center - b.center) + l.bounds.radius;
        if (l.bounds.radius == 0.0f)  // bounds not filled: measure the vertices
          for (const glm::vec3& p : l.mesh.positions) r = std::max(r, glm::length(p - b.center));
        b.radius = std::max(b.radius, r);
      }
    }
    if (chain_spheres && m < chain_spheres->size()) b = (*chain_spheres)[m];
    s.chain_bounds.push_back(b);
    s.chain_names.push_back(d.meshes[m].name);
  }
  s.chains = chains;  // geometry for ray queries (ReplayVisibility)
  for (const scene::NodeData& n : d.nodes) {
    s.node_parent.push_back(n.parent);
    s.node_local.push_back(n.local);
  }
  for (int32_t node : scene::objectNodes(d)) {
    s.object_node.push_back(node);
    s.object_chain.push_back(static_cast<uint32_t>(d.nodes[static_cast<size_t>(node)].mesh));
    s.importance.push_back(1.0f);
    s.must_draw.push_back(0);
  }
  return validateReplayScene(s, what);
}

namespace {

Error loadLevelSceneImpl(const std::string& path, ReplayScene& s) {
  s = ReplayScene();
  s.name = path;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error(Status::kIoError, path + ": cannot open level scene");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto fail = [&](const std::string& m) { return Error(Status::kParseError, path + ": " + m); };
  if (jsonNestingDepth(text.data(), text.size()) > kMaxJsonNesting)
    return fail("JSON nested deeper than " + std::to_string(kMaxJsonNesting) + " levels");
  json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return fail("not a JSON object");
  auto v = j.find("scenelod_level_scene");
  int64_t version = 0;
  if (v == j.end() || !jsonWholeNumber(*v, 1, 1, version)) return fail("missing \"scenelod_level_scene\": 1");
  auto num = [](const json& x) { return x.is_number() && std::isfinite(x.get<double>()); };
  auto vecN = [&](const json& x, size_t n) {
    if (!x.is_array() || x.size() != n) return false;
    for (const json& e : x)
      if (!num(e)) return false;
    return true;
  };
  const json& chains = j.value("chains", json());
  const json& nodes = j.value("nodes", json());
  const json& objects = j.value("objects", json());
  if (!chains.is_array() || !nodes.is_array() || !objects.is_array()) return fail("needs arrays \"chains\", \"nodes\" and \"objects\"");
  for (size_t c = 0; c < chains.size(); ++c) {
    const json& ch = chains[c];
    const std::string where = "chain " + std::to_string(c);
    if (!ch.is_object() || !ch.contains("sphere") || !vecN(ch["sphere"], 4)) return fail(where + ": needs \"sphere\": [x, y, z, r]");
    if (!ch.contains("levels") || !ch["levels"].is_array() || ch["levels"].empty())
      return fail(where + ": needs \"levels\": [[cell_width, triangles, vertices, line_points], ...]");
    std::vector<float> w;
    std::vector<uint32_t> t, vv, lp;
    for (const json& l : ch["levels"]) {
      int64_t counts[3] = {};
      if (!vecN(l, 4) || !jsonWholeNumber(l[1], 0, UINT32_MAX, counts[0]) ||
          !jsonWholeNumber(l[2], 0, UINT32_MAX, counts[1]) || !jsonWholeNumber(l[3], 0, UINT32_MAX, counts[2]))
        return fail(where + ": each level is [cell_width, triangles, vertices, line_points] with whole counts from 0 to 2^32 - 1");
      w.push_back(l[0].get<float>());
      t.push_back(static_cast<uint32_t>(counts[0]));
      vv.push_back(static_cast<uint32_t>(counts[1]));
      lp.push_back(static_cast<uint32_t>(counts[2]));
    }
    s.table.addChain(Span<const float>(w.data(), w.size()), Span<const uint32_t>(t.data(), t.size()),
                     Span<const uint32_t>(vv.data(), vv.size()), Span<const uint32_t>(lp.data(), lp.size()));
    Sphere b;
    b.center = glm::vec3(ch["sphere"][0].get<float>(), ch["sphere"][1].get<float>(), ch["sphere"][2].get<float>());
    b.radius = ch["sphere"][3].get<float>();
    s.chain_bounds.push_back(b);
    s.chain_names.push_back(ch.contains("name") && ch["name"].is_string() ? ch["name"].get<std::string>() : std::string());
  }
  for (size_t n = 0; n < nodes.size(); ++n) {
    const json& nd = nodes[n];
    const std::string where = "node " + std::to_string(n);
    if (!nd.is_object()) return fail(where + ": not an object");
    int64_t parent = -1;
    if (nd.contains("parent") && !jsonWholeNumber(nd["parent"], -1, int64_t(nodes.size()) - 1, parent))
      return fail(where + ": \"parent\" must be -1 or a node index below " + std::to_string(nodes.size()));
    glm::vec3 t(0.0f);
    glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
    float sc = 1.0f;
    if (nd.contains("t")) {
      if (!vecN(nd["t"], 3)) return fail(where + ": \"t\" must be [x, y, z]");
      t = glm::vec3(nd["t"][0].get<float>(), nd["t"][1].get<float>(), nd["t"][2].get<float>());
    }
    if (nd.contains("r")) {
      if (!vecN(nd["r"], 4)) return fail(where + ": \"r\" must be [qx, qy, qz, qw]");
      q = glm::quat(nd["r"][3].get<float>(), nd["r"][0].get<float>(), nd["r"][1].get<float>(), nd["r"][2].get<float>());
      if (!(glm::length(q) > 0.0f)) return fail(where + ": zero rotation quaternion");
      q = glm::normalize(q);
    }
    if (nd.contains("s")) {
      if (!num(nd["s"]) || !(nd["s"].get<double>() > 0)) return fail(where + ": \"s\" must be a number > 0");
      sc = nd["s"].get<float>();
    }
    s.node_parent.push_back(static_cast<int32_t>(parent));
    s.node_local.push_back(trs(t, q, sc));
  }
  for (size_t o = 0; o < objects.size(); ++o) {
    const json& ob = objects[o];
    const std::string where = "object " + std::to_string(o);
    int64_t node = 0, chain = 0;
    if (!ob.is_object() || !ob.contains("node") || !ob.contains("chain") ||
        !jsonWholeNumber(ob["node"], 0, INT32_MAX, node) || !jsonWholeNumber(ob["chain"], 0, UINT32_MAX, chain))
      return fail(where + ": needs whole numbers \"node\" and \"chain\" (0 to 2^31 - 1)");
    s.object_node.push_back(static_cast<int32_t>(node));
    s.object_chain.push_back(static_cast<uint32_t>(chain));
    double imp = 1.0;
    if (ob.contains("importance")) {
      if (!num(ob["importance"])) return fail(where + ": \"importance\" must be a number");
      imp = ob["importance"].get<double>();
    }
    s.importance.push_back(static_cast<float>(imp));
    s.must_draw.push_back(ob.contains("must_draw") && ob["must_draw"].is_boolean() && ob["must_draw"].get<bool>() ? 1 : 0);
  }
  return validateReplayScene(s, path);
}

}  // namespace

Error loadLevelScene(const std::string& path, ReplayScene& out) {
  try {
    return loadLevelSceneImpl(path, out);
  } catch (const std::exception& e) {
    return Error(Status::kParseError, path + ": " + e.what());
  }
}

Error writeLevelScene(const std::string& path, const ReplayScene& s) {
  std::ostringstream o;
  o << "{\"scenelod_level_scene\": 1,\n \"chains\": [";
  for (size_t c = 0; c < s.table.chainCount(); ++c) {
    const Sphere& b = s.chain_bounds[c];
    o << (c ? ",\n  " : "\n  ") << "{\"name\": " << json(s.chain_names.size() > c ? s.chain_names[c] : std::string()).dump(-1, ' ', false, json::error_handler_t::replace)
      << ", \"sphere\": [" << fmt(b.center.x) << ", " << fmt(b.center.y) << ", " << fmt(b.center.z) << ", " << fmt(b.radius) << "], \"levels\": [";
    for (uint32_t r = s.table.chain_level_offset[c]; r < s.table.chain_level_offset[c + 1]; ++r)
      o << (r > s.table.chain_level_offset[c] ? ", " : "") << "[" << fmt(s.table.cell_width[r]) << ", " << s.table.triangle_count[r]
        << ", " << s.table.vertex_count[r] << ", " << s.table.line_point_count[r] << "]";
    o << "]}";
  }
  o << "],\n \"nodes\": [";
  for (size_t n = 0; n < s.node_parent.size(); ++n) {
    // decompose: translation, rotation and the largest scale (level scenes hold uniform scales)
    const glm::mat4& m = s.node_local[n];
    const float sc = glm::length(glm::vec3(m[0]));
    const glm::quat q = glm::quat_cast(glm::mat3(glm::vec3(m[0]) / sc, glm::vec3(m[1]) / sc, glm::vec3(m[2]) / sc));
    o << (n ? ",\n  " : "\n  ") << "{\"parent\": " << s.node_parent[n] << ", \"t\": [" << fmt(m[3][0]) << ", " << fmt(m[3][1]) << ", "
      << fmt(m[3][2]) << "], \"r\": [" << fmt(q.x) << ", " << fmt(q.y) << ", " << fmt(q.z) << ", " << fmt(q.w) << "], \"s\": " << fmt(sc) << "}";
  }
  o << "],\n \"objects\": [";
  for (size_t i = 0; i < s.objectCount(); ++i)
    o << (i ? ",\n  " : "\n  ") << "{\"node\": " << s.object_node[i] << ", \"chain\": " << s.object_chain[i]
      << ", \"importance\": " << fmt(s.importance[i]) << ", \"must_draw\": " << (s.must_draw[i] ? "true" : "false") << "}";
  o << "]}\n";
  const std::string text = o.str();
  return writeFileAtomic(path, text.data(), text.size());
}

Error loadPackScene(const std::string& path, ReplayScene& s) {
  s = ReplayScene();
  s.name = path;
  scene::Pack pack;
  if (Error e = scene::Pack::load(path, pack); !e.ok()) return e;
  for (size_t c = 0; c < pack.chainCount(); ++c) {
    std::vector<float> w;
    std::vector<uint32_t> t, v, lp;
    for (size_t l = 0; l < pack.levelCount(c); ++l) {
      const scene::PackLevelView lv = pack.level(c, l);
      w.push_back(lv.cell_width);
      t.push_back(static_cast<uint32_t>(lv.triangles.size() / 3));
      v.push_back(static_cast<uint32_t>(lv.positions.size()));
      lp.push_back(static_cast<uint32_t>(lv.edges.size() / 2 + lv.points.size()));
    }
    s.table.addChain(Span<const float>(w.data(), w.size()), Span<const uint32_t>(t.data(), t.size()),
                     Span<const uint32_t>(v.data(), v.size()), Span<const uint32_t>(lp.data(), lp.size()));
    s.chain_bounds.push_back(pack.chainSphere(c));
    s.chain_names.push_back(pack.meshName(c));
  }
  for (size_t n = 0; n < pack.nodeCount(); ++n) {
    const scene::PackNodeView nv = pack.node(n);
    glm::mat4 m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = nv.local[c * 4 + r];
    s.node_parent.push_back(nv.parent);
    s.node_local.push_back(m);
  }
  for (size_t o = 0; o < pack.objectCount(); ++o) {
    const scene::PackObjectView ov = pack.object(o);
    s.object_node.push_back(static_cast<int32_t>(ov.node));
    s.object_chain.push_back(ov.chain);
    s.importance.push_back(ov.importance);
    s.must_draw.push_back(ov.must_draw ? 1 : 0);
  }
  return validateReplayScene(s, path);
}

namespace {

Error loadSceneWith(const std::string& path, ReplayScene& out, const ChainParams* chain) {
  const std::string built_elsewhere =
      path + ": the scene's levels come from the file; chain options (--nested, --independent) apply to "
             "glTF/GLB/OBJ meshes whose chains are built here";
  if (path.rfind("builtin:", 0) == 0) {
    if (chain) return Error(Status::kInvalidArgument, built_elsewhere);
    return makeBuiltinScene(path, out);
  }
  const size_t dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? std::string() : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (chain && (ext == "json" || ext == "slodpack" || ext == "pack")) return Error(Status::kInvalidArgument, built_elsewhere);
  if (ext == "json") return loadLevelScene(path, out);
  if (ext == "slodpack" || ext == "pack") return loadPackScene(path, out);
  if (ext == "gltf" || ext == "glb" || ext == "obj") {
    scene::SceneData data;
    std::vector<LodChain> chains;
    if (ext == "obj") {
      if (Error e = scene::loadScene(path, data); !e.ok()) return e;
    } else {
      if (Error e = scene::importGltfLods(path, data, chains); !e.ok()) return e;
    }
    // files with MSFT_lod levels keep them; otherwise every mesh's chain is built here
    bool have_levels = !chains.empty();
    for (const LodChain& c : chains) have_levels = have_levels && c.levelCount() > 1;
    if (!have_levels) {
      scene::bakeMaterialColors(data);  // the viewer draws levels by vertex colour
      scene::SceneLods lods;
      scene::LodBuildParams build;
      if (chain) build.chain = *chain;
      if (Error e = scene::buildLods(data, build, lods, nullptr, path); !e.ok()) return e;
      return replaySceneFromSceneData(data, lods.chains, path, out, &lods.chain_spheres);
    }
    if (chain) return Error(Status::kInvalidArgument, built_elsewhere + " (this one has MSFT_lod levels)");
    return replaySceneFromSceneData(data, chains, path, out);
  }
  return Error(Status::kUnsupported, path + ": a replay scene is builtin:NAME, a level-scene .json, a LOD pack (.slodpack) "
                                            "or a .gltf/.glb/.obj file");
}

}  // namespace

Error loadReplayScene(const std::string& path, ReplayScene& out) { return loadSceneWith(path, out, nullptr); }

Error loadReplayScene(const std::string& path, ReplayScene& out, const ChainParams& chain) {
  return loadSceneWith(path, out, &chain);
}

}  // namespace scenelod::selection
