#include "render_service.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/render/dvs.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/log.h"

namespace lockstep {
namespace {

using render::ImageKind;

render::Pose ToPose(const msg::Pose& p) {
  render::Pose out;
  out.position = render::Vec3(p.position().x(), p.position().y(), p.position().z());
  const auto& q = p.orientation();
  out.orientation = render::Quat(q.w(), q.x(), q.y(), q.z());
  if (out.orientation.norm() < 1e-9) out.orientation = render::Quat::Identity();
  out.orientation.normalize();
  return out;
}

msg::Pose FromPose(const render::Pose& p) {
  msg::Pose out;
  out.position().x(p.position.x());
  out.position().y(p.position.y());
  out.position().z(p.position.z());
  out.orientation().w(p.orientation.w());
  out.orientation().x(p.orientation.x());
  out.orientation().y(p.orientation.y());
  out.orientation().z(p.orientation.z());
  return out;
}

render::Vec3 ToVec(const msg::Vector3& v) { return {v.x(), v.y(), v.z()}; }

msg::ImageEncoding EncodingOf(ImageKind k) {
  using E = msg::ImageEncoding;
  switch (k) {
    case ImageKind::kRgb:
    case ImageKind::kAirSimScene: return E::IMAGE_BGRA8;
    case ImageKind::kDepth: return E::IMAGE_DEPTH_CARLA_BGRA8;
    case ImageKind::kDepthFloat:
    case ImageKind::kAirSimDepthPlanar: return E::IMAGE_DEPTH_F32;
    case ImageKind::kSemantic: return E::IMAGE_SEMANTIC_BGRA8;
    case ImageKind::kInstance: return E::IMAGE_INSTANCE_BGRA8;
    case ImageKind::kNormals:
    case ImageKind::kAirSimSurfaceNormals: return E::IMAGE_NORMALS_BGRA8;
    case ImageKind::kFlow: return E::IMAGE_FLOW_F32X2;
    case ImageKind::kDvs: return E::IMAGE_DVS_EVENTS;
    case ImageKind::kAirSimDepthPerspective: return E::IMAGE_DEPTH_PERSPECTIVE_F32;
    case ImageKind::kAirSimDepthVis: return E::IMAGE_GRAY8;
    case ImageKind::kAirSimDisparityNormalized: return E::IMAGE_DISPARITY_F32;
    case ImageKind::kAirSimSegmentation:
    case ImageKind::kAirSimInfrared: return E::IMAGE_INSTANCE_BGRA8;  // instances: the airsim client colours them
  }
  return E::IMAGE_BGRA8;
}

std::optional<std::array<std::uint8_t, 3>> ParseRgb(const std::string& s) {
  std::array<std::uint8_t, 3> c{};
  const char* p = s.data();
  const char* end = s.data() + s.size();
  for (int i = 0; i < 3; ++i) {
    int v = 0;
    auto [q, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || v < 0 || v > 255) return std::nullopt;
    c[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v);
    p = q;
    if (i < 2) {
      if (p == end || *p != ',') return std::nullopt;
      ++p;
    }
  }
  return c;
}

double Attr(const std::map<std::string, std::string>& a, const char* key, double def) {
  auto it = a.find(key);
  if (it == a.end()) return def;
  try {
    return std::stod(it->second);
  } catch (...) {
    return def;
  }
}

}  // namespace

struct RenderService::CameraRecord {
  uint32_t id = 0;
  render::CameraSettings settings;
  uint32_t parent = 0;
  render::Pose relative;
  std::string role;
  std::string topic;
  Writer<msg::Image> writer;             // images within msg::Image's bound ...
  Writer<msg::LargeImage> large_writer;  // ... or over it (render::kMaxImageBytes): lockstep/sensor/large_image/<id>
  bool large = false;
  double last_capture = -1e300;
  std::optional<render::Pose> last_pose;
  std::optional<render::Pose> world_pose;  // at the last frame drawn that found its parent
  std::unique_ptr<render::DvsSensor> dvs;
  render::AutoExposure exposure;  // colour cameras: adapts from image to image (histogram mode)
  double exposure_dt = 0;         // s of simulated time since the camera's previous image
  msg::Image image;  // reused: its buffer keeps its capacity from frame to frame
  msg::LargeImage large_image;
};

RenderOptions ParseRenderOptions(int* argc, char** argv) {
  RenderOptions o;
  int out = 1;
  for (int i = 1; i < *argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= *argc) throw std::invalid_argument("render option " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--device") {
      o.device = value();
      render::ParseDevicePreference(o.device);
    } else if (a == "--claim-unowned") {
      o.claim_unowned = true;
    } else if (a == "--save-dir") {
      o.save_dir = value();
    } else if (a == "--save-every") {
      const std::string v = value();
      try {
        o.save_every = std::stoull(v);
      } catch (...) {
        o.save_every = 0;
      }
      if (o.save_every == 0) throw std::invalid_argument("render option --save-every '" + v + "': expected a positive count");
    } else if (a == "--asset") {
      // name=path[,class[,scale]]
      const std::string v = value();
      const auto eq = v.find('=');
      if (eq == std::string::npos || eq == 0) throw std::invalid_argument("render option --asset '" + v + "': expected name=path[,class[,scale]]");
      render::AssetSpec s;
      s.name = v.substr(0, eq);
      std::string rest = v.substr(eq + 1);
      const auto c1 = rest.find(',');
      s.path = rest.substr(0, c1);
      if (c1 != std::string::npos) {
        std::string cls = rest.substr(c1 + 1);
        const auto c2 = cls.find(',');
        if (c2 != std::string::npos) {
          try {
            s.scale = std::stod(cls.substr(c2 + 1));
          } catch (...) {
            throw std::invalid_argument("render option --asset '" + v + "': bad scale");
          }
          cls = cls.substr(0, c2);
        }
        const int tag = render::ClassFromName(cls);
        if (tag < 0) throw std::invalid_argument("render option --asset '" + v + "': unknown semantic class '" + cls + "'");
        s.tag = static_cast<std::uint8_t>(tag);
      }
      o.assets.push_back(s);
    } else {
      argv[out++] = argv[i];
    }
  }
  *argc = out;
  return o;
}

