#include "commands.h"

#include <pybind11/stl.h>

#include <functional>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace lockstep::python {

namespace {

// Reads the keys of a command dict and complains about any it did not use.
class Fields {
 public:
  Fields(const py::dict& d, std::string what) : d_(d), what_(std::move(what)) {}
  ~Fields() = default;

  bool Has(const char* key) const { return d_.contains(key); }
  template <class T>
  T Get(const char* key, T fallback) {
    used_.insert(key);
    if (!d_.contains(key) || d_[key].is_none()) return fallback;
    try {
      return d_[key].cast<T>();
    } catch (const py::cast_error&) {
      throw py::value_error(what_ + ": '" + key + "' has the wrong type (" + std::string(py::str(d_[key].get_type())) + ")");
    }
  }
  template <class T>
  T Need(const char* key) {
    if (!d_.contains(key)) throw py::value_error(what_ + ": missing '" + key + "'");
    return Get<T>(key, T{});
  }
  msg::Vector3 Vec3(const char* key) {
    used_.insert(key);
    msg::Vector3 v;
    if (!d_.contains(key)) return v;
    auto t = d_[key].cast<py::sequence>();
    if (t.size() != 3) throw py::value_error(what_ + ": '" + key + "' needs 3 values");
    v.x(t[0].cast<double>());
    v.y(t[1].cast<double>());
    v.z(t[2].cast<double>());
    return v;
  }
  msg::Pose Pose(const char* key) {
    used_.insert(key);
    if (!d_.contains(key)) throw py::value_error(what_ + ": missing '" + key + "'");
    return PoseFromTuple(d_[key]);
  }
  void CheckAllUsed() const {
    for (const auto& item : d_) {
      const std::string k = py::str(item.first);
      if (k != "type" && !used_.count(k)) throw py::value_error(what_ + ": unknown key '" + k + "'");
    }
  }

