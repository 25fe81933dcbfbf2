#include "air_service.h"

#include <algorithm>
#include <cstring>
#include <sstream>
#include <type_traits>
#include <utility>

#include "lockstep/map/scene_mesh.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/wire_geometry.h"

#include "lockstep/runtime/log.h"

namespace lockstep {
namespace {

using wire::FromPose;
using wire::FromVec;
using wire::ToVec;
air::Pose ToPose(const msg::Pose& p) { return wire::ToPose<air::Pose>(p); }
double Timeout(double t) { return t > 0 ? t : air::kForever; }
air::YawMode Yaw(const msg::YawMode& y) { return air::YawMode{y.is_rate(), y.value()}; }
air::Drivetrain Drive(msg::Drivetrain d) {
  return d == msg::Drivetrain::DRIVETRAIN_FORWARD_ONLY ? air::Drivetrain::kForwardOnly : air::Drivetrain::kMaxDegreeOfFreedom;
}
msg::DroneCommandStatus ToWire(air::CommandStatus s) {
  switch (s) {
    case air::CommandStatus::kRunning: return msg::DroneCommandStatus::DRONE_CMD_RUNNING;
    case air::CommandStatus::kCompleted: return msg::DroneCommandStatus::DRONE_CMD_COMPLETED;
    case air::CommandStatus::kTimedOut: return msg::DroneCommandStatus::DRONE_CMD_TIMED_OUT;
    case air::CommandStatus::kCancelled: return msg::DroneCommandStatus::DRONE_CMD_CANCELLED;
    case air::CommandStatus::kRejected: return msg::DroneCommandStatus::DRONE_CMD_REJECTED;
  }
  return msg::DroneCommandStatus::DRONE_CMD_NONE;
}
msg::ObjectKind ToWire(air::ObjectKind k) { return wire::ObjectKindToWire(k); }

// AirSim's adaptive lookahead factor: 0 on the wire = AirSim's default 1, < 0 = off.
double AdaptiveLookahead(const msg::DroneCommand& d) {
  return d.adaptive_lookahead() == 0 ? 1.0 : std::max(0.0, d.adaptive_lookahead());
}

// The fields move-to-position and move-on-path share.
template <class Move>
Move PathMove(const msg::DroneCommand& d) {
  Move m;
  m.velocity = d.velocity();
  m.timeout = Timeout(d.timeout());
  m.drivetrain = Drive(d.drivetrain());
  m.yaw_mode = Yaw(d.yaw());
  m.lookahead = d.lookahead() > 0 ? d.lookahead() : -1;
  m.adaptive_lookahead = AdaptiveLookahead(d);
  return m;
}


// ---- snapshots (a replacement process restores them) ----
// Values in order, as their bytes: plain values (arithmetic, enums, Eigen's fixed-size
// vectors and the structs made of them: nothing owned), vectors, strings and maps of them.
// One build's representation: a snapshot goes to a replacement of the same program.
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};
template <class T>
struct IsMap : std::false_type {};
template <class K, class V>
struct IsMap<std::map<K, V>> : std::true_type {};

struct SnapOut {
  std::vector<uint8_t> bytes;
  template <class T>
  void One(const T& v) {
    if constexpr (IsVector<T>::value) {
      One(static_cast<uint64_t>(v.size()));
      for (const auto& e : v) One(e);
    } else if constexpr (IsMap<T>::value) {
      One(static_cast<uint64_t>(v.size()));
      for (const auto& [k, e] : v) {
        One(k);
        One(e);
      }
    } else if constexpr (std::is_same_v<T, std::string>) {
      One(static_cast<uint64_t>(v.size()));
      bytes.insert(bytes.end(), v.begin(), v.end());
    } else {
      static_assert(std::is_trivially_destructible_v<T> && !std::is_pointer_v<T>, "a plain value");
      const auto* p = reinterpret_cast<const uint8_t*>(&v);
      bytes.insert(bytes.end(), p, p + sizeof v);
    }
  }
  template <class... T>
  void operator()(const T&... v) {
    (One(v), ...);
  }
};

struct SnapIn {
  const std::vector<uint8_t>& bytes;
  size_t at = 0;
  void Need(uint64_t n) const {
    if (n > bytes.size() - at) throw InputError("air_sim: the snapshot is truncated");
  }
  template <class T>
  void One(T& v) {
    if constexpr (IsVector<T>::value) {
      uint64_t n = 0;
      One(n);
      Need(n);  // at least a byte each: a bad count cannot allocate without bound
      v.assign(n, typename T::value_type{});
      for (auto& e : v) One(e);
    } else if constexpr (IsMap<T>::value) {
      uint64_t n = 0;
      One(n);
      Need(n);
      v.clear();
      for (uint64_t i = 0; i < n; ++i) {
        typename T::key_type k{};
        typename T::mapped_type e{};
        One(k);
        One(e);
        v.emplace(std::move(k), std::move(e));
      }
    } else if constexpr (std::is_same_v<T, std::string>) {
      uint64_t n = 0;
      One(n);
      Need(n);
      v.assign(reinterpret_cast<const char*>(bytes.data() + at), n);
      at += n;
    } else {
      static_assert(std::is_trivially_destructible_v<T> && !std::is_pointer_v<T>, "a plain value");
      Need(sizeof v);
      std::memcpy(static_cast<void*>(&v), bytes.data() + at, sizeof v);
      at += sizeof v;
    }
  }
  template <class... T>
  void operator()(T&... v) {
    (One(v), ...);
  }
};

// One list of fields for both directions (D: DroneState or const DroneState).
template <class Ar, class D>
void DroneFields(Ar& ar, D& s) {
  ar(s.id, s.position, s.orientation, s.velocity, s.angular_velocity, s.acceleration, s.angular_acceleration, s.rotors,
     s.total_thrust, s.armed, s.api_control, s.unsteered, s.landed, s.grounded, s.carrier, s.carrier_offset, s.carrier_yaw,
     s.last_support_time, s.support_velocity, s.collision, s.touching, s.controller, s.gust, s.rng, s.reset_count);
  auto& c = s.command;
  ar(c.id, c.mode, c.running, c.start_time, c.end_time, c.path, c.path_s, c.path_vmax, c.s, c.s_dot, c.segment, c.speed,
     c.lookahead, c.adaptive_lookahead, c.velocity, c.target, c.landed_since);
}

template <class Ar, class B>
void BodyFields(Ar& ar, B& body) {
  std::visit(
      [&](auto& m) {
        using M = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<M, air::cmd::MoveOnPath>) {
          ar(m.path, m.velocity, m.timeout, m.drivetrain, m.yaw_mode, m.lookahead, m.adaptive_lookahead);
        } else if constexpr (std::is_same_v<M, air::cmd::MoveByMotorPwms>) {
          ar(m.pwm, m.duration);
        } else {
          ar(m);
        }
      },
      body);
}