RenderService::RenderService(Bus& bus, std::string name, RenderOptions options)
    : bus_(bus),
      name_(std::move(name)),
      options_(std::move(options)),
      event_writer_(bus, topics::kEvent),
      declarations_(bus),
      ground_(bus, topics::kGroundState),
      air_(bus, topics::kAirState),
      map_reader_(bus, topics::kMap, [this](const msg::MapData& m, const SampleInfo&) {
        {
          std::lock_guard<std::mutex> lock(map_mu_);
          map_ = m;
        }
        map_cv_.notify_all();
      }) {}

RenderService::~RenderService() = default;

std::vector<msg::BlueprintDeclaration> RenderService::Blueprints() const {
  std::vector<msg::BlueprintDeclaration> out;
  for (const auto& bp : render::CameraBlueprints()) {
    std::vector<msg::AttributeDeclaration> attrs;
    for (const auto& a : bp.attributes) {
      switch (a.type) {
        case 'b': attrs.push_back(blueprint::Bool(a.id, a.def == "true")); break;
        case 'i': attrs.push_back(blueprint::Int(a.id, std::stoll(a.def), a.min, a.max)); break;
        case 'f': attrs.push_back(blueprint::Float(a.id, std::stod(a.def), a.min, a.max)); break;
        default: attrs.push_back(blueprint::String(a.id, a.def, a.choices, !a.choices.empty())); break;
      }
    }
    out.push_back(blueprint::Make(bp.id, msg::ActorKind::ACTOR_SENSOR, attrs));
  }
  for (const auto& asset : options_.assets) {
    // The bounding box comes from the file, so ground physics and sensors see it.
    render::Vec3 he = render::Vec3::Zero();
    try {
      he = render::ImportAsset(asset).half_extents;
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      continue;
    }
    out.push_back(blueprint::Make("custom." + asset.name, msg::ActorKind::ACTOR_PROP, {blueprint::String("role_name", "")},
                                  std::string("custom,") + asset.name + "," + render::ClassName(asset.tag), he.x(), he.y(), he.z()));
  }
  return out;
}

