#include "ground_service.h"

#include <algorithm>
#include <chrono>

#include "lockstep/map/scene.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/log.h"
#include "wire.h"

namespace lockstep {
namespace {

using ground_wire::FromPose;
using ground_wire::FromVec;
using ground_wire::ToPose;
using ground_wire::ToVec;

// Ids the coordinator hard-coded before the blueprint declarations: drive them as these.
std::string CarlaId(const std::string& bp) {
  static const std::map<std::string, std::string> legacy = {
      {"vehicle.lockstep.sedan", "vehicle.lincoln.mkz_2020"}, {"vehicle.lockstep.hatchback", "vehicle.audi.a2"},
      {"vehicle.lockstep.suv", "vehicle.nissan.patrol_2021"}, {"vehicle.lockstep.van", "vehicle.mercedes.sprinter"},
      {"vehicle.lockstep.truck", "vehicle.carlamotors.carlacola"}, {"vehicle.lockstep.bus", "vehicle.mitsubishi.fusorosa"},
      {"vehicle.lockstep.motorbike", "vehicle.kawasaki.ninja"}};
  auto it = legacy.find(bp);
  return it == legacy.end() ? bp : it->second;
}

ground::LightWeather LightWeather(const msg::WeatherParameters& w) {
  return ground::LightWeather{w.sun_altitude_angle(), w.precipitation(), w.fog_density()};
}

bool IsMine(const std::string& bp) {
  return ground::FindVehicle(bp) || ground::FindWalker(bp) || bp == ground::kWalkerControllerBlueprint;
}

std::map<std::string, std::string> Attributes(const msg::SpawnActor& s) {
  std::map<std::string, std::string> a;
  for (const auto& x : s.attributes()) a[x.key().to_string()] = x.value().to_string();
  return a;
}

}  // namespace

GroundService::GroundService(Bus& bus, std::string name, std::string output_dir)
    : name_(std::move(name)),
      output_dir_(std::move(output_dir)),
      state_writer_(bus, topics::kGroundState),
      events_writer_(bus, topics::kPhysicsEvents),
      event_writer_(bus, topics::kEvent),
      air_(bus, topics::kAirState),
      declarations_(bus),
      map_reader_(bus, topics::kMap, [this](const msg::MapData& m, const SampleInfo&) {
        {
          std::lock_guard<std::mutex> lock(map_mu_);
          map_ = m;
        }
        map_cv_.notify_all();
      }) {}

std::vector<msg::BlueprintDeclaration> GroundService::Blueprints() const { return ground_wire::Blueprints(); }

std::optional<std::pair<ground::Pose, ground::Vec3>> GroundService::Footprint(const msg::SpawnActor& s) const {
  if (s.parent() != 0) return std::nullopt;  // attached: moves with its parent
  const std::string bp = CarlaId(s.blueprint().to_string());
  if (const auto* v = ground::FindVehicle(bp)) return std::make_pair(ToPose(s.transform()), v->half_extents);
  if (const auto* w = ground::FindWalker(bp)) return std::make_pair(ToPose(s.transform()), ground::Vec3(w->radius, w->radius, w->height / 2));
  return std::nullopt;
}

// CARLA refuses a vehicle or walker whose box overlaps another actor at the spawn transform
// ("Spawn failed because of collision at spawn position"): try_spawn_actor returns None,
// spawn_actor raises, a batch's SpawnActor response carries the error. The coordinator asks
// us before it hands out an actor id; we answer from the state of our last step plus the
// spawns we accepted that no tick has carried yet, so a refused spawn never becomes an actor.
std::string GroundService::CheckSpawn(const msg::SpawnActor& s) const {
  const std::string bp = CarlaId(s.blueprint().to_string());
  if (bp == ground::kWalkerControllerBlueprint) {
    return s.parent() == 0 ? "controller.ai.walker must be spawned attached to its walker (parent)" : "";
  }
  try {
    ground::ParseSpawnAttributes(Attributes(s));
  } catch (const std::exception& e) {
    return e.what();
  }
  const auto fp = Footprint(s);
  if (!fp || !world_) return {};
  const std::string owner = s.owner().to_string();
  if (!owner.empty() && owner != name_) return {};
  std::string why = world_->CheckFree(fp->first, fp->second);
  std::lock_guard<std::mutex> lock(reservations_mu_);
  if (why.empty()) {
    // The spawns accepted for the next tick take their spots too.
    for (const auto& r : reservations_) {
      if (ground::SpawnOverlaps(fp->first, fp->second, r.pose, r.half_extents)) {
        why = "spawn point taken by a " + r.blueprint + " spawned for the next tick";
        break;
      }
    }
  }
  if (!why.empty()) return "Spawn failed because of collision at spawn position (" + why + ")";
  reservations_.push_back(Reservation{s.blueprint().to_string(), fp->first, fp->second, kReservationSteps});
  return {};
}

// The town as the other services build it: the coordinator's map and the scene it names
// (or the one generated from the run seed), so every service collides with the same world.
void GroundService::LoadTown(const msg::WorldInfo& world) {
  if (world.map_name().to_string().empty()) throw InputError("ground_sim: the run has no map; vehicles need roads");
  if (world.map_hash() == town_hash_ && town_) return;
  std::optional<msg::MapData> data;
  {
    std::unique_lock<std::mutex> lock(map_mu_);
    map_cv_.wait_for(lock, std::chrono::seconds(30), [&] { return map_ && map_->content_hash() == world.map_hash(); });
    if (map_ && map_->content_hash() == world.map_hash()) data = map_;
  }
  if (!data) throw InputError("ground_sim: no map '" + world.map_name().to_string() + "' from the coordinator within 30 s");
  map::Map town = map::Map::FromString(data->opendrive(), data->name().to_string());
  const map::Scene scene = data->scene().empty() ? map::GenerateScene(town, world.seed())
                                                 : map::SceneFromYaml(data->scene(), data->name().to_string() + ".scene.yaml");
  town_ = ground::Town::Build(std::move(town), scene);
  town_hash_ = world.map_hash();
  spdlog::info("town '{}': {} static meshes, {} traffic lights in {} groups, {} spawn points", data->name().to_string(),
               town_->Meshes().size(), town_->Lights().size(), town_->GroupCount(), town_->SpawnPoints().size());
}

void GroundService::BeginRun(const msg::WorldInfo& world) {
  LoadTown(world);
  const auto& s = world.settings();
  physics_.substepping = s.max_substeps() > 0 && s.max_substep_delta_time() > 0;
  if (s.max_substep_delta_time() > 0) physics_.max_substep_delta_time = s.max_substep_delta_time();
  if (s.max_substeps() > 0) physics_.max_substeps = static_cast<int>(s.max_substeps());
  seed_ = world.seed();
  log_.reset();
  {
    std::lock_guard<std::mutex> lock(reservations_mu_);
    reservations_.clear();
  }
  world_ = std::make_unique<ground::World>(town_, seed_, physics_);
  world_->SetWeather(LightWeather(world.weather()));
  input_timeout_s_ = s.service_timeout() > 0 ? s.service_timeout() : 10.0;
  // Whose AirState to wait for: the other required members that declare drones (found by what
  // they simulate, never by a service name). Every member publishes its set when it joins,
  // before the coordinator counts it alive.
  std::vector<std::string> others;
  for (const std::string& r : RequiredServices(world)) {
    if (r != name_) others.push_back(r);
  }
  if (!declarations_.WaitFor(others, std::chrono::seconds(30))) {
    throw InputError(name_ + ": the blueprint declarations of the run's services did not arrive within 30 s");
  }
  drone_sources_ = others.empty() ? std::vector<std::string>{} : declarations_.Declaring(msg::ActorKind::ACTOR_DRONE, others);
  wait_for_air_ = !drone_sources_.empty();
  spdlog::info("run {}: seed {}, sub-steps of {} s (at most {}), drones {}", world.run(), seed_, physics_.max_substep_delta_time,
               physics_.max_substeps,
               wait_for_air_ ? "from " + drone_sources_.front() + "'s AirState (frame k-1)"
                             : std::string("none (no member declares drones)"));
}

std::vector<uint8_t> GroundService::SaveState() const { return world_ ? world_->Save() : std::vector<uint8_t>{}; }

void GroundService::RestoreState(const std::vector<uint8_t>& state) {
  if (!town_) throw InputError("ground_sim: restore before the town is loaded");
  world_ = ground::World::Restore(town_, state);
}

void GroundService::Fail(uint32_t actor, const std::string& why) {
  pending_events_.push_back(CommandFailedEvent(name_, actor, why));  // stamped when published
  if (!replaying()) spdlog::warn("actor {}: {}", actor, why);
}

void GroundService::Spawn(const msg::SpawnActor& s) {
  const std::string owner = s.owner().to_string();
  const std::string bp = CarlaId(s.blueprint().to_string());
  if (!owner.empty() ? owner != name_ : !IsMine(bp)) {
    SpawnProp(s, bp);
    return;
  }
  const auto attrs = Attributes(s);
  std::string why;
  if (bp == ground::kWalkerControllerBlueprint) {
    why = world_->AddWalkerController(s.actor(), s.parent());
  } else if (ground::FindVehicle(bp)) {
    // Overlaps were refused in CheckSpawn, before the id was handed out; a spawn the tick
    // carries is added whatever moved since (as CARLA's actor exists once spawned), so the
    // state stays a function of the ticks alone.
    why = world_->AddVehicle(s.actor(), bp, attrs, ToPose(s.transform()));
  } else if (ground::FindWalker(bp)) {
    why = world_->AddWalker(s.actor(), bp, attrs, ToPose(s.transform()));
  } else {
    why = "ground_sim does not simulate '" + bp + "'";
  }
  if (!why.empty()) Fail(s.actor(), "spawn of " + bp + " failed: " + why);
}

void GroundService::SpawnProp(const msg::SpawnActor& s, const std::string& bp) {
  // The coordinator accepted the spawn, so some service declared the blueprint; its set may
  // reach this reader a moment after the tick (TRANSIENT_LOCAL): wait for it, bounded.
  std::optional<msg::BlueprintDeclaration> decl;
  auto find = [&] {
    for (const auto& [service, set] : declarations_.Live()) {
      for (const auto& d : set.blueprints()) {
        if (d.id().to_string() == bp) {
          decl = d;
          return true;
        }
      }
    }
    return false;
  };
  if (!find()) declarations_.WaitUntil(find, std::chrono::seconds(5));
  if (!decl || decl->kind() != msg::ActorKind::ACTOR_PROP) return;
  const ground::Vec3 half = ToVec(decl->half_extents());
  if (!(half.array() > 0).all()) return;  // a prop without a bounding box: nothing to collide with
  if (s.parent() != 0) {
    Fail(s.actor(), "prop " + bp + " attached to actor " + std::to_string(s.parent()) +
                        ": ground_sim collides only with unattached props (its box is not added)");
    return;
  }
  if (const std::string why = world_->AddProp(s.actor(), ToPose(s.transform()), half); !why.empty()) {
    Fail(s.actor(), "prop " + bp + ": " + why);
  }
}

void GroundService::Apply(const msg::Command& c) {
  const auto& b = c.body();
  auto mine = [&](uint32_t id) { return world_->Has(id); };
  auto report = [&](uint32_t actor, const std::string& why) {
    if (!why.empty()) Fail(actor, why);
  };
  switch (b._d()) {
    case msg::CommandKind::CMD_SPAWN_ACTOR: Spawn(b.spawn_actor()); return;
    case msg::CommandKind::CMD_DESTROY_ACTOR: world_->Remove(b.destroy_actor().actor()); return;
    case msg::CommandKind::CMD_SET_TRANSFORM:
      if (mine(b.set_transform().actor()))
        report(b.set_transform().actor(), world_->SetTransform(b.set_transform().actor(), ToPose(b.set_transform().transform())));
      return;
    case msg::CommandKind::CMD_VEHICLE_CONTROL: {
      const auto& v = b.vehicle_control();
      if (!mine(v.actor())) return;
      ground::VehicleControl g;
      g.throttle = v.throttle();
      g.steer = v.steer();
      g.brake = v.brake();
      g.hand_brake = v.hand_brake();
      g.reverse = v.reverse();
      g.manual_gear_shift = v.manual_gear_shift();
      g.gear = v.gear();
      report(v.actor(), world_->ApplyControl(v.actor(), g));
      return;
    }
    case msg::CommandKind::CMD_VEHICLE_ACKERMANN: {
      const auto& a = b.ackermann();
      if (!mine(a.actor())) return;
      ground::AckermannControl g;
      g.steer = -a.steer();  // CARLA: > 0 right; the core: > 0 left (ENU)
      g.steer_speed = a.steer_speed();
      g.speed = a.speed();
      g.acceleration = a.acceleration();
      g.jerk = a.jerk();
      report(a.actor(), world_->ApplyAckermann(a.actor(), g));
      return;
    }
    case msg::CommandKind::CMD_WALKER_CONTROL: {
      const auto& w = b.walker_control();
      if (!mine(w.actor())) return;
      ground::WalkerControl g;
      g.direction = ToVec(w.direction());
      g.speed = w.speed();
      g.jump = w.jump();
      report(w.actor(), world_->ApplyWalkerControl(w.actor(), g));
      return;
    }
    case msg::CommandKind::CMD_ACTOR_PHYSICS: {
      const auto& p = b.actor_physics();
      if (!mine(p.actor())) return;
      using K = msg::ActorPhysicsKind;
      switch (p.kind()) {
        case K::PHYSICS_SET_TARGET_VELOCITY: report(p.actor(), world_->SetTargetVelocity(p.actor(), ToVec(p.value()))); return;
        case K::PHYSICS_SET_TARGET_ANGULAR_VELOCITY:
          report(p.actor(), world_->SetTargetAngularVelocity(p.actor(), ToVec(p.value())));
          return;
        case K::PHYSICS_ADD_IMPULSE: report(p.actor(), world_->AddImpulse(p.actor(), ToVec(p.value()))); return;
        case K::PHYSICS_SET_SIMULATE_PHYSICS: report(p.actor(), world_->SetSimulatePhysics(p.actor(), p.enabled())); return;
        case K::PHYSICS_SET_LIGHT_STATE: report(p.actor(), world_->SetLightState(p.actor(), p.light_state())); return;
      }
      return;
    }
    case msg::CommandKind::CMD_VEHICLE_PHYSICS: {
      const auto& p = b.vehicle_physics();
      if (!mine(p.actor())) return;
      report(p.actor(), world_->SetVehiclePhysics(p.actor(), ground_wire::FromWire(p.physics())));
      return;
    }
    case msg::CommandKind::CMD_WALKER_AI: {
      const auto& w = b.walker_ai();
      if (!world_->IsController(w.actor())) {
        if (mine(w.actor())) Fail(w.actor(), "actor " + std::to_string(w.actor()) + " is not a controller.ai.walker");
        return;
      }
      using K = msg::WalkerAIKind;
      switch (w.kind()) {
        case K::WALKER_AI_START: report(w.actor(), world_->ControllerStart(w.actor())); return;
        case K::WALKER_AI_STOP: report(w.actor(), world_->ControllerStop(w.actor())); return;
        case K::WALKER_AI_GO_TO_LOCATION: report(w.actor(), world_->ControllerGoTo(w.actor(), ToVec(w.location()))); return;
        case K::WALKER_AI_SET_MAX_SPEED: report(w.actor(), world_->ControllerMaxSpeed(w.actor(), w.max_speed())); return;
      }
      return;
    }
    case msg::CommandKind::CMD_TRAFFIC_LIGHT: {
      const auto& t = b.traffic_light();
      if (t.action() == msg::TrafficLightAction::LIGHT_RESET_ALL) {
        world_->ResetAllLights();
        return;
      }
      if (t.action() == msg::TrafficLightAction::LIGHT_RESET_GROUP) {
        report(t.actor(), world_->ResetLightGroup(t.actor()));
        return;
      }
      report(t.actor(), world_->SetTrafficLight(t.actor(), ground_wire::FromWire(t.state()), t.green_time(), t.yellow_time(),
                                                t.red_time(), t.freeze()));
      return;
    }
    case msg::CommandKind::CMD_SET_WEATHER: world_->SetWeather(LightWeather(b.weather())); return;
    case msg::CommandKind::CMD_PEDESTRIANS:
      if (b.pedestrians().seed_only()) {
        world_->SetPedestriansSeed(b.pedestrians().seed());
      } else {
        report(0, world_->SetPedestriansCrossFactor(b.pedestrians().cross_factor()));
      }
      return;
    case msg::CommandKind::CMD_TRAFFIC_MANAGER: {
      const auto& t = b.traffic_manager();
      using P = msg::TrafficManagerParameter;
      if (t.actor() != 0 && !mine(t.actor())) return;
      switch (t.parameter()) {
        case P::TM_AUTOPILOT: report(t.actor(), world_->SetAutopilot(t.actor(), t.value() != 0)); return;
        case P::TM_FORCE_LANE_CHANGE: report(t.actor(), world_->ForceLaneChange(t.actor(), t.value() != 0)); return;
        case P::TM_UPDATE_VEHICLE_LIGHTS: report(t.actor(), world_->SetUpdateVehicleLights(t.actor(), t.value() != 0)); return;
        case P::TM_COLLISION_DETECTION:
          report(t.actor(), world_->SetCollisionDetection(t.actor(), t.other_actor(), t.value() != 0));
          return;
        case P::TM_RESPAWN_BOUNDARIES: report(0, world_->SetRespawnBoundaries(t.value(), t.value2())); return;
        case P::TM_SET_PATH: {
          std::vector<ground::Vec3> path;
          for (const auto& p : t.path()) path.push_back(ToVec(p));
          report(t.actor(), world_->SetPath(t.actor(), path));
          return;
        }
        case P::TM_SET_ROUTE: {
          std::vector<std::string> route;
          for (const auto& r : t.route()) route.push_back(r.to_string());
          report(t.actor(), world_->SetRoute(t.actor(), route));
          return;
        }
        default:
          if (auto p = ground_wire::FromWire(t.parameter())) report(t.actor(), world_->SetTrafficManager(*p, t.actor(), t.value()));
          return;
      }
    }
    default: return;
  }
}

// Jacobi coupling: the drones of frame k-1 are obstacles while stepping to frame k. Never
// step without them: a missing input faults the run (the state must not depend on when a
// sample arrived), as air_sim does with GroundState.
std::vector<ground::ExternalBody> GroundService::Drones(const msg::Tick& tick) {
  std::vector<ground::ExternalBody> bodies;
  if (wait_for_air_ && tick.frame() >= 2 && !replaying()) {
    const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(input_timeout_s_ * 1000));
    // A drone service being replaced holds the wait (AwaitInput: while another service's failure
    // stops the run, the timeout does not run out), so its fault does not fail ground_sim too.
    auto air = AwaitInput([&](std::chrono::milliseconds slice) { return air_.WaitFor(tick.run(), tick.frame() - 1, slice); }, timeout);
    if (!air) {
      throw MissingInput(name_ + ": no AirState of frame " + std::to_string(tick.frame() - 1) + " (from " + drone_sources_.front() +
                       ") within " + std::to_string(input_timeout_s_) + " s; a missing input faults the run");
    }
    for (const auto& d : air->drones()) {
      ground::ExternalBody e;
      e.id = d.actor();
      e.kind = ground::ObjectKind::kDrone;
      e.pose = ToPose(d.transform());
      e.velocity = ToVec(d.linear_velocity());
      e.half_extents = wire::DroneHalfExtents();
      e.mass = 1.0;
      bodies.push_back(e);
    }
  }
  return bodies;
}

