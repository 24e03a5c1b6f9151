// Vision-characteristic edge collapse and its triangle-decimation extension, §3 of Zhang, Shu & Luo
// 2003, "Mesh Simplification Based on Shading Characteristic" (WSCG 2003 short papers).
//
// Data layout: flat arrays only. Triangles keep their three vertex ids; each vertex heads a singly
// linked list of the triangle corners that reference it (merged in O(degree) on a collapse, dead
// corners unlinked lazily while walking). Vertices (edge collapse) or triangles (extension) sit in an
// indexed binary min-heap with decrease/increase-key. Every per-collapse buffer is a member reused
// across collapses, so the common case allocates nothing.
//
// Checks (docs/ZHANG.md): a contraction is refused when the fan around the merged vertex would not
// be one disk or one half-disk (link condition, which also keeps a closed mesh closed and refuses
// fins and tetrahedron collapses), when a remaining triangle would turn by more than
// max_normal_turn_deg or lose (almost) all its area (fold-over), or when it would move a kept vertex.
#include <algorithm>
#include <cmath>
#include <utility>

#include <glm/geometric.hpp>

#include "scenelod/lodcore/mesh_attributes.h"
#include "scenelod/lodcore/zhang.h"
#include "zhang_internal.h"

namespace scenelod {
namespace {

using zhang_detail::kNone;
using zhang_detail::StarPair;
using zhang_detail::StarScratch;

// indexed 4-ary min-heap over ids 0..n-1, ordered by (key, id): a strict total order, so the popped id
// does not depend on the heap's shape and runs are deterministic. The keys sit in the heap array beside
// the ids, and the four children of a node are 32 contiguous bytes, so a sift down reads one or two
// lines per level over half the levels of a binary heap
class IndexedHeap {
 public:
  void reset(size_t n) {
    heap_.clear();
    heap_.reserve(n);
    pos_.assign(n, kNone);
  }
  bool contains(uint32_t id) const { return pos_[id] != kNone; }
  bool empty() const { return heap_.empty(); }
  uint32_t top() const { return heap_[0].id; }
  void set(uint32_t id, float key) {  // insert or update
    const uint32_t p = pos_[id];
    if (p == kNone) {
      pos_[id] = static_cast<uint32_t>(heap_.size());
      heap_.push_back({key, id});
      up(pos_[id]);
      return;
    }
    const float old = heap_[p].key;
    if (key == old) return;  // a sift would not move it
    heap_[p].key = key;
    if (key < old) up(p); else down(p);
  }
  void remove(uint32_t id) {
    const uint32_t p = pos_[id];
    if (p == kNone) return;
    const Entry last = heap_.back();
    heap_.pop_back();
    pos_[id] = kNone;
    if (p < heap_.size()) {
      heap_[p] = last;
      pos_[last.id] = p;
      up(p);
      down(pos_[last.id]);
    }
  }
  uint32_t pop() {
    const uint32_t id = heap_[0].id;
    remove(id);
    return id;
  }

 private:
  struct Entry {
    float key;
    uint32_t id;
  };
  static bool less(const Entry& a, const Entry& b) { return a.key < b.key || (a.key == b.key && a.id < b.id); }
  void up(uint32_t p) {
    const Entry e = heap_[p];
    while (p > 0) {
      const uint32_t parent = (p - 1) / 4;
      if (!less(e, heap_[parent])) break;
      heap_[p] = heap_[parent];
      pos_[heap_[p].id] = p;
      p = parent;
    }
    heap_[p] = e;
    pos_[e.id] = p;
  }
  void down(uint32_t p) {
    const Entry e = heap_[p];
    const uint32_t n = static_cast<uint32_t>(heap_.size());
    for (;;) {
      const uint32_t first = 4 * p + 1;
      if (first >= n) break;
      uint32_t c = first;
      const uint32_t last = std::min(first + 4, n);
      for (uint32_t o = first + 1; o < last; ++o)
        if (less(heap_[o], heap_[c])) c = o;
      if (!less(heap_[c], e)) break;
      heap_[p] = heap_[c];
      pos_[heap_[p].id] = p;
      p = c;
    }
    heap_[p] = e;
    pos_[e.id] = p;
  }
  std::vector<Entry> heap_;
  std::vector<uint32_t> pos_;
};

// acos to within 7e-5 rad (Abramowitz & Stegun 4.4.45); CA only ranks collapses, and libm's acosf
// was a tenth of the run time
inline float fastAcos(float x) {
  const float ax = std::min(std::fabs(x), 1.0f);
  const float r = std::sqrt(1.0f - ax) * (1.5707288f + ax * (-0.2121144f + ax * (0.0742610f - 0.0187293f * ax)));
  return x >= 0.0f ? r : 3.14159265f - r;
}

// angle between unit vectors, 0 when either is zero (a degenerate triangle's normal)
inline float fastAngle(const glm::vec3& a, const glm::vec3& b) {
  if (glm::dot(a, a) == 0.0f || glm::dot(b, b) == 0.0f) return 0.0f;
  return fastAcos(glm::dot(a, b));
}

// squared distance from p to the triangle abc (closest point by Voronoi regions, Ericson 2005 §5.1.5)
float pointTriangleDistance2(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  auto dist2 = [&](const glm::vec3& q) { return glm::dot(p - q, p - q); };
  if (d1 <= 0.0f && d2 <= 0.0f) return dist2(a);
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return dist2(b);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return dist2(a + ab * (d1 / (d1 - d3)));
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return dist2(c);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return dist2(a + ac * (d2 / (d2 - d6)));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f)
    return dist2(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) return std::min({dist2(a), dist2(b), dist2(c)});  // degenerate triangle
  return dist2(a + ab * (vb / sum) + ac * (vc / sum));
}

glm::vec3 safeNormalize(const glm::vec3& v) {
  const float len = glm::length(v);
  return len > 0.0f ? v / len : glm::vec3(0.0f);
}

// relative area below which a triangle counts as degenerate: |cross| <= eps * sum of squared edges
constexpr float kDegenerateRatio = 1e-6f;

class ZhangEngine {
 public:
  Error init(const Mesh& in, const ZhangParams& params);
  // runs until at most `target` triangles remain or nothing can be collapsed
  void run(size_t target);
  void extract(Mesh& out, ZhangStats& stats);
  // the output mesh's vertices (one per used corner key, in key order) and primitives; `present`
  // marks the welded vertices that are in it
  void emitMesh(Mesh& out, std::vector<uint8_t>& present);
  size_t aliveTriangles() const { return alive_tris_; }
  size_t initialTriangles() const { return initial_tris_; }
  bool stopped() const { return stopped_; }
  void setProgress(const ProgressCallback* p, size_t final_target) {
    progress_ = p;
    final_target_ = final_target;
  }

 private:
  template <class F>
  void forStar(uint32_t v, F&& f);  // f(triangle, corner 0..2) for each live triangle of v
  uint32_t find(uint32_t v);
  void updateTriangle(uint32_t t);
  float visionOf(uint32_t v);
  float superHeightOf(uint32_t v);
  void updateKey(uint32_t v);
  // after a collapse into k: CA of k and of its ring (the fan of k is in fan_, its faces marked)
  void refreshAround(uint32_t k);

