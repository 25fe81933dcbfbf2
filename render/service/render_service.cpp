#include "render_service.h"

#include <CLI/CLI.hpp>
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
#include "lockstep/runtime/wire_geometry.h"

namespace lockstep {
namespace {

using render::ImageKind;

// The wire's geometry (runtime/wire_geometry.h, shared by every service).
render::Pose ToPose(const msg::Pose& p) { return wire::ToPose<render::Pose>(p); }
using wire::FromPose;
using wire::ToVec;

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

// A camera attribute as blueprint.idl declares it, with CARLA's default text exactly.
msg::AttributeDeclaration Declare(const render::AttributeSpec& a) {
  msg::AttributeDeclaration d;
  switch (a.type) {
    case render::AttributeType::kBool: d = blueprint::Bool(a.id, a.def == "true"); break;
    case render::AttributeType::kInt: d = blueprint::Int(a.id, std::stoll(a.def), a.min, a.max); break;
    case render::AttributeType::kFloat: d = blueprint::Float(a.id, std::stod(a.def), a.min, a.max); break;
    case render::AttributeType::kString: return blueprint::String(a.id, a.def, a.choices, !a.choices.empty());
  }
  d.default_value(a.def);
  return d;
}

render::Weather ToWeather(const msg::WeatherParameters& w) {
  return render::Weather{w.cloudiness(), w.precipitation(), w.precipitation_deposits(), w.wind_intensity(),
                         w.sun_azimuth_angle(), w.sun_altitude_angle(), w.fog_density(), w.fog_distance(), w.fog_falloff(),
                         w.wetness(), w.scattering_intensity(), w.mie_scattering_scale(), w.rayleigh_scattering_scale(),
                         w.dust_storm()};
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

render::AssetSpec ParseAssetOption(const std::string& v) {
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
  return s;
}

void AddRenderOptions(CLI::App& app, RenderOptions& o) {
  // A check that names the option and the value from a parser that throws.
  auto checked = [](std::function<void(const std::string&)> parse, std::string what) {
    return CLI::Validator(
        [parse = std::move(parse)](std::string& v) -> std::string {
          try {
            parse(v);
          } catch (const std::exception& e) {
            return e.what();
          }
          return {};
        },
        std::move(what));
  };
  app.add_option("--device", o.device, "render device: auto (a GPU if there is one), gpu or cpu")
      ->check(checked([](const std::string& v) { render::ParseDevicePreference(v); }, "auto|gpu|cpu"));
  app.add_flag("--claim-unowned", o.claim_unowned, "also render cameras spawned with no owner named");
  app.add_option("--save-dir", o.save_dir, "write a PNG of every image here (relative: under the run's output folder)");
  app.add_option("--save-every", o.save_every, "frames between saved images")
      ->check(checked(
          [](const std::string& v) {
            std::size_t used = 0;
            unsigned long long n = 0;
            try {
              n = std::stoull(v, &used);
            } catch (...) {
              used = 0;
            }
            if (used == 0 || used != v.size() || n == 0 || v[0] == '-') {
              throw std::invalid_argument("render option --save-every '" + v + "': expected a positive count");
            }
          },
          "N > 0"));
  app.add_option_function<std::vector<std::string>>(
         "--asset",
         [&o](const std::vector<std::string>& values) {
           for (const auto& v : values) o.assets.push_back(ParseAssetOption(v));
         },
         "a custom prop blueprint custom.<name> from a mesh file (OBJ, glTF, FBX): name=path[,class[,scale]]")
      ->check(checked([](const std::string& v) { ParseAssetOption(v); }, "name=path[,class[,scale]]"));
}

RenderService::RenderService(Bus& bus, std::string name, RenderOptions options)
    : bus_(bus),
      name_(std::move(name)),
      options_(std::move(options)),
      event_writer_(bus, topics::kEvent),
      declarations_(bus),
      // A replay reads the inputs of past frames: keep what the state topics keep.
      ground_(bus, topics::kGroundState, static_cast<size_t>(QosHistoryDepth(QosKind::kState))),
      air_(bus, topics::kAirState, static_cast<size_t>(QosHistoryDepth(QosKind::kState))),
      town_source_(bus) {}

RenderService::~RenderService() = default;

std::vector<msg::BlueprintDeclaration> RenderService::Blueprints() const {
  std::vector<msg::BlueprintDeclaration> out;
  for (const auto& bp : render::CameraBlueprints()) {
    std::vector<msg::AttributeDeclaration> attrs;
    for (const auto& a : bp.attributes) attrs.push_back(Declare(a));
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
  const std::shared_ptr<const Town> source = town_source_.Load(world, "render");
  const map::Map& town = source->map;
  const map::Scene& scene = source->scene;
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
  spdlog::info("town '{}': {} triangles, {} cells", source->name, renderer_->stats().static_triangles, meshes.size());
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
  // A new world: no actors, no cameras; CARLA's persistent lines go with the old one.
  state_ = render::RenderState{};
  state_.weather = ToWeather(world.weather());
  outputs_.clear();
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
      render::SpawnedActor rec;
      rec.blueprint = s.blueprint().to_string();
      for (const auto& a : s.attributes()) rec.attributes[a.key().to_string()] = a.value().to_string();
      rec.parent = s.parent();
      rec.transform = ToPose(s.transform());
      const render::RigCamera* cam = nullptr;
      try {
        cam = state_.Spawn(s.actor(), std::move(rec), Mine(s), world_.seed());
      } catch (const std::exception& e) {
        Fail(stamp, s.actor(), std::string("spawn failed: ") + e.what());
        return;
      }
      if (!cam) return;
      OpenOutput(*cam);
      spdlog::info("camera {} ({}, {}x{}, fov {}) on {} publishes on {}", s.actor(), cam->blueprint, cam->settings.camera.width,
                   cam->settings.camera.height, cam->settings.camera.fov_deg, s.parent() ? std::to_string(s.parent()) : "the world",
                   outputs_.at(s.actor()).topic);
      return;
    }
    case msg::CommandKind::CMD_DESTROY_ACTOR: {
      const uint32_t id = b.destroy_actor().actor();
      state_.Destroy(id);
      outputs_.erase(id);
      return;
    }
    case msg::CommandKind::CMD_SET_TRANSFORM:
      state_.SetTransform(b.set_transform().actor(), ToPose(b.set_transform().transform()));
      return;
    case msg::CommandKind::CMD_SET_WEATHER: state_.weather = ToWeather(b.weather()); return;
    default: return;
  }
}

// The camera's topic and writer: lockstep/sensor/image/<id>, or large_image/<id> for images
// over msg::Image's bound.
void RenderService::OpenOutput(const render::RigCamera& cam) {
  CameraOutput& out = outputs_[cam.id] = CameraOutput{};
  out.large = cam.settings.kind != ImageKind::kDvs && static_cast<std::size_t>(cam.settings.camera.width) * cam.settings.camera.height *
                                                          render::BytesPerPixel(cam.settings.kind) > render::kMaxImageBytes;
  if (out.large) {
    out.topic = topics::LargeImageTopicName(cam.id);
    out.large_writer = Writer<msg::LargeImage>(bus_, Topic<msg::LargeImage>{out.topic.c_str(), QosKind::kLargeImage});
  } else {
    out.topic = topics::ImageTopicName(cam.id);
    out.writer = Writer<msg::Image>(bus_, Topic<msg::Image>{out.topic.c_str(), QosKind::kImage});
  }
}

std::vector<uint8_t> RenderService::SaveState() const { return state_.Save(); }

// A replacement process takes over the state of the one it replaces (after BeginRun of the
// same run): the rig's cameras publish on their topics again.
void RenderService::RestoreState(const std::vector<uint8_t>& bytes) {
  try {
    state_.Restore(bytes);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("render: ") + e.what());
  }
  outputs_.clear();
  for (const auto& [id, cam] : state_.cameras) OpenOutput(cam);
}

std::string RenderService::ModelFor(const render::SpawnedActor& s, const render::Vec3& he) {
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
  return key;
}

render::WorldView RenderService::BuildWorld(const msg::GroundState* ground, const msg::AirState* air, double sim_time,
                                            std::map<uint32_t, render::Pose>* poses, std::map<uint32_t, render::Pose>* mounts) {
  render::WorldView w;
  w.weather = state_.weather;
  auto add = [&](uint32_t id, const std::string& blueprint, const render::Pose& pose, const render::Vec3& he, bool mount_at_bottom,
                 uint32_t light_state = 0) {
    (*poses)[id] = pose;
    (*mounts)[id] = mount_at_bottom ? pose * render::Pose{render::Vec3(0, 0, -he.z()), render::Quat::Identity()} : pose;
    auto it = state_.spawned.find(id);
    render::SpawnedActor s = it != state_.spawned.end() ? it->second : render::SpawnedActor{};
    if (s.blueprint.empty()) s.blueprint = blueprint;
    render::ActorDraw a;
    a.id = id;
    a.model = ModelFor(s, he);
    a.pose = pose;
    if (auto p = state_.previous_poses.find(id); p != state_.previous_poses.end()) a.previous_pose = p->second;
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
      add(d.actor(), d.blueprint().to_string(), ToPose(d.transform()), wire::DroneHalfExtents(), false);
      if (w.actors.size() > before) {
        // Rotor angle from the rotor speed at this frame's time: a pure function of the state.
        for (const auto& r : d.rotors()) w.actors.back().rotor_angles.push_back(std::fmod(r.speed() * sim_time, 2 * M_PI));
      }
    }
  }
  // Custom props: placed by their spawn transform (relative to a parent if any).
  for (const auto& [id, s] : state_.spawned) {
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
    if (auto p = state_.previous_poses.find(id); p != state_.previous_poses.end()) a.previous_pose = p->second;
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
      AddDebugDraw(state_.debug, c.body().debug_draw(), tick.frame(), tick.sim_time() - tick.dt());
    } else {
      Apply(c, tick_stamp);
    }
  }
  if (state_.cameras.empty() || world_.settings().no_rendering_mode()) return;
  // The frame whose state the images show: this tick's (strict) or the previous (pipelined).
  const uint64_t k = PerceptionFrame(world_.settings().perception_mode(), tick.frame());
  if (k == 0) return;
  msg::FrameStamp stamp;
  stamp.run(tick.run());
  stamp.frame(k);
  stamp.sim_time(tick.sim_time() - static_cast<double>(tick.frame() - k) * tick.dt());
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(options_.input_timeout_s * 1000));
  // A producer being replaced holds the wait (AwaitInput): no cascade of failures. A replay
  // reads the inputs of past frames, which the state topics keep.
  auto await = [&](auto& buffer) {
    return AwaitInput([&](std::chrono::milliseconds slice) { return buffer.WaitFor(tick.run(), k, slice); }, timeout);
  };
  std::optional<msg::GroundState> ground;
  std::optional<msg::AirState> air;
  if (wait_ground_ && !(ground = await(ground_))) {
    throw InputError("render: no GroundState of frame " + std::to_string(k) + " within " + std::to_string(options_.input_timeout_s) + " s");
  }
  if (wait_air_ && !(air = await(air_))) {
    throw InputError("render: no AirState of frame " + std::to_string(k) + " within " + std::to_string(options_.input_timeout_s) + " s");
  }
  std::map<uint32_t, render::Pose> poses, mounts;
  render::WorldView world = BuildWorld(ground ? &*ground : nullptr, air ? &*air : nullptr, stamp.sim_time(), &poses, &mounts);
  world.debug = state_.debug.Visible(k, stamp.sim_time());
  if (std::any_of(state_.cameras.begin(), state_.cameras.end(), [](const auto& c) { return c.second.settings.camera.lines_only; })) {
    world.cosmos = CosmosLines(ground ? &*ground : nullptr, world);
  }
  // The cameras due now, in passes (cameras with one pose and one lens share one).
  const std::vector<render::CameraPass> passes = state_.Plan(k, stamp.sim_time(), mounts, world_.seed());
  // A replay publishes nothing (the process it replaces did): it renders only the passes
  // whose images change a camera's state (auto-exposure, DVS), so that it ends in the
  // state the replaced process acknowledged.
  std::vector<render::Camera> views;
  std::vector<std::size_t> rendered;
  for (std::size_t i = 0; i < passes.size(); ++i) {
    if (replaying() && !state_.NeedsImages(passes[i])) continue;
    views.push_back(passes[i].camera);
    rendered.push_back(i);
  }
  if (!views.empty()) {
    renderer_->Render(views, world, [&](std::size_t j, const render::CameraImages& images) {
      const render::CameraPass& pass = passes[rendered[j]];
      for (std::size_t m = 0; m < pass.members.size(); ++m) {
        std::vector<render::DvsEvent> events = state_.Take(pass, m, images, stamp.sim_time());
        if (replaying()) continue;
        const render::RigCamera& cam = state_.cameras.at(pass.members[m]);
        Publish(cam, pass.camera, images, std::move(events), stamp);
        if (!options_.save_dir.empty() && k % options_.save_every == 0) Save(cam, images, k);
      }
    });
  }
  state_.previous_poses = std::move(poses);
}