void GroundService::Step(const msg::Tick& tick) {
  if (!world_) throw InputError("ground_sim: a tick before the run began");
  // Inputs first: a missing one throws before anything of this frame is applied.
  std::vector<ground::ExternalBody> drones = Drones(tick);
  pending_events_.clear();
  {
    // The spawns this tick carries were reserved by our checks; the others age.
    std::lock_guard<std::mutex> lock(reservations_mu_);
    for (const auto& c : tick.commands()) {
      if (c.body()._d() != msg::CommandKind::CMD_SPAWN_ACTOR) continue;
      const auto& sp = c.body().spawn_actor();
      const ground::Pose pose = ToPose(sp.transform());
      auto it = std::find_if(reservations_.begin(), reservations_.end(), [&](const Reservation& r) {
        return r.blueprint == sp.blueprint().to_string() && r.pose.position == pose.position &&
               r.pose.orientation.coeffs() == pose.orientation.coeffs();
      });
      if (it != reservations_.end()) reservations_.erase(it);
    }
    for (auto& r : reservations_) --r.steps_left;
    std::erase_if(reservations_, [](const Reservation& r) { return r.steps_left <= 0; });
  }
  for (const auto& c : tick.commands()) Apply(c);
  world_->SetExternalBodies(std::move(drones));
  world_->Step(tick.dt());
  if (replaying()) return;
  if (!output_dir_.empty()) {
    // A replacement taking over mid-run appends to the files of the one it replaces.
    if (!log_) log_ = std::make_unique<ground::RunLog>(output_dir_ + "/run" + std::to_string(tick.run()) + "/ground", tick.frame() <= 2);
    log_->Write(*world_, tick.frame(), tick.sim_time());
  }
  msg::FrameStamp stamp;
  stamp.run(tick.run());
  stamp.frame(tick.frame());
  stamp.sim_time(tick.sim_time());
  for (auto& e : pending_events_) {
    e.stamp(stamp);
    event_writer_.Write(e);
  }
  events_writer_.Write(PublishEvents(stamp));
  state_writer_.Write(PublishState(stamp));
}