  // contraction of the set S (2 or 3 vertices) into survivor k at (p, n): checks, new CA(k)
  // a triangle that survives a contraction: its id and the two vertices after the merged one
  struct StarEntry {
    uint32_t t, u, w;
  };
  void gatherStar(uint32_t v, std::vector<StarEntry>& out);
  // checks the contraction whose surviving triangles are `entries` (the merged vertex moved to p with
  // carried normal n) and gives the new CA of the merged vertex; candidates whose CA reaches `bound`
  // stop early (they cannot win) and return false
  bool evaluate(const StarEntry* entries, size_t count, bool any_removed, const glm::vec3& p, const glm::vec3& n,
                float bound, float& new_ca);
  // the fold-over part of evaluate, raising new_ca (which the caller initialises); `ring`: the
  // triangles changed shape, so their ring vertices' CA counts too (ZhangParams::ring_vision)
  bool checkGeometry(const StarEntry* entries, size_t count, const glm::vec3& p, const glm::vec3& n, float bound, bool ring,
                     float& new_ca);
  // the link-condition part of evaluate
  bool checkTopology(const StarEntry* entries, size_t count, bool any_removed);
  static constexpr size_t kLocalStar = 32;
  bool checkTopologyLocal(const StarEntry* entries, size_t count);
  void apply(const uint32_t* s, int s_count, uint32_t k, const glm::vec3& p, const glm::vec3& n);
  // position and normal of the merged vertex and the weight of each merged vertex in it
  void interpolate(const uint32_t* s, int s_count, uint32_t& k, glm::vec3& p, glm::vec3& n, float* weights, bool& ok);

  // attribute seams (meshes with uvs, tangents, skin or several groups; docs/ZHANG.md "Seams")
  void initWedges(const Mesh& in, std::vector<uint32_t>& corner_wedge);
  void weldByPosition(const Mesh& in);
  struct SeamInfo {
    uint32_t edges = 0;                    // seam edges around the vertex (a border edge counts)
    uint32_t neighbour[2] = {kNone, kNone};  // the far ends of the first two
  };
  SeamInfo seamsAround(uint32_t v);
  // a movable vertex with seam edges; cached until a collapse changes its fan
  bool onSeam(uint32_t v) {
    if (vs_[v].kept) return false;
    if (seam_state_[v] < 0) seam_state_[v] = seamsAround(v).edges > 0 ? 1 : 0;
    return seam_state_[v] == 1;
  }
  // the wedge each wedge of the merged vertices s[] != k takes, into map_; false when a surviving
  // triangle's wedge has none or two (the collapse would carry a triangle into another chart)
  bool mapWedges(const uint32_t* s, int s_count, uint32_t k);
  // the seam vertices along which the popped vertex i may collapse (all neighbours when it is on no seam)
  void seamCandidates(uint32_t i);
  // the one wedge pair of a collapse of the popped vertex i, on no seam, onto its neighbour j
  void onePair(uint32_t i, uint32_t j);
  void blendWedges(const uint32_t* s, int s_count, uint32_t k);
  void pinToSeam(const uint32_t* s, uint32_t& k, glm::vec3& p, glm::vec3& n, bool& ok);
  uint32_t wedgeFind(uint32_t w);
  // output vertex of a triangle corner / of an input vertex, and the welded vertex giving its position
  uint32_t cornerKey(uint32_t t, int c) const { return attr_ ? faces_[t].a[c] : faces_[t].v[c]; }
  uint32_t inputKey(uint32_t v) { return attr_ ? wedgeFind(input_wedge_[v]) : find(v); }
  uint32_t keyVertex(uint32_t key) { return attr_ ? find(wedge_topo_[key]) : key; }

  bool stepEdge();
  bool stepTriangle();
  float triangleVision(uint32_t t);
  void refreshTrianglesAround(uint32_t k);

  const Mesh* in_ = nullptr;
  ZhangParams params_;
  float cos_max_turn_ = 0.5f;
  // per vertex, hot: position (12 B), carried geometric normal (12 B), corner list head (4 B)
  std::vector<glm::vec3> pos_, nrm_;
  std::vector<uint32_t> vhead_;
  // per vertex, the state read together on every collapse around it, one 16 B record (one line miss
  // instead of one per array)
  struct VertexState {
    float ca = 0.0f;         // CA(V), definition 9
    uint32_t ca_arg = kNone;  // the triangle giving CA (its max), kNone when CA is 0; while it is alive
                              // and unchanged, a collapse next to the vertex only raises CA through
                              // the changed triangles
    uint32_t mark = 0;       // generation mark of the per-collapse vertex sets
    uint8_t kept = 0;        // edge, complex (or angle on request): never moves
    uint8_t alive = 0;       // in at least one live triangle and not merged away
  };
  std::vector<VertexState> vs_;
  // per vertex, cold: attributes blended on collapse with the area weight, union-find parent. With
  // attributes (attr_) the attribute arrays are per wedge: one per (attribute-distinct vertex,
  // triangle group) pair, several at one welded position along a seam
  std::vector<glm::vec3> attr_nrm_, col_;
  std::vector<glm::vec2> uv_;
  std::vector<float> weight_;
  std::vector<uint32_t> parent_;
  bool attr_ = false;
  std::vector<std::vector<glm::vec2>> extra_uv_;
  std::vector<glm::vec4> tan_;
  std::vector<uint32_t> wedge_parent_, wedge_topo_, wedge_src_, input_wedge_, face_group_;
  std::vector<int8_t> seam_state_;  // per vertex: -1 unknown, 0 on no seam, 1 on a seam
  struct WedgePair {
    uint32_t from, to;
    int s;  // index of the merged vertex in s[]
  };
  std::vector<WedgePair> map_, best_map_;
  float blend_w_[3] = {0.0f, 0.0f, 0.0f}, best_w_[3] = {0.0f, 0.0f, 0.0f};
  struct FanCorner {
    uint32_t u, w, ai, au, aw;
  };
  std::vector<FanCorner> fan_corners_;
  // per triangle, one record aligned to a cache line so that walking a fan touches exactly one line per
  // triangle (60 B used of 64; unaligned records straddled two lines on most steps):
  // vertex ids (12 B), next corner of each vertex's corner list (12 B), unit normal (12 B), area (4 B),
  // alive flag (4 B), mark (4 B), corner wedges (12 B); corner c is vertex c % 3 of triangle c / 3
  struct alignas(64) Face {
    uint32_t v[3] = {kNone, kNone, kNone};
    uint32_t next[3] = {kNone, kNone, kNone};
    glm::vec3 n{0.0f};
    float area = 0.0f;
    uint32_t alive = 1;
    uint32_t mark = 0;  // generation of the last collapse whose fan held this triangle
    uint32_t a[3] = {kNone, kNone, kNone};  // wedge of each corner (with attributes only)
  };
  std::vector<Face> faces_;
  uint32_t& cornerNext(uint32_t c) { return faces_[c / 3].next[c % 3]; }
  size_t alive_tris_ = 0, initial_tris_ = 0;
  IndexedHeap heap_;
  bool stopped_ = false;
  ZhangStats stats_;
  const ProgressCallback* progress_ = nullptr;
  size_t final_target_ = 0, current_target_ = 0;
  // scratch reused by every evaluation
  StarScratch star_;
  std::vector<StarPair> pairs_;
  std::vector<uint32_t> tris_, neighbours_, removed_;
  std::vector<StarEntry> star_i_, star_j_, union_, fan_;
  uint32_t mark_gen_ = 0;
};

template <class F>
void ZhangEngine::forStar(uint32_t v, F&& f) {
  uint32_t prev = kNone;
  for (uint32_t c = vhead_[v]; c != kNone;) {
    const uint32_t t = c / 3, next = cornerNext(c);
    if (!faces_[t].alive) {  // unlink the dead corner
      if (prev == kNone) vhead_[v] = next; else cornerNext(prev) = next;
      c = next;
      continue;
    }
    f(t, c % 3);
    prev = c;
    c = next;
  }
}

// union-find root with path compression
uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t v) {
  uint32_t r = v;
  while (parent[r] != r) r = parent[r];
  while (parent[v] != r) {
    const uint32_t n = parent[v];
    parent[v] = r;
    v = n;
  }
  return r;
}