template <size_t... I>
air::CommandBody BodyOfIndex(size_t index, std::index_sequence<I...>) {
  air::CommandBody out;
  bool known = false;
  ((index == I ? (out.emplace<I>(), known = true) : false), ...);
  if (!known) throw InputError("air_sim: the snapshot names an unknown command kind");
  return out;
}

constexpr uint32_t kSnapshotVersion = 1;
}  // namespace

std::optional<air::CommandBody> ToAirCommand(const msg::DroneCommand& d, std::string* why) {
  using K = msg::DroneCommandKind;
  const auto& v = d.values();
  auto need = [&](size_t n) {
    if (v.size() >= n) return true;
    *why = "needs " + std::to_string(n) + " values, got " + std::to_string(v.size());
    return false;
  };
  switch (d.kind()) {
    case K::DRONE_ARM: return air::cmd::Arm{};
    case K::DRONE_DISARM: return air::cmd::Disarm{};
    case K::DRONE_TAKEOFF: return air::cmd::Takeoff{v.empty() ? 0.0 : v[0], d.timeout() > 0 ? d.timeout() : 20.0};
    case K::DRONE_LAND: return air::cmd::Land{d.timeout() > 0 ? d.timeout() : 60.0};
    case K::DRONE_HOVER:
    case K::DRONE_CANCEL: return air::cmd::Hover{};
    case K::DRONE_GO_HOME: return air::cmd::GoHome{d.velocity() > 0 ? d.velocity() : 0.5, Timeout(d.timeout())};
    case K::DRONE_MOVE_TO_Z: {
      air::cmd::MoveToZ m;
      m.z = d.target().z();
      m.velocity = d.velocity();
      m.timeout = Timeout(d.timeout());
      m.yaw_mode = Yaw(d.yaw());
      m.lookahead = d.lookahead() > 0 ? d.lookahead() : -1;
      m.adaptive_lookahead = AdaptiveLookahead(d);
      return m;
    }
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_THROTTLE:
      if (!need(4)) return std::nullopt;
      return air::cmd::MoveByRollPitchYawrateThrottle{v[0], v[1], v[2], v[3], d.duration()};
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_Z:
      if (!need(4)) return std::nullopt;
      return air::cmd::MoveByRollPitchYawrateZ{v[0], v[1], v[2], v[3], d.duration()};
    case K::DRONE_MOVE_BY_ANGLE_RATES_Z:
      if (!need(4)) return std::nullopt;
      return air::cmd::MoveByAngleRatesZ{air::Vec3(v[0], v[1], v[2]), v[3], d.duration()};
    case K::DRONE_SET_KINEMATICS: {
      if (v.size() != 4 && v.size() != 7 && v.size() != 10) {
        *why = "set_kinematics needs 4, 7 or 10 values, got " + std::to_string(v.size());
        return std::nullopt;
      }
      air::cmd::SetKinematics k;
      k.pose.position = ToVec(d.target());
      k.pose.orientation = air::Quat(v[0], v[1], v[2], v[3]);
      if (v.size() >= 7) k.velocity = air::Vec3(v[4], v[5], v[6]);
      if (v.size() >= 10) k.angular_velocity = air::Vec3(v[7], v[8], v[9]);
      return k;
    }
    case K::DRONE_SET_API_CONTROL:
      if (!need(1)) return std::nullopt;
      return air::cmd::SetApiControl{v[0] != 0};
    case K::DRONE_MOVE_TO_GPS:
    case K::DRONE_SET_WIND:
      *why = "mapped by the service (needs the map's geo-reference / applies to every drone)";
      return std::nullopt;
    case K::DRONE_MOVE_TO_POSITION: {
      auto m = PathMove<air::cmd::MoveToPosition>(d);
      m.position = ToVec(d.target());
      return m;
    }
    case K::DRONE_MOVE_ON_PATH: {
      auto m = PathMove<air::cmd::MoveOnPath>(d);
      for (const auto& p : d.path()) m.path.push_back(ToVec(p));
      return m;
    }
    case K::DRONE_TRACK_TARGET: {
      if (!need(3)) return std::nullopt;
      air::cmd::TrackTarget t;
      t.position = ToVec(d.target());
      t.velocity = air::Vec3(v[0], v[1], v[2]);
      t.max_speed = d.velocity();
      t.duration = d.duration() > 0 ? d.duration() : 1.0;
      t.yaw_mode = Yaw(d.yaw());
      return t;
    }
    case K::DRONE_MOVE_BY_VELOCITY:
      return air::cmd::MoveByVelocity{ToVec(d.target()), d.duration(),
                                      d.body_frame() ? air::VelocityFrame::kBody : air::VelocityFrame::kWorld,
                                      Drive(d.drivetrain()), Yaw(d.yaw())};
    case K::DRONE_MOVE_BY_VELOCITY_Z:
      return air::cmd::MoveByVelocityZ{d.target().x(), d.target().y(), d.target().z(), d.duration(),
                                       d.body_frame() ? air::VelocityFrame::kBody : air::VelocityFrame::kWorld,
                                       Drive(d.drivetrain()), Yaw(d.yaw())};
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAW_THROTTLE:
      if (!need(4)) return std::nullopt;
      return air::cmd::MoveByRollPitchYawThrottle{v[0], v[1], v[2], v[3], d.duration()};
    case K::DRONE_MOVE_BY_ROLL_PITCH_YAW_Z:
      if (!need(4)) return std::nullopt;
      return air::cmd::MoveByRollPitchYawZ{v[0], v[1], v[2], v[3], d.duration()};
    case K::DRONE_MOVE_BY_ANGLE_RATES_THROTTLE:
      if (!need(4)) return std::nullopt;
      return air::cmd::MoveByAngleRatesThrottle{air::Vec3(v[0], v[1], v[2]), v[3], d.duration()};
    case K::DRONE_MOVE_BY_MOTOR_PWMS:
      return air::cmd::MoveByMotorPwms{std::vector<double>(v.begin(), v.end()), d.duration()};
    case K::DRONE_ROTATE_TO_YAW: {
      air::cmd::RotateToYaw r;
      r.yaw = d.yaw().value();
      r.timeout = Timeout(d.timeout());
      if (d.margin() > 0) r.margin = d.margin();
      return r;
    }
    case K::DRONE_ROTATE_BY_YAW_RATE: return air::cmd::RotateByYawRate{d.yaw().value(), d.duration()};
    case K::DRONE_SET_GAINS: {
      // Only the loop named changes; the service fills in the rest from the drone's gains.
      *why = "set_gains is mapped by the service";
      return std::nullopt;
    }
  }
  *why = "unknown drone command kind";
  return std::nullopt;
}

