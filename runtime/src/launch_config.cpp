#include "lockstep/runtime/launch_config.h"

#include <cmath>
#include <set>

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

std::vector<std::string> LaunchConfig::RequiredServices() const {
  std::vector<std::string> out;
  for (const auto& s : services) {
    if (s.required) out.push_back(s.name);
  }
  return out;
}

void ValidateWorldSettings(const msg::WorldSettings& s, const std::string& where) {
  auto bad = [&](const std::string& what) { throw InputError(where + ": " + what); };
  if (!std::isfinite(s.fixed_delta_seconds()) || s.fixed_delta_seconds() <= 0 || s.fixed_delta_seconds() > 1.0) {
    bad("fixed_delta_seconds must be in (0, 1] s, got " + std::to_string(s.fixed_delta_seconds()));
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

ServiceLaunch LoadService(YamlMap m) {
  ServiceLaunch s;
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
  c.world = LoadWorld(m.Map("world"));
  YAML::Node services = m.Child("services");
  if (services && !services.IsSequence()) m.Fail(services, "services", "must be a list");
  std::set<std::string> names;
  for (size_t i = 0; services && i < services.size(); ++i) {
    ServiceLaunch s = LoadService(YamlMap(services[i], where, "services[" + std::to_string(i) + "]"));
    if (!names.insert(s.name).second) {
      m.Fail(services[i], "services[" + std::to_string(i) + "].name", "'" + s.name + "' is used twice");
    }
    c.services.push_back(std::move(s));
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

LaunchConfig LoadLaunchConfig(const std::string& file) { return Load(LoadYamlFile(file), file); }

}  // namespace lockstep