uint32_t ZhangEngine::find(uint32_t v) { return findRoot(parent_, v); }

void ZhangEngine::updateTriangle(uint32_t t) {
  const glm::vec3 &a = pos_[faces_[t].v[0]], &b = pos_[faces_[t].v[1]], &c = pos_[faces_[t].v[2]];
  const glm::vec3 x = glm::cross(b - a, c - a);
  const float len = glm::length(x);
  faces_[t].n = len > 0.0f ? x / len : glm::vec3(0.0f);
  faces_[t].area = 0.5f * len;
}

float ZhangEngine::visionOf(uint32_t v) {
  float ca = 0.0f;
  uint32_t arg = kNone;
  const glm::vec3 nv = nrm_[v];
  forStar(v, [&](uint32_t t, uint32_t) {
    const float c = fastAngle(nv, faces_[t].n) * faces_[t].area;
    if (c > ca) ca = c, arg = t;
  });
  vs_[v].ca_arg = arg;
  return ca;
}

float ZhangEngine::superHeightOf(uint32_t v) {
  pairs_.clear();
  forStar(v, [&](uint32_t t, uint32_t k) { pairs_.push_back({faces_[t].v[(k + 1) % 3], faces_[t].v[(k + 2) % 3]}); });
  return zhang_detail::superHeightOfStar(pos_[v], pairs_.data(), pairs_.size(), pos_.data(), star_);
}

void ZhangEngine::updateKey(uint32_t v) {
  if (params_.mode != ZhangMode::kEdgeCollapse || vs_[v].kept || !vs_[v].alive) return;
  const float key = params_.influence == ZhangInfluence::kSuperHeight ? superHeightOf(v) : vs_[v].ca;
  heap_.set(v, key);
}

void ZhangEngine::refreshAround(uint32_t k) {
  float ca_k = 0.0f;
  uint32_t arg_k = kNone;
  for (const StarEntry& e : fan_) {
    const float c = fastAngle(nrm_[k], faces_[e.t].n) * faces_[e.t].area;
    if (c > ca_k) ca_k = c, arg_k = e.t;
  }
  vs_[k].ca = ca_k;
  vs_[k].ca_arg = arg_k;
  updateKey(k);
  // a ring vertex whose max triangle died or changed is walked again (unmarked); the others keep
  // their max and only meet the changed triangles (marked), all of which are in k's fan
  for (uint32_t u : neighbours_) {
    const uint32_t arg = vs_[u].ca_arg;
    if (arg != kNone && (!faces_[arg].alive || faces_[arg].mark == mark_gen_)) {
      vs_[u].ca = visionOf(u);
      vs_[u].mark = 0;
    }
  }
  for (const StarEntry& e : fan_) {
    if (faces_[e.t].mark != mark_gen_) continue;  // unchanged: already within the ring's CA
    for (uint32_t u : {e.u, e.w}) {
      if (vs_[u].mark != mark_gen_) continue;
      const float c = fastAngle(nrm_[u], faces_[e.t].n) * faces_[e.t].area;
      if (c > vs_[u].ca) vs_[u].ca = c, vs_[u].ca_arg = e.t;
    }
  }
  for (uint32_t u : neighbours_) updateKey(u);
}

Error ZhangEngine::init(const Mesh& in, const ZhangParams& params) {
  in_ = &in;
  params_ = params;
  if (!(params.max_normal_turn_deg > 0.0f) || !(params.max_normal_turn_deg <= 180.0f))
    return {Status::kInvalidArgument, "zhang: max_normal_turn_deg must be in (0, 180]"};
  if (!(params.feature_angle_deg >= 0.0f) || !(params.angle_height_ratio >= 0.0f))
    return {Status::kInvalidArgument, "zhang: feature_angle_deg and angle_height_ratio must be >= 0"};
  if (!(params.max_seam_bend_deg >= 0.0f) || !(params.max_seam_bend_deg <= 180.0f))
    return {Status::kInvalidArgument, "zhang: max_seam_bend_deg must be in [0, 180]"};
  cos_max_turn_ = std::cos(params.max_normal_turn_deg * 3.14159265f / 180.0f);
  const size_t vn = in.vertexCount(), tn = in.triangleCount();
  if (vn >= kNone || 3 * tn >= kNone) return {Status::kUnsupported, "zhang: mesh too large for 32-bit indices"};
  stats_ = ZhangStats{};
  pos_ = in.positions;
  nrm_.assign(vn, glm::vec3(0.0f));
  vs_.assign(vn, VertexState{});
  vhead_.assign(vn, kNone);
  attr_nrm_ = in.normals;
  col_ = in.colors;
  uv_ = in.uvs;
  weight_.assign(vn, 0.0f);
  parent_.resize(vn);
  for (size_t v = 0; v < vn; ++v) parent_[v] = static_cast<uint32_t>(v);
  faces_.clear();
  faces_.reserve(tn);
  star_.resize(vn);
  mark_gen_ = 0;

  // texture coordinates, tangents, skins and groups keep their seams on a mesh welded by position;
  // without them, welding is the caller's choice
  attr_ = !in.uvs.empty() || !in.extra_uvs.empty() || !in.tangents.empty() || !in.joints.empty();
  for (size_t t = 1; t < in.triangle_groups.size() && !attr_; ++t) attr_ = in.triangle_groups[t] != in.triangle_groups[0];
  if ((attr_ || params_.weld_positions) && vn > 1) weldByPosition(in);
  // split normals of hard edges do not survive a plain weld; geometric normals are output
  if (params_.weld_positions && !attr_) attr_nrm_.clear();
  std::vector<uint32_t> corner_wedge;
  if (attr_) initWedges(in, corner_wedge);
  seam_state_.assign(attr_ ? vn : 0, -1);
  auto welded = [&](uint32_t v) { return parent_[v]; };
  face_group_.clear();

  // triangles: drop repeated indices and repeated vertex sets (the first occurrence stays)
  for (size_t t = 0; t < tn; ++t) {
    const uint32_t a = welded(in.triangles[3 * t]), b = welded(in.triangles[3 * t + 1]),
                   c = welded(in.triangles[3 * t + 2]);
    if (a == b || b == c || a == c) {
      ++stats_.dropped_degenerate;
      continue;
    }
    const uint32_t lo = std::min({a, b, c}), hi = std::max({a, b, c}), mid = a ^ b ^ c ^ lo ^ hi;
    bool duplicate = false;
    for (uint32_t corner = vhead_[lo]; corner != kNone && !duplicate; corner = cornerNext(corner)) {
      const uint32_t* o = faces_[corner / 3].v;
      const uint32_t olo = std::min({o[0], o[1], o[2]}), ohi = std::max({o[0], o[1], o[2]});
      duplicate = olo == lo && ohi == hi && (o[0] ^ o[1] ^ o[2] ^ olo ^ ohi) == mid;
    }
    if (duplicate) {
      ++stats_.dropped_duplicate;
      continue;
    }
    const uint32_t id = static_cast<uint32_t>(faces_.size());
    Face f;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = welded(in.triangles[3 * t + k]);
      f.v[k] = v;
      f.next[k] = vhead_[v];
      vhead_[v] = 3 * id + k;
      if (attr_) f.a[k] = corner_wedge[3 * t + k];
    }
    faces_.push_back(f);
    if (!in.triangle_groups.empty()) face_group_.push_back(in.triangle_groups[t]);
  }
  const size_t live = faces_.size();
  alive_tris_ = initial_tris_ = live;
  stats_.input_triangles = live;
  corner_wedge = {};
  for (uint32_t t = 0; t < live; ++t) {
    updateTriangle(t);
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = faces_[t].v[k];
      nrm_[v] += faces_[t].n * faces_[t].area;
      weight_[v] += faces_[t].area / 3.0f;
      vs_[v].alive = 1;
    }
  }
  for (glm::vec3& n : nrm_) n = safeNormalize(n);

  // classification (§2): complex and edge vertices are kept, angle vertices on request
  heap_.reset(params_.mode == ZhangMode::kEdgeCollapse ? vn : live);
  std::vector<StarPair> pairs;
  for (uint32_t v = 0; v < vn; ++v) {
    if (!vs_[v].alive) continue;
    pairs.clear();
    float max_angle = 0.0f, ca = 0.0f;
    uint32_t ca_arg = kNone;
    forStar(v, [&](uint32_t t, uint32_t k) {
      pairs.push_back({faces_[t].v[(k + 1) % 3], faces_[t].v[(k + 2) % 3]});
      const float angle = fastAngle(nrm_[v], faces_[t].n);
      max_angle = std::max(max_angle, angle);
      if (angle * faces_[t].area > ca) ca = angle * faces_[t].area, ca_arg = t;
    });
    vs_[v].ca_arg = ca_arg;
    zhang_detail::StarMeasure m;
    zhang_detail::measureStar(pos_[v], pairs.data(), pairs.size(), pos_.data(), max_angle, params_, star_, m,
                              params_.influence == ZhangInfluence::kSuperHeight);
    vs_[v].ca = ca;
    vs_[v].kept = m.vertex_class == ZhangVertexClass::kComplex || m.vertex_class == ZhangVertexClass::kEdge ||
               (params_.keep_angle_vertices && m.vertex_class == ZhangVertexClass::kAngle);
    stats_.kept_edge_vertices += m.vertex_class == ZhangVertexClass::kEdge;
    stats_.kept_complex_vertices += m.vertex_class == ZhangVertexClass::kComplex;
    stats_.kept_angle_vertices += params_.keep_angle_vertices && m.vertex_class == ZhangVertexClass::kAngle;
    if (attr_) stats_.seam_vertices += onSeam(v);
    if (params_.mode == ZhangMode::kEdgeCollapse && !vs_[v].kept)
      heap_.set(v, params_.influence == ZhangInfluence::kSuperHeight ? m.super_height : ca);
  }
  if (params_.mode == ZhangMode::kTriangleDecimation)
    for (uint32_t t = 0; t < live; ++t) heap_.set(t, triangleVision(t));
  stopped_ = false;
  return {};
}