void RenderService::Publish(const render::RigCamera& cam, const render::Camera& view, const render::CameraImages& images,
                            std::vector<render::DvsEvent> events, const msg::FrameStamp& stamp) {
  CameraOutput& out = outputs_.at(cam.id);
  msg::Image& img = out.image;
  img.sensor(cam.id);
  img.stamp(stamp);
  img.sensor_pose(FromPose(view.pose));
  img.fov(view.fov_deg * M_PI / 180);
  img.encoding(static_cast<uint32_t>(EncodingOf(cam.settings.kind)));
  const ImageKind kind = cam.settings.kind;
  if (kind == ImageKind::kDvs) {
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
  if (!out.large) {
    out.writer.Write(img);
    return;
  }
  // Over Image's bound: the same fields as a LargeImage; the pixels move over and back (no copy).
  msg::LargeImage& big = out.large_image;
  big.sensor(img.sensor());
  big.stamp(img.stamp());
  big.sensor_pose(img.sensor_pose());
  big.width(img.width());
  big.height(img.height());
  big.step(img.step());
  big.encoding(img.encoding());
  big.fov(img.fov());
  big.data().swap(img.data());
  out.large_writer.Write(big);
  big.data().swap(img.data());
}

void RenderService::Save(const render::RigCamera& cam, const render::CameraImages& images, uint64_t frame) {
  namespace fs = std::filesystem;
  const std::string role = cam.role();
  const fs::path dir = fs::path(options_.save_dir) / (std::to_string(cam.id) + (role.empty() ? "" : "_" + role) + "_" +
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
