#include "lockstep/render/render_state.h"

#include <cmath>
#include <stdexcept>

namespace lockstep::render {
namespace {

constexpr std::uint32_t kSnapshotVersion = 1;

void SaveWeather(StateOut& out, const Weather& w) {
  for (float v : {w.cloudiness, w.precipitation, w.precipitation_deposits, w.wind_intensity, w.sun_azimuth_angle, w.sun_altitude_angle,
                  w.fog_density, w.fog_distance, w.fog_falloff, w.wetness, w.scattering_intensity, w.mie_scattering_scale,
                  w.rayleigh_scattering_scale, w.dust_storm}) {
    out.Put(v);
  }
}

void RestoreWeather(StateIn& in, Weather& w) {
  for (float* v : {&w.cloudiness, &w.precipitation, &w.precipitation_deposits, &w.wind_intensity, &w.sun_azimuth_angle,
                   &w.sun_altitude_angle, &w.fog_density, &w.fog_distance, &w.fog_falloff, &w.wetness, &w.scattering_intensity,
                   &w.mie_scattering_scale, &w.rayleigh_scattering_scale, &w.dust_storm}) {
    in.Get(*v);
  }
}

// A camera of the rig from its spawn (settings, exposure, DVS sensor).
RigCamera MakeCamera(std::uint32_t id, const SpawnedActor& a, std::uint64_t seed) {
  RigCamera cam;
  cam.id = id;
  cam.blueprint = a.blueprint;
  cam.attributes = a.attributes;
  cam.settings = ParseCamera(a.blueprint, a.attributes);
  cam.parent = a.parent;
  cam.relative = a.transform;
  cam.exposure = AutoExposure(cam.settings.exposure);
  if (cam.settings.kind == ImageKind::kDvs) cam.dvs.emplace(cam.settings.dvs, cam.settings.camera.width, cam.settings.camera.height, seed ^ id);
  return cam;
}

}  // namespace

std::string RigCamera::role() const {
  auto it = attributes.find("role_name");
  return it != attributes.end() ? it->second : std::string();
}

bool RigCamera::ImagesChangeState() const {
  return dvs.has_value() || ((OutputsFor(settings.kind) & kOutColor) && settings.exposure.histogram);
}

const RigCamera* RenderState::Spawn(std::uint32_t id, SpawnedActor actor, bool mine, std::uint64_t seed) {
  const SpawnedActor& a = spawned[id] = std::move(actor);
  if (!mine || !IsCameraBlueprint(a.blueprint)) return nullptr;
  RigCamera cam = MakeCamera(id, a, seed);  // throws on bad attributes: no camera then
  return &(cameras[id] = std::move(cam));
}

void RenderState::Destroy(std::uint32_t id) {
  spawned.erase(id);
  cameras.erase(id);
  for (auto& [cid, cam] : cameras) {
    if (cam.parent != id) continue;
    cam.parent = 0;
    if (cam.world_pose) cam.relative = *cam.world_pose;
    if (auto r = spawned.find(cid); r != spawned.end()) r->second.parent = 0, r->second.transform = cam.relative;
  }
}

void RenderState::SetTransform(std::uint32_t id, const Pose& transform) {
  if (auto it = spawned.find(id); it != spawned.end()) it->second.transform = transform;
  if (auto cam = cameras.find(id); cam != cameras.end()) cam->second.relative = transform;
}

std::vector<CameraPass> RenderState::Plan(std::uint64_t k, double t, const std::map<std::uint32_t, Pose>& mounts, std::uint64_t seed) {
  std::vector<CameraPass> passes;
  for (auto& [id, cam] : cameras) {
    if (cam.parent) {
      if (auto p = mounts.find(cam.parent); p != mounts.end()) cam.world_pose = p->second * cam.relative;
    }
    const double tick_s = cam.settings.sensor_tick;
    if (tick_s > 0 && t - cam.last_capture < tick_s - 1e-9) continue;
    Pose pose = cam.relative;
    if (cam.parent) {
      auto p = mounts.find(cam.parent);
      if (p == mounts.end()) continue;  // the parent is not in this frame's state (yet)
      pose = p->second * cam.relative;
    }
    Camera view = cam.settings.camera;
    view.exposure = cam.exposure.Multiplier();
    const double exposure_dt = cam.last_capture > -1e299 ? t - cam.last_capture : 0.0;
    view.pose = pose;
    view.previous_pose = cam.last_pose;
    view.noise_seed = seed ^ (static_cast<std::uint64_t>(id) << 32) ^ k;
    cam.last_capture = t;
    cam.last_pose = pose;
    bool joined = false;
    for (auto& pass : passes) {
      const auto& c = pass.camera;
      if (SameLens(c, view) && c.pose.position == view.pose.position && c.pose.orientation.coeffs() == view.pose.orientation.coeffs() &&
          c.previous_pose.has_value() == view.previous_pose.has_value()) {
        if ((view.outputs & kOutColor) && !(pass.camera.outputs & kOutColor)) TakeColourSettings(pass.camera, view);
        pass.camera.outputs |= view.outputs;
        pass.members.push_back(id);
        pass.exposure_dt.push_back(exposure_dt);
        joined = true;
        break;
      }
    }
    if (!joined) passes.push_back(CameraPass{view, {id}, {exposure_dt}});
  }
  return passes;
}

std::vector<DvsEvent> RenderState::Take(const CameraPass& pass, std::size_t i, const CameraImages& images, double t) {
  RigCamera& cam = cameras.at(pass.members.at(i));
  const Camera& v = pass.camera;
  if (images.color && (OutputsFor(cam.settings.kind) & kOutColor)) {
    cam.exposure.Update(images.color, images.width, images.height, v.exposure * std::exp2(v.exposure_compensation), v.gamma,
                        pass.exposure_dt.at(i));
  }
  if (!cam.dvs) return {};
  return cam.dvs->Update(images.color, static_cast<std::int64_t>(std::llround(t * 1e9)));
}

bool RenderState::NeedsImages(const CameraPass& pass) const {
  for (std::uint32_t id : pass.members) {
    if (cameras.at(id).ImagesChangeState()) return true;
  }
  return false;
}

void RenderState::Save(StateOut& out) const {
  out.Put(kSnapshotVersion);
  SaveWeather(out, weather);
  out.Put<std::uint64_t>(spawned.size());
  for (const auto& [id, a] : spawned) out.Put(id).Put(a.blueprint).Put(a.attributes).Put(a.parent).Put(a.transform);
  out.Put<std::uint64_t>(cameras.size());
  for (const auto& [id, c] : cameras) {
    // The settings, the exposure settings and the DVS parameters follow from blueprint and
    // attributes (ParseCamera); the rest is the camera's history.
    out.Put(id).Put(c.blueprint).Put(c.attributes).Put(c.parent).Put(c.relative).Put(c.last_capture).Put(c.last_pose).Put(c.world_pose);
    c.exposure.Save(out);
    out.Put<std::uint8_t>(c.dvs.has_value());
    if (c.dvs) c.dvs->Save(out);
  }
  out.Put<std::uint64_t>(previous_poses.size());
  for (const auto& [id, p] : previous_poses) out.Put(id).Put(p);
  debug.Save(out);
}

std::vector<std::uint8_t> RenderState::Save() const {
  StateOut out;
  Save(out);
  return std::move(out.bytes());
}

std::uint64_t RenderState::Hash() const {
  StateOut out(StateOut::Mode::kHash);
  Save(out);
  return out.hash();
}

void RenderState::Restore(const std::vector<std::uint8_t>& bytes) {
  StateIn in(bytes);
  std::uint32_t version = 0;
  in.Get(version);
  if (version != kSnapshotVersion) {
    throw std::invalid_argument("render snapshot: version " + std::to_string(version) + " is not this build's (" +
                                std::to_string(kSnapshotVersion) + ")");
  }
  RenderState s;
  RestoreWeather(in, s.weather);
  for (std::uint64_t n = in.Count(4 + 8 + 8 + 4 + 56); n > 0; --n) {
    std::uint32_t id = 0;
    SpawnedActor a;
    in.Get(id).Get(a.blueprint).Get(a.attributes).Get(a.parent).Get(a.transform);
    s.spawned[id] = std::move(a);
  }
  for (std::uint64_t n = in.Count(4 + 8 + 8 + 4 + 56); n > 0; --n) {
    std::uint32_t id = 0;
    SpawnedActor a;
    in.Get(id).Get(a.blueprint).Get(a.attributes).Get(a.parent).Get(a.transform);
    RigCamera c;
    try {
      c = MakeCamera(id, a, 0);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("render snapshot: camera " + std::to_string(id) + ": " + e.what());
    }
    in.Get(c.last_capture).Get(c.last_pose).Get(c.world_pose);
    c.exposure.Restore(in);
    std::uint8_t has_dvs = 0;
    in.Get(has_dvs);
    if ((has_dvs != 0) != c.dvs.has_value()) throw std::invalid_argument("render snapshot: camera " + std::to_string(id) + ": DVS state of another kind of camera");
    if (c.dvs) c.dvs->Restore(in);
    s.cameras[id] = std::move(c);
  }
  for (std::uint64_t n = in.Count(4 + 56); n > 0; --n) {
    std::uint32_t id = 0;
    Pose p;
    in.Get(id).Get(p);
    s.previous_poses[id] = p;
  }
  s.debug.Restore(in);
  if (!in.done()) throw std::invalid_argument("render snapshot: trailing bytes");
  *this = std::move(s);
}

}  // namespace lockstep::render