// vertices at exactly the same position become one (the lowest id) for the topology
void ZhangEngine::weldByPosition(const Mesh& in) {
  const size_t vn = in.vertexCount();
  std::vector<uint32_t> order(vn);
  for (uint32_t v = 0; v < vn; ++v) order[v] = v;
  auto less = [&](uint32_t x, uint32_t y) {
    const glm::vec3 &a = in.positions[x], &b = in.positions[y];
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    if (a.z != b.z) return a.z < b.z;
    return x < y;
  };
  std::sort(order.begin(), order.end(), less);
  for (size_t i = 1; i < vn; ++i)
    if (in.positions[order[i]] == in.positions[order[i - 1]]) parent_[order[i]] = parent_[order[i - 1]];
}

// wedges: one per (vertex equal in position and every attribute, triangle group) pair used by a
// triangle, numbered in the order of the vertices' first occurrence; a vertex used only by edges or
// points takes the first wedge of its attribute class, or one of its own. `corner_wedge` gets the
// wedge of every input triangle corner.
void ZhangEngine::initWedges(const Mesh& in, std::vector<uint32_t>& corner_wedge) {
  Mesh attrs = in;  // welded for its vertex classes only
  std::vector<uint32_t> cls;
  weldVertices(attrs, &cls);
  const size_t vn = in.vertexCount(), tn = in.triangleCount();
  std::vector<uint32_t> first(attrs.vertexCount(), kNone);  // attribute class -> its lowest vertex
  for (uint32_t v = static_cast<uint32_t>(vn); v-- > 0;) first[cls[v]] = v;
  std::vector<uint64_t> keys;
  keys.reserve(3 * tn);
  for (size_t t = 0; t < tn; ++t)
    for (int k = 0; k < 3; ++k) keys.push_back(uint64_t(cls[in.triangles[3 * t + k]]) << 32 | in.triangleGroup(t));
  auto sortUnique = [](std::vector<uint64_t>& x) {
    std::sort(x.begin(), x.end());
    x.erase(std::unique(x.begin(), x.end()), x.end());
  };
  sortUnique(keys);
  auto firstOfClass = [&](uint32_t c) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), uint64_t(c) << 32);
    return it != keys.end() && uint32_t(*it >> 32) == c ? uint32_t(it - keys.begin()) : kNone;
  };
  std::vector<uint64_t> loose;
  for (const std::vector<uint32_t>* list : {&in.edges, &in.points})
    for (uint32_t v : *list)
      if (firstOfClass(cls[v]) == kNone) loose.push_back(uint64_t(cls[v]) << 32 | 0xffffffffu);
  if (!loose.empty()) {
    keys.insert(keys.end(), loose.begin(), loose.end());
    sortUnique(keys);
  }
  const size_t wn = keys.size();
  wedge_src_.resize(wn);
  wedge_topo_.resize(wn);
  wedge_parent_.resize(wn);
  for (size_t w = 0; w < wn; ++w) {
    wedge_src_[w] = first[keys[w] >> 32];
    wedge_topo_[w] = parent_[wedge_src_[w]];
    wedge_parent_[w] = static_cast<uint32_t>(w);
  }
  input_wedge_.resize(vn);
  for (size_t v = 0; v < vn; ++v) input_wedge_[v] = firstOfClass(cls[v]);
  corner_wedge.resize(3 * tn);
  for (size_t t = 0; t < tn; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint64_t key = uint64_t(cls[in.triangles[3 * t + k]]) << 32 | in.triangleGroup(t);
      corner_wedge[3 * t + k] = uint32_t(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin());
    }
  auto perWedge = [&](auto& dst, const auto& src) {
    dst.clear();
    if (src.empty()) return;
    dst.resize(wn);
    for (size_t w = 0; w < wn; ++w) dst[w] = src[wedge_src_[w]];
  };
  perWedge(attr_nrm_, in.normals);
  perWedge(col_, in.colors);
  perWedge(uv_, in.uvs);
  perWedge(tan_, in.tangents);
  extra_uv_.resize(in.extra_uvs.size());
  for (size_t set = 0; set < in.extra_uvs.size(); ++set) perWedge(extra_uv_[set], in.extra_uvs[set]);
}

uint32_t ZhangEngine::wedgeFind(uint32_t w) { return findRoot(wedge_parent_, w); }

// the seam edges around v: edges whose two triangles disagree on the wedge of either end (a UV or
// attribute seam, a group border), and border edges
ZhangEngine::SeamInfo ZhangEngine::seamsAround(uint32_t v) {
  fan_corners_.clear();
  forStar(v, [&](uint32_t t, uint32_t c) {
    const Face& f = faces_[t];
    fan_corners_.push_back({f.v[(c + 1) % 3], f.v[(c + 2) % 3], f.a[c], f.a[(c + 1) % 3], f.a[(c + 2) % 3]});
  });
  SeamInfo info;
  for (const FanCorner& e : fan_corners_) {
    // the triangle across the edge (v, e.w) starts its pair at e.w (a linear scan: fans are small,
    // and the callers' fan walks are quadratic in the degree anyway)
    const auto it = std::find_if(fan_corners_.begin(), fan_corners_.end(), [&](const FanCorner& x) { return x.u == e.w; });
    const bool border = it == fan_corners_.end();
    if (!border && it->ai == e.ai && it->au == e.aw) continue;
    if (info.edges < 2) info.neighbour[info.edges] = e.w;
    ++info.edges;
  }
  return info;
}

