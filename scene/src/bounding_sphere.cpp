// Bounding spheres: Ritter 1990 ("An efficient bounding sphere", Graphics Gems I) and the minimal
// enclosing sphere of Welzl 1991 ("Smallest enclosing disks (balls and ellipsoids)") in the
// move-to-front form of Gärtner 1999 ("Fast and robust smallest enclosing balls"), in double
// precision with an explicit support set of at most 4 points. Skinned meshes: per-joint spheres
// posed over the animations (bounding_sphere.h, animatedMeshSphere).
#include "scenelod/scene/bounding_sphere.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>

#include "scenelod/scene/scene.h"
#include "scenelod/scene/skin_pose.h"

namespace scenelod::scene {

float coveringRadius(Span<const glm::vec3> points, const glm::vec3& c) {
  double max_d2 = 0.0;
  for (const glm::vec3& p : points) {
    const double dx = double(p.x) - c.x, dy = double(p.y) - c.y, dz = double(p.z) - c.z;
    max_d2 = std::max(max_d2, dx * dx + dy * dy + dz * dz);
  }
  float r = std::nextafter(static_cast<float>(std::sqrt(max_d2)), INFINITY);
  // the float distance a caller computes may round above the double one: check in float too
  for (const glm::vec3& p : points) {
    const float d = glm::length(p - c);
    if (d > r) r = std::nextafter(d, INFINITY);
  }
  return points.empty() ? 0.0f : r;
}

Sphere ritterSphere(Span<const glm::vec3> points) {
  Sphere s;
  if (points.empty()) return s;
  auto farthest = [&](const glm::vec3& from) {
    size_t best = 0;
    float best_d2 = -1.0f;
    for (size_t i = 0; i < points.size(); ++i) {
      const glm::vec3 d = points[i] - from;
      const float d2 = glm::dot(d, d);
      if (d2 > best_d2) { best_d2 = d2; best = i; }
    }
    return points[best];
  };
  const glm::vec3 y = farthest(points[0]);
  const glm::vec3 z = farthest(y);
  glm::dvec3 c = (glm::dvec3(y) + glm::dvec3(z)) * 0.5;
  double r = glm::length(glm::dvec3(z) - glm::dvec3(y)) * 0.5;
  for (const glm::vec3& p : points) {
    const glm::dvec3 d = glm::dvec3(p) - c;
    const double dist = glm::length(d);
    if (dist > r) {
      // grow to the sphere touching the old one's far side and p
      const double new_r = (r + dist) * 0.5;
      c += d * ((new_r - r) / dist);
      r = new_r;
    }
  }
  s.center = glm::vec3(c);
  s.radius = coveringRadius(points, s.center);
  return s;
}

namespace {

struct Ball {
  glm::dvec3 c{0.0};
  double r2 = -1.0;  // negative: the empty ball
};

// the smallest ball with all `k` points on its boundary (centre in their affine hull); false when
// the points are affinely dependent (numerically)
bool circumBall(const glm::dvec3* q, int k, Ball& out) {
  if (k == 0) { out = Ball{}; return true; }
  if (k == 1) { out.c = q[0]; out.r2 = 0.0; return true; }
  const int m = k - 1;
  glm::dvec3 v[3];
  double a[3][4];
  double scale = 0.0;
  for (int i = 0; i < m; ++i) { v[i] = q[i + 1] - q[0]; scale = std::max(scale, glm::dot(v[i], v[i])); }
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j) a[i][j] = 2.0 * glm::dot(v[i], v[j]);
    a[i][m] = glm::dot(v[i], v[i]);
  }
  // gaussian elimination with partial pivoting on the m x m system
  for (int col = 0; col < m; ++col) {
    int piv = col;
    for (int r = col + 1; r < m; ++r)
      if (std::fabs(a[r][col]) > std::fabs(a[piv][col])) piv = r;
    if (!(std::fabs(a[piv][col]) > 1e-12 * scale)) return false;
    if (piv != col)
      for (int j = 0; j <= m; ++j) std::swap(a[piv][j], a[col][j]);
    for (int r = 0; r < m; ++r) {
      if (r == col) continue;
      const double f = a[r][col] / a[col][col];
      for (int j = col; j <= m; ++j) a[r][j] -= f * a[col][j];
    }
  }
  glm::dvec3 c = q[0];
  for (int i = 0; i < m; ++i) c += v[i] * (a[i][m] / a[i][i]);
  out.c = c;
  const glm::dvec3 d = q[0] - c;
  out.r2 = glm::dot(d, d);
  return true;
}

