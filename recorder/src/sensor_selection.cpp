#include "lockstep/recorder/sensor_selection.h"

#include <fnmatch.h>

#include <algorithm>
#include <stdexcept>

namespace lockstep::recorder {
namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

SensorSelection SensorSelection::Parse(const std::string& spec) {
  SensorSelection s;
  s.spec_ = Trim(spec);
  size_t at = 0;
  while (at <= spec.size()) {
    const size_t comma = spec.find(',', at);
    const std::string term = Trim(spec.substr(at, comma == std::string::npos ? std::string::npos : comma - at));
    at = comma == std::string::npos ? spec.size() + 1 : comma + 1;
    if (term.empty()) {
      if (s.spec_.empty()) break;  // "" chooses none
      throw std::invalid_argument("sensor selection '" + spec + "': an empty term");
    }
    if (term == "all" || term == "*") {
      s.all_ = true;
    } else if (std::all_of(term.begin(), term.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      const unsigned long long id = term.size() <= 10 ? std::stoull(term) : 0;
      if (id == 0 || id > 0xffffffffull) throw std::invalid_argument("sensor selection '" + spec + "': '" + term + "' is no actor id");
      s.ids_.push_back(static_cast<uint32_t>(id));
    } else if (StartsWith(term, "role_name=")) {
      const std::string role = term.substr(10);
      if (role.empty()) throw std::invalid_argument("sensor selection '" + spec + "': role_name= needs a name");
      s.roles_.push_back(role);
    } else if (StartsWith(term, "sensor") || term.find_first_of("*?[") != std::string::npos) {
      s.patterns_.push_back(term);
    } else {
      throw std::invalid_argument("sensor selection '" + spec + "': '" + term +
                                  "' is neither all, an actor id, role_name=NAME nor a sensor blueprint pattern "
                                  "(sensor.camera.*, sensor.lidar.ray_cast)");
    }
  }
  return s;
}

bool SensorSelection::Chooses(uint32_t id, const std::string& blueprint, const std::string& role_name) const {
  if (all_) return true;
  if (std::find(ids_.begin(), ids_.end(), id) != ids_.end()) return true;
  if (!role_name.empty() && std::find(roles_.begin(), roles_.end(), role_name) != roles_.end()) return true;
  return std::any_of(patterns_.begin(), patterns_.end(), [&](const std::string& p) { return fnmatch(p.c_str(), blueprint.c_str(), 0) == 0; });
}

bool SensorSelection::MayChoose(const std::string& blueprint) const {
  if (all_ || !ids_.empty() || !roles_.empty()) return true;
  return Chooses(0, blueprint, "");
}

std::string SensorMessageType(const std::string& bp) {
  if (StartsWith(bp, "sensor.camera.")) return "Image";
  if (StartsWith(bp, "sensor.lidar.")) return "PointCloud";
  static const std::pair<const char*, const char*> kOther[] = {
      {"sensor.other.radar", "RadarScan"},
      {"sensor.other.imu", "Imu"},
      {"sensor.other.gnss", "Gnss"},
      {"sensor.other.barometer", "Barometer"},
      {"sensor.other.magnetometer", "Magnetometer"},
      {"sensor.other.collision", "CollisionEvent"},
      {"sensor.other.lane_invasion", "LaneInvasionEvent"},
      {"sensor.other.obstacle", "ObstacleDetection"},
      {"sensor.other.distance", "DistanceMeasurement"},
      {"sensor.other.v2x", "V2XData"},
      {"sensor.other.v2x_custom", "V2XData"},
  };
  for (const auto& [name, type] : kOther) {
    if (bp == name) return type;
  }
  return {};
}

}  // namespace lockstep::recorder