bool ZhangEngine::mapWedges(const uint32_t* s, int s_count, uint32_t k) {
  map_.clear();
  auto mapped = [&](uint32_t from) {
    for (const WedgePair& m : map_)
      if (m.from == from) return &m;
    return static_cast<const WedgePair*>(nullptr);
  };
  bool ok = true;
  for (int si = 0; si < s_count && ok; ++si) {
    if (s[si] == k) continue;
    // pairs from the triangles that die with k in them first, then every surviving corner needs one
    for (int pass = 0; pass < 2 && ok; ++pass)
      forStar(s[si], [&](uint32_t t, uint32_t c) {
        const Face& f = faces_[t];
        int ck = -1, others = 0;
        for (int x = 0; x < 3; ++x) {
          if (f.v[x] == k) ck = x;
          for (int i = 0; i < s_count; ++i) others += f.v[x] == s[i] && s[i] != s[si];
        }
        const WedgePair* m = mapped(f.a[c]);
        if (pass == 0 && ck >= 0) {
          if (!m) map_.push_back({f.a[c], f.a[ck], si});
          else if (m->to != f.a[ck]) ok = false;
        } else if (pass == 1 && others == 0 && !m) {
          ok = false;
        }
      });
  }
  return ok;
}

void ZhangEngine::onePair(uint32_t i, uint32_t j) {
  for (const StarEntry& e : star_i_) {
    if (e.u != j && e.w != j) continue;
    const Face& f = faces_[e.t];
    WedgePair pair{kNone, kNone, 0};
    for (int c = 0; c < 3; ++c) {
      if (f.v[c] == i) pair.from = f.a[c];
      if (f.v[c] == j) pair.to = f.a[c];
    }
    map_.assign(1, pair);
    return;
  }
}

void ZhangEngine::seamCandidates(uint32_t i) {
  const SeamInfo seams = seamsAround(i);
  if (seams.edges == 0) return;  // every neighbour stays a candidate
  tris_.clear();
  if (seams.edges != 2) return;  // a seam end or a junction of seams stays
  const float cos_bend = std::cos(params_.max_seam_bend_deg * 3.14159265f / 180.0f);
  for (int x = 0; x < 2; ++x) {
    const uint32_t j = seams.neighbour[x], other = seams.neighbour[1 - x];
    const glm::vec3 in_dir = safeNormalize(pos_[i] - pos_[other]), out_dir = safeNormalize(pos_[j] - pos_[i]);
    if (glm::dot(in_dir, out_dir) >= cos_bend) tris_.push_back(j);
  }
}

// the merged vertices' wedges join their targets: attributes interpolated with the position's
// weights (kept exactly when the position is the survivor's)
void ZhangEngine::blendWedges(const uint32_t* s, int s_count, uint32_t k) {
  int ks = 0;
  for (int i = 0; i < s_count; ++i)
    if (s[i] == k) ks = i;
  const bool keep = blend_w_[ks] == 1.0f;
  for (size_t m = 0; m < map_.size(); ++m) {
    const uint32_t to = map_[m].to;
    bool first_of_target = true;
    for (size_t e = 0; e < m; ++e) first_of_target = first_of_target && map_[e].to != to;
    if (keep || !first_of_target) continue;
    auto blend = [&](auto& a) {
      if (a.empty()) return;
      auto acc = blend_w_[ks] * a[to];
      for (const WedgePair& x : map_)
        if (x.to == to) acc += blend_w_[x.s] * a[x.from];
      a[to] = acc;
    };
    const float sign = tan_.empty() ? 1.0f : tan_[to].w;
    blend(attr_nrm_);
    blend(col_);
    blend(uv_);
    for (std::vector<glm::vec2>& set : extra_uv_) blend(set);
    blend(tan_);
    if (!tan_.empty()) tan_[to].w = sign;  // the survivor's handedness
  }
  for (const WedgePair& m : map_)
    if (m.from != m.to) wedge_parent_[m.from] = m.to;
}

// position and normal of the merged vertex, interpolated by the CA of the merged vertices (§3);
// a kept vertex never moves, and two kept vertices never merge
void ZhangEngine::interpolate(const uint32_t* s, int s_count, uint32_t& k, glm::vec3& p, glm::vec3& n, float* weights,
                              bool& ok) {
  int kept_count = 0;
  k = s[0];
  for (int i = 0; i < s_count; ++i)
    if (vs_[s[i]].kept) {
      ++kept_count;
      k = s[i];
    }
  ok = kept_count <= 1;
  if (!ok) return;
  if (kept_count == 0 && params_.placement == ZhangPlacement::kNeighbour)  // s[s_count - 1] is V_j
    k = s[s_count - 1];
  if (kept_count == 1 || params_.placement == ZhangPlacement::kNeighbour) {
    for (int i = 0; i < s_count; ++i) weights[i] = s[i] == k ? 1.0f : 0.0f;
    p = pos_[k];
    n = nrm_[k];
    return;
  }
  float sum = 0.0f;
  for (int i = 0; i < s_count; ++i) sum += vs_[s[i]].ca;
  p = glm::vec3(0.0f);
  glm::vec3 nn(0.0f);
  for (int i = 0; i < s_count; ++i) {
    const float w = sum > 0.0f ? vs_[s[i]].ca / sum : 1.0f / static_cast<float>(s_count);
    weights[i] = w;
    p += w * pos_[s[i]];
    nn += w * nrm_[s[i]];
  }
  n = safeNormalize(nn);
  if (glm::dot(n, n) == 0.0f) n = nrm_[k];
}

void ZhangEngine::gatherStar(uint32_t v, std::vector<StarEntry>& out) {
  out.clear();
  forStar(v, [&](uint32_t t, uint32_t corner) {
    out.push_back({t, faces_[t].v[(corner + 1) % 3], faces_[t].v[(corner + 2) % 3]});
  });
}

bool ZhangEngine::evaluate(const StarEntry* entries, size_t count, bool any_removed, const glm::vec3& p,
                           const glm::vec3& n, float bound, float& new_ca) {
  new_ca = 0.0f;
  return checkGeometry(entries, count, p, n, bound, true, new_ca) && checkTopology(entries, count, any_removed);
}

bool ZhangEngine::checkGeometry(const StarEntry* entries, size_t count, const glm::vec3& p, const glm::vec3& n,
                                float bound, bool ring, float& new_ca) {
  for (size_t e = 0; e < count; ++e) {
    const uint32_t t = entries[e].t;
    const glm::vec3 &pu = pos_[entries[e].u], &pw = pos_[entries[e].w];
    if (glm::dot(faces_[t].n, faces_[t].n) == 0.0f) continue;  // already degenerate: nothing to turn
    const glm::vec3 x = glm::cross(pu - p, pw - p);
    const float len = glm::length(x);
    const float scale = glm::dot(pu - p, pu - p) + glm::dot(pw - p, pw - p) + glm::dot(pw - pu, pw - pu);
    if (!(len > kDegenerateRatio * scale)) {
      ++stats_.rejected_fold;
      return false;
    }
    const glm::vec3 nt = x / len;
    // against the triangle's current normal (a flip) and against the merged vertex's carried
    // normal, interpolated from the original's (drift from the original orientation)
    const float dot_n = glm::dot(nt, n);
    if (glm::dot(nt, faces_[t].n) < cos_max_turn_ || dot_n < cos_max_turn_) {
      ++stats_.rejected_fold;
      return false;
    }
    // the largest angle is the one of the smallest dot (acos decreases); a zero normal gives angle 0.
    // The ring vertices count too over a triangle that changed (paper Fig. 6: a fold raises CA(V_2))
    float min_dot = 2.0f;
    if (glm::dot(n, n) != 0.0f) min_dot = dot_n;
    if (ring && params_.ring_vision)
      for (uint32_t r : {entries[e].u, entries[e].w}) {
        const glm::vec3& nr = nrm_[r];
        if (glm::dot(nr, nr) != 0.0f) min_dot = std::min(min_dot, glm::dot(nr, nt));
      }
    const float angle = min_dot > 1.5f ? 0.0f : fastAcos(min_dot);
    new_ca = std::max(new_ca, angle * 0.5f * len);
    if (new_ca >= bound) return false;  // cannot beat the best candidate so far
  }
  return true;
}