class MoveToFront {
 public:
  explicit MoveToFront(std::vector<glm::dvec3> pts) : pts_(std::move(pts)) {
    const size_t n = pts_.size();
    next_.resize(n + 1);
    prev_.resize(n + 1);
    // a circular doubly linked list with a sentinel at index n
    for (size_t i = 0; i <= n; ++i) {
      next_[i] = static_cast<uint32_t>((i + 1) % (n + 1));
      prev_[i] = static_cast<uint32_t>((i + n) % (n + 1));
    }
  }

  Ball run() {
    // pivoting (Gärtner §2): repeatedly restart with the farthest violator in the support set,
    // which keeps the recursion shallow on large inputs
    mtf(sentinel());
    for (int round = 0; round < 64; ++round) {
      uint32_t worst = sentinel();
      double worst_excess = 0.0;
      for (uint32_t i = next_[sentinel()]; i != sentinel(); i = next_[i]) {
        const double e = excess(pts_[i]);
        if (e > worst_excess) { worst_excess = e; worst = i; }
      }
      if (worst == sentinel()) break;
      support_count_ = 0;
      push(pts_[worst]);
      mtf(worst);
      support_count_ = 0;
      moveToFront(worst);
    }
    return ball_;
  }

 private:
  uint32_t sentinel() const { return static_cast<uint32_t>(pts_.size()); }

  double excess(const glm::dvec3& p) const {
    if (ball_.r2 < 0.0) return 1.0;
    const glm::dvec3 d = p - ball_.c;
    const double e = glm::dot(d, d) - ball_.r2;
    return e > 1e-12 * std::max(ball_.r2, 1e-300) ? e : 0.0;
  }

  bool push(const glm::dvec3& p) {
    support_[support_count_] = p;
    Ball b;
    if (!circumBall(support_, support_count_ + 1, b)) return false;
    ball_ = b;
    ++support_count_;
    return true;
  }

  void moveToFront(uint32_t i) {
    next_[prev_[i]] = next_[i];
    prev_[next_[i]] = prev_[i];
    const uint32_t first = next_[sentinel()];
    next_[i] = first;
    prev_[i] = sentinel();
    prev_[first] = i;
    next_[sentinel()] = i;
  }

  // the smallest ball containing the list before `end` with the current support set on its boundary
  void mtf(uint32_t end) {
    Ball b;
    circumBall(support_, support_count_, b);
    ball_ = b;
    if (support_count_ == 4) return;
    for (uint32_t i = next_[sentinel()]; i != end;) {
      const uint32_t nxt = next_[i];
      if (excess(pts_[i]) > 0.0) {
        if (push(pts_[i])) {
          mtf(i);
          --support_count_;
          moveToFront(i);
        }
      }
      i = nxt;
    }
  }

  std::vector<glm::dvec3> pts_;
  std::vector<uint32_t> next_, prev_;
  glm::dvec3 support_[4];
  int support_count_ = 0;
  Ball ball_;
};

}  // namespace

Sphere minimalSphere(Span<const glm::vec3> points) {
  Sphere s;
  if (points.empty()) return s;
  std::vector<glm::dvec3> pts(points.size());
  for (size_t i = 0; i < points.size(); ++i) pts[i] = glm::dvec3(points[i]);
  // deterministic shuffle (xorshift) so sorted or scanline inputs keep the expected linear time
  uint64_t state = 0x9E3779B97F4A7C15ull;
  for (size_t i = pts.size(); i > 1; --i) {
    state ^= state << 13; state ^= state >> 7; state ^= state << 17;
    std::swap(pts[i - 1], pts[state % i]);
  }
  MoveToFront mtf(std::move(pts));
  const Ball b = mtf.run();
  s.center = glm::vec3(b.c);
  s.radius = coveringRadius(points, s.center);
  return s;
}

