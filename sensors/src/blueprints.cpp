#include "lockstep/sensors/blueprints.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace lockstep::sensors {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

AttributeSpec F(const std::string& id, double def, double min = -kInf, double max = kInf) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, def);  // shortest text that reads back exactly
  return {id, AttrType::kFloat, std::string(buf, ec == std::errc() ? end : buf), min, max};
}
AttributeSpec I(const std::string& id, int64_t def, double min, double max) {
  return {id, AttrType::kInt, std::to_string(def), min, max};
}
AttributeSpec B(const std::string& id, bool def) { return {id, AttrType::kBool, def ? "true" : "false"}; }
AttributeSpec S(const std::string& id, const std::string& def) { return {id, AttrType::kString, def}; }
// A string restricted to `choices`; the default is the first (CARLA's first recommended value).
AttributeSpec Choice(const std::string& id, std::vector<std::string> choices) {
  AttributeSpec a{id, AttrType::kString, choices.front()};
  a.choices = std::move(choices);
  return a;
}

// Every sensor: role_name, and sensor_tick (s between samples, 0 = every frame).
std::vector<AttributeSpec> Common(std::vector<AttributeSpec> more, bool ticked = true) {
  std::vector<AttributeSpec> v{S("role_name", "")};
  if (ticked) v.push_back(F("sensor_tick", 0.0, 0, 3600));
  v.insert(v.end(), more.begin(), more.end());
  return v;
}

// CARLA 0.9.16's V2X radio (UActorBlueprintFunctionLibrary::MakeV2XDefinition /
// MakeCustomV2XDefinition): the path-loss model's attributes, in CARLA's order.
std::vector<AttributeSpec> V2XRadio() {
  return {I("noise_seed", 0, 0, 4294967295.0),
          F("transmit_power", 21.5, -1e3, 1e3),
          F("receiver_sensitivity", -99.0, -1e3, 1e3),
          F("frequency_ghz", 5.9, 1e-3, 1e3),
          F("combined_antenna_gain", 10.0, -1e3, 1e3),
          Choice("scenario", {"highway", "rural", "urban"}),
          Choice("path_loss_model", {"winner", "geometric"}),
          F("path_loss_exponent", 2.7, 0, 100),
          F("d_ref", 1.0, 1e-6, 1e6),
          F("filter_distance", 500.0, 0, 1e7),
          B("use_etsi_fading", true),
          F("custom_fading_stddev", 0.0, 0, 1e3)};
}

std::vector<AttributeSpec> V2XAttributes() {
  std::vector<AttributeSpec> v = V2XRadio();
  for (auto a : {F("gen_cam_min", 0.1, 0, 3600), F("gen_cam_max", 1.0, 0, 3600), B("fixed_rate", false),
                 F("noise_lat_stddev", 0.0, 0, 90), F("noise_lat_bias", 0.0, -90, 90), F("noise_lon_stddev", 0.0, 0, 180),
                 F("noise_lon_bias", 0.0, -180, 180), F("noise_alt_stddev", 0.0, 0, 1e6), F("noise_alt_bias", 0.0, -1e6, 1e6),
                 F("noise_head_stddev", 0.0, 0, 360), F("noise_head_bias", 0.0, -360, 360), F("noise_accel_stddev_x", 0.0, 0, 1e3),
                 F("noise_accel_stddev_y", 0.0, 0, 1e3), F("noise_accel_stddev_z", 0.0, 0, 1e3),
                 F("noise_yawrate_stddev", 0.0, 0, 1e3), F("noise_yawrate_bias", 0.0, -1e3, 1e3), F("noise_vel_stddev_x", 0.0, 0, 1e3)}) {
    v.push_back(a);
  }
  return Common(v);
}