bool ZhangEngine::checkTopology(const StarEntry* entries, size_t count, bool any_removed) {
  if (count == 0 || !any_removed) {
    ++stats_.rejected_topology;
    return false;
  }
  if (count <= kLocalStar) return checkTopologyLocal(entries, count);
  star_.reset();
  for (size_t e = 0; e < count; ++e) {
    const uint32_t u = entries[e].u, w = entries[e].w;
    if (star_.count[u] == 0 && star_.next[u] == kNone) star_.touched.push_back(u);
    if (star_.count[w] == 0 && star_.next[w] == kNone) star_.touched.push_back(w);
    star_.count[u] += 1u;
    star_.count[w] += 1u << 16;
    star_.next[u] = w;
  }
  // link condition: the surviving fan around the merged vertex is one cycle or one chain
  const size_t pc = count;
  size_t chain_starts = 0;
  uint32_t start = entries[0].u;
  for (uint32_t v : star_.touched) {
    const uint32_t c = star_.count[v], first = c & 0xffffu, second = c >> 16;
    if (first > 1 || second > 1) {
      ++stats_.rejected_topology;
      return false;
    }
    if (second == 0) {
      ++chain_starts;
      start = v;
    }
  }
  if (chain_starts > 1 || star_.touched.size() != pc + chain_starts) {
    ++stats_.rejected_topology;
    return false;
  }
  size_t steps = 0;
  uint32_t v = start;
  do {
    if ((star_.count[v] & 0xffffu) == 0) break;  // end of the chain
    v = star_.next[v];
    ++steps;
  } while (v != start && steps <= pc);
  if (steps != pc || (chain_starts == 0 && (v != start || pc < 3))) {
    ++stats_.rejected_topology;
    return false;
  }
  return true;
}

// the same test as checkTopology on a small star, with the ring vertices in a local table found by a
// linear scan instead of the per-vertex scratch arrays (which cost a cache miss per ring vertex)
bool ZhangEngine::checkTopologyLocal(const StarEntry* entries, size_t count) {
  uint32_t ids[2 * kLocalStar], next[2 * kLocalStar];
  uint8_t first[2 * kLocalStar], second[2 * kLocalStar];
  uint32_t n = 0;
  auto slot = [&](uint32_t v) {
    for (uint32_t i = 0; i < n; ++i)
      if (ids[i] == v) return i;
    ids[n] = v;
    first[n] = second[n] = 0;
    next[n] = kNone;
    return n++;
  };
  for (size_t e = 0; e < count; ++e) {
    const uint32_t a = slot(entries[e].u), b = slot(entries[e].w);
    ++first[a];
    ++second[b];
    next[a] = b;
  }
  size_t chain_starts = 0;
  uint32_t start = 0;  // the slot of entries[0].u
  for (uint32_t i = 0; i < n; ++i) {
    if (first[i] > 1 || second[i] > 1) {
      ++stats_.rejected_topology;
      return false;
    }
    if (second[i] == 0) {
      ++chain_starts;
      start = i;
    }
  }
  if (chain_starts > 1 || n != count + chain_starts) {
    ++stats_.rejected_topology;
    return false;
  }
  size_t steps = 0;
  uint32_t v = start;
  do {
    if (first[v] == 0) break;  // end of the chain
    v = next[v];
    ++steps;
  } while (v != start && steps <= count);
  if (steps != count || (chain_starts == 0 && (v != start || count < 3))) {
    ++stats_.rejected_topology;
    return false;
  }
  return true;
}

void ZhangEngine::apply(const uint32_t* s, int s_count, uint32_t k, const glm::vec3& p, const glm::vec3& n) {
  // triangles with two or more merged vertices die
  removed_.clear();
  for (int si = 0; si < s_count; ++si) {
    forStar(s[si], [&](uint32_t t, uint32_t) {
      int inside = 0;
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < s_count; ++i) inside += faces_[t].v[c] == s[i];
      if (inside >= 2) removed_.push_back(t);
    });
  }
  for (uint32_t t : removed_) {
    if (!faces_[t].alive) continue;
    faces_[t].alive = 0;
    --alive_tris_;
    if (params_.mode == ZhangMode::kTriangleDecimation) heap_.remove(t);
  }
  // attributes blended with the area weights; the merged vertex keeps id k
  float wsum = 0.0f;
  for (int i = 0; i < s_count; ++i) wsum += weight_[s[i]];
  auto blend3 = [&](std::vector<glm::vec3>& a) {
    if (a.empty()) return;
    glm::vec3 acc(0.0f);
    for (int i = 0; i < s_count; ++i) acc += (wsum > 0.0f ? weight_[s[i]] / wsum : 1.0f / s_count) * a[s[i]];
    a[k] = acc;
  };
  if (!vs_[k].kept && !attr_) {
    blend3(attr_nrm_);
    blend3(col_);
    if (!uv_.empty()) {
      glm::vec2 acc(0.0f);
      for (int i = 0; i < s_count; ++i) acc += (wsum > 0.0f ? weight_[s[i]] / wsum : 1.0f / s_count) * uv_[s[i]];
      uv_[k] = acc;
    }
  }
  if (attr_) blendWedges(s, s_count, k);
  weight_[k] = wsum;
  const bool k_moved = pos_[k] != p;
  pos_[k] = p;
  nrm_[k] = n;
  // the triangles that change shape get this collapse's mark: the relabelled ones, and all of k's fan
  // when k moved
  ++mark_gen_;
  for (int i = 0; i < s_count; ++i) {
    const uint32_t v = s[i];
    if (v == k) continue;
    // relabel v's corners to k and splice v's list in front of k's
    uint32_t last = kNone;
    forStar(v, [&](uint32_t t, uint32_t corner) {
      faces_[t].v[corner] = k;
      faces_[t].mark = mark_gen_;
      last = 3 * t + corner;
      if (attr_) faces_[t].a[corner] = wedgeFind(faces_[t].a[corner]);
    });
    if (last != kNone) {
      cornerNext(last) = vhead_[k];
      vhead_[k] = vhead_[v];
    }
    vhead_[v] = kNone;
    parent_[v] = k;
    vs_[v].alive = 0;
    if (params_.mode == ZhangMode::kEdgeCollapse) heap_.remove(v);
  }
  // new normals and areas of the changed triangles, then the CA (and queue key) of k and of its ring
  neighbours_.clear();
  fan_.clear();
  forStar(k, [&](uint32_t t, uint32_t corner) {
    if (k_moved || faces_[t].mark == mark_gen_) {
      updateTriangle(t);
      faces_[t].mark = mark_gen_;
    }
    fan_.push_back({t, faces_[t].v[(corner + 1) % 3], faces_[t].v[(corner + 2) % 3]});
    for (uint32_t c = 1; c < 3; ++c) {
      const uint32_t u = faces_[t].v[(corner + c) % 3];
      if (vs_[u].mark != mark_gen_) {
        vs_[u].mark = mark_gen_;
        neighbours_.push_back(u);
      }
    }
  });
  if (attr_) {  // the fans that changed are k's and its ring's
    seam_state_[k] = -1;
    for (uint32_t u : neighbours_) seam_state_[u] = -1;
  }
  refreshAround(k);
  ++stats_.collapses;
}