AirService::AirService(Bus& bus, std::string name)
    : name_(std::move(name)),
      state_writer_(bus, topics::kAirState),
      event_writer_(bus, topics::kEvent),
      // The vehicles of the frames the state topic keeps: a replacement replays from them.
      ground_(bus, topics::kGroundState, static_cast<size_t>(QosHistoryDepth(QosKind::kState))),
      declarations_(bus),
      physics_writer_(bus, topics::kPhysicsEvents),
      town_source_(bus) {}

// The town's static meshes from the map the coordinator publishes (no shared disk needed):
// roads, sidewalks, buildings, poles and trees become the drones' static collision mesh.
void AirService::LoadTown(const msg::WorldInfo& world) {
  if (world.map_name().to_string().empty()) {
    town_mesh_.reset();
    town_hash_ = 0;
    geo_ = map::GeoReference{};
    return;
  }
  if (world.map_hash() == town_hash_ && town_mesh_) return;  // same map as before: reuse
  const auto town = town_source_.Load(world, "air_sim");
  geo_ = town->geo;
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  for (const auto& m : map::BuildWorldMeshes(town->map, town->scene)) {
    // The ground plane is the model's own (exact, cheaper); the mesh adds what stands on it.
    if (m.semantic_tag == map::semantic::kGround) continue;
    const auto base = static_cast<std::uint32_t>(xyz.size() / 3);
    xyz.insert(xyz.end(), m.vertices.begin(), m.vertices.end());
    for (auto i : m.indices) indices.push_back(base + i);
  }
  town_mesh_ = air::StaticMesh::Build(xyz, indices, 4.0, 1);
  town_hash_ = world.map_hash();
  spdlog::info("town '{}': {} triangles for drone contact", town->name, town_mesh_->triangle_count());
}

