#include "sensors_service.h"

#include <algorithm>
#include <filesystem>

#include "lockstep/map/scene_mesh.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/log.h"
#include "frame_actors.h"

namespace lockstep {

namespace {

namespace s = sensors;

using wire::FromPose;
using wire::FromQuat;
using wire::FromVec;
using wire::ToVec;
s::Pose ToPose(const msg::Pose& p) { return s::FromWire(p); }
msg::ObjectKind ToWire(s::HitKind k) { return wire::ObjectKindToWire(k); }
s::HitKind FromWire(msg::ObjectKind k) {
  switch (k) {
    case msg::ObjectKind::OBJECT_NONE: return s::HitKind::kNone;
    case msg::ObjectKind::OBJECT_GROUND: return s::HitKind::kGround;
    case msg::ObjectKind::OBJECT_STATIC: return s::HitKind::kStatic;
    case msg::ObjectKind::OBJECT_VEHICLE: return s::HitKind::kVehicle;
    case msg::ObjectKind::OBJECT_WALKER: return s::HitKind::kWalker;
    case msg::ObjectKind::OBJECT_DRONE: return s::HitKind::kDrone;
  }
  return s::HitKind::kNone;
}
msg::LaneMarking ToWire(const s::LaneMarking& m) {
  msg::LaneMarking out;
  out.type(static_cast<msg::LaneMarkingType>(m.type));
  out.color(m.color);
  out.width(m.width);
  out.lane_change_left(m.lane_change_left);
  out.lane_change_right(m.lane_change_right);
  return out;
}

msg::AttributeDeclaration Declare(const s::AttributeSpec& a) {
  switch (a.type) {
    case s::AttrType::kBool: return blueprint::Bool(a.id, a.default_value == "true");
    case s::AttrType::kInt: return blueprint::Int(a.id, std::stoll(a.default_value), a.min, a.max);
    case s::AttrType::kFloat: {
      msg::AttributeDeclaration d = blueprint::Float(a.id, std::stod(a.default_value), a.min, a.max);
      d.default_value(a.default_value);  // the exact default, not a 6-digit rendering
      return d;
    }
    case s::AttrType::kString: return blueprint::String(a.id, a.default_value, a.choices, !a.choices.empty());
  }
  return blueprint::String(a.id, a.default_value);
}

}  // namespace

PhysicsEventsBuffer::PhysicsEventsBuffer(Bus& bus, size_t capacity)
    : capacity_(capacity), reader_(bus, topics::kPhysicsEvents, [this](const msg::PhysicsEvents& e, const SampleInfo&) {
        {
          std::lock_guard<std::mutex> lock(mu_);
          batches_[Key{e.stamp().run(), e.stamp().frame()}][e.service().to_string()] = e;
          while (batches_.size() > capacity_) batches_.erase(batches_.begin());
        }
        cv_.notify_all();
      }) {}

std::optional<std::vector<msg::PhysicsEvents>> PhysicsEventsBuffer::WaitFor(uint32_t run, uint64_t frame, const std::set<std::string>& from,
                                                                            std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  const Key key{run, frame};
  auto complete = [&] {
    auto it = batches_.find(key);
    if (it == batches_.end()) return from.empty();
    for (const auto& s : from) {
      if (!it->second.count(s)) return false;
    }
    return true;
  };
  if (!cv_.wait_for(lock, timeout, complete)) return std::nullopt;
  std::vector<msg::PhysicsEvents> out;
  if (auto it = batches_.find(key); it != batches_.end()) {
    for (const auto& s : from) out.push_back(it->second.at(s));  // in service-name order: deterministic
  }
  return out;
}

SensorsService::SensorsService(Bus& bus, std::string name, SensorsOptions options)
    : name_(std::move(name)),
      options_(std::move(options)),
      point_cloud_writer_(bus, topics::kPointCloud),
      radar_writer_(bus, topics::kRadar),
      imu_writer_(bus, topics::kImu),
      gnss_writer_(bus, topics::kGnss),
      barometer_writer_(bus, topics::kBarometer),
      magnetometer_writer_(bus, topics::kMagnetometer),
      distance_writer_(bus, topics::kDistance),
      obstacle_writer_(bus, topics::kObstacle),
      collision_writer_(bus, topics::kCollision),
      lane_invasion_writer_(bus, topics::kLaneInvasion),
      v2x_writer_(bus, topics::kV2X),
      event_writer_(bus, topics::kEvent),
      declarations_(bus),
      // The inputs of the frames the state topics keep: a replacement replays from them.
      ground_(bus, topics::kGroundState, static_cast<size_t>(QosHistoryDepth(QosKind::kState))),
      air_(bus, topics::kAirState, static_cast<size_t>(QosHistoryDepth(QosKind::kState))),
      events_(bus, static_cast<size_t>(QosHistoryDepth(QosKind::kState))),
      town_source_(bus) {}

SensorsService::~SensorsService() = default;

std::vector<msg::BlueprintDeclaration> SensorsService::Blueprints() const {
  std::vector<msg::BlueprintDeclaration> out;
  for (const auto& bp : s::SensorBlueprints()) {
    std::vector<msg::AttributeDeclaration> attrs;
    for (const auto& a : bp.attributes) attrs.push_back(Declare(a));
    out.push_back(blueprint::Make(bp.id, msg::ActorKind::ACTOR_SENSOR, attrs));
  }
  return out;
}

bool SensorsService::Owns(const msg::SpawnActor& spawn) const {
  const std::string owner = spawn.owner().to_string();
  if (!owner.empty()) return owner == name_;
  return s::FindSensorBlueprint(spawn.blueprint().to_string()) != nullptr;
}

std::string SensorsService::CheckSpawn(const msg::SpawnActor& spawn) const {
  s::SensorSpawn sp;
  sp.blueprint = spawn.blueprint().to_string();
  for (const auto& a : spawn.attributes()) sp.attributes[a.key().to_string()] = a.value().to_string();
  return s::CheckSensorSpawn(sp);
}

// The town's meshes (the ones the renderer draws) and the map's geo reference, from the
// map the coordinator publishes.
void SensorsService::LoadTown(const msg::WorldInfo& world) {
  if (world.map_name().to_string().empty()) {
    town_meshes_.reset();
    town_hash_ = 0;
    geo_ = {};
    return;
  }
  if (world.map_hash() == town_hash_ && town_meshes_) return;
  const auto town = town_source_.Load(world, "sensors");
  town_meshes_ = std::make_shared<const std::vector<map::Mesh>>(map::BuildWorldMeshes(town->map, town->scene));
  geo_ = town->geo;
  town_hash_ = world.map_hash();
  spdlog::info("town '{}': {} triangles for ray casting, geo reference {:.6f}, {:.6f}", town->name,
               map::TotalTriangles(*town_meshes_), geo_.latitude, geo_.longitude);
}

void SensorsService::BeginRun(const msg::WorldInfo& world) {
  LoadTown(world);
  mode_ = world.settings().perception_mode();
  seed_ = world.seed();
  run_ = world.run();
  weather_ = s::Weather{world.weather().precipitation(), world.weather().fog_density()};
  // The physics inputs, by what the required services simulate (never by their names):
  // vehicles or walkers come in GroundState, drones in AirState, and each of those
  // services publishes one PhysicsEvents batch per frame.
  const std::vector<std::string> required = RequiredServices(world);
  // Declarations come as the services start (render's EGL, a town's meshes): on a loaded
  // machine that takes longer than a frame's inputs, so the run's service timeout bounds it.
  const double declare_s = std::max(options_.input_timeout_s, world.settings().service_timeout());
  if (!declarations_.WaitFor(required, std::chrono::milliseconds(static_cast<int64_t>(declare_s * 1000)))) {
    throw InputError("sensors: not every required service declared its blueprints within " + std::to_string(declare_s) +
                     " s (the input timeout, or the run's service_timeout if longer)");
  }
  event_publishers_.clear();
  const auto ground = declarations_.Declaring(msg::ActorKind::ACTOR_VEHICLE, required);
  const auto walkers = declarations_.Declaring(msg::ActorKind::ACTOR_WALKER, required);
  const auto air = declarations_.Declaring(msg::ActorKind::ACTOR_DRONE, required);
  ground_in_run_ = !ground.empty() || !walkers.empty();
  air_in_run_ = !air.empty();
  for (const auto* list : {&ground, &walkers, &air}) event_publishers_.insert(list->begin(), list->end());
  world_ = std::make_unique<s::SensorWorld>(seed_, geo_);
  props_.clear();
  special_types_.clear();
  world_->set_weather(weather_);
  if (town_meshes_) world_->scene().SetStatic(*town_meshes_);
  files_.reset();
  spdlog::info("run {}: seed {}, perception {}, inputs:{}{}", run_, seed_,
               mode_ == msg::PerceptionMode::PERCEPTION_PIPELINED ? "pipelined" : "strict", ground_in_run_ ? " GroundState" : "",
               air_in_run_ ? " AirState" : "");
}

namespace {
constexpr uint32_t kSnapshotVersion = 1;
}

std::vector<uint8_t> SensorsService::SaveState() const {
  if (!world_) return {};
  s::StateOut out;
  out.Put(kSnapshotVersion);
  out.Put(weather_.precipitation);
  out.Put(weather_.fog_density);
  out.Put(static_cast<uint64_t>(props_.size()));
  for (const auto& [id, p] : props_) {
    out.Put(p.id);
    out.Put(p.parent);
    out.Put(p.transform);
    out.Put(p.half_extents);
    out.Put(p.tag);
  }
  world_->Save(out);
  return std::move(out.bytes());
}

void SensorsService::RestoreState(const std::vector<uint8_t>& state) {
  if (!world_) throw InputError("sensors: a snapshot before the run began");
  s::StateIn in(state);
  uint32_t version = 0;
  in.Get(version);
  if (version != kSnapshotVersion) throw InputError("sensors: snapshot version " + std::to_string(version) + " is not this build's");
  in.Get(weather_.precipitation);
  in.Get(weather_.fog_density);
  uint64_t n = 0;
  in.Get(n);
  props_.clear();
  for (uint64_t i = 0; i < n; ++i) {
    s::CustomProp p;
    in.Get(p.id);
    in.Get(p.parent);
    in.Get(p.transform);
    in.Get(p.half_extents);
    in.Get(p.tag);
    props_[p.id] = p;
  }
  world_->Restore(in);
  world_->set_weather(weather_);
  if (!in.done()) throw InputError("sensors: snapshot has trailing bytes");
}

void SensorsService::Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why) {
  if (!replaying()) event_writer_.Write(CommandFailedEvent(name_, actor, why, stamp));
  spdlog::warn("actor {}: {}", actor, why);
}