std::vector<AttributeSpec> LidarAttributes(bool semantic) {
  std::vector<AttributeSpec> v{I("channels", 32, 1, 256),          F("range", 10.0, 0.1, 10000),
                               I("points_per_second", 56000, 1, 1e8), F("rotation_frequency", 10.0, 0.001, 1000),
                               F("upper_fov", 10.0, -90, 90),        F("lower_fov", -30.0, -90, 90),
                               F("horizontal_fov", 360.0, 0.001, 360)};
  if (!semantic) {
    for (auto a : {F("atmosphere_attenuation_rate", 0.004, 0, 10), F("dropoff_general_rate", 0.45, 0, 1),
                   F("dropoff_intensity_limit", 0.8, 0, 1), F("dropoff_zero_intensity", 0.4, 0, 1), F("noise_stddev", 0.0, 0, 100),
                   I("noise_seed", 0, 0, 4294967295.0)}) {
      v.push_back(a);
    }
  }
  return Common(v);
}

std::vector<SensorBlueprint> Build() {
  return {
      {"sensor.lidar.ray_cast", SensorType::kLidar, LidarAttributes(false)},
      {"sensor.lidar.ray_cast_semantic", SensorType::kSemanticLidar, LidarAttributes(true)},
      {"sensor.other.radar", SensorType::kRadar,
       Common({F("horizontal_fov", 30.0, 0.001, 179), F("vertical_fov", 30.0, 0.001, 179), F("range", 100.0, 0.1, 10000),
               I("points_per_second", 1500, 1, 1e8), I("noise_seed", 0, 0, 4294967295.0)})},
      {"sensor.other.imu", SensorType::kImu,
       Common({F("noise_accel_stddev_x", 0.0, 0, 1e3), F("noise_accel_stddev_y", 0.0, 0, 1e3), F("noise_accel_stddev_z", 0.0, 0, 1e3),
               F("noise_gyro_stddev_x", 0.0, 0, 1e3), F("noise_gyro_stddev_y", 0.0, 0, 1e3), F("noise_gyro_stddev_z", 0.0, 0, 1e3),
               F("noise_gyro_bias_x", 0.0, -1e3, 1e3), F("noise_gyro_bias_y", 0.0, -1e3, 1e3), F("noise_gyro_bias_z", 0.0, -1e3, 1e3),
               // Lockstep's: a bias random walk (sigma per sqrt(s)), AirSim's model; CARLA has none, so 0
               // (off) by default; the airsim module sets AirSim's 4.6 deg/h and 36 ug.
               F("noise_gyro_bias_stability", 0.0, 0, 1e3), F("noise_accel_bias_stability", 0.0, 0, 1e3),
               I("noise_seed", 0, 0, 4294967295.0)})},
      {"sensor.other.gnss", SensorType::kGnss,
       Common({F("noise_alt_bias", 0.0, -1e6, 1e6), F("noise_alt_stddev", 0.0, 0, 1e6), F("noise_lat_bias", 0.0, -90, 90),
               F("noise_lat_stddev", 0.0, 0, 90), F("noise_lon_bias", 0.0, -180, 180), F("noise_lon_stddev", 0.0, 0, 180),
               I("noise_seed", 0, 0, 4294967295.0)})},
      {"sensor.other.barometer", SensorType::kBarometer,
       Common({F("qnh", 1013.25, 800, 1100), F("noise_pressure_stddev", 2.7, 0, 1e4), F("drift_pressure_factor_sigma", 0.0365 / 20, 0, 1),
               F("drift_pressure_factor_tau", 3600.0, 0.001, 1e9), I("noise_seed", 0, 0, 4294967295.0)})},
      {"sensor.other.magnetometer", SensorType::kMagnetometer,
       Common({F("noise_stddev", 0.005, 0, 100), F("noise_bias", 0.0, -100, 100), F("scale_factor", 1.0, 0, 100),
               I("noise_seed", 0, 0, 4294967295.0)})},
      {"sensor.other.distance", SensorType::kDistance,
       Common({F("min_distance", 0.2, 0, 1e4), F("max_distance", 40.0, 0.01, 1e4), F("noise_stddev", 0.2, 0, 100),
               I("noise_seed", 0, 0, 4294967295.0)})},
      {"sensor.other.obstacle", SensorType::kObstacle,
       Common({F("distance", 5.0, 0, 1e4), F("hit_radius", 0.5, 0, 100), B("only_dynamics", false), B("debug_linetrace", false)})},
      {"sensor.other.collision", SensorType::kCollision, Common({}, false)},
      {"sensor.other.lane_invasion", SensorType::kLaneInvasion, Common({}, false)},
      {"sensor.other.v2x", SensorType::kV2X, V2XAttributes()},
      {"sensor.other.v2x_custom", SensorType::kCustomV2X, Common(V2XRadio())},
  };
}