std::string RenderService::CheckSpawn(const msg::SpawnActor& spawn) const {
  const std::string bp = spawn.blueprint().to_string();
  if (!render::IsCameraBlueprint(bp)) return {};
  std::map<std::string, std::string> attrs;
  for (const auto& a : spawn.attributes()) attrs[a.key().to_string()] = a.value().to_string();
  try {
    render::ParseCamera(bp, attrs);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

void RenderService::LoadTown(const msg::WorldInfo& world) {
  if (world.map_name().to_string().empty()) {
    renderer_->SetStaticScene({});
    town_hash_ = 0;
    return;
  }
  if (world.map_hash() == town_hash_) return;
  std::optional<msg::MapData> data;
  {
    std::unique_lock<std::mutex> lock(map_mu_);
    map_cv_.wait_for(lock, std::chrono::seconds(30), [&] { return map_ && map_->content_hash() == world.map_hash(); });
    if (map_ && map_->content_hash() == world.map_hash()) data = map_;
  }
  if (!data) throw InputError("render: no map '" + world.map_name().to_string() + "' from the coordinator within 30 s");
  const map::Map town = map::Map::FromString(data->opendrive(), data->name().to_string());
  const map::Scene scene = data->scene().empty() ? map::GenerateScene(town, world.seed())
                                                 : map::SceneFromYaml(data->scene(), data->name().to_string() + ".scene.yaml");
  const auto meshes = map::BuildWorldMeshes(town, scene);
  renderer_->SetStaticScene(meshes, render::StreetLamps(scene));
  // The cosmos camera's lines of the map (CARLA's CosmosControlSensor: lane routes outside
  // junctions, 20 cm, blue; crosswalk outlines, orange).
  cosmos_map_ = render::DebugDrawList{};
  for (const auto& w : town.GenerateWaypoints(2.0)) {
    if (w.IsJunction()) continue;
    for (const auto& n : town.Next(w, 2.0)) {
      if (!n.IsJunction()) cosmos_map_.lines.push_back({w.transform.location, n.transform.location, 0.2, {71, 134, 183}});
    }
  }
  for (const auto& zone : town.Crosswalks()) {
    for (std::size_t i = 1; i < zone.size(); ++i) cosmos_map_.lines.push_back({zone[i - 1], zone[i], 0.2, {202, 132, 58}});
  }
  light_heads_.clear();
  for (const auto& p : scene.props) {
    if (p.kind == "traffic_light" && !p.ref.empty()) light_heads_[p.ref] = {p.height > 0 ? p.height : 3.0, p.yaw};
  }
  town_hash_ = world.map_hash();
  spdlog::info("town '{}': {} triangles, {} cells", data->name().to_string(), renderer_->stats().static_triangles, meshes.size());
}

void RenderService::BeginRun(const msg::WorldInfo& world) {
  if (!renderer_) {
    renderer_ = std::make_unique<render::Renderer>(render::ParseDevicePreference(options_.device));
    const auto& d = renderer_->device();
    spdlog::info("render device: {} ({} platform; GL_RENDERER {}; {})", d.name, d.platform, d.gl_renderer, d.gl_version);
    for (const auto& asset : options_.assets) {
      try {
        renderer_->AddModel("custom." + asset.name, render::ImportAsset(asset));
      } catch (const std::exception& e) {
        spdlog::error("{}", e.what());
      }
    }
  }
  LoadTown(world);
  world_ = world;
  const auto& w = world.weather();
  weather_ = render::Weather{w.cloudiness(), w.precipitation(), w.precipitation_deposits(), w.wind_intensity(),
                             w.sun_azimuth_angle(), w.sun_altitude_angle(), w.fog_density(), w.fog_distance(), w.fog_falloff(),
                             w.wetness(), w.scattering_intensity(), w.mie_scattering_scale(), w.rayleigh_scattering_scale(),
                             w.dust_storm()};
  // Whose state to wait for: the required services that simulate vehicles or walkers
  // (GroundState) and drones (AirState), found by what they declare, not by their names.
  const auto required = RequiredServices(world);
  if (!declarations_.WaitFor(required, std::chrono::seconds(30))) {
    throw InputError("render: the required services did not all declare their blueprints within 30 s");
  }
  wait_ground_ = declarations_.AnyDeclares(msg::ActorKind::ACTOR_VEHICLE, required) ||
                 declarations_.AnyDeclares(msg::ActorKind::ACTOR_WALKER, required);
  wait_air_ = declarations_.AnyDeclares(msg::ActorKind::ACTOR_DRONE, required);
  spdlog::info("run {}: state from {}{}", world.run(), wait_ground_ ? "GroundState " : "", wait_air_ ? "AirState" : "");
  spawned_.clear();
  cameras_.clear();
  previous_poses_.clear();
  debug_.Clear();  // a new world: CARLA's persistent lines go with the old one
}

// CARLA's CosmosControlSensor: each vehicle's box red, each walker's green, traffic light
// heads grey-green (10 cm lines), over the map's lanes and crosswalks.
render::DebugDrawList RenderService::CosmosLines(const msg::GroundState* ground, const render::WorldView& world) const {
  render::DebugDrawList out = cosmos_map_;
  if (ground) {
    for (const auto& v : ground->vehicles()) out.AddBox(ToPose(v.transform()), ToVec(v.half_extents()), 0.1, {255, 0, 0});
    for (const auto& w : ground->walkers()) out.AddBox(ToPose(w.transform()), ToVec(w.half_extents()), 0.1, {0, 255, 0});
  }
  for (const auto& t : world.traffic_lights) {
    render::Pose head = t.pose;
    head.position += head.orientation * render::Vec3(0.18, 0, t.height + 0.42);
    out.AddBox(head, render::Vec3(0.05, 0.2, 0.5), 0.1, {109, 144, 136});
  }
  return out;
}

// world.debug shapes of a tick issued at `issued` (the frame before it, when the client
// drew them). Strings and HUD shapes are for CARLA's spectator HUD, which no camera shows.
// flush_persistent (AirSim's simFlushPersistentMarkers: Unreal's FlushPersistentDebugLines)
// first erases every world shape drawn so far: Unreal's persistent line batcher holds the
// persistent shapes and the timed ones alike (DrawDebugHelpers' GetDebugLineBatcher), and
// CARLA draws all of its shapes into it; only a shape drawn for one frame is elsewhere, and
// such a shape, drawn before this tick, is already gone.
void AddDebugDraw(render::DebugShapes& shapes, const msg::DebugDraw& d, uint64_t first_frame, double issued) {
  if (d.flush_persistent()) shapes.Clear();
  for (const auto& s : d.shapes()) {
    if (s.hud()) continue;
    const render::DebugColor c{s.r(), s.g(), s.b()};
    render::DebugDrawList list;
    switch (s.kind()) {
      case msg::DebugShapeKind::DEBUG_POINT:
        shapes.AddPoint(render::DebugPoint{ToVec(s.begin()), s.size(), c}, first_frame, issued, s.life_time());
        continue;
      case msg::DebugShapeKind::DEBUG_LINE: list.lines.push_back({ToVec(s.begin()), ToVec(s.end()), s.size(), c}); break;
      case msg::DebugShapeKind::DEBUG_ARROW: list.AddArrow(ToVec(s.begin()), ToVec(s.end()), s.size(), s.arrow_size(), c); break;
      case msg::DebugShapeKind::DEBUG_BOX: {
        msg::Pose p;
        p.position(s.begin());
        p.orientation(s.rotation());
        list.AddBox(ToPose(p), ToVec(s.extent()), s.size(), c);
        break;
      }
      case msg::DebugShapeKind::DEBUG_STRING: continue;
    }
    for (const auto& l : list.lines) shapes.AddLine(l, first_frame, issued, s.life_time());
  }
}

void RenderService::AddDebugShapes(const msg::DebugDraw& d, uint64_t first_frame, double issued) {
  AddDebugDraw(debug_, d, first_frame, issued);
}

bool RenderService::Mine(const msg::SpawnActor& s) const {
  const std::string owner = s.owner().to_string();
  return owner == name_ || (owner.empty() && options_.claim_unowned);
}

void RenderService::Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why) {
  spdlog::warn("actor {}: {}", actor, why);
  if (replaying()) return;
  msg::SimEvent e;
  e.stamp(stamp);
  e.service(name_);
  e.kind(msg::EventKind::EVENT_COMMAND_FAILED);
  e.actor(actor);
  e.message(why.substr(0, 511));
  event_writer_.Write(e);
}

void RenderService::Apply(const msg::Command& c, const msg::FrameStamp& stamp) {
  const auto& b = c.body();
  switch (b._d()) {
    case msg::CommandKind::CMD_SPAWN_ACTOR: {
      const auto& s = b.spawn_actor();
      Spawned rec;
      rec.blueprint = s.blueprint().to_string();
      for (const auto& a : s.attributes()) rec.attributes[a.key().to_string()] = a.value().to_string();
      rec.parent = s.parent();
      rec.transform = ToPose(s.transform());
      spawned_[s.actor()] = rec;
      if (!render::IsCameraBlueprint(rec.blueprint) || !Mine(s)) return;
      auto cam = std::make_unique<CameraRecord>();
      try {
        cam->settings = render::ParseCamera(rec.blueprint, rec.attributes);
      } catch (const std::exception& e) {
        Fail(stamp, s.actor(), std::string("spawn failed: ") + e.what());
        return;
      }
      cam->id = s.actor();
      cam->parent = s.parent();
      cam->relative = rec.transform;
      cam->exposure = render::AutoExposure(cam->settings.exposure);
      cam->role = rec.attributes.count("role_name") ? rec.attributes["role_name"] : "";
      cam->large = cam->settings.kind != ImageKind::kDvs &&
                   static_cast<std::size_t>(cam->settings.camera.width) * cam->settings.camera.height *
                           render::BytesPerPixel(cam->settings.kind) > render::kMaxImageBytes;
      if (cam->large) {
        cam->topic = topics::LargeImageTopicName(s.actor());
        cam->large_writer = Writer<msg::LargeImage>(bus_, Topic<msg::LargeImage>{cam->topic.c_str(), QosKind::kLargeImage});
      } else {
        cam->topic = topics::ImageTopicName(s.actor());
        cam->writer = Writer<msg::Image>(bus_, Topic<msg::Image>{cam->topic.c_str(), QosKind::kImage});
      }
      if (cam->settings.kind == ImageKind::kDvs) {
        cam->dvs = std::make_unique<render::DvsSensor>(cam->settings.dvs, cam->settings.camera.width, cam->settings.camera.height,
                                                       world_.seed() ^ s.actor());
      }
      spdlog::info("camera {} ({}, {}x{}, fov {}) on {} publishes on {}", s.actor(), rec.blueprint, cam->settings.camera.width,
                   cam->settings.camera.height, cam->settings.camera.fov_deg, s.parent() ? std::to_string(s.parent()) : "the world",
                   cam->topic);
      cameras_[s.actor()] = std::move(cam);
      return;
    }
    case msg::CommandKind::CMD_DESTROY_ACTOR: {
      const uint32_t id = b.destroy_actor().actor();
      spawned_.erase(id);
      cameras_.erase(id);
      // CARLA destroys only the actor; Unreal detaches its cameras keeping their world
      // transform: they stay and draw from where they were.
      for (auto& [cid, cam] : cameras_) {
        if (cam->parent != id) continue;
        cam->parent = 0;
        if (cam->world_pose) cam->relative = *cam->world_pose;
        if (auto r = spawned_.find(cid); r != spawned_.end()) r->second.parent = 0, r->second.transform = cam->relative;
      }
      return;
    }
    case msg::CommandKind::CMD_SET_TRANSFORM: {
      const uint32_t id = b.set_transform().actor();
      auto it = spawned_.find(id);
      if (it != spawned_.end()) it->second.transform = ToPose(b.set_transform().transform());
      auto cam = cameras_.find(id);
      if (cam != cameras_.end()) cam->second->relative = ToPose(b.set_transform().transform());
      return;
    }
    case msg::CommandKind::CMD_SET_WEATHER: {
      const auto& w = b.weather();
      weather_ = render::Weather{w.cloudiness(), w.precipitation(), w.precipitation_deposits(), w.wind_intensity(),
                                 w.sun_azimuth_angle(), w.sun_altitude_angle(), w.fog_density(), w.fog_distance(), w.fog_falloff(),
                                 w.wetness(), w.scattering_intensity(), w.mie_scattering_scale(), w.rayleigh_scattering_scale(),
                                 w.dust_storm()};
      return;
    }
    default: return;
  }
}

std::string RenderService::ModelFor(uint32_t id, const Spawned& s, const render::Vec3& he) {
  char ext[64];
  std::snprintf(ext, sizeof ext, "%.3f,%.3f,%.3f", he.x(), he.y(), he.z());
  std::string key;
  const std::string& bp = s.blueprint;
  if (bp.rfind("vehicle.", 0) == 0) {
    const std::string style = render::VehicleStyleFor(bp);
    key = "vehicle:" + style + ":" + ext;
    if (!renderer_->HasModel(key)) renderer_->AddModel(key, render::BuildVehicle(style, he));
  } else if (bp.rfind("walker.", 0) == 0) {
    const int variant = render::WalkerVariant(bp);
    key = "walker:" + std::to_string(variant) + ":" + ext;
    if (!renderer_->HasModel(key)) renderer_->AddModel(key, render::BuildWalker(variant, he));
  } else if (bp.rfind("drone.", 0) == 0) {
    render::DroneShape d;
    auto f = s.attributes.find("frame");
    d.frame = f != s.attributes.end() ? f->second : (bp == "drone.quad_plus" ? "quad_plus" : bp == "drone.hexa_x" ? "hexa_x" : "quad_x");
    d.arm_length = Attr(s.attributes, "arm_length", d.arm_length);
    d.propeller_diameter = Attr(s.attributes, "rotor.propeller_diameter", d.propeller_diameter);
    d.rotor_z = Attr(s.attributes, "rotor_z", d.rotor_z);
    char k[160];
    std::snprintf(k, sizeof k, "drone:%s:%.4f:%.4f:%.4f", d.frame.c_str(), d.arm_length, d.propeller_diameter, d.rotor_z);
    key = k;
    if (!renderer_->HasModel(key)) renderer_->AddModel(key, render::BuildDrone(d));
  } else {
    key = bp;  // custom.<name>
  }
  (void)id;
  return key;
}

render::WorldView RenderService::BuildWorld(const msg::GroundState* ground, const msg::AirState* air, double sim_time,
                                            std::map<uint32_t, render::Pose>* poses, std::map<uint32_t, render::Pose>* mounts) {
  render::WorldView w;
  w.weather = weather_;
  auto add = [&](uint32_t id, const std::string& blueprint, const render::Pose& pose, const render::Vec3& he, bool mount_at_bottom,
                 uint32_t light_state = 0) {
    (*poses)[id] = pose;
    (*mounts)[id] = mount_at_bottom ? pose * render::Pose{render::Vec3(0, 0, -he.z()), render::Quat::Identity()} : pose;
    auto it = spawned_.find(id);
    Spawned s = it != spawned_.end() ? it->second : Spawned{};
    if (s.blueprint.empty()) s.blueprint = blueprint;
    render::ActorDraw a;
    a.id = id;
    a.model = ModelFor(id, s, he);
    a.pose = pose;
    if (auto p = previous_poses_.find(id); p != previous_poses_.end()) a.previous_pose = p->second;
    auto color = s.attributes.find("color");
    auto rgb = color != s.attributes.end() ? ParseRgb(color->second) : std::nullopt;
    a.paint = rgb ? *rgb : render::DefaultPaint(id);
    a.light_state = light_state;  // CARLA: a vehicle's lights are off until a client or the TM sets them
    w.actors.push_back(std::move(a));
  };
  if (ground) {
    for (const auto& v : ground->vehicles()) {
      add(v.actor(), v.blueprint().to_string(), ToPose(v.transform()), ToVec(v.half_extents()), true, v.light_state());
    }
    for (const auto& v : ground->walkers()) add(v.actor(), v.blueprint().to_string(), ToPose(v.transform()), ToVec(v.half_extents()), true);
    for (const auto& t : ground->traffic_lights()) {
      render::TrafficLightDraw d;
      d.id = t.actor();
      d.pose = ToPose(t.transform());
      auto head = light_heads_.find(t.opendrive_id().to_string());
      if (head != light_heads_.end()) {
        d.height = head->second.first;
        d.pose.orientation = render::Quat(Eigen::AngleAxisd(head->second.second, render::Vec3::UnitZ()));
      }
      switch (t.state()) {
        case msg::TrafficLightColor::LIGHT_RED: d.state = 0; break;
        case msg::TrafficLightColor::LIGHT_YELLOW: d.state = 1; break;
        case msg::TrafficLightColor::LIGHT_GREEN: d.state = 2; break;
        default: d.state = 3; break;
      }
      (*mounts)[t.actor()] = d.pose;
      w.traffic_lights.push_back(d);
    }
  }
  if (air) {
    for (const auto& d : air->drones()) {
      const std::size_t before = w.actors.size();
      add(d.actor(), d.blueprint().to_string(), ToPose(d.transform()), render::Vec3(0.3, 0.3, 0.1), false);
      if (w.actors.size() > before) {
        // Rotor angle from the rotor speed at this frame's time: a pure function of the state.
        for (const auto& r : d.rotors()) w.actors.back().rotor_angles.push_back(std::fmod(r.speed() * sim_time, 2 * M_PI));
      }
    }
  }
  // Custom props: placed by their spawn transform (relative to a parent if any).
  for (const auto& [id, s] : spawned_) {
    if (s.blueprint.rfind("custom.", 0) != 0 || !renderer_->HasModel(s.blueprint)) continue;
    render::Pose pose = s.transform;
    if (s.parent) {
      auto p = mounts->find(s.parent);
      if (p == mounts->end()) continue;
      pose = p->second * s.transform;
    }
    (*poses)[id] = pose;
    (*mounts)[id] = pose;
    render::ActorDraw a;
    a.id = id;
    a.model = s.blueprint;
    a.pose = pose;
    a.cull_faces = false;
    if (auto p = previous_poses_.find(id); p != previous_poses_.end()) a.previous_pose = p->second;
    w.actors.push_back(a);
  }
  return w;
}

void RenderService::Step(const msg::Tick& tick) {
  msg::FrameStamp tick_stamp;
  tick_stamp.run(tick.run());
  tick_stamp.frame(tick.frame());
  tick_stamp.sim_time(tick.sim_time());
  for (const auto& c : tick.commands()) {
    if (c.body()._d() == msg::CommandKind::CMD_DEBUG_DRAW) {
      AddDebugShapes(c.body().debug_draw(), tick.frame(), tick.sim_time() - tick.dt());
    } else {
      Apply(c, tick_stamp);
    }
  }
  if (replaying() || cameras_.empty() || world_.settings().no_rendering_mode()) return;
  // The frame whose state the images show: this tick's (strict) or the previous (pipelined).
  const uint64_t k = PerceptionFrame(world_.settings().perception_mode(), tick.frame());
  if (k == 0) return;
  msg::FrameStamp stamp;
  stamp.run(tick.run());
  stamp.frame(k);
  stamp.sim_time(tick.sim_time() - static_cast<double>(tick.frame() - k) * tick.dt());
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(options_.input_timeout_s * 1000));
  std::optional<msg::GroundState> ground;
  std::optional<msg::AirState> air;
  if (wait_ground_ && !(ground = ground_.WaitFor(tick.run(), k, timeout))) {
    throw InputError("render: no GroundState of frame " + std::to_string(k) + " within " + std::to_string(options_.input_timeout_s) + " s");
  }
  if (wait_air_ && !(air = air_.WaitFor(tick.run(), k, timeout))) {
    throw InputError("render: no AirState of frame " + std::to_string(k) + " within " + std::to_string(options_.input_timeout_s) + " s");
  }
  std::map<uint32_t, render::Pose> poses, mounts;
  render::WorldView world = BuildWorld(ground ? &*ground : nullptr, air ? &*air : nullptr, stamp.sim_time(), &poses, &mounts);
  world.debug = debug_.Visible(k, stamp.sim_time());
  if (std::any_of(cameras_.begin(), cameras_.end(), [](const auto& c) { return c.second->settings.camera.lines_only; })) {
    world.cosmos = CosmosLines(ground ? &*ground : nullptr, world);
  }
  // Cameras due now, grouped: cameras with one pose and one lens share a pass.
  struct Pass {
    render::Camera camera;
    std::vector<CameraRecord*> members;
  };
  std::vector<Pass> passes;
  for (auto& [id, cam] : cameras_) {
    if (cam->parent) {
      if (auto p = mounts.find(cam->parent); p != mounts.end()) cam->world_pose = p->second * cam->relative;
    }
    const double tick_s = cam->settings.sensor_tick;
    if (tick_s > 0 && stamp.sim_time() - cam->last_capture < tick_s - 1e-9) continue;
    render::Pose pose = cam->relative;
    if (cam->parent) {
      auto p = mounts.find(cam->parent);
      if (p == mounts.end()) continue;  // the parent is not in this frame's state (yet)
      pose = p->second * cam->relative;
    }
    render::Camera view = cam->settings.camera;
    view.exposure = cam->exposure.Multiplier();
    cam->exposure_dt = cam->last_capture > -1e299 ? stamp.sim_time() - cam->last_capture : 0.0;
    view.pose = pose;
    view.previous_pose = cam->last_pose;
    view.noise_seed = world_.seed() ^ (static_cast<uint64_t>(id) << 32) ^ k;
    cam->last_capture = stamp.sim_time();
    cam->last_pose = pose;
    bool joined = false;
    for (auto& pass : passes) {
      const auto& c = pass.camera;
      if (render::SameLens(c, view) && c.pose.position == view.pose.position &&
          c.pose.orientation.coeffs() == view.pose.orientation.coeffs() &&
          c.previous_pose.has_value() == view.previous_pose.has_value()) {
        if ((view.outputs & render::kOutColor) && !(pass.camera.outputs & render::kOutColor)) render::TakeColourSettings(pass.camera, view);
        pass.camera.outputs |= view.outputs;
        pass.members.push_back(cam.get());
        joined = true;
        break;
      }
    }
    if (!joined) passes.push_back(Pass{view, {cam.get()}});
  }
  std::vector<render::Camera> views;
  for (const auto& p : passes) views.push_back(p.camera);
  renderer_->Render(views, world, [&](std::size_t i, const render::CameraImages& images) {
    for (CameraRecord* cam : passes[i].members) {
      const render::Camera& v = passes[i].camera;
      if (images.color && (render::OutputsFor(cam->settings.kind) & render::kOutColor)) {
        cam->exposure.Update(images.color, images.width, images.height, v.exposure * std::exp2(v.exposure_compensation), v.gamma,
                             cam->exposure_dt);
      }
      Publish(*cam, passes[i].camera, images, stamp);
      if (!options_.save_dir.empty() && k % options_.save_every == 0) Save(*cam, images, k);
    }
  });
  previous_poses_ = std::move(poses);
}