bool ZhangEngine::stepEdge() {
  if (heap_.empty()) return false;
  const uint32_t i = heap_.pop();
  // candidate partners: NV(V_i), in a fixed order
  gatherStar(i, star_i_);
  tris_.clear();
  ++mark_gen_;
  for (const StarEntry& e : star_i_)
    for (uint32_t u : {e.u, e.w})
      if (vs_[u].mark != mark_gen_) {
        vs_[u].mark = mark_gen_;
        tris_.push_back(u);
      }
  const bool i_on_seam = attr_ && onSeam(i);
  if (i_on_seam) seamCandidates(i);
  float best_ca = INFINITY;
  uint32_t best_j = kNone;
  glm::vec3 best_p(0.0f), best_n(0.0f);
  for (uint32_t j : tris_) {
    const uint32_t s[2] = {i, j};
    uint32_t k;
    glm::vec3 p, n;
    bool ok;
    interpolate(s, 2, k, p, n, blend_w_, ok);
    if (!ok) continue;
    if (attr_) {
      // off the seams, i has one wedge and both triangles on the edge agree on j's: one pair
      if (!i_on_seam) onePair(i, j);
      else if (!mapWedges(s, 2, j)) continue;
      if (i_on_seam || onSeam(j)) {  // a seam vertex never moves off its seam: onto V_j
        p = pos_[j];
        n = nrm_[j];
        blend_w_[0] = 0.0f;
        blend_w_[1] = 1.0f;
      }
    }
    // surviving triangles: those of V_i without V_j and those of V_j without V_i
    union_.clear();
    bool any_removed = false;
    for (const StarEntry& e : star_i_) {
      if (e.u == j || e.w == j) any_removed = true;
      else union_.push_back(e);
    }
    // V_i's side first: most candidates lose there, before V_j's fan is walked
    float ca = 0.0f;
    if (!checkGeometry(union_.data(), union_.size(), p, n, best_ca, true, ca)) continue;
    const size_t i_part = union_.size();
    gatherStar(j, star_j_);
    for (const StarEntry& e : star_j_)
      if (e.u != i && e.w != i) union_.push_back(e);
    if (!checkGeometry(union_.data() + i_part, union_.size() - i_part, p, n, best_ca, p != pos_[j], ca)) continue;
    if (!checkTopology(union_.data(), union_.size(), any_removed)) continue;
    if (ca < best_ca) {
      best_ca = ca;
      best_j = j;
      best_p = p;
      best_n = n;
      best_map_.swap(map_);
      std::copy(blend_w_, blend_w_ + 2, best_w_);
    }
  }
  if (best_j == kNone) {  // blocked until a neighbour's collapse changes its fan
    ++stats_.blocked;
    return true;
  }
  const uint32_t s[2] = {i, best_j};
  map_.swap(best_map_);
  std::copy(best_w_, best_w_ + 2, blend_w_);
  apply(s, 2, best_j, best_p, best_n);
  return true;
}

// CA(T): the triangle's area times the largest angle between its normal and the normals of NT(T),
// the triangles sharing a vertex with it (definition 4)
float ZhangEngine::triangleVision(uint32_t t) {
  float max_angle = 0.0f;
  const glm::vec3 nt = faces_[t].n;
  for (int c = 0; c < 3; ++c)
    forStar(faces_[t].v[c], [&](uint32_t o, uint32_t) {
      if (o != t) max_angle = std::max(max_angle, fastAngle(nt, faces_[o].n));
    });
  return max_angle * faces_[t].area;
}

void ZhangEngine::refreshTrianglesAround(uint32_t k) {
  // triangles whose NT(T) holds a triangle of k's fan: those touching k or its ring
  ++mark_gen_;
  auto touch = [&](uint32_t t, uint32_t) {
    if (faces_[t].mark == mark_gen_) return;
    faces_[t].mark = mark_gen_;
    heap_.set(t, triangleVision(t));
  };
  forStar(k, touch);
  for (uint32_t u : neighbours_) forStar(u, touch);
}

// with attributes, a contracted triangle keeps a vertex on a seam where it is (at most one may be)
void ZhangEngine::pinToSeam(const uint32_t* s, uint32_t& k, glm::vec3& p, glm::vec3& n, bool& ok) {
  int pinned = -1;
  for (int i = 0; i < 3; ++i)
    if (vs_[s[i]].kept || onSeam(s[i])) {
      if (pinned >= 0) {
        ok = false;
        return;
      }
      pinned = i;
    }
  if (pinned >= 0) {
    k = s[pinned];
    p = pos_[k];
    n = nrm_[k];
    for (int i = 0; i < 3; ++i) blend_w_[i] = i == pinned ? 1.0f : 0.0f;
  }
  ok = mapWedges(s, 3, k);
}

bool ZhangEngine::stepTriangle() {
  if (heap_.empty()) return false;
  const uint32_t t = heap_.pop();
  uint32_t s[3] = {faces_[t].v[0], faces_[t].v[1], faces_[t].v[2]};
  // the vertex with the largest CA last: with ZhangPlacement::kNeighbour the triangle goes onto it
  for (int a = 0; a < 2; ++a)
    if (vs_[s[a]].ca > vs_[s[2]].ca || (vs_[s[a]].ca == vs_[s[2]].ca && s[a] < s[2])) std::swap(s[a], s[2]);
  uint32_t k;
  glm::vec3 p, n;
  bool ok;
  interpolate(s, 3, k, p, n, blend_w_, ok);
  if (ok && !vs_[k].kept) k = s[2];  // survivor: the vertex with the largest CA
  if (ok && attr_) pinToSeam(s, k, p, n, ok);
  if (!ok) {  // re-queued when its neighbourhood changes
    ++stats_.blocked;
    return true;
  }
  union_.clear();
  bool any_removed = false;
  for (int si = 0; si < 3; ++si) {
    gatherStar(s[si], star_j_);
    for (const StarEntry& e : star_j_) {
      const bool u_in = e.u == s[0] || e.u == s[1] || e.u == s[2], w_in = e.w == s[0] || e.w == s[1] || e.w == s[2];
      if (u_in || w_in) any_removed = true;
      else union_.push_back(e);
    }
  }
  float ca;
  if (!evaluate(union_.data(), union_.size(), any_removed, p, n, INFINITY, ca)) {
    ++stats_.blocked;
    return true;
  }
  apply(s, 3, k, p, n);
  refreshTrianglesAround(k);
  return true;
}

void ZhangEngine::run(size_t target) {
  current_target_ = target;
  size_t since_report = 0;
  while (alive_tris_ > target && !stopped_) {
    const bool progressed = params_.mode == ZhangMode::kEdgeCollapse ? stepEdge() : stepTriangle();
    if (!progressed) stopped_ = true;
    if (progress_ && ++since_report >= 8192) {
      since_report = 0;
      const double span = static_cast<double>(initial_tris_ - std::min(initial_tris_, final_target_));
      (*progress_)(span > 0 ? static_cast<double>(initial_tris_ - alive_tris_) / span : 1.0, "zhang collapse");
    }
  }
}