bool ParseNumber(const std::string& s, double* out) {
  if (s.empty()) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(*out);
}

const char* TypeName(AttrType t) {
  switch (t) {
    case AttrType::kBool: return "bool";
    case AttrType::kInt: return "int";
    case AttrType::kFloat: return "float";
    case AttrType::kString: return "string";
  }
  return "?";
}

std::string CheckValue(const AttributeSpec& a, const std::string& v) {
  auto bad = [&](const std::string& why) { return "attribute '" + a.id + "' (" + TypeName(a.type) + "): " + why + ", got '" + v + "'"; };
  double x = 0;
  switch (a.type) {
    case AttrType::kString: {
      if (a.choices.empty() || std::find(a.choices.begin(), a.choices.end(), v) != a.choices.end()) return {};
      std::string list;
      for (const auto& c : a.choices) list += (list.empty() ? "" : ", ") + c;
      return bad("expected one of " + list);
    }
    case AttrType::kBool:
      return v == "true" || v == "false" || v == "True" || v == "False" ? std::string() : bad("expected true or false");
    case AttrType::kInt:
      if (!ParseNumber(v, &x) || x != std::floor(x)) return bad("expected an integer");
      break;
    case AttrType::kFloat:
      if (!ParseNumber(v, &x)) return bad("expected a finite number");
      break;
  }
  if (x < a.min || x > a.max) {
    std::ostringstream r;
    r << "out of range [" << a.min << ", " << a.max << "]";
    return bad(r.str());
  }
  return {};
}

}  // namespace

const std::vector<SensorBlueprint>& SensorBlueprints() {
  static const std::vector<SensorBlueprint> all = Build();
  return all;
}

const SensorBlueprint* FindSensorBlueprint(const std::string& id) {
  for (const auto& bp : SensorBlueprints()) {
    if (bp.id == id) return &bp;
  }
  return nullptr;
}

std::string ResolveAttributes(const SensorBlueprint& bp, const std::map<std::string, std::string>& given, Attributes* out) {
  Attributes r;
  for (const auto& a : bp.attributes) r.values_[a.id] = a.default_value;
  for (const auto& [key, value] : given) {
    const AttributeSpec* spec = nullptr;
    for (const auto& a : bp.attributes) {
      if (a.id == key) spec = &a;
    }
    if (!spec) {
      std::string known;
      for (const auto& a : bp.attributes) known += (known.empty() ? "" : ", ") + a.id;
      return "blueprint '" + bp.id + "' has no attribute '" + key + "' (it has: " + known + ")";
    }
    if (std::string why = CheckValue(*spec, value); !why.empty()) return bp.id + ": " + why;
    r.values_[key] = value;
    r.given_[key] = true;
  }
  *out = std::move(r);
  return {};
}

double Attributes::Float(const std::string& id) const {
  auto it = values_.find(id);
  if (it == values_.end()) throw std::logic_error("sensors: no attribute '" + id + "'");
  double x = 0;
  ParseNumber(it->second, &x);
  return x;
}
int64_t Attributes::Int(const std::string& id) const { return static_cast<int64_t>(Float(id)); }
bool Attributes::Bool(const std::string& id) const {
  const std::string& v = String(id);
  return v == "true" || v == "True";
}
const std::string& Attributes::String(const std::string& id) const {
  auto it = values_.find(id);
  if (it == values_.end()) throw std::logic_error("sensors: no attribute '" + id + "'");
  return it->second;
}

}  // namespace lockstep::sensors