 private:
  const py::dict& d_;
  std::string what_;
  std::set<std::string> used_;
};

template <class E>
E EnumOf(const std::string& name, const std::map<std::string, E>& table, const std::string& what) {
  auto it = table.find(name);
  if (it != table.end()) return it->second;
  std::string names;
  for (const auto& [k, v] : table) names += (names.empty() ? "" : ", ") + k;
  throw py::value_error(what + ": unknown value '" + name + "' (one of: " + names + ")");
}

const std::map<std::string, msg::DroneCommandKind> kDroneKinds = {
    {"arm", msg::DroneCommandKind::DRONE_ARM},
    {"disarm", msg::DroneCommandKind::DRONE_DISARM},
    {"takeoff", msg::DroneCommandKind::DRONE_TAKEOFF},
    {"land", msg::DroneCommandKind::DRONE_LAND},
    {"hover", msg::DroneCommandKind::DRONE_HOVER},
    {"go_home", msg::DroneCommandKind::DRONE_GO_HOME},
    {"move_to_position", msg::DroneCommandKind::DRONE_MOVE_TO_POSITION},
    {"move_on_path", msg::DroneCommandKind::DRONE_MOVE_ON_PATH},
    {"move_by_velocity", msg::DroneCommandKind::DRONE_MOVE_BY_VELOCITY},
    {"move_by_velocity_z", msg::DroneCommandKind::DRONE_MOVE_BY_VELOCITY_Z},
    {"cancel", msg::DroneCommandKind::DRONE_CANCEL},
    {"track_target", msg::DroneCommandKind::DRONE_TRACK_TARGET},
    {"rotate_to_yaw", msg::DroneCommandKind::DRONE_ROTATE_TO_YAW},
    {"rotate_by_yaw_rate", msg::DroneCommandKind::DRONE_ROTATE_BY_YAW_RATE},
};

const std::map<std::string, msg::TrafficLightAction> kLightActions = {
    {"set", msg::TrafficLightAction::LIGHT_SET},
    {"reset_group", msg::TrafficLightAction::LIGHT_RESET_GROUP},
    {"reset_all", msg::TrafficLightAction::LIGHT_RESET_ALL}};

const std::map<std::string, msg::TrafficLightColor> kLightColors = {
    {"red", msg::TrafficLightColor::LIGHT_RED},       {"yellow", msg::TrafficLightColor::LIGHT_YELLOW},
    {"green", msg::TrafficLightColor::LIGHT_GREEN},   {"off", msg::TrafficLightColor::LIGHT_OFF},
    {"unknown", msg::TrafficLightColor::LIGHT_UNKNOWN},
};

const std::map<std::string, msg::TrafficManagerParameter> kTmParameters = {
    {"autopilot", msg::TrafficManagerParameter::TM_AUTOPILOT},
    {"distance_to_leading_vehicle", msg::TrafficManagerParameter::TM_DISTANCE_TO_LEADING_VEHICLE},
    {"percentage_speed_difference", msg::TrafficManagerParameter::TM_PERCENTAGE_SPEED_DIFFERENCE},
    {"ignore_lights_percentage", msg::TrafficManagerParameter::TM_IGNORE_LIGHTS_PERCENTAGE},
    {"ignore_signs_percentage", msg::TrafficManagerParameter::TM_IGNORE_SIGNS_PERCENTAGE},
    {"ignore_vehicles_percentage", msg::TrafficManagerParameter::TM_IGNORE_VEHICLES_PERCENTAGE},
    {"ignore_walkers_percentage", msg::TrafficManagerParameter::TM_IGNORE_WALKERS_PERCENTAGE},
    {"auto_lane_change", msg::TrafficManagerParameter::TM_AUTO_LANE_CHANGE},
    {"hybrid_physics_radius", msg::TrafficManagerParameter::TM_HYBRID_PHYSICS_RADIUS},
    {"random_seed", msg::TrafficManagerParameter::TM_RANDOM_SEED},
    {"desired_speed", msg::TrafficManagerParameter::TM_DESIRED_SPEED},
    {"keep_right_rule_percentage", msg::TrafficManagerParameter::TM_KEEP_RIGHT_RULE_PERCENTAGE},
    {"random_left_lanechange_percentage", msg::TrafficManagerParameter::TM_RANDOM_LEFT_LANECHANGE_PERCENTAGE},
    {"random_right_lanechange_percentage", msg::TrafficManagerParameter::TM_RANDOM_RIGHT_LANECHANGE_PERCENTAGE},
    {"force_lane_change", msg::TrafficManagerParameter::TM_FORCE_LANE_CHANGE},
    {"set_path", msg::TrafficManagerParameter::TM_SET_PATH},
    {"set_route", msg::TrafficManagerParameter::TM_SET_ROUTE},
    {"hybrid_physics_mode", msg::TrafficManagerParameter::TM_HYBRID_PHYSICS_MODE},
    {"respawn_dormant_vehicles", msg::TrafficManagerParameter::TM_RESPAWN_DORMANT_VEHICLES},
    {"update_vehicle_lights", msg::TrafficManagerParameter::TM_UPDATE_VEHICLE_LIGHTS},
    {"lane_offset", msg::TrafficManagerParameter::TM_LANE_OFFSET},
    {"collision_detection", msg::TrafficManagerParameter::TM_COLLISION_DETECTION},
    {"respawn_boundaries", msg::TrafficManagerParameter::TM_RESPAWN_BOUNDARIES},
};

const std::map<std::string, msg::DebugShapeKind> kDebugShapes = {
    {"point", msg::DebugShapeKind::DEBUG_POINT}, {"line", msg::DebugShapeKind::DEBUG_LINE},
    {"arrow", msg::DebugShapeKind::DEBUG_ARROW}, {"box", msg::DebugShapeKind::DEBUG_BOX},
    {"string", msg::DebugShapeKind::DEBUG_STRING}};

// One world.debug shape: kind, hud, begin, end, extent, rotation (w, x, y, z), size,
// arrow_size, color (r, g, b, a), life_time, persistent_lines, draw_shadow, text.
msg::DebugShape DebugShapeFromDict(const py::dict& d) {
  Fields f(d, "debug shape");
  msg::DebugShape s;
  s.kind(EnumOf(f.Need<std::string>("kind"), kDebugShapes, "debug shape kind"));
  s.hud(f.Get<bool>("hud", false));
  s.begin(f.Vec3("begin"));
  s.end(f.Vec3("end"));
  s.extent(f.Vec3("extent"));
  const auto q = f.Get<std::vector<double>>("rotation", {1, 0, 0, 0});
  if (q.size() != 4) throw py::value_error("debug shape: 'rotation' needs 4 values (w, x, y, z)");
  s.rotation().w(q[0]);
  s.rotation().x(q[1]);
  s.rotation().y(q[2]);
  s.rotation().z(q[3]);
  s.size(f.Get<double>("size", 0.1));
  s.arrow_size(f.Get<double>("arrow_size", 0.1));
  const auto c = f.Get<std::vector<int>>("color", {255, 0, 0, 255});
  if (c.size() != 4) throw py::value_error("debug shape: 'color' needs 4 values (r, g, b, a)");
  for (int v : c) {
    if (v < 0 || v > 255) throw py::value_error("debug shape: colour values are 0..255");
  }
  s.r(static_cast<uint8_t>(c[0]));
  s.g(static_cast<uint8_t>(c[1]));
  s.b(static_cast<uint8_t>(c[2]));
  s.a(static_cast<uint8_t>(c[3]));
  s.life_time(f.Get<double>("life_time", -1));
  s.persistent_lines(f.Get<bool>("persistent_lines", true));
  s.draw_shadow(f.Get<bool>("draw_shadow", false));
  const std::string text = f.Get<std::string>("text", "");
  s.text(text.substr(0, 256));
  f.CheckAllUsed();
  return s;
}

const std::map<std::string, msg::ActorPhysicsKind> kPhysicsKinds = {
    {"set_target_velocity", msg::ActorPhysicsKind::PHYSICS_SET_TARGET_VELOCITY},
    {"set_target_angular_velocity", msg::ActorPhysicsKind::PHYSICS_SET_TARGET_ANGULAR_VELOCITY},
    {"add_impulse", msg::ActorPhysicsKind::PHYSICS_ADD_IMPULSE},
    {"set_simulate_physics", msg::ActorPhysicsKind::PHYSICS_SET_SIMULATE_PHYSICS},
    {"set_light_state", msg::ActorPhysicsKind::PHYSICS_SET_LIGHT_STATE},
};

const std::map<std::string, msg::WalkerAIKind> kWalkerAIKinds = {
    {"start", msg::WalkerAIKind::WALKER_AI_START},
    {"stop", msg::WalkerAIKind::WALKER_AI_STOP},
    {"go_to_location", msg::WalkerAIKind::WALKER_AI_GO_TO_LOCATION},
    {"set_max_speed", msg::WalkerAIKind::WALKER_AI_SET_MAX_SPEED},
};

}  // namespace