Sphere mergeSpheres(const Sphere& a, const Sphere& b) {
  const glm::dvec3 ca(a.center), cb(b.center);
  const double d = glm::length(cb - ca);
  if (d + b.radius <= a.radius) return a;
  if (d + a.radius <= b.radius) return b;
  const double r = (d + a.radius + b.radius) * 0.5;
  const glm::dvec3 c = ca + (cb - ca) * ((r - a.radius) / d);
  Sphere s;
  s.center = glm::vec3(c);
  // round up so both input spheres stay inside after the float conversion of the centre
  const double ra = glm::length(ca - glm::dvec3(s.center)) + a.radius;
  const double rb = glm::length(cb - glm::dvec3(s.center)) + b.radius;
  s.radius = std::nextafter(static_cast<float>(std::max(ra, rb)), INFINITY);
  return s;
}

Sphere computeChainBounds(LodChain& chain) {
  std::vector<glm::vec3> all;
  size_t total = 0;
  for (const LodLevel& l : chain.levels) total += l.mesh.positions.size();
  all.reserve(total);
  for (LodLevel& l : chain.levels) {
    l.bounds = minimalSphere(Span<const glm::vec3>(l.mesh.positions.data(), l.mesh.positions.size()));
    all.insert(all.end(), l.mesh.positions.begin(), l.mesh.positions.end());
  }
  return minimalSphere(Span<const glm::vec3>(all.data(), all.size()));
}

Sphere sphereOfSpheres(Span<const Sphere> spheres) {
  if (spheres.empty()) return Sphere{};
  std::vector<glm::vec3> extremes;
  extremes.reserve(6 * spheres.size());
  for (const Sphere& s : spheres)
    for (int axis = 0; axis < 3; ++axis) {
      glm::vec3 d(0.0f);
      d[axis] = s.radius;
      extremes.push_back(s.center + d);
      extremes.push_back(s.center - d);
    }
  Sphere out = minimalSphere(Span<const glm::vec3>(extremes.data(), extremes.size()));
  double r = 0.0;
  for (const Sphere& s : spheres)
    r = std::max(r, glm::length(glm::dvec3(s.center) - glm::dvec3(out.center)) + double(s.radius));
  out.radius = std::nextafter(static_cast<float>(r), INFINITY);
  return out;
}

std::vector<uint8_t> meshesDrawnWithSkin(const SceneData& scene) {
  std::vector<uint8_t> out(scene.meshes.size(), 0);
  for (const NodeData& node : scene.nodes)
    if (node.skin >= 0 && node.mesh >= 0 && static_cast<size_t>(node.mesh) < out.size()) out[node.mesh] = 1;
  return out;
}

