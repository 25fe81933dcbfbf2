#include "lockstep/air/params.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <variant>

namespace lockstep::air {
namespace {

using FieldPtr = std::variant<double*, Vec3*, FrameType*, DragModel*, GainModel*, LandingModel*>;
struct Field {
  std::string key;
  FieldPtr ptr;
};

std::vector<Field> Fields(MultirotorParams& p) {
  std::vector<Field> out;
  VisitParams(p, [&](const char* key, auto& value) { out.push_back({key, &value}); });
  return out;
}

bool ParseFrame(const std::string& s, FrameType* f) {
  if (s == "quad_x" || s == "quadx" || s == "QuadX") {
    *f = FrameType::kQuadX;
  } else if (s == "quad_plus" || s == "quadplus" || s == "quad+" || s == "QuadPlus") {
    *f = FrameType::kQuadPlus;
  } else if (s == "hexa_x" || s == "hexax" || s == "HexaX") {
    *f = FrameType::kHexaX;
  } else {
    return false;
  }
  return true;
}

// Model choices by their names (ToString of each value).
template <class E>
bool ParseChoice(const std::string& s, E* out, int count) {
  for (int i = 0; i < count; ++i) {
    if (s == ToString(static_cast<E>(i))) {
      *out = static_cast<E>(i);
      return true;
    }
  }
  return false;
}
template <class E>
std::string ChoiceNames(int count) {
  std::string out;
  for (int i = 0; i < count; ++i) out += std::string(i ? " or " : "") + ToString(static_cast<E>(i));
  return out;
}
// Parses a string into any field kind; `expected` says what was wanted when it fails.
bool ParseField(const FieldPtr& f, const std::string& value, std::string* expected);

bool ParseDouble(const std::string& s, double* out) {
  if (s.empty()) return false;
  const char* b = s.c_str();
  char* e = nullptr;
  const double v = std::strtod(b, &e);
  while (*e == ' ' || *e == '\t') ++e;
  if (e == b || *e != '\0' || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool ParseVec3(const std::string& s, Vec3* out) {
  std::string t = s;
  for (char& c : t) {
    if (c == '[' || c == ']' || c == '(' || c == ')') c = ' ';
  }
  std::stringstream ss(t);
  std::string item;
  Vec3 v;
  int n = 0;
  while (std::getline(ss, item, ',')) {
    if (n >= 3 || !ParseDouble(item, &v[n])) return false;
    ++n;
  }
  if (n != 3) return false;
  *out = v;
  return true;
}

std::string Check(bool ok, const char* key, const std::string& what, double value) {
  if (ok) return {};
  std::ostringstream os;
  os << key << ": " << what << " (got " << value << ")";
  return os.str();
}

[[noreturn]] void YamlError(const YAML::Node& node, const std::string& msg) {
  const int line = node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
  throw std::invalid_argument("line " + std::to_string(line) + ": " + msg);
}

double YamlDouble(const YAML::Node& key, const YAML::Node& value, const std::string& name) {
  if (!value.IsScalar()) YamlError(key, "key '" + name + "': expected a number");
  double v = 0;
  if (!ParseDouble(value.Scalar(), &v)) {
    YamlError(value, "key '" + name + "': expected a finite number, got '" + value.Scalar() + "'");
  }
  return v;
}

Vec3 YamlVec3(const YAML::Node& key, const YAML::Node& value, const std::string& name) {
  if (!value.IsSequence() || value.size() != 3) {
    YamlError(key, "key '" + name + "': expected a sequence of 3 numbers [x, y, z]");
  }
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = YamlDouble(key, value[i], name);
  return v;
}

void LoadMap(const YAML::Node& map, const std::string& prefix, std::vector<Field>& fields,
             MultirotorParams& p) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    // Copies: the iterator's pair is a temporary proxy (a reference would dangle).
    const YAML::Node k = it->first;
    const YAML::Node v = it->second;
    if (!k.IsScalar()) YamlError(k, "keys must be strings");
    const std::string name = prefix + k.Scalar();
    if (name == "contact_spheres") {
      if (!v.IsSequence()) YamlError(k, "key 'contact_spheres': expected a sequence");
      p.contact_spheres.clear();
      for (const YAML::Node& s : v) {  // binds the temporary (lifetime extended)
        if (!s.IsMap()) YamlError(s, "contact_spheres: each entry is {center: [x,y,z], radius: r}");
        ContactSphere cs;
        for (auto jt = s.begin(); jt != s.end(); ++jt) {
          const YAML::Node sk_node = jt->first;
          const YAML::Node sv = jt->second;
          const std::string sk = sk_node.Scalar();
          if (sk == "center") {
            cs.center = YamlVec3(sk_node, sv, "contact_spheres.center");
          } else if (sk == "radius") {
            cs.radius = YamlDouble(sk_node, sv, "contact_spheres.radius");
          } else {
            YamlError(sk_node, "unknown key 'contact_spheres." + sk + "'");
          }
        }
        p.contact_spheres.push_back(cs);
      }
      continue;
    }
    if (v.IsMap() && (name == "rotor" || name == "gains")) {
      LoadMap(v, name + ".", fields, p);
      continue;
    }
    Field* f = nullptr;
    for (Field& cand : fields) {
      if (cand.key == name) f = &cand;
    }
    if (f == nullptr) YamlError(k, "unknown key '" + name + "'");
    if (auto* d = std::get_if<double*>(&f->ptr)) {
      **d = YamlDouble(k, v, name);
    } else if (auto* vec = std::get_if<Vec3*>(&f->ptr)) {
      **vec = YamlVec3(k, v, name);
    } else {
      std::string expected;
      if (!v.IsScalar() || !ParseField(f->ptr, v.Scalar(), &expected)) {
        YamlError(v, "key '" + name + "': expected " + expected + ", got '" +
                         (v.IsScalar() ? v.Scalar() : std::string("?")) + "'");
      }
    }
  }
}

bool ParseField(const FieldPtr& f, const std::string& value, std::string* expected) {
  if (auto* d = std::get_if<double*>(&f)) {
    *expected = "a finite number";
    return ParseDouble(value, *d);
  }
  if (auto* v = std::get_if<Vec3*>(&f)) {
    *expected = "three numbers 'x,y,z'";
    return ParseVec3(value, *v);
  }
  if (auto* fr = std::get_if<FrameType*>(&f)) {
    *expected = "quad_x, quad_plus or hexa_x";
    return ParseFrame(value, *fr);
  }
  if (auto* m = std::get_if<DragModel*>(&f)) {
    *expected = ChoiceNames<DragModel>(2);
    return ParseChoice(value, *m, 2);
  }
  if (auto* m = std::get_if<GainModel*>(&f)) {
    *expected = ChoiceNames<GainModel>(2);
    return ParseChoice(value, *m, 2);
  }
  if (auto* m = std::get_if<LandingModel*>(&f)) {
    *expected = ChoiceNames<LandingModel>(2);
    return ParseChoice(value, *m, 2);
  }
  return false;
}

}  // namespace

const char* ToString(DragModel m) { return m == DragModel::kAirSim ? "airsim" : "faces"; }
const char* ToString(GainModel m) { return m == GainModel::kAirSim ? "airsim" : "physical"; }
const char* ToString(LandingModel m) { return m == LandingModel::kGroundLock ? "ground_lock" : "impulse"; }

const char* ToString(FrameType f) {
  switch (f) {
    case FrameType::kQuadX: return "quad_x";
    case FrameType::kQuadPlus: return "quad_plus";
    case FrameType::kHexaX: return "hexa_x";
  }
  return "?";
}

int RotorCount(FrameType f) { return f == FrameType::kHexaX ? 6 : 4; }

std::string ValidateParams(const MultirotorParams& p) {
  MultirotorParams copy = p;
  std::string err;
  VisitParams(copy, [&](const char* key, auto& value) {
    if (!err.empty()) return;
    using T = std::decay_t<decltype(value)>;
    if constexpr (std::is_same_v<T, double>) {
      if (!std::isfinite(value)) err = std::string(key) + ": not finite";
    } else if constexpr (std::is_same_v<T, Vec3>) {
      if (!value.allFinite()) err = std::string(key) + ": not finite";
    }
  });
  if (!err.empty()) return err;
  const double n = RotorCount(p.frame);
  const auto& g = p.gains;
  const auto& r = p.rotor;
  std::string e;
  if (!(e = Check(p.mass > 0, "mass", "must be > 0 kg", p.mass)).empty()) return e;
  if (!(e = Check(p.motor_mass >= 0, "motor_mass", "must be >= 0 kg", p.motor_mass)).empty()) return e;
  if (!(e = Check(n * p.motor_mass < p.mass, "mass", "must exceed the total motor mass", p.mass)).empty()) return e;
  if (!(e = Check(p.arm_length > 0, "arm_length", "must be > 0 m", p.arm_length)).empty()) return e;
  if (!(e = Check(p.body_box.minCoeff() > 0, "body_box", "extents must be > 0 m", p.body_box.minCoeff())).empty()) return e;
  if (!(e = Check(r.thrust_coefficient > 0, "rotor.thrust_coefficient", "must be > 0", r.thrust_coefficient)).empty()) return e;
  if (!(e = Check(r.power_coefficient >= 0, "rotor.power_coefficient", "must be >= 0", r.power_coefficient)).empty()) return e;
  if (!(e = Check(r.max_rpm > 0, "rotor.max_rpm", "must be > 0", r.max_rpm)).empty()) return e;
  if (!(e = Check(r.propeller_diameter > 0, "rotor.propeller_diameter", "must be > 0 m", r.propeller_diameter)).empty()) return e;
  if (!(e = Check(r.propeller_height >= 0, "rotor.propeller_height", "must be >= 0 m", r.propeller_height)).empty()) return e;
  if (!(e = Check(r.time_constant > 0, "rotor.time_constant", "must be > 0 s", r.time_constant)).empty()) return e;
  if (!(e = Check(p.linear_drag_coefficient >= 0, "linear_drag_coefficient", "must be >= 0", p.linear_drag_coefficient)).empty()) return e;
  if (!(e = Check(p.angular_drag_coefficient >= 0, "angular_drag_coefficient", "must be >= 0", p.angular_drag_coefficient)).empty()) return e;
  if (!(e = Check(p.restitution >= 0 && p.restitution <= 1, "restitution", "must be in [0, 1]", p.restitution)).empty()) return e;
  if (!(e = Check(p.friction >= 0, "friction", "must be >= 0", p.friction)).empty()) return e;
  if (!(e = Check(p.contact_radius > 0, "contact_radius", "must be > 0 m", p.contact_radius)).empty()) return e;
  for (const ContactSphere& s : p.contact_spheres) {
    if (!s.center.allFinite() || !std::isfinite(s.radius) || s.radius <= 0) {
      return "contact_spheres: centers must be finite and radii > 0";
    }
  }
  if (!(e = Check(g.angle_rate_p.minCoeff() >= 0 && g.angle_rate_i.minCoeff() >= 0 && g.angle_rate_d.minCoeff() >= 0,
                  "gains.angle_rate_*", "must be >= 0", g.angle_rate_p.minCoeff())).empty()) return e;
  if (!(e = Check(g.max_angle_rate > 0, "gains.max_angle_rate", "must be > 0 rad/s", g.max_angle_rate)).empty()) return e;
  if (!(e = Check(g.angle_level_p.minCoeff() >= 0, "gains.angle_level_p", "must be >= 0", g.angle_level_p.minCoeff())).empty()) return e;
  if (!(e = Check(g.max_tilt > 0 && g.max_tilt < std::numbers::pi / 2, "gains.max_tilt", "must be in (0, pi/2) rad", g.max_tilt)).empty()) return e;
  for (double v : {g.velocity_p_xy, g.velocity_i_xy, g.velocity_p_z, g.velocity_i_z, g.position_p_xy, g.position_p_z, g.integrator_limit, g.altitude_gain}) {
    if (!(e = Check(v >= 0, "gains.velocity_*/position_*/integrator_limit", "must be >= 0", v)).empty()) return e;
  }
  if (!(e = Check(g.max_velocity > 0, "gains.max_velocity", "must be > 0 m/s", g.max_velocity)).empty()) return e;
  if (!(e = Check(g.min_throttle >= 0 && g.min_throttle < 1, "gains.min_throttle", "must be in [0, 1)", g.min_throttle)).empty()) return e;
  if (!(e = Check(p.takeoff_height > 0, "takeoff_height", "must be > 0 m", p.takeoff_height)).empty()) return e;
  if (!(e = Check(p.takeoff_speed > 0, "takeoff_speed", "must be > 0 m/s", p.takeoff_speed)).empty()) return e;
  if (!(e = Check(p.landing_speed > 0, "landing_speed", "must be > 0 m/s", p.landing_speed)).empty()) return e;
  if (!(e = Check(p.path_accel > 0, "path_accel", "must be > 0 m/s^2", p.path_accel)).empty()) return e;
  if (!(e = Check(p.arrival_tolerance > 0, "arrival_tolerance", "must be > 0 m", p.arrival_tolerance)).empty()) return e;
  if (!(e = Check(p.turbulence_scale >= 0, "turbulence_scale", "must be >= 0", p.turbulence_scale)).empty()) return e;
  const double rps = r.max_rpm / 60.0;
  const double tmax = r.thrust_coefficient * 1.225 * rps * rps * std::pow(r.propeller_diameter, 4);
  const double hover = p.mass * 9.80665 / (n * tmax);
  if (!(e = Check(hover < 0.9, "mass", "too heavy: hover would need more than 90% throttle", hover)).empty()) return e;
  return {};
}

DerivedParams DeriveParams(const MultirotorParams& p) {
  if (std::string err = ValidateParams(p); !err.empty()) throw std::invalid_argument(err);
  DerivedParams d;
  const int n = RotorCount(p.frame);
  struct Layout {
    double angle_deg;
    double spin;
  };
  std::vector<Layout> layout;
  switch (p.frame) {
    case FrameType::kQuadX:  // AirSim order: front-right, rear-left, front-left, rear-right
      layout = {{-45, 1}, {135, 1}, {45, -1}, {-135, -1}};
      break;
    case FrameType::kQuadPlus:  // front, left, back, right
      layout = {{0, 1}, {90, -1}, {180, 1}, {-90, -1}};
      break;
    case FrameType::kHexaX:  // counter-clockwise from front-left, alternating spin
      layout = {{30, 1}, {90, -1}, {150, 1}, {210, -1}, {270, 1}, {330, -1}};
      break;
  }
  double max_x = 0, max_y = 0;
  for (const Layout& l : layout) {
    RotorGeometry rg;
    const double a = l.angle_deg * std::numbers::pi / 180.0;
    rg.position = Vec3(p.arm_length * std::cos(a), p.arm_length * std::sin(a), p.rotor_z);
    if (std::abs(rg.position.x()) < 1e-12) rg.position.x() = 0;
    if (std::abs(rg.position.y()) < 1e-12) rg.position.y() = 0;
    rg.spin = l.spin;
    max_x = std::max(max_x, std::abs(rg.position.x()));
    max_y = std::max(max_y, std::abs(rg.position.y()));
    d.rotors.push_back(rg);
  }
  for (RotorGeometry& rg : d.rotors) {
    rg.mix_roll = rg.position.y() / max_y;    // tau_x = y T
    rg.mix_pitch = -rg.position.x() / max_x;  // tau_y = -x T
    rg.mix_yaw = -rg.spin;                    // reaction torque = -spin Q about +z
  }
  // Drag faces.
  const Vec3& b = p.body_box;
  const double nrot = static_cast<double>(d.rotors.size());
  const double dia = p.rotor.propeller_diameter;
  if (p.drag_model == DragModel::kAirSim) {
    // AirSim (MultiRotorPhysicsBody::createDragVertices): six faces at +-body_box (full extent,
    // as AirSim places them), the rotors folded in: pi D^2 per rotor on top and bottom (AirSim's
    // formula, four times the disc area), pi D h per rotor on the four sides.
    const Vec3 area(b.y() * b.z() + nrot * std::numbers::pi * dia * p.rotor.propeller_height,
                    b.x() * b.z() + nrot * std::numbers::pi * dia * p.rotor.propeller_height,
                    b.x() * b.y() + nrot * std::numbers::pi * dia * dia);
    for (int axis = 2; axis >= 0; --axis) {
      for (double sign : {-1.0, 1.0}) {
        DragFace f;
        f.normal = Vec3::Zero();
        f.normal[axis] = sign;
        f.position = f.normal * b[axis];
        f.area = area[axis];
        d.faces.push_back(f);
      }
    }
  } else {
    // Lockstep's faces model: the bare body faces, then top and bottom of each rotor disc.
    for (int axis = 0; axis < 3; ++axis) {
      const double area = b[(axis + 1) % 3] * b[(axis + 2) % 3];
      for (double sign : {1.0, -1.0}) {
        DragFace f;
        f.normal = Vec3::Zero();
        f.normal[axis] = sign;
        f.position = f.normal * (b[axis] / 2);
        f.area = area;
        d.faces.push_back(f);
      }
    }
    const double disc = std::numbers::pi * dia * dia / 4;
    for (const RotorGeometry& rg : d.rotors) {
      for (double sign : {1.0, -1.0}) {
        DragFace f;
        f.normal = Vec3(0, 0, sign);
        f.position = rg.position + Vec3(0, 0, sign * p.rotor.propeller_height / 2);
        f.area = disc;
        d.faces.push_back(f);
      }
    }
  }
  // Inertia: solid box of the non-motor mass plus point masses at the hubs.
  const double mb = p.mass - n * p.motor_mass;
  Mat3 inertia = Mat3::Zero();
  inertia(0, 0) = mb / 12 * (b.y() * b.y() + b.z() * b.z());
  inertia(1, 1) = mb / 12 * (b.x() * b.x() + b.z() * b.z());
  inertia(2, 2) = mb / 12 * (b.x() * b.x() + b.y() * b.y());
  for (const RotorGeometry& rg : d.rotors) {
    const Vec3& r = rg.position;
    inertia += p.motor_mass * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
  }
  d.inertia = inertia;
  d.inertia_inv = inertia.inverse();
  d.max_rev_per_s = p.rotor.max_rpm / 60.0;
  const double n2 = d.max_rev_per_s * d.max_rev_per_s;
  d.max_thrust_per_rotor = p.rotor.thrust_coefficient * 1.225 * n2 * std::pow(p.rotor.propeller_diameter, 4);
  d.max_torque_per_rotor = p.rotor.power_coefficient * 1.225 * n2 *
                           std::pow(p.rotor.propeller_diameter, 5) / (2 * std::numbers::pi);
  d.hover_throttle = p.mass * 9.80665 / (n * d.max_thrust_per_rotor);
  if (p.contact_spheres.empty()) {
    // Centre, each hub and each arm's midpoint: the arms are covered end to end when
    // arm_length / 2 < 2 contact_radius (generic quad: 0.114 m < 0.12 m). The propeller tips
    // beyond contact_radius from the hub are not covered (docs/air.md, contact_test).
    d.spheres.push_back({Vec3::Zero(), p.contact_radius});
    for (const RotorGeometry& rg : d.rotors) d.spheres.push_back({rg.position, p.contact_radius});
    for (const RotorGeometry& rg : d.rotors) d.spheres.push_back({rg.position / 2, p.contact_radius});
  } else {
    d.spheres = p.contact_spheres;
  }
  for (const ContactSphere& s : d.spheres) {
    d.bounding_radius = std::max(d.bounding_radius, s.center.norm() + s.radius);
  }
  return d;
}

double RestHeight(const DerivedParams& d) {
  double h = 0;
  for (const ContactSphere& s : d.spheres) h = std::max(h, s.radius - s.center.z());
  return h;
}

MultirotorParams LoadParamsYaml(const std::string& yaml_text, const MultirotorParams& base) {
  MultirotorParams p = base;
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("line " + std::to_string(e.mark.line + 1) + ": YAML syntax: " + e.msg);
  }
  if (root.IsNull()) return p;
  if (!root.IsMap()) YamlError(root, "multirotor params must be a mapping");
  std::vector<Field> fields = Fields(p);
  LoadMap(root, "", fields, p);
  if (std::string err = ValidateParams(p); !err.empty()) throw std::invalid_argument(err);
  return p;
}

MultirotorParams LoadParamsYamlFile(const std::string& path, const MultirotorParams& base) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open multirotor params file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return LoadParamsYaml(ss.str(), base);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

MultirotorParams ParamsFromAttributes(const std::map<std::string, std::string>& attributes,
                                      const MultirotorParams& base) {
  MultirotorParams p = base;
  std::vector<Field> fields = Fields(p);
  for (const auto& [key, value] : attributes) {
    Field* f = nullptr;
    for (Field& cand : fields) {
      if (cand.key == key) f = &cand;
    }
    if (f == nullptr) {
      throw std::invalid_argument("unknown multirotor attribute '" + key + "'");
    }
    std::string expected;
    if (!ParseField(f->ptr, value, &expected)) {
      throw std::invalid_argument("multirotor attribute '" + key + "': expected " + expected +
                                  ", got '" + value + "'");
    }
  }
  if (std::string err = ValidateParams(p); !err.empty()) {
    throw std::invalid_argument("multirotor attributes: " + err);
  }
  return p;
}

std::vector<std::string> ParamKeys() {
  MultirotorParams p;
  std::vector<std::string> keys;
  for (const Field& f : Fields(p)) keys.push_back(f.key);
  return keys;
}

}  // namespace lockstep::air
