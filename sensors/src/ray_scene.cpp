#include "lockstep/sensors/ray_scene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace lockstep::sensors {

namespace {

constexpr unsigned kInvalid = RTC_INVALID_GEOMETRY_ID;

struct StaticInfo {
  uint8_t tag = 0;
  uint32_t instance_id = 0;
  uint32_t geometry = 0;  // index among the town's meshes + 1
  HitKind kind = HitKind::kStatic;
};

struct ActorInstance {
  unsigned geom = kInvalid;
  uint32_t actor = 0;
  HitKind kind = HitKind::kNone;
  uint8_t tag = 0;
  Eigen::Matrix3d normal_to_world = Eigen::Matrix3d::Identity();  // R * diag(1 / half)
};

void Check(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(e) + ")");
}

}  // namespace

struct RayScene::Impl {
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  RTCScene town = nullptr;
  RTCScene box = nullptr;
  unsigned town_geom = kInvalid;     // the town's instance in `top`
  size_t town_triangles = 0;
  std::vector<StaticInfo> statics;   // by geometry id in `town`
  std::map<uint32_t, ActorInstance> actors;  // by actor id
  std::vector<const ActorInstance*> by_geom;  // top-level geometry id -> actor

  Impl() {
    device = rtcNewDevice("threads=1");
    if (!device) throw std::runtime_error("embree: cannot create a device");
    top = rtcNewScene(device);
    rtcSetSceneFlags(top, RTC_SCENE_FLAG_DYNAMIC);
    rtcSetSceneBuildQuality(top, RTC_BUILD_QUALITY_LOW);
    BuildBox();
    rtcCommitScene(top);
    Check(device, "scene setup");
  }
  ~Impl() {
    if (top) rtcReleaseScene(top);
    if (town) rtcReleaseScene(town);
    if (box) rtcReleaseScene(box);
    if (device) rtcReleaseDevice(device);
  }