void AirService::BeginRun(const msg::WorldInfo& world) {
  LoadTown(world);
  model_ = air::World{};
  model_.seed = world.seed();
  model_.statics.mesh = town_mesh_;
  state_ = air::MakeState(model_);
  blueprints_.clear();
  last_command_.clear();
  spawn_attributes_.clear();
  api_wind_.setZero();
  wind_intensity_ = world.weather().wind_intensity();
  input_timeout_s_ = world.settings().service_timeout() > 0 ? world.settings().service_timeout() : 10.0;
  // Whose GroundState to wait for: the members that declare vehicles or walkers. Every member
  // publishes its set when it joins, before the coordinator counts it alive.
  std::vector<std::string> others;
  for (const std::string& s : RequiredServices(world)) {
    if (s != name_) others.push_back(s);
  }
  if (!declarations_.WaitFor(others, std::chrono::seconds(30))) {
    throw InputError(name_ + ": the blueprint declarations of the run's services did not arrive within 30 s");
  }
  std::vector<std::string> ground = declarations_.Declaring(msg::ActorKind::ACTOR_VEHICLE, others);
  for (const std::string& s : declarations_.Declaring(msg::ActorKind::ACTOR_WALKER, others)) ground.push_back(s);
  wait_for_ground_ = !ground.empty();
  spdlog::info("run {}: seed {}, vehicles {}", world.run(), world.seed(),
               wait_for_ground_ ? "from " + ground.front() + "'s GroundState (frame k-1)"
                                : std::string("none (no member declares vehicles or walkers)"));
}

