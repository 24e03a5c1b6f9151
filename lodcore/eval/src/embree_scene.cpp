// One mesh as an Embree scene (Embree 3 point queries and ray casts). Closest point on a triangle
// by Voronoi regions (Ericson, Real-Time Collision Detection §5.1.5); capsules and spheres are a
// user geometry so edges keep their thickness (Low & Tan 1997 §3.3.1).
#include "embree_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace scenelod::eval::detail {

namespace {

const glm::vec3 kTriangleGrey(0.70f, 0.70f, 0.70f);
const glm::vec3 kEdgeBlue(0.10f, 0.30f, 0.85f);
const glm::vec3 kPointRed(0.85f, 0.15f, 0.10f);

void roundBounds(const RTCBoundsFunctionArguments* args) {
  const auto* self = static_cast<const EmbreeScene*>(args->geometryUserPtr);
  const RoundPrim& p = self->rounds_[args->primID];
  const glm::vec3 lo = glm::min(p.a, p.b) - glm::vec3(p.radius);
  const glm::vec3 hi = glm::max(p.a, p.b) + glm::vec3(p.radius);
  args->bounds_o->lower_x = lo.x;
  args->bounds_o->lower_y = lo.y;
  args->bounds_o->lower_z = lo.z;
  args->bounds_o->upper_x = hi.x;
  args->bounds_o->upper_y = hi.y;
  args->bounds_o->upper_z = hi.z;
}

void roundIntersect(const RTCIntersectFunctionNArguments* args) {
  const auto* self = static_cast<const EmbreeScene*>(args->geometryUserPtr);
  const RoundPrim& p = self->rounds_[args->primID];
  if (p.radius <= 0.0f) return;
  RTCRayHitN* rh = args->rayhit;
  RTCRayN* ray = RTCRayHitN_RayN(rh, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(rh, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const glm::vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i), RTCRayN_org_z(ray, args->N, i));
    const glm::vec3 d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i), RTCRayN_dir_z(ray, args->N, i));
    float t = 0.0f;
    glm::vec3 axis;
    if (!intersectCapsule(o, d, p.a, p.b, p.radius, RTCRayN_tnear(ray, args->N, i), RTCRayN_tfar(ray, args->N, i), t, axis))
      continue;
    RTCRayN_tfar(ray, args->N, i) = t;
    const glm::vec3 n = o + t * d - axis;  // geometric normal of the capsule; shading replaces it
    RTCHitN_Ng_x(hit, args->N, i) = n.x;
    RTCHitN_Ng_y(hit, args->N, i) = n.y;
    RTCHitN_Ng_z(hit, args->N, i) = n.z;
    RTCHitN_u(hit, args->N, i) = 0.0f;
    RTCHitN_v(hit, args->N, i) = 0.0f;
    RTCHitN_primID(hit, args->N, i) = args->primID;
    RTCHitN_geomID(hit, args->N, i) = args->geomID;
    RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
  }
}

struct QueryState {
  const EmbreeScene* self;
  float best;
};

bool closestCallback(RTCPointQueryFunctionArguments* args) {
  auto* st = static_cast<QueryState*>(args->userPtr);
  const EmbreeScene* self = st->self;
  const glm::vec3 q(args->query->x, args->query->y, args->query->z);
  float d;
  if (args->geomID == self->tri_geom_) {
    const auto& tri = self->mesh_->triangles;
    const auto& pos = self->mesh_->positions;
    const size_t k = static_cast<size_t>(args->primID) * 3;
    const glm::vec3 &a = pos[tri[k]], &b = pos[tri[k + 1]], &c = pos[tri[k + 2]];
    // cheap reject: the triangle's box is already farther than the best answer
    const glm::vec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
    const glm::vec3 out = glm::max(lo - q, glm::max(q - hi, glm::vec3(0.0f)));
    if (glm::dot(out, out) >= st->best * st->best) return false;
    const glm::vec3 p = closestPointOnTriangle(q, a, b, c);
    d = glm::length(q - p);
  } else {
    const RoundPrim& p = self->rounds_[args->primID];
    d = std::max(0.0f, distanceToSegment(q, p.a, p.b) - p.radius);
  }
  if (d < st->best) {
    st->best = d;
    args->query->radius = d;
    return true;
  }
  return false;
}

}  // namespace

glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float den = d1 - d3;
    return den > 0.0f ? a + ab * (d1 / den) : a;
  }
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float den = d2 - d6;
    return den > 0.0f ? a + ac * (d2 / den) : a;
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float den = (d4 - d3) + (d5 - d6);
    return den > 0.0f ? b + (c - b) * ((d4 - d3) / den) : b;
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) {
    // degenerate (zero-area) triangle: nearest of its three edges
    const glm::vec3 e[3][2] = {{a, b}, {b, c}, {c, a}};
    glm::vec3 best = a;
    float best_d = std::numeric_limits<float>::infinity();
    for (const auto& s : e) {
      const glm::vec3 ds = s[1] - s[0];
      const float l2 = glm::dot(ds, ds);
      const float t = l2 > 0.0f ? std::clamp(glm::dot(p - s[0], ds) / l2, 0.0f, 1.0f) : 0.0f;
      const glm::vec3 q = s[0] + t * ds;
      const float dq = glm::length(p - q);
      if (dq < best_d) best_d = dq, best = q;
    }
    return best;
  }
  const float v = vb / sum, w = vc / sum;
  return a + ab * v + ac * w;
}

float distanceToSegment(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 ab = b - a;
  const float l2 = glm::dot(ab, ab);
  const float t = l2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / l2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

bool intersectCapsule(const glm::vec3& o, const glm::vec3& d, const glm::vec3& a, const glm::vec3& b, float r,
                      float t_min, float t_max, float& t_hit, glm::vec3& axis_point) {
  // body: points at distance r from the axis line, between the end planes; then the two end spheres
  const glm::vec3 ba = b - a, oa = o - a;
  const float baba = glm::dot(ba, ba), bard = glm::dot(ba, d), baoa = glm::dot(ba, oa);
  const float rdoa = glm::dot(d, oa), oaoa = glm::dot(oa, oa);
  float best = std::numeric_limits<float>::infinity();
  glm::vec3 best_axis(0.0f);
  if (baba > 0.0f) {
    const float qa = baba - bard * bard;
    const float qb = baba * rdoa - baoa * bard;
    const float qc = baba * oaoa - baoa * baoa - r * r * baba;
    const float h = qb * qb - qa * qc;
    if (qa > 1e-12f * baba && h >= 0.0f) {
      const float t = (-qb - std::sqrt(h)) / qa;
      const float y = baoa + t * bard;
      if (y > 0.0f && y < baba && t >= t_min && t <= t_max) {
        best = t;
        best_axis = a + ba * (y / baba);
      }
    }
  }
  for (const glm::vec3& c : {a, b}) {
    const glm::vec3 oc = o - c;
    const float hb = glm::dot(d, oc);
    const float hc = glm::dot(oc, oc) - r * r;
    const float h = hb * hb - hc;
    if (h < 0.0f) continue;
    const float t = -hb - std::sqrt(h);
    if (t >= t_min && t <= t_max && t < best) {
      best = t;
      best_axis = c;
    }
  }
  if (!(best < std::numeric_limits<float>::infinity())) return false;
  t_hit = best;
  axis_point = best_axis;
  return true;
}

namespace {
// one device for the process: creating a device starts Embree's task system, which costs far more
// than building a small scene; devices are thread-safe
RTCDevice sharedDevice() {
  static RTCDevice device = rtcNewDevice(nullptr);
  return device;
}
}  // namespace

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
}

Error EmbreeScene::build(const Mesh& mesh, float min_radius) {
  mesh_ = &mesh;
  device_ = sharedDevice();
  if (!device_) return {Status::kUnsupported, "Embree: cannot create a device"};
  scene_ = rtcNewScene(device_);
  tri_count_ = mesh.triangleCount();
  if (tri_count_ > 0) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    // buffers allocated by Embree, which pads them for its 16-byte vertex loads
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.vertexCount()));
    for (size_t i = 0; i < mesh.vertexCount(); ++i) {
      v[3 * i] = mesh.positions[i].x;
      v[3 * i + 1] = mesh.positions[i].y;
      v[3 * i + 2] = mesh.positions[i].z;
    }
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), tri_count_));
    std::copy(mesh.triangles.begin(), mesh.triangles.end(), idx);
    rtcCommitGeometry(g);
    tri_geom_ = rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
  }
  const bool has_colors = mesh.colors.size() == mesh.vertexCount();
  rounds_.clear();
  rounds_.reserve(mesh.edgeCount() + mesh.pointCount());
  for (size_t e = 0; e < mesh.edgeCount(); ++e) {
    RoundPrim p;
    const uint32_t i0 = mesh.edges[2 * e], i1 = mesh.edges[2 * e + 1];
    p.a = mesh.positions[i0];
    p.b = mesh.positions[i1];
    p.radius = std::max(0.5f * mesh.edgeThickness(e), min_radius);
    p.color = has_colors ? 0.5f * (mesh.colors[i0] + mesh.colors[i1]) : kEdgeBlue;
    rounds_.push_back(p);
  }
  for (uint32_t i : mesh.points) {
    RoundPrim p;
    p.a = p.b = mesh.positions[i];
    p.radius = min_radius;  // a point has no thickness: a sphere of radius 0 unless a floor is set
    p.color = has_colors ? mesh.colors[i] : kPointRed;
    p.is_point = true;
    rounds_.push_back(p);
  }
  if (!rounds_.empty()) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(rounds_.size()));
    rtcSetGeometryUserData(g, this);
    rtcSetGeometryBoundsFunction(g, roundBounds, nullptr);
    rtcSetGeometryIntersectFunction(g, roundIntersect);
    rtcCommitGeometry(g);
    round_geom_ = rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(scene_);
  if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) return {Status::kOutOfMemory, "Embree: scene build failed"};
  return {};
}