  // The unit box [-1, 1]^3 every actor instance scales by its half extents.
  void BuildBox() {
    box = rtcNewScene(device);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 8));
    for (int i = 0; i < 8; ++i) {
      v[3 * i + 0] = (i & 1) ? 1.f : -1.f;
      v[3 * i + 1] = (i & 2) ? 1.f : -1.f;
      v[3 * i + 2] = (i & 4) ? 1.f : -1.f;
    }
    static const unsigned kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                           {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 12));
    for (int f = 0; f < 12; ++f) {
      for (int k = 0; k < 3; ++k) idx[3 * f + k] = kFaces[f][k];
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(box, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(box);
  }

  void SetStatic(const std::vector<map::Mesh>& meshes) {
    if (town_geom != kInvalid) {
      rtcDetachGeometry(top, town_geom);
      town_geom = kInvalid;
    }
    if (town) rtcReleaseScene(town);
    town = rtcNewScene(device);
    rtcSetSceneBuildQuality(town, RTC_BUILD_QUALITY_HIGH);
    statics.clear();
    town_triangles = 0;
    for (size_t mesh_index = 0; mesh_index < meshes.size(); ++mesh_index) {
      const auto& m = meshes[mesh_index];
      if (m.TriangleCount() == 0) continue;
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.VertexCount()));
      std::copy(m.vertices.begin(), m.vertices.end(), v);
      auto* idx = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.TriangleCount()));
      std::copy(m.indices.begin(), m.indices.end(), idx);
      rtcCommitGeometry(g);
      const unsigned id = rtcAttachGeometry(town, g);
      rtcReleaseGeometry(g);
      if (statics.size() <= id) statics.resize(id + 1);
      statics[id] = StaticInfo{m.semantic_tag, m.instance_id, static_cast<uint32_t>(mesh_index + 1),
                               m.semantic_tag == map::semantic::kGround || m.semantic_tag == map::semantic::kRoads ||
                                       m.semantic_tag == map::semantic::kTerrain || m.semantic_tag == map::semantic::kRoadLine ||
                                       m.semantic_tag == map::semantic::kSideWalks
                                   ? HitKind::kGround
                                   : HitKind::kStatic};
      town_triangles += m.TriangleCount();
    }
    rtcCommitScene(town);
    Check(device, "town build");
    RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(inst, town);
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
    rtcCommitGeometry(inst);
    town_geom = rtcAttachGeometry(top, inst);
    rtcReleaseGeometry(inst);
    rtcCommitScene(top);
    Check(device, "town instance");
  }

  void SetActors(const std::vector<Actor>& list) {
    std::map<uint32_t, bool> seen;
    for (const auto& a : list) {
      auto [it, fresh] = actors.try_emplace(a.id);
      ActorInstance& inst = it->second;
      RTCGeometry g = nullptr;
      if (fresh) {
        g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, box);
        inst.geom = rtcAttachGeometry(top, g);
        rtcReleaseGeometry(g);
        inst.actor = a.id;
      }
      g = rtcGetGeometry(top, inst.geom);
      inst.kind = ActorHitKind(a.kind);
      inst.tag = ActorTag(a);
      const Eigen::Matrix3d r = a.pose.orientation.normalized().toRotationMatrix();
      const Vec3 h = a.half_extents.cwiseMax(Vec3::Constant(1e-3));
      const Eigen::Matrix3d m = r * h.asDiagonal();
      inst.normal_to_world = r * h.cwiseInverse().asDiagonal();
      float xf[12];
      for (int c = 0; c < 3; ++c) {
        for (int rr = 0; rr < 3; ++rr) xf[3 * c + rr] = static_cast<float>(m(rr, c));
      }
      for (int rr = 0; rr < 3; ++rr) xf[9 + rr] = static_cast<float>(a.pose.position[rr]);
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xf);
      rtcCommitGeometry(g);
      seen[a.id] = true;
    }
    for (auto it = actors.begin(); it != actors.end();) {
      if (seen.count(it->first)) {
        ++it;
        continue;
      }
      rtcDetachGeometry(top, it->second.geom);
      it = actors.erase(it);
    }
    by_geom.clear();
    for (const auto& [id, inst] : actors) {
      if (by_geom.size() <= inst.geom) by_geom.resize(inst.geom + 1, nullptr);
      by_geom[inst.geom] = &inst;
    }
    rtcCommitScene(top);
    Check(device, "actor update");
  }

  void Decode(unsigned inst_id, unsigned geom_id, float t, float nx, float ny, float nz, Hit* out) const {
    out->distance = t;
    if (inst_id == town_geom) {
      const StaticInfo& s = statics[geom_id];
      out->tag = s.tag;
      out->instance_id = s.instance_id;
      out->geometry = s.geometry;
      out->kind = s.kind;
      const float len = std::sqrt(nx * nx + ny * ny + nz * nz);
      out->normal[0] = nx / len;
      out->normal[1] = ny / len;
      out->normal[2] = nz / len;
      return;
    }
    const ActorInstance* a = inst_id < by_geom.size() ? by_geom[inst_id] : nullptr;
    if (!a) return;
    out->actor = a->actor;
    out->kind = a->kind;
    out->tag = a->tag;
    const Vec3 n = (a->normal_to_world * Vec3(nx, ny, nz)).normalized();
    for (int k = 0; k < 3; ++k) out->normal[k] = static_cast<float>(n[k]);
  }
};

RayScene::RayScene() : impl_(std::make_unique<Impl>()) {}
RayScene::~RayScene() = default;

void RayScene::SetStatic(const std::vector<map::Mesh>& meshes) { impl_->SetStatic(meshes); }
void RayScene::SetActors(const std::vector<Actor>& actors) { impl_->SetActors(actors); }
size_t RayScene::static_triangles() const { return impl_->town_triangles; }
size_t RayScene::actor_count() const { return impl_->actors.size(); }