msg::Pose PoseFromTuple(const py::handle& h) {
  auto t = h.cast<py::sequence>();
  if (t.size() != 7) throw py::value_error("a pose is (x, y, z, qw, qx, qy, qz), got " + std::to_string(t.size()) + " values");
  msg::Pose p;
  p.position().x(t[0].cast<double>());
  p.position().y(t[1].cast<double>());
  p.position().z(t[2].cast<double>());
  p.orientation().w(t[3].cast<double>());
  p.orientation().x(t[4].cast<double>());
  p.orientation().y(t[5].cast<double>());
  p.orientation().z(t[6].cast<double>());
  return p;
}

py::tuple PoseToTuple(const msg::Pose& p) {
  return py::make_tuple(p.position().x(), p.position().y(), p.position().z(), p.orientation().w(), p.orientation().x(),
                        p.orientation().y(), p.orientation().z());
}

py::tuple Vec(const msg::Vector3& v) { return py::make_tuple(v.x(), v.y(), v.z()); }

msg::CommandBody CommandFromDict(const py::dict& d) {
  if (!d.contains("type")) throw py::value_error("a command dict needs a 'type'");
  const std::string type = py::str(d["type"]);
  Fields f(d, "command '" + type + "'");
  msg::CommandBody b;
  if (type == "spawn") {
    msg::SpawnActor s;
    s.blueprint(f.Need<std::string>("blueprint"));
    s.transform(f.Pose("transform"));
    s.parent(f.Get<uint32_t>("parent", 0));
    s.owner(f.Get<std::string>("owner", ""));
    std::vector<msg::BlueprintAttribute> attrs;
    for (const auto& [k, v] : f.Get<std::map<std::string, std::string>>("attributes", {})) {
      msg::BlueprintAttribute a;
      a.key(k);
      a.value(v);
      attrs.push_back(a);
    }
    s.attributes(attrs);
    b.spawn_actor(s);
  } else if (type == "destroy") {
    msg::DestroyActor x;
    x.actor(f.Need<uint32_t>("actor"));
    b.destroy_actor(x);
  } else if (type == "set_transform") {
    msg::SetTransform x;
    x.actor(f.Need<uint32_t>("actor"));
    x.transform(f.Pose("transform"));
    b.set_transform(x);
  } else if (type == "vehicle_control") {
    msg::VehicleControl x;
    x.actor(f.Need<uint32_t>("actor"));
    x.throttle(f.Get<float>("throttle", 0));
    x.steer(f.Get<float>("steer", 0));
    x.brake(f.Get<float>("brake", 0));
    x.hand_brake(f.Get<bool>("hand_brake", false));
    x.reverse(f.Get<bool>("reverse", false));
    x.manual_gear_shift(f.Get<bool>("manual_gear_shift", false));
    x.gear(f.Get<int32_t>("gear", 0));
    b.vehicle_control(x);
  } else if (type == "walker_control") {
    msg::WalkerControl x;
    x.actor(f.Need<uint32_t>("actor"));
    x.direction(f.Vec3("direction"));
    x.speed(f.Get<float>("speed", 0));
    x.jump(f.Get<bool>("jump", false));
    b.walker_control(x);
  } else if (type == "traffic_light") {
    msg::TrafficLightCommand x;
    x.actor(f.Need<uint32_t>("actor"));
    x.state(EnumOf(f.Get<std::string>("state", "unknown"), kLightColors, "traffic light state"));
    x.green_time(f.Get<double>("green_time", -1));
    x.yellow_time(f.Get<double>("yellow_time", -1));
    x.red_time(f.Get<double>("red_time", -1));
    x.freeze(f.Get<bool>("freeze", false));
    x.action(EnumOf(f.Get<std::string>("action", "set"), kLightActions, "traffic light action"));
    b.traffic_light(x);
  } else if (type == "pedestrians") {
    msg::PedestrianSettings x;
    if (f.Has("seed")) {
      x.seed_only(true);
      x.seed(f.Need<uint64_t>("seed"));
    } else {
      x.cross_factor(f.Need<double>("cross_factor"));
    }
    b.pedestrians(x);
  } else if (type == "traffic_manager") {
    msg::TrafficManagerCommand x;
    x.parameter(EnumOf(f.Need<std::string>("parameter"), kTmParameters, "traffic manager parameter"));
    x.actor(f.Get<uint32_t>("actor", 0));
    x.value(f.Get<double>("value", 0));
    x.other_actor(f.Get<uint32_t>("other_actor", 0));
    x.value2(f.Get<double>("value2", 0));
    if (f.Has("path")) {
      for (const auto& [px, py_, pz] : f.Get<std::vector<std::tuple<double, double, double>>>("path", {})) {
        msg::Vector3 v;
        v.x(px);
        v.y(py_);
        v.z(pz);
        x.path().push_back(v);
      }
      if (x.path().size() > 256) throw py::value_error("command 'traffic_manager': a path has at most 256 locations");
    }
    if (f.Has("route")) {
      const auto route = f.Get<std::vector<std::string>>("route", {});
      if (route.size() > 64) throw py::value_error("command 'traffic_manager': a route has at most 64 entries");
      for (const auto& r : route) {
        if (r.size() > 16) throw py::value_error("command 'traffic_manager': route entry '" + r + "' is longer than 16");
        x.route().push_back(r);
      }
    }
    b.traffic_manager(x);
  } else if (type == "ackermann") {
    msg::VehicleAckermannControl x;
    x.actor(f.Need<uint32_t>("actor"));
    x.steer(f.Get<float>("steer", 0));
    x.steer_speed(f.Get<float>("steer_speed", 0));
    x.speed(f.Get<float>("speed", 0));
    x.acceleration(f.Get<float>("acceleration", 0));
    x.jerk(f.Get<float>("jerk", 0));
    b.ackermann(x);
  } else if (type == "actor_physics") {
    msg::ActorPhysicsCommand x;
    x.actor(f.Need<uint32_t>("actor"));
    x.kind(EnumOf(f.Need<std::string>("kind"), kPhysicsKinds, "actor physics kind"));
    x.value(f.Vec3("value"));
    x.enabled(f.Get<bool>("enabled", false));
    x.light_state(f.Get<uint32_t>("light_state", 0));
    b.actor_physics(x);
  } else if (type == "vehicle_physics") {
    msg::VehiclePhysicsCommand x;
    x.actor(f.Need<uint32_t>("actor"));
    x.physics(PhysicsFromDict(f.Need<py::dict>("physics")));
    b.vehicle_physics(x);
  } else if (type == "walker_ai") {
    msg::WalkerAICommand x;
    x.actor(f.Need<uint32_t>("actor"));
    x.kind(EnumOf(f.Need<std::string>("kind"), kWalkerAIKinds, "walker AI kind"));
    x.location(f.Vec3("location"));
    x.max_speed(f.Get<double>("max_speed", 0));
    b.walker_ai(x);
  } else if (type == "debug_draw") {
    msg::DebugDraw x;
    for (const auto& item : f.Need<py::list>("shapes")) x.shapes().push_back(DebugShapeFromDict(item.cast<py::dict>()));
    if (x.shapes().size() > 4096) throw py::value_error("command 'debug_draw': at most 4096 shapes");
    x.flush_persistent(f.Get<bool>("flush_persistent", false));  // AirSim's simFlushPersistentMarkers
    b.debug_draw(x);
  } else if (type == "v2x_send") {
    msg::V2XSend x;
    x.sensor(f.Need<uint32_t>("sensor"));
    const std::string data = f.Need<std::string>("data");
    if (data.size() > 1024) throw py::value_error("command 'v2x_send': a V2X message takes at most 1024 bytes, got " + std::to_string(data.size()));
    x.data(data);
    b.v2x_send(x);
  } else if (type == "drone") {
    msg::DroneCommand x;
    x.actor(f.Need<uint32_t>("actor"));
    x.kind(EnumOf(f.Need<std::string>("kind"), kDroneKinds, "drone command kind"));
    x.target(f.Vec3("target"));
    x.velocity(f.Get<double>("velocity", 0));
    x.duration(f.Get<double>("duration", 0));
    x.timeout(f.Get<double>("timeout", 0));
    x.values(f.Get<std::vector<double>>("values", {}));
    msg::YawMode y;
    y.is_rate(f.Get<bool>("yaw_is_rate", true));
    y.value(f.Get<double>("yaw", 0));
    x.yaw(y);
    b.drone(x);
  } else {
    throw py::value_error("unknown command type '" + type +
                          "' (spawn, destroy, set_transform, vehicle_control, walker_control, traffic_light, "
                          "traffic_manager, drone, ackermann, actor_physics, vehicle_physics, walker_ai, pedestrians, debug_draw, v2x_send)");
  }
  f.CheckAllUsed();
  return b;
}