msg::PhysicsEvents GroundService::PublishEvents(const msg::FrameStamp& stamp) const {
  msg::PhysicsEvents out;
  out.stamp(stamp);
  out.service(name_);
  for (const auto& c : world_->Collisions()) {
    msg::ActorCollision m;
    m.actor(c.actor);
    m.other_actor(c.other_actor);
    m.other_kind(ground_wire::ToWire(c.other_kind));
    m.other_semantic_tag(c.other_semantic_tag);
    m.normal_impulse(FromVec(c.normal_impulse));
    out.collisions().push_back(m);
  }
  for (const auto& inv : world_->LaneInvasions()) {
    msg::ActorLaneInvasion m;
    m.actor(inv.actor);
    for (size_t i = 0; i < inv.crossed.size() && i < 16; ++i) m.crossed().push_back(ground_wire::ToWire(inv.crossed[i]));
    out.lane_invasions().push_back(m);
  }
  return out;
}

msg::GroundState GroundService::PublishState(const msg::FrameStamp& stamp) const {
  msg::GroundState out;
  out.stamp(stamp);
  for (const auto& v : world_->Vehicles()) {
    msg::VehicleState m = ground_wire::ToWire(v);
    if (auto p = world_->GetVehiclePhysics(v.id)) m.physics(ground_wire::ToWire(*p));
    out.vehicles().push_back(std::move(m));
  }
  for (const auto& w : world_->Walkers()) {
    msg::WalkerState m;
    m.actor(w.id);
    m.blueprint(w.blueprint);
    m.transform(FromPose(w.pose));
    m.half_extents(FromVec(w.half_extents));
    m.velocity(FromVec(w.velocity));
    m.ai_controlled(w.ai_controlled);
    msg::WalkerControl c;
    c.actor(w.id);
    c.direction(FromVec(w.control.direction));
    c.speed(static_cast<float>(w.control.speed));
    c.jump(w.control.jump);
    m.control(c);
    out.walkers().push_back(std::move(m));
  }
  for (const auto& l : world_->Lights()) {
    msg::TrafficLightState m;
    m.actor(l.id);
    ground::Pose p = ground::Pose::FromYaw(l.pose.location, l.pose.yaw);
    m.transform(FromPose(p));
    m.state(ground_wire::ToWire(l.state.color));
    m.elapsed(l.state.elapsed);
    m.green_time(l.state.green_time);
    m.yellow_time(l.state.yellow_time);
    m.red_time(l.state.red_time);
    m.frozen(l.state.frozen);
    m.group(static_cast<uint32_t>(l.state.group));
    m.opendrive_id(l.opendrive_id);
    out.traffic_lights().push_back(std::move(m));
  }
  out.state_hash(world_->StateHash());
  return out;
}

}  // namespace lockstep