void SensorsService::Apply(const msg::Command& c, const msg::FrameStamp& stamp) {
  const auto& b = c.body();
  switch (b._d()) {
    case msg::CommandKind::CMD_SPAWN_ACTOR: {
      const auto& sp = b.spawn_actor();
      if (sp.blueprint().to_string().rfind("custom.", 0) == 0) {
        AddCustomProp(sp, stamp);
        return;
      }
      if (!Owns(sp)) return;
      s::SensorSpawn spawn;
      spawn.id = sp.actor();
      spawn.blueprint = sp.blueprint().to_string();
      for (const auto& a : sp.attributes()) spawn.attributes[a.key().to_string()] = a.value().to_string();
      spawn.parent = sp.parent();
      spawn.transform = ToPose(sp.transform());
      if (std::string why = world_->Add(spawn); !why.empty()) Fail(stamp, sp.actor(), "spawn failed: " + why);
      return;
    }
    case msg::CommandKind::CMD_DESTROY_ACTOR:
      world_->Remove(b.destroy_actor().actor());
      world_->Detach(b.destroy_actor().actor());  // its sensors stay where they were (CARLA)
      props_.erase(b.destroy_actor().actor());
      return;
    case msg::CommandKind::CMD_V2X_SEND: {
      const auto& v = b.v2x_send();
      if (!world_->Has(v.sensor())) return;  // another sensors service's
      if (std::string why = world_->V2XSend(v.sensor(), v.data().to_string()); !why.empty()) Fail(stamp, v.sensor(), "send: " + why);
      return;
    }
    case msg::CommandKind::CMD_SET_WEATHER:
      weather_ = s::Weather{b.weather().precipitation(), b.weather().fog_density()};
      world_->set_weather(weather_);
      return;
    default: return;
  }
}

