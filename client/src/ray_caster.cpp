#include "lockstep/client/ray_caster.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "lockstep/client/client.h"

#ifdef LOCKSTEP_CLIENT_RAYS
#include "frame_actors.h"
#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/sensors/ray_scene.h"
#endif

namespace lockstep::client {

#ifdef LOCKSTEP_CLIENT_RAYS

namespace s = sensors;

struct RayCaster::Impl {
  explicit Impl(Client& c) : client(c) {}
  Client& client;
  std::mutex mu;
  uint64_t town_hash = 0;
  bool has_town = false;
  s::RayScene scene;

  // The town of the current map (built once per map) and the actors of the latest frame.
  void Prepare(const char* call) {
    const std::optional<msg::MapData> data = client.map_data();
    if (!data || data->opendrive().empty()) throw ClientError(std::string(call) + ": the simulation has no map loaded");
    if (!has_town || data->content_hash() != town_hash) {
      const map::Map town = map::Map::FromString(data->opendrive(), data->name().to_string());
      // As the sensors service: the map's scene file, else the scene generated from the run seed.
      const map::Scene sc = data->scene().empty() ? map::GenerateScene(town, client.world_info().seed())
                                                  : map::SceneFromYaml(data->scene(), data->name().to_string() + ".scene.yaml");
      scene.SetStatic(map::BuildWorldMeshes(town, sc));
      town_hash = data->content_hash();
      has_town = true;
    }
    const Snapshot snap = client.snapshot();
    std::vector<s::Actor> actors;
    if (snap.ground) s::AppendActors(*snap.ground, &actors);
    if (snap.air) s::AppendActors(*snap.air, &actors);
    // Custom props (custom.<name>), as the sensors service places them: the declared box on
    // the spawn transform, relative to the parent's mount.
    std::vector<s::CustomProp> props;
    std::optional<BlueprintLibrary> library;
    for (const ActorInfo& info : client.actors()) {
      if (info.blueprint.rfind("custom.", 0) != 0) continue;
      if (!library) library = client.blueprints(0.5);
      if (auto d = library->Find(info.blueprint)) props.push_back(s::MakeCustomProp(*d, info.id, info.parent, info.spawn_pose));
    }
    std::sort(props.begin(), props.end(), [](const s::CustomProp& a, const s::CustomProp& b) { return a.id < b.id; });
    s::AppendProps(props, &actors);
    std::sort(actors.begin(), actors.end(), [](const s::Actor& a, const s::Actor& b) { return a.id < b.id; });
    scene.SetActors(actors);
  }
};

namespace {
s::Vec3 Vec(const msg::Vector3& v) { return {v.x(), v.y(), v.z()}; }
LabelledPoint Point(const s::Vec3& p, uint8_t label) {
  LabelledPoint out;
  out.location.x(p.x());
  out.location.y(p.y());
  out.location.z(p.z());
  out.label = label;
  return out;
}
bool Finite(const s::Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }
}  // namespace

RayCaster::RayCaster(Client& client) : impl_(std::make_unique<Impl>(client)) {}
RayCaster::~RayCaster() = default;

std::vector<LabelledPoint> RayCaster::CastRay(const msg::Vector3& from, const msg::Vector3& to) {
  const s::Vec3 a = Vec(from), b = Vec(to);
  if (!Finite(a) || !Finite(b)) throw ClientError("cast_ray(): a location has a NaN or infinite value");
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->Prepare("cast_ray()");
  std::vector<LabelledPoint> out;
  const double length = (b - a).norm();
  if (!(length > 0)) return out;
  const s::Vec3 dir = (b - a) / length;
  for (const s::Hit& h : impl_->scene.IntersectAll(a, b)) out.push_back(Point(a + dir * static_cast<double>(h.distance), h.tag));
  return out;
}

std::optional<LabelledPoint> RayCaster::ProjectPoint(const msg::Vector3& location, const msg::Vector3& direction,
                                                     double search_distance) {
  const s::Vec3 p = Vec(location), d = Vec(direction);
  if (!Finite(p) || !Finite(d) || !std::isfinite(search_distance)) {
    throw ClientError("project_point(): a location, direction or distance has a NaN or infinite value");
  }
  const double n = d.norm();
  if (!(n > 1e-8) || !(search_distance > 0)) return std::nullopt;  // Unreal's GetSafeNormal: a zero vector
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->Prepare("project_point()");
  const s::Vec3 dir = d / n;
  s::Ray r;
  for (int k = 0; k < 3; ++k) {
    r.origin[k] = static_cast<float>(p[k]);
    r.dir[k] = static_cast<float>(dir[k]);
  }
  r.tfar = static_cast<float>(search_distance);
  const s::Hit h = impl_->scene.Intersect(r);
  if (!h.hit()) return std::nullopt;
  return Point(p + dir * static_cast<double>(h.distance), h.tag);
}

#else  // built without the sensors core (no Embree): the calls say so

struct RayCaster::Impl {};
RayCaster::RayCaster(Client&) : impl_(std::make_unique<Impl>()) {}
RayCaster::~RayCaster() = default;
std::vector<LabelledPoint> RayCaster::CastRay(const msg::Vector3&, const msg::Vector3&) {
  throw ClientError("cast_ray(): this build has no ray casting (the sensors core, Embree, was not built)");
}
std::optional<LabelledPoint> RayCaster::ProjectPoint(const msg::Vector3&, const msg::Vector3&, double) {
  throw ClientError("project_point(): this build has no ray casting (the sensors core, Embree, was not built)");
}

#endif

}  // namespace lockstep::client
