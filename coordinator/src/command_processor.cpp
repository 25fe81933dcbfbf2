#include "lockstep/coordinator/command_processor.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "lockstep/recorder/recordings.h"
#include "lockstep/runtime/launch_config.h"
#include "playback.h"

namespace lockstep {
namespace {

using msg::CommandKind;

bool Finite(const msg::Vector3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

std::string InRange(const char* name, double v, double lo, double hi) {
  if (!std::isfinite(v)) return std::string(name) + " is NaN or infinite";
  if (v < lo || v > hi) {
    std::ostringstream r;
    r << name << " = " << v << " is outside [" << lo << ", " << hi << "]";
    return r.str();
  }
  return {};
}

// How far from the map's origin a position may be. Farther is no place in a town, and the
// physics engines' broad phases overflow (ODE asserts on an AABB beyond int range, and a
// hostile 1e300 killed ground_sim): refused, as NaN is.
constexpr double kMaxCoordinate = 1e6;  // m

std::string OutOfWorld(const msg::Vector3& v, const std::string& what) {
  if (std::abs(v.x()) <= kMaxCoordinate && std::abs(v.y()) <= kMaxCoordinate && std::abs(v.z()) <= kMaxCoordinate) return {};
  std::ostringstream r;
  r << what << " (" << v.x() << ", " << v.y() << ", " << v.z() << ") is more than " << kMaxCoordinate
    << " m from the map's origin";
  return r.str();
}

// |v| of a physics command's vector within `max` (its unit by kind).
std::string NormAtMost(const msg::Vector3& v, double max, const char* what) {
  const double n = std::sqrt(v.x() * v.x() + v.y() * v.y() + v.z() * v.z());
  if (n <= max) return {};
  std::ostringstream r;
  r << what << " of magnitude " << n << " is above " << max;
  return r.str();
}

// carla.VehiclePhysicsControl as the wire carries it: every number finite, a plausible mass
// (ground_sim checks the rest of its ranges and refuses what it cannot simulate).
std::string CheckVehiclePhysics(const msg::VehiclePhysicsControl& p) {
  for (const auto& c : p.torque_curve()) {
    if (!std::isfinite(c.x()) || !std::isfinite(c.y())) return "torque curve has a NaN or infinite point";
  }
  for (const auto& g : p.forward_gears()) {
    if (!std::isfinite(g.ratio()) || !std::isfinite(g.down_ratio()) || !std::isfinite(g.up_ratio())) {
      return "forward gears have a NaN or infinite ratio";
    }
  }
  if (!Finite(p.center_of_mass())) return "center_of_mass has a NaN or infinite value";
  const double scalars[] = {p.max_rpm(), p.moi(), p.damping_rate_full_throttle(), p.gear_switch_time(), p.clutch_strength(),
                            p.final_ratio(), p.mass(), p.drag_coefficient(), p.tire_friction(), p.wheel_radius(),
                            p.max_steer_angle(), p.max_brake_torque(), p.max_handbrake_torque(), p.suspension_stiffness(),
                            p.suspension_damping(), p.wheelbase(), p.track()};
  for (double v : scalars) {
    if (!std::isfinite(v)) return "vehicle physics control has a NaN or infinite value";
  }
  return InRange("mass", p.mass(), 1, 1e5);
}

std::string CheckPose(const msg::Pose& p, const char* what) {
  const auto& q = p.orientation();
  if (!Finite(p.position()) || !std::isfinite(q.w()) || !std::isfinite(q.x()) || !std::isfinite(q.y()) || !std::isfinite(q.z())) {
    return std::string(what) + " has a NaN or infinite value";
  }
  if (auto r = OutOfWorld(p.position(), std::string(what) + " position"); !r.empty()) return r;
  const double n = std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z());
  if (std::abs(n - 1.0) > 1e-3) {
    std::ostringstream r;
    r << what << " orientation is not a unit quaternion (norm " << n << ")";
    return r.str();
  }
  return {};
}

// First non-empty reason of a list.
template <class... S>
std::string First(S&&... reasons) {
  std::string out;
  ((out.empty() ? (void)(out = reasons) : (void)0), ...);
  return out;
}

// CARLA's world.debug shapes: finite geometry, sizes >= 0, a unit box rotation.
std::string CheckDebugDraw(const msg::DebugDraw& d) {
  if (d.shapes().empty() && !d.flush_persistent()) return "debug draw without shapes (nor a flush)";
  for (std::size_t i = 0; i < d.shapes().size(); ++i) {
    const auto& s = d.shapes()[i];
    const std::string at = "debug shape " + std::to_string(i) + ": ";
    if (!Finite(s.begin()) || !Finite(s.end()) || !Finite(s.extent())) return at + "a location has a NaN or infinite value";
    if (auto r = First(InRange("size", s.size(), 0, 1e4), InRange("arrow_size", s.arrow_size(), 0, 1e4),
                       InRange("life_time", s.life_time(), -1e9, 1e9));
        !r.empty()) {
      return at + r;
    }
    if (s.kind() == msg::DebugShapeKind::DEBUG_BOX) {
      if (s.extent().x() < 0 || s.extent().y() < 0 || s.extent().z() < 0) return at + "box extent must be >= 0";
      msg::Pose p;
      p.position(s.begin());
      p.orientation(s.rotation());
      if (auto r = CheckPose(p, "box"); !r.empty()) return at + r;
    }
  }
  return {};
}

}  // namespace

CommandProcessor::CommandProcessor(BlueprintLibrary library) : library_(std::move(library)) {}

void CommandProcessor::ResetActors() {
  actors_.clear();
  next_actor_ = 1;
  pending_.clear();
}

uint32_t CommandProcessor::AddMapActor(const std::string& blueprint, msg::ActorKind kind) {
  const uint32_t id = next_actor_++;
  actors_[id] = ActorRecord{id, blueprint, kind, 0, {}};
  return id;
}

std::string CommandProcessor::CheckActor(uint32_t id, msg::ActorKind kind) const {
  auto it = actors_.find(id);
  if (it == actors_.end()) return "unknown actor " + std::to_string(id);
  if (it->second.kind != kind) {
    return "actor " + std::to_string(id) + " is a " + ActorKindName(it->second.kind) + " (" + it->second.blueprint +
           "), not a " + ActorKindName(kind);
  }
  return {};
}

std::string CommandProcessor::CheckDrone(const msg::DroneCommand& d) const {
  using K = msg::DroneCommandKind;
  if (auto r = CheckActor(d.actor(), msg::ACTOR_DRONE); !r.empty()) return r;
  if (!Finite(d.target())) return "drone target has a NaN or infinite value";
  if (auto r = OutOfWorld(d.target(), "drone target"); !r.empty()) return r;
  for (const auto& p : d.path()) {
    if (!Finite(p)) return "drone path has a NaN or infinite point";
    if (auto r = OutOfWorld(p, "drone path point"); !r.empty()) return r;
  }
  for (double v : d.values()) {
    if (!std::isfinite(v)) return "drone values have a NaN or infinite entry";
  }
  if (auto r = First(InRange("velocity", d.velocity(), 0, 100), InRange("duration", d.duration(), 0, 1e6),
                     InRange("timeout", d.timeout(), -1e9, 1e6), InRange("lookahead", d.lookahead(), -1e9, 1e3),
                     InRange("margin", d.margin(), -1e9, 1e3), InRange("yaw", d.yaw().value(), -1e3, 1e3));
      !r.empty()) {
    return r;
  }
  auto need_values = [&](size_t n, const char* what) -> std::string {
    if (d.values().size() != n) {
      return std::string(what) + " needs " + std::to_string(n) + " values, got " + std::to_string(d.values().size());
    }
    return {};
  };
  switch (d.kind()) {
    case K::DRONE_MOVE_TO_POSITION:
    case K::DRONE_MOVE_TO_Z:
      if (d.velocity() <= 0) return "velocity must be > 0 m/s";
      return {};
    case K::DRONE_GO_HOME:  // AirSim's goHome has no velocity: 0 = its 0.5 m/s
      return {};
    case K::DRONE_MOVE_TO_GPS:
      if (auto r = need_values(3, "latitude/longitude/altitude"); !r.empty()) return r;
      if (d.velocity() <= 0) return "velocity must be > 0 m/s";
      return First(InRange("latitude", d.values()[0], -90, 90), InRange("longitude", d.values()[1], -180, 180));
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_THROTTLE:
      if (auto r = need_values(4, "this command"); !r.empty()) return r;
      return InRange("throttle", d.values()[3], 0, 1);
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_Z:
    case K::DRONE_MOVE_BY_ANGLE_RATES_Z:
      return need_values(4, "this command");
    case K::DRONE_SET_WIND:
      return InRange("wind speed", std::sqrt(d.target().x() * d.target().x() + d.target().y() * d.target().y() +
                                             d.target().z() * d.target().z()), 0, 100);
    case K::DRONE_SET_API_CONTROL:
      return need_values(1, "take (1) or release (0)");
    case K::DRONE_SET_KINEMATICS:
      if (d.values().size() != 4 && d.values().size() != 7 && d.values().size() != 10) {
        return "set kinematics needs 4, 7 or 10 values (orientation w x y z, velocity, angular velocity)";
      }
      return {};
    case K::DRONE_MOVE_ON_PATH:
      if (d.path().empty()) return "move on path needs at least one point";
      if (d.velocity() <= 0) return "velocity must be > 0 m/s";
      return {};
    case K::DRONE_MOVE_BY_VELOCITY:
    case K::DRONE_MOVE_BY_VELOCITY_Z:
      return InRange("speed", std::hypot(d.target().x(), d.target().y()), 0, 100);
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAW_THROTTLE:
    case K::DRONE_MOVE_BY_ANGLE_RATES_THROTTLE:
      if (auto r = need_values(4, "this command"); !r.empty()) return r;
      return InRange("throttle", d.values()[3], 0, 1);
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAW_Z:
      return need_values(4, "roll/pitch/yaw/z");
    case K::DRONE_MOVE_BY_MOTOR_PWMS:
      if (d.values().empty() || d.values().size() > 8) return "motor PWMs need 1..8 values";
      for (double v : d.values()) {
        if (auto r = InRange("pwm", v, 0, 1); !r.empty()) return r;
      }
      return {};
    case K::DRONE_SET_GAINS:
      if (!Finite(d.gains().kp()) || !Finite(d.gains().ki()) || !Finite(d.gains().kd())) return "gains have a NaN";
      if (d.gains().kp().x() < 0 || d.gains().kp().y() < 0 || d.gains().kp().z() < 0) return "gains must be >= 0";
      return {};
    default:
      return {};
  }
}

std::string CommandProcessor::Check(const msg::Command& cmd, bool synchronous) const {
  const auto& b = cmd.body();
  switch (b._d()) {
    case CommandKind::CMD_SPAWN_ACTOR: {
      const auto& s = b.spawn_actor();
      const std::string id = s.blueprint().to_string();
      const msg::BlueprintDeclaration* bp = library_.Find(id);
      if (!bp) return library_.WhyUnknown(id);
      if (auto r = BlueprintLibrary::Check(*bp, s.attributes()); !r.empty()) return r;
      if (auto r = CheckPose(s.transform(), "spawn transform"); !r.empty()) return r;
      if (s.parent() != 0 && !actors_.count(s.parent())) return "unknown parent actor " + std::to_string(s.parent());
      if (const std::string owner = s.owner().to_string(); !owner.empty()) {
        const auto declarers = library_.Declarers(id);
        if (std::find(declarers.begin(), declarers.end(), owner) == declarers.end()) {
          std::string list;
          for (const auto& d : declarers) list += (list.empty() ? "'" : ", '") + d + "'";
          return "owner '" + owner + "' does not declare blueprint '" + id + "' (declared by " + list + ")";
        }
      }
      return {};
    }
    case CommandKind::CMD_DESTROY_ACTOR:
      if (!actors_.count(b.destroy_actor().actor())) return "unknown actor " + std::to_string(b.destroy_actor().actor());
      return {};
    case CommandKind::CMD_SET_TRANSFORM:
      if (!actors_.count(b.set_transform().actor())) return "unknown actor " + std::to_string(b.set_transform().actor());
      return CheckPose(b.set_transform().transform(), "transform");
    case CommandKind::CMD_VEHICLE_CONTROL: {
      const auto& c = b.vehicle_control();
      return First(CheckActor(c.actor(), msg::ACTOR_VEHICLE), InRange("throttle", c.throttle(), 0, 1),
                   InRange("steer", c.steer(), -1, 1), InRange("brake", c.brake(), 0, 1), InRange("gear", c.gear(), -1, 10));
    }
    case CommandKind::CMD_WALKER_CONTROL: {
      const auto& c = b.walker_control();
      if (!Finite(c.direction())) return "walker direction has a NaN or infinite value";
      return First(CheckActor(c.actor(), msg::ACTOR_WALKER), InRange("speed", c.speed(), 0, 10));
    }
    case CommandKind::CMD_DRONE:
      return CheckDrone(b.drone());
    case CommandKind::CMD_TRAFFIC_LIGHT: {
      const auto& t = b.traffic_light();
      if (t.action() == msg::TrafficLightAction::LIGHT_RESET_ALL) return {};
      return First(CheckActor(t.actor(), msg::ACTOR_TRAFFIC_LIGHT), InRange("green_time", t.green_time(), -1, 3600),
                   InRange("yellow_time", t.yellow_time(), -1, 3600), InRange("red_time", t.red_time(), -1, 3600));
    }
    case CommandKind::CMD_TRAFFIC_MANAGER: {
      using P = msg::TrafficManagerParameter;
      const auto& t = b.traffic_manager();
      if (t.actor() != 0) {
        if (auto r = CheckActor(t.actor(), msg::ACTOR_VEHICLE); !r.empty()) return r;
      }
      switch (t.parameter()) {
        case P::TM_AUTOPILOT:
          if (t.actor() == 0) return "autopilot needs a vehicle actor";
          return InRange("autopilot", t.value(), 0, 1);
        case P::TM_DISTANCE_TO_LEADING_VEHICLE: return InRange("distance", t.value(), 0, 100);
        case P::TM_PERCENTAGE_SPEED_DIFFERENCE: return InRange("percentage", t.value(), -500, 100);
        case P::TM_IGNORE_LIGHTS_PERCENTAGE:
        case P::TM_IGNORE_SIGNS_PERCENTAGE:
        case P::TM_IGNORE_VEHICLES_PERCENTAGE:
        case P::TM_IGNORE_WALKERS_PERCENTAGE: return InRange("percentage", t.value(), 0, 100);
        case P::TM_AUTO_LANE_CHANGE: return InRange("auto_lane_change", t.value(), 0, 1);
        case P::TM_HYBRID_PHYSICS_RADIUS: return InRange("radius", t.value(), 0, 10000);
        case P::TM_RANDOM_SEED: return InRange("seed", t.value(), 0, 4294967295.0);
        case P::TM_DESIRED_SPEED: return InRange("desired speed", t.value(), 0, 100);
        case P::TM_KEEP_RIGHT_RULE_PERCENTAGE:
        case P::TM_RANDOM_LEFT_LANECHANGE_PERCENTAGE:
        case P::TM_RANDOM_RIGHT_LANECHANGE_PERCENTAGE: return InRange("percentage", t.value(), 0, 100);
        case P::TM_FORCE_LANE_CHANGE:
        case P::TM_SET_PATH:
        case P::TM_SET_ROUTE:
          if (t.actor() == 0) return "this traffic manager call needs a vehicle actor";
          for (const auto& p : t.path()) {
            if (!Finite(p)) return "set_path has a NaN or infinite location";
          }
          return {};
        case P::TM_HYBRID_PHYSICS_MODE:
        case P::TM_SYNCHRONOUS_MODE:
        case P::TM_RESPAWN_DORMANT_VEHICLES: return InRange("flag", t.value(), 0, 1);
        case P::TM_UPDATE_VEHICLE_LIGHTS:
          if (t.actor() == 0) return "update_vehicle_lights needs a vehicle actor";
          return InRange("update_vehicle_lights", t.value(), 0, 1);
        case P::TM_LANE_OFFSET: return InRange("lane offset", t.value(), -100, 100);
        case P::TM_COLLISION_DETECTION:
          if (t.actor() == 0) return "collision_detection needs a vehicle actor";
          if (!actors_.count(t.other_actor())) return "collision_detection: unknown other actor " + std::to_string(t.other_actor());
          return InRange("collision_detection", t.value(), 0, 1);
        case P::TM_RESPAWN_BOUNDARIES:
          if (auto r = First(InRange("lower bound", t.value(), 0, 1e5), InRange("upper bound", t.value2(), 0, 1e5)); !r.empty()) return r;
          if (t.value2() < t.value()) return "respawn boundaries: the upper bound is below the lower bound";
          return {};
      }
      return "unknown traffic manager parameter";
    }
    case CommandKind::CMD_SET_WEATHER: {
      const auto& w = b.weather();
      return First(InRange("cloudiness", w.cloudiness(), -1, 100), InRange("precipitation", w.precipitation(), -1, 100),
                   InRange("precipitation_deposits", w.precipitation_deposits(), -1, 100),
                   InRange("wind_intensity", w.wind_intensity(), -1, 100), InRange("sun_azimuth_angle", w.sun_azimuth_angle(), -1, 360),
                   InRange("sun_altitude_angle", w.sun_altitude_angle(), -90, 90), InRange("fog_density", w.fog_density(), -1, 100),
                   InRange("fog_distance", w.fog_distance(), -1, 1e5), InRange("fog_falloff", w.fog_falloff(), -1, 1e3),
                   InRange("wetness", w.wetness(), -1, 100), InRange("scattering_intensity", w.scattering_intensity(), 0, 1e3),
                   InRange("mie_scattering_scale", w.mie_scattering_scale(), 0, 1e3),
                   InRange("rayleigh_scattering_scale", w.rayleigh_scattering_scale(), 0, 1e3),
                   InRange("dust_storm", w.dust_storm(), 0, 100));
    }
    case CommandKind::CMD_SET_WORLD_SETTINGS:
      try {
        ValidateWorldSettings(b.world_settings(), "world settings");
      } catch (const std::exception& e) {
        return e.what();
      }
      return {};
    case CommandKind::CMD_LOAD_MAP: {
      const auto& m = b.load_map();
      if (m.name().to_string().empty() && m.opendrive().empty()) return "load_map needs a map name or OpenDRIVE text";
      if (!m.opendrive().empty() && m.opendrive().find("<OpenDRIVE") == std::string::npos) {
        return "load_map: the inline text is not OpenDRIVE (no <OpenDRIVE> element)";
      }
      return {};
    }
    case CommandKind::CMD_RESET:
      return {};
    case CommandKind::CMD_TICK:
      if (b.tick_request().count() == 0) return {};  // a ping: answered in any mode, no effect
      if (!synchronous) return "tick requests need synchronous_mode; the world is free-running";
      return InRange("tick count", b.tick_request().count(), 1, 1e6);
    // ground_sim's commands: the actor and finite values here, the rest in the service.
    case CommandKind::CMD_VEHICLE_ACKERMANN: {
      const auto& a = b.ackermann();
      return First(CheckActor(a.actor(), msg::ACTOR_VEHICLE), InRange("steer", a.steer(), -3.2, 3.2),
                   InRange("steer_speed", a.steer_speed(), 0, 100), InRange("speed", a.speed(), -100, 100),
                   InRange("acceleration", a.acceleration(), 0, 100), InRange("jerk", a.jerk(), 0, 1e4));
    }
    case CommandKind::CMD_ACTOR_PHYSICS: {
      using PK = msg::ActorPhysicsKind;
      const auto& p = b.actor_physics();
      if (!actors_.count(p.actor())) return "unknown actor " + std::to_string(p.actor());
      if (!Finite(p.value())) return "physics command value has a NaN or infinite entry";
      // Bounds far beyond anything in a town, so that no value sends a body out of the world.
      switch (p.kind()) {
        case PK::PHYSICS_SET_TARGET_VELOCITY: return NormAtMost(p.value(), 1e3, "target velocity (m/s)");
        case PK::PHYSICS_SET_TARGET_ANGULAR_VELOCITY: return NormAtMost(p.value(), 1e3, "target angular velocity (rad/s)");
        case PK::PHYSICS_ADD_IMPULSE: return NormAtMost(p.value(), 1e7, "impulse (N s)");
        default: return {};
      }
    }
    case CommandKind::CMD_VEHICLE_PHYSICS:
      return First(CheckActor(b.vehicle_physics().actor(), msg::ACTOR_VEHICLE), CheckVehiclePhysics(b.vehicle_physics().physics()));
    case CommandKind::CMD_WALKER_AI:
      if (!actors_.count(b.walker_ai().actor())) return "unknown actor " + std::to_string(b.walker_ai().actor());
      return First(Finite(b.walker_ai().location()) ? std::string() : "go_to_location has a NaN or infinite value",
                   OutOfWorld(b.walker_ai().location(), "go_to_location"), InRange("max_speed", b.walker_ai().max_speed(), 0, 10));
    case CommandKind::CMD_PEDESTRIANS:
      if (b.pedestrians().seed_only()) return {};
      return InRange("pedestrians cross factor", b.pedestrians().cross_factor(), 0, 1);
    case CommandKind::CMD_DEBUG_DRAW:
      return CheckDebugDraw(b.debug_draw());
    case CommandKind::CMD_RECORDER: {
      // Playback (REPLAY_*) is the coordinator's own (playback.h): no recorder service needed.
      if (IsReplayAction(b.recorder().action())) return CheckReplayCommand(b.recorder());
      if (recorders_.empty()) {
        return "recorder commands need a recorder service; none runs in this simulation (lockstep up starts one unless "
               "the config says recorder: false)";
      }
      const auto& r = b.recorder();
      switch (r.action()) {
        case msg::RecorderAction::RECORDER_START:
          if (r.name().to_string().empty()) return "start_recorder needs a file name";
          return {};
        case msg::RecorderAction::RECORDER_STOP:
          return {};
        default:
          return "unknown recorder action";
      }
    }
    case CommandKind::CMD_V2X_SEND: {
      // CARLA's send(): only a sensor.other.v2x_custom takes messages (ActorTypeMismatch).
      const uint32_t id = b.v2x_send().sensor();
      auto it = actors_.find(id);
      if (it == actors_.end()) return "send: unknown actor " + std::to_string(id);
      if (it->second.blueprint != "sensor.other.v2x_custom") {
        return "send: actor " + std::to_string(id) + " is a " + it->second.blueprint + ", not a sensor.other.v2x_custom";
      }
      return {};
    }
  }
  return "unknown command kind";
}

std::string CommandProcessor::ChooseOwner(const msg::SpawnActor& spawn) const {
  if (!spawn.owner().to_string().empty()) return spawn.owner().to_string();
  std::string best;
  size_t best_count = 0;
  for (const auto& name : library_.Declarers(spawn.blueprint().to_string())) {
    const size_t n = std::count_if(actors_.begin(), actors_.end(), [&](const auto& a) { return a.second.owner == name; });
    if (best.empty() || n < best_count) {
      best = name;
      best_count = n;
    }
  }
  return best;
}

msg::CommandReply CommandProcessor::Submit(const msg::Command& cmd, uint32_t run, uint64_t next_frame, bool synchronous,
                                           const OwnerCheck& owner_check) {
  msg::CommandReply reply;
  reply.client(cmd.client());
  reply.sequence_number(cmd.sequence_number());
  reply.run(run);
  reply.frame(next_frame);
  std::string reason = Check(cmd, synchronous);
  msg::Command accepted = cmd;
  auto& b = accepted.body();
  if (reason.empty() && b._d() == CommandKind::CMD_SPAWN_ACTOR) {
    b.spawn_actor().owner(ChooseOwner(b.spawn_actor()));
    b.spawn_actor().actor(0);
    if (owner_check) {
      reason = owner_check(b.spawn_actor());
      if (!reason.empty()) reason = "owner '" + b.spawn_actor().owner().to_string() + "' rejected the spawn: " + reason;
    }
  }
  if (!reason.empty()) {
    reply.accepted(false);
    reply.reason(reason.substr(0, 511));
    return reply;
  }
  reply.accepted(true);
  switch (b._d()) {
    case CommandKind::CMD_SPAWN_ACTOR: {
      const uint32_t id = next_actor_++;
      b.spawn_actor().actor(id);
      actors_[id] = ActorRecord{id, b.spawn_actor().blueprint().to_string(), library_.Find(b.spawn_actor().blueprint().to_string())->kind(),
                                b.spawn_actor().parent(), b.spawn_actor().owner().to_string()};
      reply.actor(id);
      break;
    }
    case CommandKind::CMD_DESTROY_ACTOR: {
      // Only the actor goes, as CARLA's UActorDispatcher::DestroyActor: Unreal detaches what
      // was attached to it, keeping its world transform (UWorld::DestroyActor), so attached
      // sensors live on where they were, unattached.
      const uint32_t gone = b.destroy_actor().actor();
      actors_.erase(gone);
      for (auto& [id, rec] : actors_) {
        if (rec.parent == gone) rec.parent = 0;
      }
      break;
    }
    case CommandKind::CMD_TICK:
      reply.frame(next_frame + b.tick_request().count() - 1);
      return reply;  // the coordinator counts it; services never see tick requests
    case CommandKind::CMD_RECORDER: {
      // A relative name resolves in the recordings folder; the tick carries the absolute
      // path, so the recorder writes where the reply says (CARLA's "Recording on file").
      auto& r = b.recorder();
      if (r.action() == msg::RecorderAction::RECORDER_START) {
        recording_ = recorder::ResolveLogPath(r.name().to_string());
        r.name(recording_);
        reply.text(recording_);
      } else if (r.action() == msg::RecorderAction::RECORDER_STOP) {
        reply.text(recording_);
        recording_.clear();
      }
      break;
    }
    default:
      break;
  }
  pending_.push_back(std::move(accepted));
  return reply;
}

std::vector<msg::Command> CommandProcessor::TakePending() {
  std::vector<msg::Command> out;
  out.swap(pending_);
  return out;
}

}  // namespace lockstep