// The service's state: the drones (spawn attributes and pose rebuild each model; the state
// itself field by field), and what the adapter keeps beside them: blueprints, each drone's
// last command status, simSetWind's wind and the weather's wind intensity.
std::vector<uint8_t> AirService::SaveState() const {
  SnapOut out;
  out(kSnapshotVersion, state_.frame, state_.time, static_cast<uint64_t>(model_.drones.size()));
  for (size_t i = 0; i < model_.drones.size(); ++i) {
    const air::DroneModel& m = model_.drones[i];
    auto a = spawn_attributes_.find(m.id);
    out(m.id, a == spawn_attributes_.end() ? std::map<std::string, std::string>{} : a->second, m.spawn);
    DroneFields(out, state_.drones[i]);
    out(static_cast<uint64_t>(state_.drones[i].command.body.index()));
    BodyFields(out, state_.drones[i].command.body);
  }
  out(blueprints_, last_command_, api_wind_, wind_intensity_);
  return std::move(out.bytes);
}

void AirService::RestoreState(const std::vector<uint8_t>& bytes) {
  SnapIn in{bytes};
  uint32_t version = 0;
  uint64_t frame = 0, drones = 0;
  double time = 0;
  in(version);
  if (version != kSnapshotVersion) throw InputError("air_sim: snapshot version " + std::to_string(version) + " is not this build's");
  in(frame, time, drones);
  in.Need(drones);
  model_.drones.clear();
  state_ = air::MakeState(model_);
  spawn_attributes_.clear();
  for (uint64_t i = 0; i < drones; ++i) {
    uint32_t id = 0;
    std::map<std::string, std::string> attrs;
    air::Pose spawn;
    in(id, attrs, spawn);
    air::AddDrone(&model_, &state_, id, air::ParamsFromAttributes(attrs), spawn);
    spawn_attributes_[id] = std::move(attrs);
    air::DroneState& d = *state_.Find(id);
    DroneFields(in, d);
    uint64_t index = 0;
    in(index);
    d.command.body = BodyOfIndex(index, std::make_index_sequence<std::variant_size_v<air::CommandBody>>{});
    BodyFields(in, d.command.body);
  }
  state_.frame = frame;
  state_.time = time;
  in(blueprints_, last_command_, api_wind_, wind_intensity_);
  if (in.at != bytes.size()) throw InputError("air_sim: the snapshot has trailing bytes");
}

// The drones' state (air::StateHash) and what the adapter keeps that changes later steps or
// what it publishes: simSetWind's wind, the weather's wind intensity, each drone's last
// command id and status, and its blueprint.
uint64_t AirService::StateHash() const {
  Fnv1a64 h;
  h.Add(air::StateHash(state_));
  for (int i = 0; i < 3; ++i) h.Add(api_wind_[i]);
  h.Add(wind_intensity_);
  h.Add<uint64_t>(last_command_.size());
  for (const auto& [drone, c] : last_command_) h.Add(drone).Add(c.first).Add(static_cast<int32_t>(c.second));
  h.Add<uint64_t>(blueprints_.size());
  for (const auto& [drone, bp] : blueprints_) h.Add(drone).Add(std::string_view(bp));
  return h.value();
}

void AirService::Fail(const msg::FrameStamp& stamp, uint32_t actor, const std::string& why) {
  pending_events_.push_back(CommandFailedEvent(name_, actor, why, stamp));
  spdlog::warn("actor {}: {}", actor, why);
}