namespace {

// per joint, the bind-space sphere of every level vertex the joint moves (radius < 0: none)
Error bindJointSpheres(Span<const Mesh* const> levels, size_t joint_count, const std::string& what,
                       std::vector<Sphere>& out) {
  std::vector<std::vector<glm::vec3>> points(joint_count);
  for (size_t l = 0; l < levels.size(); ++l) {
    const Mesh& m = *levels[l];
    if (!m.skinned()) continue;
    for (size_t v = 0; v < m.joints.size(); ++v)
      for (int c = 0; c < 4; ++c) {
        if (m.weights[v][c] == 0.0f) continue;
        if (m.joints[v][c] >= joint_count)
          return {Status::kInvalidMesh, what + " level " + std::to_string(l) + ": vertex " + std::to_string(v) +
                                            " uses joint " + std::to_string(m.joints[v][c]) + " but the skin has " +
                                            std::to_string(joint_count) + " joints"};
        points[m.joints[v][c]].push_back(m.positions[v]);
      }
  }
  out.assign(joint_count, Sphere{glm::vec3(0.0f), -1.0f});
  for (size_t j = 0; j < joint_count; ++j)
    if (!points[j].empty()) out[j] = minimalSphere(Span<const glm::vec3>(points[j].data(), points[j].size()));
  return {};
}

// every key time of an animation's samplers, each interval cut into `steps` equal parts
std::vector<float> sampleTimes(const AnimationData& a, uint32_t steps) {
  std::vector<float> keys;
  for (const AnimationData::Sampler& s : a.samplers) keys.insert(keys.end(), s.times.begin(), s.times.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<float> out;
  for (size_t k = 0; k < keys.size(); ++k) {
    out.push_back(keys[k]);
    if (k + 1 < keys.size())
      for (uint32_t i = 1; i < steps; ++i) out.push_back(keys[k] + (keys[k + 1] - keys[k]) * (float(i) / float(steps)));
  }
  return out;
}

// the joint spheres of skin `skin` posed at one time, in node `node`'s frame at that time
void posedJointSpheres(const SceneData& scene, int32_t node, int32_t animation, float t,
                       const std::vector<Sphere>& bind, std::vector<Sphere>& out) {
  std::vector<glm::mat4> locals, joints;
  animatedLocals(scene, animation, t, locals);
  const std::vector<glm::mat4> world = worldTransforms(scene, Span<const glm::mat4>(locals.data(), locals.size()));
  skinMatrices(scene, scene.nodes[node].skin, Span<const glm::mat4>(world.data(), world.size()), joints);
  // a node scaled to nothing has no frame; its world sphere is a point whatever this one is
  const glm::mat4 frame = nodeFrame(scene, Span<const glm::mat4>(locals.data(), locals.size()), node);
  glm::mat4 to_node = glm::inverse(frame);
  if (!(std::fabs(glm::determinant(frame)) > 1e-30f)) to_node = glm::mat4(1.0f);
  out.resize(bind.size());
  for (size_t j = 0; j < bind.size(); ++j)
    out[j] = bind[j].radius < 0.0f ? bind[j] : transformSphere(bind[j], to_node * joints[j]);
}

}  // namespace

Error animatedMeshSphere(const SceneData& scene, int32_t mesh, Span<const Mesh* const> levels, Sphere& out,
                         const std::string& what, uint32_t steps_per_key) {
  std::vector<Sphere> all, bind, prev, cur;
  // levels without a skin, and every level on a node without one, are drawn as stored
  bool unskinned_node = false;
  for (const NodeData& node : scene.nodes) unskinned_node = unskinned_node || (node.mesh == mesh && node.skin < 0);
  std::vector<glm::vec3> unposed;
  for (const Mesh* m : levels)
    if (!m->skinned() || unskinned_node) unposed.insert(unposed.end(), m->positions.begin(), m->positions.end());
  if (!unposed.empty()) all.push_back(minimalSphere(Span<const glm::vec3>(unposed.data(), unposed.size())));
  for (size_t n = 0; n < scene.nodes.size(); ++n) {
    const NodeData& node = scene.nodes[n];
    if (node.mesh != mesh || node.skin < 0) continue;
    if (Error e = bindJointSpheres(levels, scene.skins[node.skin].joints.size(), what, bind); !e.ok()) return e;
    const int32_t ni = static_cast<int32_t>(n);
    posedJointSpheres(scene, ni, kRestPose, 0.0f, bind, cur);
    all.insert(all.end(), cur.begin(), cur.end());
    for (size_t a = 0; a < scene.animations.size(); ++a) {
      const std::vector<float> times = sampleTimes(scene.animations[a], std::max(steps_per_key, 1u));
      for (size_t i = 0; i < times.size(); ++i) {
        posedJointSpheres(scene, ni, static_cast<int32_t>(a), times[i], bind, cur);
        for (size_t j = 0; j < cur.size(); ++j) {
          if (cur[j].radius < 0.0f) continue;
          if (i == 0) { all.push_back(cur[j]); continue; }
          // the step from the previous sample: the chord's diametral ball, grown by the radius
          const float chord = glm::length(cur[j].center - prev[j].center);
          all.push_back(Sphere{(cur[j].center + prev[j].center) * 0.5f,
                               chord * 0.5f + std::max(cur[j].radius, prev[j].radius)});
        }
        std::swap(prev, cur);
      }
    }
  }
  all.erase(std::remove_if(all.begin(), all.end(), [](const Sphere& s) { return s.radius < 0.0f; }), all.end());
  out = sphereOfSpheres(Span<const Sphere>(all.data(), all.size()));
  return {};
}

}  // namespace scenelod::scene
