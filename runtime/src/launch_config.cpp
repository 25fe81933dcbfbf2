#include "lockstep/runtime/launch_config.h"
#include "lockstep/runtime/service.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <cmath>
#include <map>
#include <set>
#include <unistd.h>

#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/yaml_config.h"

namespace lockstep {

msg::WorldSettings DefaultWorldSettings() {
  msg::WorldSettings s;
  s.synchronous_mode(false);
  s.fixed_delta_seconds(0.05);
  s.real_time_factor(0.0);
  s.no_rendering_mode(false);
  s.max_substep_delta_time(0.01);
  s.max_substeps(10);
  s.perception_mode(msg::PerceptionMode::PERCEPTION_STRICT);
  s.service_timeout(2.0);
  return s;
}

const HostLaunch* LaunchConfig::HostOf(const std::string& service) const {
  auto it = service_host.find(service);
  if (it == service_host.end()) return nullptr;
  for (const auto& h : hosts) {
    if (h.name == it->second) return &h;
  }
  return nullptr;
}

std::vector<std::string> LaunchConfig::RequiredServices() const {
  std::vector<std::string> out;
  for (const auto& s : services) {
    if (s.required) out.push_back(s.name);
  }
  return out;
}

void ValidateWorldSettings(const msg::WorldSettings& s, const std::string& where) {
  auto bad = [&](const std::string& what) { throw InputError(where + ": " + what); };
  // Any finite positive step, as CARLA accepts (a step above max_substep_delta_time x
  // max_substeps only makes ground_sim's sub-steps longer, as CARLA warns).
  if (!std::isfinite(s.fixed_delta_seconds()) || s.fixed_delta_seconds() <= 0) {
    bad("fixed_delta_seconds must be a finite number > 0 s, got " + std::to_string(s.fixed_delta_seconds()));
  }
  if (!std::isfinite(s.real_time_factor()) || s.real_time_factor() < 0) {
    bad("real_time_factor must be >= 0 (0 = as fast as possible), got " + std::to_string(s.real_time_factor()));
  }
  if (!std::isfinite(s.max_substep_delta_time()) || s.max_substep_delta_time() <= 0) {
    bad("max_substep_delta_time must be > 0");
  }
  if (s.max_substeps() < 1 || s.max_substeps() > 16) bad("max_substeps must be in 1..16");
  if (!std::isfinite(s.service_timeout()) || s.service_timeout() <= 0) bad("service_timeout must be > 0 s");
}

namespace {

msg::PerceptionMode ParsePerception(YamlMap& m, const std::string& key, const std::string& value) {
  if (value == "strict") return msg::PerceptionMode::PERCEPTION_STRICT;
  if (value == "pipelined") return msg::PerceptionMode::PERCEPTION_PIPELINED;
  m.Fail(m.Child(key), key, "must be 'strict' or 'pipelined', got '" + value + "'");
}

msg::WorldSettings LoadWorld(YamlMap m) {
  msg::WorldSettings s = DefaultWorldSettings();
  bool b;
  double d;
  uint32_t u;
  std::string str;
  if (m.Get("synchronous_mode", &b)) s.synchronous_mode(b);
  if (m.Get("fixed_delta_seconds", &d)) s.fixed_delta_seconds(d);
  if (m.Get("real_time_factor", &d)) s.real_time_factor(d);
  if (m.Get("no_rendering_mode", &b)) s.no_rendering_mode(b);
  if (m.Get("max_substep_delta_time", &d)) s.max_substep_delta_time(d);
  if (m.Get("max_substeps", &u)) s.max_substeps(u);
  if (m.Get("perception_mode", &str)) s.perception_mode(ParsePerception(m, "perception_mode", str));
  if (m.Get("service_timeout", &d)) s.service_timeout(d);
  m.Finish();
  ValidateWorldSettings(s, m.where() + ": world");
  return s;
}

ServiceLaunch LoadService(YamlMap m, std::string* host) {
  ServiceLaunch s;
  m.Get("host", host);
  m.Require("name", &s.name);
  m.Require("kind", &s.kind);
  m.Get("executable", &s.executable);
  m.Get("args", &s.args);
  m.Get("required", &s.required);
  m.Get("perception", &s.perception);
  m.Get("restart", &s.restart);
  if (s.restart != "never" && s.restart != "on-failure") {
    m.Fail(m.Child("restart"), "restart", "must be 'never' or 'on-failure', got '" + s.restart + "'");
  }
  m.Finish();
  return s;
}

HostLaunch LoadHost(YamlMap m, const std::string& name) {
  HostLaunch h;
  h.name = name;
  m.Get("address", &h.address);
  m.Get("build_dir", &h.build_dir);
  m.Get("config", &h.config);
  m.Get("container", &h.container);
  m.Get("image_prefix", &h.image_prefix);
  m.Get("network", &h.network);
  m.Finish();
  const std::string where = m.where() + ": hosts." + name;
  if (h.address.empty() == h.container.empty()) {
    throw InputError(where + ": give either 'address' (a machine, [user@]host) or 'container' (podman or docker)");
  }
  if (!h.container.empty() && h.container != "podman" && h.container != "docker") {
    throw InputError(where + ".container: must be 'podman' or 'docker', got '" + h.container + "'");
  }
  if (!h.container.empty() && (!h.build_dir.empty() || !h.config.empty())) {
    throw InputError(where + ": 'build_dir' and 'config' are for a machine ('address'); a container has its image's programs and gets the config mounted");
  }
  if (!h.address.empty() && h.network.size() > 0) {
    throw InputError(where + ".network: only a container host has a network");
  }
  return h;
}

// Names a service's `host` may give for the machine `lockstep up` runs on.
bool IsThisMachine(const std::string& host) {
  if (host.empty() || host == "local" || host == "localhost") return true;
  char name[256] = {};
  return gethostname(name, sizeof(name) - 1) == 0 && host == name;
}

msg::Vector3 Vec(YamlMap& m, const std::string& key, const YAML::Node& n) {
  if (!n.IsSequence() || n.size() != 3) m.Fail(n, key, "must be [x, y, z]");
  msg::Vector3 v;
  try {
    v.x(n[0].as<double>());
    v.y(n[1].as<double>());
    v.z(n[2].as<double>());
  } catch (const YAML::Exception&) {
    m.Fail(n, key, "must be three numbers");
  }
  return v;
}

msg::DroneCommandKind DroneKind(YamlMap& m, const std::string& name) {
  using K = msg::DroneCommandKind;
  static const std::map<std::string, K> kinds{
      {"arm", K::DRONE_ARM}, {"disarm", K::DRONE_DISARM}, {"takeoff", K::DRONE_TAKEOFF}, {"land", K::DRONE_LAND},
      {"hover", K::DRONE_HOVER}, {"go_home", K::DRONE_GO_HOME}, {"move_to_position", K::DRONE_MOVE_TO_POSITION},
      {"move_on_path", K::DRONE_MOVE_ON_PATH}, {"move_by_velocity", K::DRONE_MOVE_BY_VELOCITY},
      {"move_by_velocity_z", K::DRONE_MOVE_BY_VELOCITY_Z}, {"rotate_to_yaw", K::DRONE_ROTATE_TO_YAW},
      {"rotate_by_yaw_rate", K::DRONE_ROTATE_BY_YAW_RATE}};
  auto it = kinds.find(name);
  if (it == kinds.end()) {
    std::string known;
    for (const auto& [k, v] : kinds) known += " " + k;
    m.Fail(m.Child("drone"), "drone", "unknown drone command '" + name + "' (known:" + known + ")");
  }
  return it->second;
}

// One scenario step: {frame, spawn, as, at, yaw, attributes, parent}, {frame, actor, drone, ...},
// {frame, actor, autopilot: true|false} (Traffic Manager), {frame, actor, walker_ai: start|stop}
// or {frame, weather: {wind_intensity: 30, ...}} (CARLA's set_weather).
ScheduledCommand LoadStep(YamlMap m, uint64_t index) {
  ScheduledCommand s;
  s.command.client("scenario");
  s.command.sequence_number(index + 1);
  m.Require("frame", &s.frame);
  if (s.frame < 1) m.Fail(m.Child("frame"), "frame", "must be >= 1");
  std::string spawn, drone, walker_ai;
  bool autopilot = false;
  msg::CommandBody body;
  if (m.Get("spawn", &spawn)) {
    m.Require("as", &s.alias);
    msg::Vector3 at;
    if (YAML::Node n = m.Child("at")) at = Vec(m, "at", n);
    double yaw = 0, pitch = 0;  // rad: ENU heading; nose up (cameras)
    m.Get("yaw", &yaw);
    m.Get("pitch", &pitch);
    std::map<std::string, std::string> attrs;
    m.Get("attributes", &attrs);
    m.Get("parent", &s.actor_alias);  // attach to this actor (by alias): `at`, `yaw` and `pitch` are then relative to it
    msg::Pose pose = MakePose(at.x(), at.y(), at.z(), yaw);
    if (pitch != 0) {  // yaw about z, then pitch about the new y (nose up = negative rotation about y)
      const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2), cp = std::cos(-pitch / 2), sp = std::sin(-pitch / 2);
      pose.orientation().w(cy * cp);
      pose.orientation().x(-sy * sp);
      pose.orientation().y(cy * sp);
      pose.orientation().z(sy * cp);
    }
    body = SpawnBody(spawn, pose, AttributeList(attrs.begin(), attrs.end()));
  } else if (m.Get("autopilot", &autopilot)) {
    m.Require("actor", &s.actor_alias);
    msg::TrafficManagerCommand tm;
    tm.parameter(msg::TrafficManagerParameter::TM_AUTOPILOT);
    tm.value(autopilot ? 1 : 0);
    body.traffic_manager(tm);
  } else if (m.Get("walker_ai", &walker_ai)) {
    m.Require("actor", &s.actor_alias);
    if (walker_ai != "start" && walker_ai != "stop") m.Fail(m.Child("walker_ai"), "walker_ai", "must be start or stop");
    msg::WalkerAICommand w;
    w.kind(walker_ai == "start" ? msg::WalkerAIKind::WALKER_AI_START : msg::WalkerAIKind::WALKER_AI_STOP);
    body.walker_ai(w);
  } else if (m.Get("drone", &drone)) {
    msg::DroneCommand d;
    m.Require("actor", &s.actor_alias);
    d.kind(DroneKind(m, drone));
    d.command_id(index + 1);
    double x = 0;
    if (YAML::Node t = m.Child("target")) d.target(Vec(m, "target", t));
    if (YAML::Node p = m.Child("path")) {
      if (!p.IsSequence()) m.Fail(p, "path", "must be a list of [x, y, z]");
      std::vector<msg::Vector3> path;
      for (const auto& pt : p) path.push_back(Vec(m, "path", pt));
      d.path(path);
    }
    d.velocity(5);
    if (m.Get("velocity", &x)) d.velocity(x);
    if (m.Get("duration", &x)) d.duration(x);
    if (m.Get("timeout", &x)) d.timeout(x);
    // Without `yaw` the heading is kept (AirSim's default YawMode: rate 0).
    msg::YawMode y;
    y.is_rate(true);
    y.value(0);
    if (m.Get("yaw", &x)) {
      y.is_rate(drone == "rotate_by_yaw_rate");
      y.value(x);
    }
    d.yaw(y);
    body.drone(d);
  } else if (m.Child("weather")) {
    // CARLA's set_weather: every parameter, CARLA's WeatherParameters() defaults for those not named.
    YamlMap w = m.Map("weather");
    msg::WeatherParameters p;
    float v = 0;
    p.rayleigh_scattering_scale(0.0331f);
    if (w.Get("cloudiness", &v)) p.cloudiness(v);
    if (w.Get("precipitation", &v)) p.precipitation(v);
    if (w.Get("precipitation_deposits", &v)) p.precipitation_deposits(v);
    if (w.Get("wind_intensity", &v)) p.wind_intensity(v);
    if (w.Get("sun_azimuth_angle", &v)) p.sun_azimuth_angle(v);
    if (w.Get("sun_altitude_angle", &v)) p.sun_altitude_angle(v);
    if (w.Get("fog_density", &v)) p.fog_density(v);
    if (w.Get("fog_distance", &v)) p.fog_distance(v);
    if (w.Get("fog_falloff", &v)) p.fog_falloff(v);
    if (w.Get("wetness", &v)) p.wetness(v);
    if (w.Get("scattering_intensity", &v)) p.scattering_intensity(v);
    if (w.Get("mie_scattering_scale", &v)) p.mie_scattering_scale(v);
    if (w.Get("rayleigh_scattering_scale", &v)) p.rayleigh_scattering_scale(v);
    if (w.Get("dust_storm", &v)) p.dust_storm(v);
    w.Finish();
    body.weather(p);
  } else {
    m.Fail(m.Child("frame"), "spawn", "or 'drone', 'autopilot', 'walker_ai', 'weather' is required in a scenario step");
  }
  s.command.body(body);
  m.Finish();
  return s;
}

LaunchConfig Load(const YAML::Node& root, const std::string& where) {
  LaunchConfig c;
  c.source = where;
  YamlMap m(root, where, "");
  m.Get("name", &c.name);
  m.Get("domain_id", &c.domain_id);
  m.Get("participant_profile", &c.participant_profile);
  m.Get("qos_file", &c.qos_file);
  m.Get("seed", &c.seed);
  m.Get("map", &c.map);
  m.Get("ticks", &c.ticks);
  m.Get("output_dir", &c.output_dir);
  if (YAML::Node n = m.Child("snapshot_period")) {
    m.Get("snapshot_period", &c.snapshot_period);
    if (c.snapshot_period < 1 || c.snapshot_period > MaxSnapshotPeriod()) {
      m.Fail(n, "snapshot_period",
             "must be 1 .. " + std::to_string(MaxSnapshotPeriod()) + " frames (the state topics keep the inputs of that many)");
    }
  }
  c.world = LoadWorld(m.Map("world"));
  YAML::Node services = m.Child("services");
  if (services && !services.IsSequence()) m.Fail(services, "services", "must be a list");
  YAML::Node hosts = m.Child("hosts");
  if (hosts && !hosts.IsMap()) m.Fail(hosts, "hosts", "must be a map of host name to {address: ...} or {container: podman|docker}");
  for (auto it = hosts.begin(); hosts && it != hosts.end(); ++it) {
    const std::string host = it->first.as<std::string>();
    if (IsThisMachine(host)) m.Fail(it->first, "hosts." + host, "names this machine; services without 'host' run here");
    c.hosts.push_back(LoadHost(YamlMap(it->second, where, "hosts." + host), host));
  }
  std::set<std::string> names;
  for (size_t i = 0; services && i < services.size(); ++i) {
    const std::string path = "services[" + std::to_string(i) + "]";
    std::string host;
    ServiceLaunch s = LoadService(YamlMap(services[i], where, path), &host);
    if (!names.insert(s.name).second) {
      m.Fail(services[i], path + ".name", "'" + s.name + "' is used twice");
    }
    if (!IsThisMachine(host)) {
      if (std::none_of(c.hosts.begin(), c.hosts.end(), [&](const HostLaunch& h) { return h.name == host; })) {
        std::string known;
        for (const auto& h : c.hosts) known += (known.empty() ? "" : ", ") + h.name;
        m.Fail(services[i]["host"], path + ".host",
               "unknown host '" + host + "' (" + (known.empty() ? "no `hosts:` in this config" : "hosts: " + known) +
                   "; 'local' or no host = this machine)");
      }
      c.service_host[s.name] = host;
    }
    c.services.push_back(std::move(s));
  }
  YAML::Node scenario = m.Child("scenario");
  if (scenario && !scenario.IsSequence()) m.Fail(scenario, "scenario", "must be a list of steps");
  for (size_t i = 0; scenario && i < scenario.size(); ++i) {
    c.scenario.push_back(LoadStep(YamlMap(scenario[i], where, "scenario[" + std::to_string(i) + "]"), i));
  }
  std::stable_sort(c.scenario.begin(), c.scenario.end(), [](const auto& a, const auto& b) { return a.frame < b.frame; });
  // `recorder: false`: no recorder service unless the config lists one. Otherwise
  // `lockstep up` (which sets LOCKSTEP_DEFAULT_RECORDER for itself and its children, so the
  // coordinator requires what the launcher starts) adds one, as CARLA's server always has
  // its recorder; it costs next to nothing while not recording (docs/recorder.md).
  bool recorder = true;
  m.Get("recorder", &recorder);
  const char* default_recorder = std::getenv("LOCKSTEP_DEFAULT_RECORDER");
  if (recorder && default_recorder != nullptr && std::string(default_recorder) == "1" &&
      std::none_of(c.services.begin(), c.services.end(), [](const ServiceLaunch& s) { return s.kind == "recorder"; }) &&
      !names.count("recorder")) {
    c.services.push_back({"recorder", "recorder", "", {}, true, true, "never"});
  }
  // `ros2: true` (or LOCKSTEP_ROS2=1, which `lockstep up --ros2` sets for itself and its
  // children): the ROS 2 view of the run, as CARLA's server started with --ros2
  // (docs/deployment.md#ros-2). A required member, so the run never moves past a frame the
  // ROS 2 topics have not shown.
  m.Get("ros2", &c.ros2);
  if (const char* env = std::getenv("LOCKSTEP_ROS2"); env != nullptr && std::string(env) == "1") c.ros2 = true;
  if (c.ros2 && std::none_of(c.services.begin(), c.services.end(), [](const ServiceLaunch& s) { return s.kind == "ros2_bridge"; })) {
    if (names.count("ros2_bridge")) {
      throw InputError(where + ": ros2: the service name 'ros2_bridge' is taken by a service of another kind");
    }
    c.services.push_back({"ros2_bridge", "ros2_bridge", "", {}, true, true, "never"});
  }
  m.Finish();
  if (c.domain_id < 0 || c.domain_id > 232) {
    throw InputError(where + ": domain_id must be in 0..232, got " + std::to_string(c.domain_id));
  }
  return c;
}

}  // namespace