float EmbreeScene::closestDistance(const glm::vec3& p, float hint) const {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  if (empty()) return kInf;
  // growing radii: a bounded query visits only what is inside it, an unbounded one may visit much
  // before its radius shrinks
  float radius = hint > 0.0f ? hint : kInf;
  for (int pass = 0;; ++pass) {
    if (pass >= 6) radius = kInf;
    RTCPointQuery q;
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    q.time = 0.0f;
    q.radius = radius;
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    // primitives farther than the radius are never visited, so only a find within it counts
    QueryState st{this, radius};
    rtcPointQuery(scene_, &q, &ctx, closestCallback, &st);
    if (st.best < radius || radius == kInf) return st.best;
    radius *= 4.0f;
  }
}

RayHit EmbreeScene::intersect(const glm::vec3& origin, const glm::vec3& dir, float t_max) const {
  RayHit out;
  if (empty()) return out;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = origin.x;
  rh.ray.org_y = origin.y;
  rh.ray.org_z = origin.z;
  rh.ray.dir_x = dir.x;
  rh.ray.dir_y = dir.y;
  rh.ray.dir_z = dir.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = t_max;
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
  out.hit = true;
  out.t = rh.ray.tfar;
  out.prim = rh.hit.primID;
  if (rh.hit.geomID == tri_geom_) {
    glm::vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : -dir;
    out.normal = glm::dot(n, dir) > 0.0f ? -n : n;
    out.kind = 0;
    out.shading = out.normal;
    const size_t k = static_cast<size_t>(rh.hit.primID) * 3;
    const float u = rh.hit.u, v = rh.hit.v;
    out.u = u;
    out.v = v;
    if (mesh_->normals.size() == mesh_->vertexCount()) {
      const glm::vec3 s = (1.0f - u - v) * mesh_->normals[mesh_->triangles[k]] +
                          u * mesh_->normals[mesh_->triangles[k + 1]] + v * mesh_->normals[mesh_->triangles[k + 2]];
      const float sl = glm::length(s);
      if (sl > 1e-12f) out.shading = glm::dot(s, dir) > 0.0f ? -s / sl : s / sl;
    }
    if (mesh_->colors.size() == mesh_->vertexCount()) {
      out.color = (1.0f - u - v) * mesh_->colors[mesh_->triangles[k]] + u * mesh_->colors[mesh_->triangles[k + 1]] +
                  v * mesh_->colors[mesh_->triangles[k + 2]];
    } else {
      out.color = kTriangleGrey;
    }
  } else {
    const RoundPrim& p = rounds_[rh.hit.primID];
    out.color = p.color;
    out.kind = p.is_point ? 2 : 1;
    const glm::vec3 e = p.b - p.a;
    const float el = glm::length(e);
    if (p.is_point || el <= 0.0f) {
      out.normal = -dir;
    } else {
      // dynamic normal of a thick edge (Low & Tan §3.3.2): ((V1-C)x(V2-C))x(V2-V1) with the
      // orthographic camera C at infinity along -dir, i.e. -dir made perpendicular to the edge
      const glm::vec3 eu = e / el;
      glm::vec3 n = eu * glm::dot(eu, dir) - dir;
      const float nl = glm::length(n);
      out.normal = nl > 1e-6f ? n / nl : -dir;
    }
    out.shading = out.normal;
  }
  return out;
}

}  // namespace scenelod::eval::detail