// a unit tangent perpendicular to n, as near to t as possible (any perpendicular when t is along n)
glm::vec3 orthonormalTangent(const glm::vec3& t, const glm::vec3& n) {
  glm::vec3 x = safeNormalize(t - n * glm::dot(n, t));
  if (glm::dot(x, x) > 0.0f) return x;
  x = safeNormalize(glm::cross(n, std::fabs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
  return glm::dot(x, x) > 0.0f ? x : glm::vec3(1, 0, 0);
}

void ZhangEngine::emitMesh(Mesh& out, std::vector<uint8_t>& present) {
  const Mesh& in = *in_;
  const size_t kn = attr_ ? wedge_src_.size() : in.vertexCount();
  out = Mesh{};
  std::vector<uint32_t> remap(kn, kNone);
  auto use = [&](uint32_t key) { remap[key] = 0; };  // mark; ids assigned in key order below
  for (size_t t = 0; t < faces_.size(); ++t)
    if (faces_[t].alive)
      for (int c = 0; c < 3; ++c) use(cornerKey(uint32_t(t), c));
  for (size_t e = 0; e < in.edgeCount(); ++e) {
    const uint32_t a = inputKey(in.edges[2 * e]), b = inputKey(in.edges[2 * e + 1]);
    if (keyVertex(a) != keyVertex(b)) {
      use(a);
      use(b);
    }
  }
  for (uint32_t p : in.points) use(inputKey(p));
  uint32_t next_id = 0;
  for (size_t key = 0; key < kn; ++key)
    if (remap[key] != kNone) remap[key] = next_id++;
  out.positions.resize(next_id);
  out.normals.resize(next_id);
  if (!col_.empty()) out.colors.resize(next_id);
  if (!uv_.empty()) out.uvs.resize(next_id);
  out.extra_uvs.assign(extra_uv_.size(), std::vector<glm::vec2>(next_id));
  if (!tan_.empty()) out.tangents.resize(next_id);
  if (attr_ && in.skinned()) {
    out.joints.resize(next_id);
    out.weights.resize(next_id);
    out.joint_parents = in.joint_parents;
  }
  stats_.source_vertex.resize(next_id);
  stats_.output_vertex_of.resize(next_id);
  present.assign(in.vertexCount(), 0);
  for (size_t key = 0; key < kn; ++key) {
    if (remap[key] == kNone) continue;
    const uint32_t o = remap[key], v = keyVertex(uint32_t(key)), src = attr_ ? wedge_src_[key] : uint32_t(key);
    present[v] = 1;
    stats_.source_vertex[o] = src;
    stats_.output_vertex_of[o] = v;
    out.positions[o] = pos_[v];
    glm::vec3 nrm = attr_nrm_.empty() ? nrm_[v] : safeNormalize(attr_nrm_[key]);
    out.normals[o] = glm::dot(nrm, nrm) > 0.0f ? nrm : glm::vec3(0.0f, 0.0f, 1.0f);
    if (!col_.empty()) out.colors[o] = col_[key];
    if (!uv_.empty()) out.uvs[o] = uv_[key];
    for (size_t set = 0; set < extra_uv_.size(); ++set) out.extra_uvs[set][o] = extra_uv_[set][key];
    if (!tan_.empty()) out.tangents[o] = glm::vec4(orthonormalTangent(glm::vec3(tan_[key]), out.normals[o]), tan_[key].w);
    if (!out.joints.empty()) {
      out.joints[o] = in.joints[src];
      out.weights[o] = in.weights[src];
    }
  }
  out.triangles.reserve(3 * alive_tris_);
  for (size_t t = 0; t < faces_.size(); ++t) {
    if (!faces_[t].alive) continue;
    for (int c = 0; c < 3; ++c) out.triangles.push_back(remap[cornerKey(uint32_t(t), c)]);
    if (!face_group_.empty()) out.triangle_groups.push_back(face_group_[t]);
  }
  for (size_t e = 0; e < in.edgeCount(); ++e) {
    const uint32_t a = inputKey(in.edges[2 * e]), b = inputKey(in.edges[2 * e + 1]);
    if (keyVertex(a) == keyVertex(b)) continue;
    out.edges.push_back(remap[a]);
    out.edges.push_back(remap[b]);
    if (!in.edge_thickness.empty()) out.edge_thickness.push_back(in.edge_thickness[e]);
  }
  for (uint32_t p : in.points) out.points.push_back(remap[inputKey(p)]);
}

void ZhangEngine::extract(Mesh& out, ZhangStats& stats) {
  const Mesh& in = *in_;
  const size_t vn = in.vertexCount();
  std::vector<uint8_t> present;
  emitMesh(out, present);
  // measured error: the largest distance an input vertex moved to its representative
  float max_d2 = 0.0f;
  stats_.collapsed_into.assign(vn, kNone);
  for (size_t v = 0; v < vn; ++v) {
    const uint32_t r = find(static_cast<uint32_t>(v));
    if (!present[r]) continue;
    stats_.collapsed_into[v] = r;
    const glm::vec3 d = in.positions[v] - pos_[r];
    max_d2 = std::max(max_d2, glm::dot(d, d));
  }
  stats_.max_displacement = std::sqrt(max_d2);
  // an upper bound of the distance from the input vertices to the result: from each input vertex's
  // representative, walk over the result towards the vertex (to the fan vertex nearest to it, at most
  // 16 steps) and take the nearest triangle met; the result's nearest triangle can only be nearer
  float max_s2 = 0.0f;
  for (size_t v = 0; v < vn; ++v) {
    uint32_t c = find(static_cast<uint32_t>(v));
    if (!present[c]) continue;
    const glm::vec3& q = in.positions[v];
    float best = glm::dot(q - pos_[c], q - pos_[c]);
    // best only falls during the walk, so a vertex already within the running max cannot raise it
    for (int step = 0; step < 16 && best > max_s2; ++step) {
      uint32_t next = c;
      float next_d2 = glm::dot(q - pos_[c], q - pos_[c]);
      forStar(c, [&](uint32_t t, uint32_t) {
        const Face& f = faces_[t];
        best = std::min(best, pointTriangleDistance2(q, pos_[f.v[0]], pos_[f.v[1]], pos_[f.v[2]]));
        for (uint32_t u : f.v) {
          const float d2 = glm::dot(q - pos_[u], q - pos_[u]);
          if (d2 < next_d2) next_d2 = d2, next = u;
        }
      });
      if (next == c) break;
      c = next;
    }
    max_s2 = std::max(max_s2, best);
  }
  stats_.max_surface_distance = std::sqrt(max_s2);
  stats_.output_triangles = alive_tris_;
  stats_.free_vertices_left = 0;
  for (size_t v = 0; v < vn; ++v) stats_.free_vertices_left += vs_[v].alive && !vs_[v].kept;
  stats_.stop_reason = alive_tris_ > current_target_ && stopped_ ? ZhangStopReason::kNoValidCollapse
                                                                 : ZhangStopReason::kTargetReached;
  stats = stats_;
}

}  // namespace

Error simplifyZhangMulti(const Mesh& in, const std::vector<size_t>& targets, const ZhangParams& params,
                         std::vector<Mesh>& out, std::vector<ZhangStats>* stats, const ProgressCallback& progress) {
  out.clear();
  if (stats) stats->clear();
  if (Error e = validateMesh(in, "zhang simplification input"); !e.ok()) return e;
  for (size_t i = 1; i < targets.size(); ++i)
    if (targets[i] >= targets[i - 1])
      return {Status::kInvalidArgument, "zhang: targets must be strictly decreasing"};
  ZhangEngine engine;
  if (Error e = engine.init(in, params); !e.ok()) return e;
  out.resize(targets.size());
  for (size_t i = 0; i < targets.size(); ++i) {
    engine.setProgress(progress.fn ? &progress : nullptr, targets.back());
    engine.run(targets[i]);
    ZhangStats s;
    engine.extract(out[i], s);
    if (stats) stats->push_back(s);
  }
  progress(1.0, "zhang collapse");
  return {};
}

Error simplifyZhang(const Mesh& in, size_t target_triangles, const ZhangParams& params, Mesh& out,
                    ZhangStats* stats) {
  std::vector<Mesh> meshes;
  std::vector<ZhangStats> all;
  if (Error e = simplifyZhangMulti(in, {target_triangles}, params, meshes, &all); !e.ok()) {
    out = Mesh{};
    return e;
  }
  out = std::move(meshes[0]);
  if (stats) *stats = all[0];
  return {};
}

}  // namespace scenelod