// The special_type a vehicle blueprint declares (CARLA's V2X station type reads it).
const std::string& SensorsService::SpecialType(const std::string& blueprint) {
  auto it = special_types_.find(blueprint);
  if (it != special_types_.end()) return it->second;
  std::string value;
  for (const auto& [service, set] : declarations_.Live()) {
    for (const auto& d : set.blueprints()) {
      if (d.id().to_string() != blueprint) continue;
      for (const auto& a : d.attributes()) {
        if (a.id().to_string() == "special_type") value = a.default_value().to_string();
      }
    }
  }
  return special_types_[blueprint] = value;
}

void SensorsService::AddCustomProp(const msg::SpawnActor& sp, const msg::FrameStamp& stamp) {
  const std::string bp = sp.blueprint().to_string();
  for (const auto& [service, set] : declarations_.Live()) {
    for (const auto& d : set.blueprints()) {
      if (d.id().to_string() != bp) continue;
      props_[sp.actor()] = s::MakeCustomProp(d, sp.actor(), sp.parent(), sp.transform());
      return;
    }
  }
  Fail(stamp, sp.actor(), "custom prop '" + bp + "': no live service declares it; sensors do not see it");
}

s::WorldFrame SensorsService::Gather(const msg::Tick& tick, uint64_t frame, s::FrameEvents* events) {
  s::WorldFrame f;
  f.run = tick.run();
  f.frame = frame;
  f.sim_time = tick.sim_time() - static_cast<double>(tick.frame() - frame) * tick.dt();
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(options_.input_timeout_s * 1000));
  // A producer being replaced holds the wait (AwaitInput): no cascade of failures.
  auto await = [&](auto& buffer) {
    return AwaitInput([&](std::chrono::milliseconds slice) { return buffer.WaitFor(tick.run(), frame, slice); }, timeout);
  };
  if (ground_in_run_) {
    auto g = await(ground_);
    if (!g) throw MissingInput("sensors: no GroundState of frame " + std::to_string(frame) + " within the input timeout");
    f.sim_time = g->stamp().sim_time();
    s::AppendActors(*g, &f.actors);
    for (auto& a : f.actors) {
      if (a.kind == s::ActorKind::kVehicle) a.special_type = SpecialType(a.blueprint);
    }
  }
  if (air_in_run_) {
    auto air = await(air_);
    if (!air) throw MissingInput("sensors: no AirState of frame " + std::to_string(frame) + " within the input timeout");
    f.sim_time = air->stamp().sim_time();
    s::AppendActors(*air, &f.actors);
  }
  // Custom props: their declared box at the spawn transform, relative to the parent's mount
  // as the render service draws them (vehicles and walkers: the bottom of their box).
  std::vector<s::CustomProp> props;
  for (const auto& [id, p] : props_) props.push_back(p);
  s::AppendProps(props, &f.actors);
  std::sort(f.actors.begin(), f.actors.end(), [](const s::Actor& a, const s::Actor& b) { return a.id < b.id; });
  if (world_->HasEventSensors() && !event_publishers_.empty()) {
    auto batches = AwaitInput(
        [&](std::chrono::milliseconds slice) { return events_.WaitFor(tick.run(), frame, event_publishers_, slice); }, timeout);
    if (!batches) throw MissingInput("sensors: no PhysicsEvents of frame " + std::to_string(frame) + " from every physics service within the input timeout");
    for (const auto& b : *batches) {
      for (const auto& c : b.collisions()) {
        events->collisions.push_back(s::CollisionEvent{c.actor(), c.other_actor(), FromWire(c.other_kind()), c.other_semantic_tag(),
                                                       ToVec(c.normal_impulse()), ToVec(c.location())});
      }
      for (const auto& l : b.lane_invasions()) {
        s::LaneInvasionEvent e;
        e.actor = l.actor();
        for (const auto& m : l.crossed()) {
          e.crossed.push_back(s::LaneMarking{static_cast<int>(m.type()), m.color().to_string(), m.width(), m.lane_change_left(),
                                             m.lane_change_right()});
        }
        events->lane_invasions.push_back(std::move(e));
      }
    }
  }
  return f;
}