#define LOCKSTEP_SETTINGS_FIELDS(X)                                                                       \
  X(bool, synchronous_mode) X(double, fixed_delta_seconds) X(double, real_time_factor)                    \
  X(bool, no_rendering_mode) X(double, max_substep_delta_time) X(uint32_t, max_substeps)                 \
  X(double, service_timeout)

msg::WorldSettings SettingsFromDict(const py::dict& d, msg::WorldSettings s) {
  Fields f(d, "world settings");
#define X(T, name) \
  if (f.Has(#name)) s.name(f.Get<T>(#name, s.name()));
  LOCKSTEP_SETTINGS_FIELDS(X)
#undef X
  if (f.Has("perception_mode")) {
    s.perception_mode(EnumOf(f.Get<std::string>("perception_mode", "strict"),
                             std::map<std::string, msg::PerceptionMode>{{"strict", msg::PerceptionMode::PERCEPTION_STRICT},
                                                                        {"pipelined", msg::PerceptionMode::PERCEPTION_PIPELINED}},
                             "perception_mode"));
  }
  f.CheckAllUsed();
  return s;
}

py::dict SettingsToDict(const msg::WorldSettings& s) {
  py::dict d;
#define X(T, name) d[#name] = s.name();
  LOCKSTEP_SETTINGS_FIELDS(X)
#undef X
  d["perception_mode"] = s.perception_mode() == msg::PerceptionMode::PERCEPTION_PIPELINED ? "pipelined" : "strict";
  return d;
}

#define LOCKSTEP_WEATHER_FIELDS(X)                                                                     \
  X(cloudiness) X(precipitation) X(precipitation_deposits) X(wind_intensity) X(sun_azimuth_angle)      \
  X(sun_altitude_angle) X(fog_density) X(fog_distance) X(fog_falloff) X(wetness)                       \
  X(scattering_intensity) X(mie_scattering_scale) X(rayleigh_scattering_scale) X(dust_storm)

msg::WeatherParameters WeatherFromDict(const py::dict& d, msg::WeatherParameters w) {
  Fields f(d, "weather");
#define X(name) \
  if (f.Has(#name)) w.name(f.Get<float>(#name, w.name()));
  LOCKSTEP_WEATHER_FIELDS(X)
#undef X
  f.CheckAllUsed();
  return w;
}

py::dict WeatherToDict(const msg::WeatherParameters& w) {
  py::dict d;
#define X(name) d[#name] = w.name();
  LOCKSTEP_WEATHER_FIELDS(X)
#undef X
  return d;
}

}  // namespace lockstep::python