void RenderService::Publish(CameraRecord& cam, const render::Camera& view, const render::CameraImages& images,
                            const msg::FrameStamp& stamp) {
  msg::Image& img = cam.image;
  img.sensor(cam.id);
  img.stamp(stamp);
  img.sensor_pose(FromPose(view.pose));
  img.fov(view.fov_deg * M_PI / 180);
  img.encoding(static_cast<uint32_t>(EncodingOf(cam.settings.kind)));
  const ImageKind kind = cam.settings.kind;
  if (kind == ImageKind::kDvs) {
    auto events = cam.dvs->Update(images.color, static_cast<std::int64_t>(std::llround(stamp.sim_time() * 1e9)));
    if (events.size() * 16 > render::kMaxImageBytes) events.resize(render::kMaxImageBytes / 16);  // the type's bound
    img.data(render::DvsSensor::Pack(events));
    img.width(static_cast<uint32_t>(events.size()));
    img.height(1);
    img.step(static_cast<uint32_t>(events.size() * 16));
  } else {
    const int bpp = render::BytesPerPixel(kind);
    img.width(static_cast<uint32_t>(images.width));
    img.height(static_cast<uint32_t>(images.height));
    img.step(static_cast<uint32_t>(images.width * bpp));
    img.data().resize(static_cast<std::size_t>(images.width) * images.height * bpp);
    render::EncodeImage(kind, view, images, img.data().data());
    if (kind == ImageKind::kSemantic && cam.settings.paper_classes) {
      for (std::size_t i = 2; i < img.data().size(); i += 4) img.data()[i] = render::ToPaperClass(img.data()[i]);
    }
  }
  if (!cam.large) {
    cam.writer.Write(img);
    return;
  }
  // Over Image's bound: the same fields as a LargeImage; the pixels move over and back (no copy).
  msg::LargeImage& big = cam.large_image;
  big.sensor(img.sensor());
  big.stamp(img.stamp());
  big.sensor_pose(img.sensor_pose());
  big.width(img.width());
  big.height(img.height());
  big.step(img.step());
  big.encoding(img.encoding());
  big.fov(img.fov());
  big.data().swap(img.data());
  cam.large_writer.Write(big);
  big.data().swap(img.data());
}