void SensorsService::Step(const msg::Tick& tick) {
  msg::FrameStamp tick_stamp;
  tick_stamp.run(tick.run());
  tick_stamp.frame(tick.frame());
  tick_stamp.sim_time(tick.sim_time());
  for (const auto& c : tick.commands()) Apply(c, tick_stamp);
  const uint64_t frame = PerceptionFrame(mode_, tick.frame());
  if (frame < 1 || world_->size() == 0) return;
  s::FrameEvents events;
  const s::WorldFrame f = Gather(tick, frame, &events);
  // A replacement replays the frames since its snapshot with the inputs the state topics
  // kept (their noise streams and schedules advance as they did), publishing nothing.
  const s::StepOutput out = world_->Step(f, tick.dt(), events);
  if (replaying()) return;
  msg::FrameStamp stamp;
  stamp.run(tick.run());
  stamp.frame(frame);
  stamp.sim_time(f.sim_time);
  Publish(out, stamp);
  if (!options_.output_dir.empty()) {
    if (!files_) files_ = std::make_unique<SampleWriter>(options_.output_dir + "/run" + std::to_string(run_) + "/sensors", tick.frame() <= 2);
    files_->Write(out, frame, f.sim_time);
  }
}

void SensorsService::Publish(const s::StepOutput& out, const msg::FrameStamp& stamp) {
  for (const auto& t : out.point_clouds) {
    msg::PointCloud m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.sensor_pose(FromPose(t.pose));
    m.format(t.data.semantic ? msg::PointFormat::POINTS_SEMANTIC : msg::PointFormat::POINTS_XYZI);
    m.point_count(t.data.point_count);
    m.point_step(t.data.point_step);
    m.points_per_channel(t.data.points_per_channel);
    m.data(t.data.data);
    point_cloud_writer_.Write(m);
  }
  for (const auto& t : out.radar) {
    msg::RadarScan m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.sensor_pose(FromPose(t.pose));
    std::vector<msg::RadarDetection> dets;
    dets.reserve(t.data.size());
    for (const auto& d : t.data) {
      msg::RadarDetection r;
      r.velocity(d.velocity);
      r.azimuth(d.azimuth);
      r.altitude(d.altitude);
      r.depth(d.depth);
      dets.push_back(r);
    }
    m.detections(std::move(dets));
    radar_writer_.Write(m);
  }
  for (const auto& t : out.imu) {
    msg::Imu m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.accelerometer(FromVec(t.data.accelerometer));
    m.gyroscope(FromVec(t.data.gyroscope));
    m.compass(t.data.compass);
    m.orientation(FromQuat(t.data.orientation));
    imu_writer_.Write(m);
  }
  for (const auto& t : out.gnss) {
    msg::Gnss m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.latitude(t.data.latitude);
    m.longitude(t.data.longitude);
    m.altitude(t.data.altitude);
    m.eph(t.data.eph);
    m.epv(t.data.epv);
    m.fix(t.data.fix);
    gnss_writer_.Write(m);
  }
  for (const auto& t : out.barometer) {
    msg::Barometer m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.altitude(t.data.altitude);
    m.pressure(t.data.pressure);
    m.qnh(t.data.qnh);
    barometer_writer_.Write(m);
  }
  for (const auto& t : out.magnetometer) {
    msg::Magnetometer m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.magnetic_field(FromVec(t.data));
    magnetometer_writer_.Write(m);
  }
  for (const auto& t : out.distance) {
    msg::DistanceMeasurement m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.sensor_pose(FromPose(t.pose));
    m.distance(t.data.distance);
    m.min_distance(t.data.min_distance);
    m.max_distance(t.data.max_distance);
    distance_writer_.Write(m);
  }
  for (const auto& t : out.obstacle) {
    msg::ObstacleDetection m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.actor(t.parent);
    m.other_actor(t.data.other_actor);
    m.other_kind(ToWire(t.data.other_kind));
    m.distance(t.data.distance);
    m.other_semantic_tag(t.data.other_tag);
    obstacle_writer_.Write(m);
  }
  for (const auto& t : out.collision) {
    msg::CollisionEvent m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.actor(t.parent);
    m.other_actor(t.data.event.other_actor);
    m.other_kind(ToWire(t.data.event.other_kind));
    m.normal_impulse(FromVec(t.data.event.normal_impulse));
    m.other_semantic_tag(t.data.event.other_tag);
    collision_writer_.Write(m);
  }
  for (const auto& t : out.lane_invasion) {
    msg::LaneInvasionEvent m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    m.actor(t.parent);
    std::vector<msg::LaneMarking> crossed;
    for (const auto& c : t.data.crossed) crossed.push_back(ToWire(c));
    m.crossed(crossed);
    lane_invasion_writer_.Write(m);
  }
  for (const auto& t : out.v2x) {
    msg::V2XData m;
    m.sensor(t.sensor);
    m.stamp(stamp);
    std::vector<msg::V2XReceived> got;
    for (const auto& r : t.data) {
      if (got.size() >= 256) break;  // the message's bound: the nearest senders' ids come first
      msg::V2XReceived x;
      x.sender(r.sender);
      x.power_dbm(r.power_dbm);
      x.payload(std::vector<uint8_t>(r.payload.begin(), r.payload.begin() + std::min<size_t>(r.payload.size(), 2048)));
      got.push_back(std::move(x));
    }
    m.messages(std::move(got));
    v2x_writer_.Write(m);
  }
}

}  // namespace lockstep