LaunchConfig ParseLaunchConfig(const std::string& yaml_text, const std::string& source_name) {
  return Load(LoadYamlString(yaml_text, source_name), source_name);
}

std::string BuildDir() {
  if (const char* env = std::getenv("LOCKSTEP_BUILD_DIR"); env && *env) return env;
  std::error_code ec;
  const auto exe = std::filesystem::canonical("/proc/self/exe", ec);
  return ec ? std::string("build") : exe.parent_path().parent_path().string();  // build/bin/<program>
}

std::string ExpandBuildDir(const std::string& path) {
  const std::string var = "${LOCKSTEP_BUILD_DIR}";
  const size_t at = path.find(var);
  return at == std::string::npos ? path : path.substr(0, at) + BuildDir() + path.substr(at + var.size());
}

LaunchConfig LoadLaunchConfig(const std::string& file) {
  LaunchConfig c = Load(LoadYamlFile(file), file);
  c.map = ExpandBuildDir(c.map);
  c.output_dir = ExpandBuildDir(c.output_dir);
  // Paths in a config are relative to the config file.
  const std::filesystem::path dir = std::filesystem::path(file).parent_path();
  if (!c.map.empty() && std::filesystem::path(c.map).is_relative()) c.map = (dir / c.map).lexically_normal().string();
  if (!c.qos_file.empty() && std::filesystem::path(c.qos_file).is_relative()) {
    c.qos_file = (dir / c.qos_file).lexically_normal().string();
  }
  if (!c.output_dir.empty() && std::filesystem::path(c.output_dir).is_relative()) {
    c.output_dir = (dir / c.output_dir).lexically_normal().string();
  }
  return c;
}

}  // namespace lockstep