void AirService::Apply(const msg::Command& c, uint64_t frame, air::Commands* out) {
  msg::FrameStamp stamp;
  stamp.run(0);
  stamp.frame(frame);
  const auto& b = c.body();
  switch (b._d()) {
    case msg::CommandKind::CMD_SPAWN_ACTOR: {
      const auto& s = b.spawn_actor();
      const std::string bp = s.blueprint().to_string();
      if (s.owner().to_string() != name_) return;  // the coordinator names who simulates it
      std::map<std::string, std::string> attrs;
      bool api_control = true;  // Lockstep's own commands drive a drone at once; AirSim's clients spawn without
      for (const auto& a : s.attributes()) {
        const std::string key = a.key().to_string();
        if (key == "api_control") {
          api_control = a.value().to_string() == "true" || a.value().to_string() == "1";
        } else if (key != "role_name") {
          attrs[key] = a.value().to_string();
        }
      }
      if (bp == "drone.quad_plus" && !attrs.count("frame")) attrs["frame"] = "quad_plus";
      if (bp == "drone.hexa_x" && !attrs.count("frame")) attrs["frame"] = "hexa_x";
      try {
        air::AddDrone(&model_, &state_, s.actor(), air::ParamsFromAttributes(attrs), ToPose(s.transform()));
        state_.Find(s.actor())->api_control = api_control;
        blueprints_[s.actor()] = bp;
        spawn_attributes_[s.actor()] = attrs;
      } catch (const std::exception& e) {
        Fail(stamp, s.actor(), std::string("spawn failed: ") + e.what());
      }
      return;
    }
    case msg::CommandKind::CMD_DESTROY_ACTOR:
      if (air::RemoveDrone(&model_, &state_, b.destroy_actor().actor())) {
        blueprints_.erase(b.destroy_actor().actor());
        last_command_.erase(b.destroy_actor().actor());
        spawn_attributes_.erase(b.destroy_actor().actor());
      }
      return;
    case msg::CommandKind::CMD_SET_TRANSFORM:
      if (model_.Find(b.set_transform().actor())) {
        out->push_back(air::Command{0, b.set_transform().actor(), air::cmd::SetPose{ToPose(b.set_transform().transform())}});
      }
      return;
    case msg::CommandKind::CMD_SET_WEATHER:
      wind_intensity_ = b.weather().wind_intensity();
      return;
    case msg::CommandKind::CMD_DRONE: {
      const auto& d = b.drone();
      if (!model_.Find(d.actor())) return;  // coordinator checked the id; a failed spawn leaves it unknown
      std::string why;
      std::optional<air::CommandBody> body;
      if (d.kind() == msg::DroneCommandKind::DRONE_SET_WIND) {
        // simSetWind: one wind for every drone, from the next step on; completes at once.
        api_wind_ = ToVec(d.target());
        last_command_[d.actor()] = {d.command_id(), msg::DroneCommandStatus::DRONE_CMD_COMPLETED};
        return;
      }
      if (d.kind() == msg::DroneCommandKind::DRONE_MOVE_TO_GPS) {
        // AirSim moveToGPS: the geodetic goal through the map's geo-reference, then a move.
        const auto& v = d.values();
        air::cmd::MoveToPosition m;
        m.position = map::FromGeo(geo_, map::GeoPoint{v.size() > 0 ? v[0] : 0, v.size() > 1 ? v[1] : 0, v.size() > 2 ? v[2] : 0});
        m.velocity = d.velocity();
        m.timeout = Timeout(d.timeout());
        m.drivetrain = Drive(d.drivetrain());
        m.yaw_mode = Yaw(d.yaw());
        m.lookahead = d.lookahead() > 0 ? d.lookahead() : -1;
        m.adaptive_lookahead = AdaptiveLookahead(d);
        body = m;
      } else if (d.kind() == msg::DroneCommandKind::DRONE_SET_GAINS) {
        air::ControllerGains g = state_.Find(d.actor())->controller.gains;
        const auto& w = d.gains();
        switch (d.gains_loop()) {
          case msg::GainsLoop::GAINS_ANGLE_RATE:
            g.angle_rate_p = ToVec(w.kp());
            g.angle_rate_i = ToVec(w.ki());
            g.angle_rate_d = ToVec(w.kd());
            break;
          case msg::GainsLoop::GAINS_ANGLE_LEVEL: g.angle_level_p = ToVec(w.kp()); break;
          case msg::GainsLoop::GAINS_VELOCITY:
            g.velocity_p_xy = w.kp().x();
            g.velocity_p_z = w.kp().z();
            g.velocity_i_xy = w.ki().x();
            g.velocity_i_z = w.ki().z();
            break;
          case msg::GainsLoop::GAINS_POSITION:
            g.position_p_xy = w.kp().x();
            g.position_p_z = w.kp().z();
            break;
        }
        body = air::cmd::SetGains{g};
      } else {
        body = ToAirCommand(d, &why);
      }
      if (!body) {
        Fail(stamp, d.actor(), why);
        last_command_[d.actor()] = {d.command_id(), msg::DroneCommandStatus::DRONE_CMD_REJECTED};
        return;
      }
      out->push_back(air::Command{d.command_id(), d.actor(), std::move(*body)});
      return;
    }
    default:
      return;
  }
}