void RenderService::Save(const CameraRecord& cam, const render::CameraImages& images, uint64_t frame) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(options_.save_dir) / (std::to_string(cam.id) + (cam.role.empty() ? "" : "_" + cam.role) + "_" +
                                                       render::ImageKindName(cam.settings.kind));
  std::error_code ec;
  fs::create_directories(dir, ec);
  char name[32];
  std::snprintf(name, sizeof name, "%08llu.png", static_cast<unsigned long long>(frame));
  std::vector<std::uint8_t> bgra;
  const int w = images.width, h = images.height;
  switch (cam.settings.kind) {
    case ImageKind::kSemantic:
    case ImageKind::kInstance:
    case ImageKind::kAirSimSegmentation:
    case ImageKind::kAirSimInfrared: bgra = render::SemanticToPalette(images.labels, w, h); break;
    case ImageKind::kDepth:
    case ImageKind::kDepthFloat:
    case ImageKind::kAirSimDepthPlanar:
    case ImageKind::kAirSimDepthPerspective:
    case ImageKind::kAirSimDepthVis:
    case ImageKind::kAirSimDisparityNormalized: bgra = render::DepthToGray(images.depth, w, h); break;
    case ImageKind::kNormals:
    case ImageKind::kAirSimSurfaceNormals: bgra.assign(images.normals, images.normals + static_cast<std::size_t>(w) * h * 4); break;
    case ImageKind::kFlow: bgra = render::FlowToColor(images.flow, w, h); break;
    default: bgra.assign(images.color, images.color + static_cast<std::size_t>(w) * h * 4); break;
  }
  cv::Mat m(h, w, CV_8UC4, bgra.data());
  if (!cv::imwrite((dir / name).string(), m)) spdlog::warn("could not write {}", (dir / name).string());
}

}  // namespace lockstep