void RayScene::Intersect(const Ray* rays, Hit* hits, size_t n) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // neighbouring rays: LiDAR columns, radar cones
  alignas(64) RTCRayHit16 p;
  alignas(64) int valid[16];
  for (size_t base = 0; base < n; base += 16) {
    const size_t count = std::min<size_t>(16, n - base);
    for (size_t i = 0; i < 16; ++i) {
      const bool on = i < count;
      valid[i] = on ? -1 : 0;
      const Ray& r = rays[base + (on ? i : 0)];
      p.ray.org_x[i] = r.origin[0];
      p.ray.org_y[i] = r.origin[1];
      p.ray.org_z[i] = r.origin[2];
      p.ray.dir_x[i] = r.dir[0];
      p.ray.dir_y[i] = r.dir[1];
      p.ray.dir_z[i] = r.dir[2];
      p.ray.tnear[i] = 0.f;
      p.ray.tfar[i] = r.tfar;
      p.ray.time[i] = 0.f;
      p.ray.mask[i] = 0xFFFFFFFFu;
      p.ray.id[i] = static_cast<unsigned>(i);
      p.ray.flags[i] = 0;
      p.hit.geomID[i] = kInvalid;
      p.hit.instID[0][i] = kInvalid;
    }
    rtcIntersect16(valid, impl_->top, &ctx, &p);
    for (size_t i = 0; i < count; ++i) {
      Hit& h = hits[base + i];
      h = Hit{};
      if (p.hit.geomID[i] == kInvalid) continue;
      impl_->Decode(p.hit.instID[0][i], p.hit.geomID[i], p.ray.tfar[i], p.hit.Ng_x[i], p.hit.Ng_y[i], p.hit.Ng_z[i], &h);
    }
  }
}

Hit RayScene::Intersect(const Ray& ray) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = ray.origin[0];
  rh.ray.org_y = ray.origin[1];
  rh.ray.org_z = ray.origin[2];
  rh.ray.dir_x = ray.dir[0];
  rh.ray.dir_y = ray.dir[1];
  rh.ray.dir_z = ray.dir[2];
  rh.ray.tnear = 0.f;
  rh.ray.tfar = ray.tfar;
  rh.ray.time = 0.f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = kInvalid;
  rh.hit.instID[0] = kInvalid;
  rtcIntersect1(impl_->top, &ctx, &rh);
  Hit h;
  if (rh.hit.geomID != kInvalid) impl_->Decode(rh.hit.instID[0], rh.hit.geomID, rh.ray.tfar, rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z, &h);
  return h;
}

std::vector<Hit> RayScene::IntersectAll(const Vec3& from, const Vec3& to, size_t max_hits) const {
  std::vector<Hit> out;
  const Vec3 d = to - from;
  const double length = d.norm();
  if (!(length > 0) || !std::isfinite(length)) return out;
  const Vec3 dir = d / length;
  // March along the segment: each hit found restarts the ray just behind it. An object
  // already reported (an actor's box exit face, a mesh hit again further on) is passed.
  double travelled = 0;
  for (size_t guard = 0; guard < 4 * max_hits + 16 && out.size() < max_hits; ++guard) {
    Ray r;
    const Vec3 o = from + dir * travelled;
    for (int a = 0; a < 3; ++a) {
      r.origin[a] = static_cast<float>(o[a]);
      r.dir[a] = static_cast<float>(dir[a]);
    }
    r.tfar = static_cast<float>(length - travelled);
    if (r.tfar <= 0) break;
    Hit h = Intersect(r);
    if (!h.hit()) break;
    const double at = travelled + h.distance;
    travelled = at + 1e-3;
    const bool seen = std::any_of(out.begin(), out.end(), [&](const Hit& e) {
      return h.geometry ? e.geometry == h.geometry : (e.geometry == 0 && e.actor == h.actor);
    });
    if (seen) continue;
    h.distance = static_cast<float>(at);
    out.push_back(h);
  }
  return out;
}

}  // namespace lockstep::sensors