std::vector<air::VehicleBox> AirService::Vehicles(const msg::Tick& tick) {
  std::vector<air::VehicleBox> out;
  if (!wait_for_ground_ || tick.frame() < 2) return out;
  // Jacobi coupling: the vehicles of frame k-1 while stepping to frame k. Never step without
  // them: a missing input faults the run (the coordinator restarts or reports it).
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(input_timeout_s_ * 1000));
  // A ground service being replaced holds the wait (AwaitInput): no cascade of failures.
  auto ground = AwaitInput([&](std::chrono::milliseconds slice) { return ground_.WaitFor(tick.run(), tick.frame() - 1, slice); }, timeout);
  if (!ground) {
    throw MissingInput(name_ + ": no GroundState of frame " + std::to_string(tick.frame() - 1) + " within " +
                       std::to_string(input_timeout_s_) + " s; a missing input faults the run");
  }
  for (const auto& v : ground->vehicles()) {
    air::VehicleBox box;
    box.id = v.actor();
    box.pose = ToPose(v.transform());
    box.velocity = ToVec(v.velocity());
    box.angular_velocity = ToVec(v.angular_velocity());
    box.half_extents = ToVec(v.half_extents());
    out.push_back(box);
  }
  return out;
}

// Weather wind_intensity (0..100) as a mean wind of intensity / 10 m/s towards +x (east; CARLA
// gives no direction) with gusts of 30 % of it; simSetWind's wind adds to it.
air::Environment AirService::Environment(std::vector<air::VehicleBox> vehicles) const {
  air::Environment env;
  const double weather_wind = std::clamp(static_cast<double>(wind_intensity_), 0.0, 100.0) / 10.0;
  env.wind = api_wind_ + air::Vec3(weather_wind, 0, 0);
  env.turbulence_sigma = 0.3 * weather_wind;
  env.vehicles = std::move(vehicles);
  return env;
}

void AirService::Step(const msg::Tick& tick) {
  pending_events_.clear();
  std::vector<air::VehicleBox> vehicles = Vehicles(tick);  // first: a fault leaves the state as it was
  air::Commands commands;
  for (const auto& c : tick.commands()) Apply(c, tick.frame(), &commands);
  air::Step(model_, &state_, commands, Environment(std::move(vehicles)), tick.dt());
  for (const auto& r : state_.reports) {
    // Id 0: a command of no client's future (set_transform, enableApiControl), which must not
    // look like the end of the drone's running command. Part of the state: also in a replay.
    if (r.id != 0) last_command_[r.drone] = {r.id, ToWire(r.status)};
  }
  if (replaying()) return;  // a replacement rebuilding past frames: they were published already
  msg::FrameStamp stamp;
  stamp.run(tick.run());
  stamp.frame(tick.frame());
  stamp.sim_time(tick.sim_time());
  for (const auto& r : state_.reports) {
    if (r.status == air::CommandStatus::kRejected) Fail(stamp, r.drone, "command " + std::to_string(r.id) + " rejected: " + r.message);
  }
  for (const auto& e : state_.events) {
    if (e.kind != air::EventKind::kReset && e.kind != air::EventKind::kCollision) continue;
    msg::SimEvent m;
    m.stamp(stamp);
    m.service(name_);
    m.kind(e.kind == air::EventKind::kReset ? msg::EventKind::EVENT_ACTOR_RESET : msg::EventKind::EVENT_COLLISION);
    m.actor(e.drone);
    m.other_actor(e.object_kind == air::ObjectKind::kVehicle || e.object_kind == air::ObjectKind::kDrone ? e.object_id : 0);
    m.message(e.kind == air::EventKind::kReset ? e.message.substr(0, 511) : std::string("collision with ") + air::ToString(e.object_kind));
    pending_events_.push_back(m);
  }
  for (auto& e : pending_events_) {
    e.stamp(stamp);
    event_writer_.Write(e);
  }
  PublishPhysicsEvents(stamp);
  state_writer_.Write(Publish(stamp));
}

