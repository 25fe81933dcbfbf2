// Scene file: YAML written with fixed formatting (byte-identical for equal scenes),
// read back with yaml-cpp.
#include "lockstep/map/scene.h"

#include <yaml-cpp/yaml.h>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "lockstep/map/buildings.h"
#include "lockstep/map/error.h"

namespace lockstep::map {
namespace {

std::string F(double v, int digits = 3) {
  if (v == 0) v = 0;  // no "-0.000"
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  std::string s = buf;
  if (s == "-0.000" || s == "-0.000000") s.erase(0, 1);
  return s;
}

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

template <class T, class Fn>
void List(std::ostringstream& os, const char* key, const std::vector<T>& items, Fn fn) {
  os << key << ":";
  if (items.empty()) {
    os << " []\n";
    return;
  }
  os << "\n";
  for (const T& it : items) os << "  - {" << fn(it) << "}\n";
}

[[noreturn]] void Fail(const std::string& source, const YAML::Node& n, const std::string& what) {
  std::ostringstream os;
  os << source << ":" << (n.Mark().line + 1) << ": " << what;
  throw MapError(os.str());
}

double Num(const std::string& src, const YAML::Node& n, const char* key, bool required = true, double fallback = 0) {
  const YAML::Node v = n[key];
  if (!v) {
    if (required) Fail(src, n, std::string("missing key '") + key + "'");
    return fallback;
  }
  double d = 0;
  try {
    d = v.as<double>();
  } catch (const YAML::Exception&) {
    Fail(src, v, std::string("key '") + key + "' is not a number");
  }
  if (!std::isfinite(d)) Fail(src, v, std::string("key '") + key + "' is not a finite number");
  return d;
}

// An integer key within [lo, hi] (a cast of NaN or 3e9 to int is undefined: the scene fuzzer).
int Int(const std::string& src, const YAML::Node& n, const char* key, int lo, int hi) {
  const double d = Num(src, n, key);
  if (d < lo || d > hi || d != std::floor(d)) {
    Fail(src, n[key], std::string("key '") + key + "' must be an integer in [" + std::to_string(lo) + ", " +
                          std::to_string(hi) + "]");
  }
  return static_cast<int>(d);
}

std::string Str(const std::string& src, const YAML::Node& n, const char* key, bool required = true) {
  const YAML::Node v = n[key];
  if (!v) {
    if (required) Fail(src, n, std::string("missing key '") + key + "'");
    return "";
  }
  if (!v.IsScalar()) Fail(src, v, std::string("key '") + key + "' is not a string");
  return v.as<std::string>();
}

template <class Fn>
void ReadList(const std::string& src, const YAML::Node& root, const char* key, Fn fn) {
  const YAML::Node list = root[key];
  if (!list) return;
  if (!list.IsSequence()) Fail(src, list, std::string("key '") + key + "' must be a list");
  for (const YAML::Node& item : list) {
    if (!item.IsMap()) Fail(src, item, std::string("entries of '") + key + "' must be maps");
    fn(item);
  }
}

}  // namespace

std::string SceneToYaml(const Scene& s) {
  std::ostringstream os;
  os << "# Lockstep scene: static content placed along the roads of one OpenDRIVE map.\n";
  os << "# Units: metres and radians, ENU (OpenDRIVE inertial frame).\n";
  os << "format: lockstep-scene/1\n";
  os << "map: " << Quote(s.map) << "\n";
  os << "seed: " << s.seed << "\n";
  List(os, "buildings", s.buildings, [](const BuildingInstance& b) {
    return "design: " + std::to_string(b.design) + ", x: " + F(b.x) + ", y: " + F(b.y) + ", z: " + F(b.z) +
           ", yaw: " + F(b.yaw, 6) + ", width: " + F(b.width) + ", depth: " + F(b.depth) +
           ", storeys: " + std::to_string(b.storeys) + ", storey_height: " + F(b.storey_height);
  });
  List(os, "vegetation", s.vegetation, [](const VegetationInstance& v) {
    return "kind: " + v.kind + ", x: " + F(v.x) + ", y: " + F(v.y) + ", z: " + F(v.z) + ", height: " + F(v.height) +
           ", radius: " + F(v.radius);
  });
  List(os, "props", s.props, [](const PropInstance& p) {
    return "kind: " + p.kind + ", x: " + F(p.x) + ", y: " + F(p.y) + ", z: " + F(p.z) + ", yaw: " + F(p.yaw, 6) +
           ", length: " + F(p.length) + ", height: " + F(p.height) + ", ref: " + Quote(p.ref);
  });
  auto spawn = [](const SpawnPoint& p) {
    return "x: " + F(p.x) + ", y: " + F(p.y) + ", z: " + F(p.z) + ", yaw: " + F(p.yaw, 6);
  };
  List(os, "vehicle_spawn_points", s.vehicle_spawn_points, spawn);
  List(os, "pedestrian_spawn_points", s.pedestrian_spawn_points, spawn);
  return os.str();
}

Scene SceneFromYaml(const std::string& text, const std::string& src) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw MapError(src + ":" + std::to_string(e.mark.line + 1) + ": YAML error: " + e.msg);
  }
  if (!root.IsMap()) throw MapError(src + ": scene file must be a YAML map");
  const std::string format = Str(src, root, "format");
  if (format != "lockstep-scene/1") Fail(src, root["format"], "unsupported format '" + format + "'");
  Scene s;
  s.map = Str(src, root, "map", false);
  if (const YAML::Node seed = root["seed"]) {
    try {
      s.seed = seed.as<std::uint64_t>();
    } catch (const YAML::Exception&) {
      Fail(src, seed, "key 'seed' is not an unsigned integer");
    }
  }
  ReadList(src, root, "buildings", [&](const YAML::Node& n) {
    BuildingInstance b;
    b.design = Int(src, n, "design", 0, kBuildingDesignCount - 1);
    b.x = Num(src, n, "x");
    b.y = Num(src, n, "y");
    b.z = Num(src, n, "z", false, 0);
    b.yaw = Num(src, n, "yaw", false, 0);
    b.width = Num(src, n, "width");
    b.depth = Num(src, n, "depth");
    b.storeys = Int(src, n, "storeys", 1, 200);
    b.storey_height = Num(src, n, "storey_height", false, 3.2);
    if (b.design < 0 || b.width <= 0 || b.depth <= 0 || b.storeys < 1) Fail(src, n, "invalid building");
    s.buildings.push_back(b);
  });
  ReadList(src, root, "vegetation", [&](const YAML::Node& n) {
    VegetationInstance v;
    v.kind = Str(src, n, "kind");
    v.x = Num(src, n, "x");
    v.y = Num(src, n, "y");
    v.z = Num(src, n, "z", false, 0);
    v.height = Num(src, n, "height");
    v.radius = Num(src, n, "radius");
    s.vegetation.push_back(v);
  });
  ReadList(src, root, "props", [&](const YAML::Node& n) {
    PropInstance p;
    p.kind = Str(src, n, "kind");
    p.x = Num(src, n, "x");
    p.y = Num(src, n, "y");
    p.z = Num(src, n, "z", false, 0);
    p.yaw = Num(src, n, "yaw", false, 0);
    p.length = Num(src, n, "length", false, 0);
    p.height = Num(src, n, "height", false, 0);
    p.ref = Str(src, n, "ref", false);
    s.props.push_back(p);
  });
  auto spawns = [&](const char* key, std::vector<SpawnPoint>* out) {
    ReadList(src, root, key, [&](const YAML::Node& n) {
      out->push_back(SpawnPoint{Num(src, n, "x"), Num(src, n, "y"), Num(src, n, "z", false, 0), Num(src, n, "yaw", false, 0)});
    });
  };
  spawns("vehicle_spawn_points", &s.vehicle_spawn_points);
  spawns("pedestrian_spawn_points", &s.pedestrian_spawn_points);
  return s;
}

Scene LoadSceneFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::size_t slash = path.find_last_of('/');
  return SceneFromYaml(ss.str(), slash == std::string::npos ? path : path.substr(slash + 1));
}

}  // namespace lockstep::map