// Every tick, also when empty: the drones' collision onsets of this frame, for the sensors
// service's collision sensor. Impulse: the one that stops the approach, m v_n along the normal.
void AirService::PublishPhysicsEvents(const msg::FrameStamp& stamp) {
  msg::PhysicsEvents out;
  out.stamp(stamp);
  out.service(name_);
  std::vector<msg::ActorCollision> collisions;
  for (const auto& e : state_.events) {
    if (e.kind != air::EventKind::kCollision) continue;
    const air::DroneModel* dm = model_.Find(e.drone);
    msg::ActorCollision c;
    c.actor(e.drone);
    c.other_actor(e.object_kind == air::ObjectKind::kVehicle || e.object_kind == air::ObjectKind::kDrone ? e.object_id : 0);
    c.other_kind(ToWire(e.object_kind));
    c.normal_impulse(FromVec(e.normal * (e.impact_speed * (dm != nullptr ? dm->params.mass : 0.0))));
    c.location(FromVec(e.position));
    collisions.push_back(c);
  }
  out.collisions(std::move(collisions));
  physics_writer_.Write(out);
}

msg::AirState AirService::Publish(const msg::FrameStamp& stamp) const {
  msg::AirState out;
  out.stamp(stamp);
  out.state_hash(StateHash());
  std::vector<msg::DroneState> drones;
  drones.reserve(state_.drones.size());
  for (size_t i = 0; i < state_.drones.size(); ++i) {
    const auto& s = state_.drones[i];
    const auto& m = model_.drones[i];
    msg::DroneState d;
    d.actor(s.id);
    if (auto it = blueprints_.find(s.id); it != blueprints_.end()) d.blueprint(it->second);
    d.transform(FromPose(air::Pose{s.position, s.orientation}));
    d.linear_velocity(FromVec(s.velocity));
    d.angular_velocity(FromVec(s.angular_velocity));
    d.linear_acceleration(FromVec(s.acceleration));
    d.angular_acceleration(FromVec(s.angular_acceleration));
    std::vector<msg::RotorState> rotors;
    for (int r = 0; r < air::RotorCount(m.params.frame); ++r) {
      msg::RotorState rs;
      rs.speed(s.rotors[r].speed);
      rs.thrust(s.rotors[r].thrust);
      rs.torque(s.rotors[r].torque);
      rs.control(s.rotors[r].signal);
      rotors.push_back(rs);
    }
    d.rotors(rotors);
    d.landed(s.landed == air::LandedState::kLanded ? msg::LandedState::LANDED_LANDED : msg::LandedState::LANDED_FLYING);
    d.armed(s.armed);
    d.api_control(s.api_control);
    msg::CollisionInfo c;
    c.has_collided(s.collision.has_collided);
    c.other_kind(ToWire(s.collision.kind));
    c.other_actor(s.collision.kind == air::ObjectKind::kVehicle || s.collision.kind == air::ObjectKind::kDrone ? s.collision.object_id : 0);
    c.normal(FromVec(s.collision.normal));
    c.impact_point(FromVec(s.collision.impact_point));
    c.penetration_depth(s.collision.penetration_depth);
    c.frame(s.collision.frame);
    const air::AirSimCollisionInfo a = air::ToAirSim(m, s.collision);
    c.other_name(s.collision.kind == air::ObjectKind::kNone ? std::string() : a.object_name);
    c.other_id(a.object_id);
    c.position(FromVec(s.collision.position));
    c.collision_count(s.collision.collision_count);
    d.collision(c);
    const map::GeoPoint g = map::ToGeo(geo_, s.position);
    msg::GeoPoint gps;
    gps.latitude(g.latitude);
    gps.longitude(g.longitude);
    gps.altitude(g.altitude);
    d.gps_location(gps);
    d.timestamp(static_cast<uint64_t>(std::llround(stamp.sim_time() * 1e9)));
    // AirSim: ready once the API has control (always here); can_arm when at rest.
    d.ready(true);
    d.can_arm(s.landed == air::LandedState::kLanded && s.velocity.norm() < 0.05);
    d.home_pose(FromPose(m.spawn));
    if (auto it = last_command_.find(s.id); it != last_command_.end()) {
      d.command_id(it->second.first);
      d.command_status(it->second.second);
    }
    drones.push_back(std::move(d));
  }
  out.drones(std::move(drones));
  return out;
}

}  // namespace lockstep
