#include "lockstep/render/models.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "lockstep/render/camera.h"

namespace lockstep::render {
namespace {

using Rgb = std::array<std::uint8_t, 3>;
using V3 = Eigen::Vector3d;

std::uint64_t Fnv(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

// One model under construction: parts appended with a colour, material and tag.
struct Builder {
  Model model;
  void Add(const map::Mesh& m, const Rgb& rgb, Material mat, std::uint8_t tag) {
    AppendMesh(&model.vertices, m, rgb, mat, tag);
  }
};

map::Mesh Box(const V3& centre, const V3& size, double yaw = 0) {
  map::Mesh m;
  map::AddBox(m, centre - V3(0, 0, size.z() / 2), size.x(), size.y(), size.z(), yaw, true);
  return m;
}

// A box whose top face is shorter (taper) and shifted along x: car cabins, windscreens.
map::Mesh Prism(double x, double half_w, double z0, double z1, double len_bottom, double len_top, double top_shift) {
  map::Mesh m;
  const V3 b0(x - len_bottom / 2, -half_w, z0), b1(x + len_bottom / 2, -half_w, z0), b2(x + len_bottom / 2, half_w, z0),
      b3(x - len_bottom / 2, half_w, z0);
  const double tx = x + top_shift;
  const V3 t0(tx - len_top / 2, -half_w, z1), t1(tx + len_top / 2, -half_w, z1), t2(tx + len_top / 2, half_w, z1),
      t3(tx - len_top / 2, half_w, z1);
  m.AddQuad(b0, b1, b2, b3, -V3::UnitZ());
  m.AddQuad(t0, t1, t2, t3, V3::UnitZ());
  m.AddQuad(b0, b1, t1, t0, -V3::UnitY());
  m.AddQuad(b3, b2, t2, t3, V3::UnitY());
  m.AddQuad(b1, b2, t2, t1, V3(z1 - z0, 0, -(len_top / 2 + top_shift - len_bottom / 2)).normalized());
  m.AddQuad(b0, b3, t3, t0, V3(-(z1 - z0), 0, -(len_bottom / 2 - len_top / 2 + top_shift)).normalized());
  return m;
}

// Cylinder with its axis along body y (wheels), centred at c.
map::Mesh Wheel(const V3& c, double radius, double width) {
  map::Mesh m;
  map::AddCylinder(m, V3::Zero(), radius, width, 10);
  for (std::size_t i = 0; i < m.vertices.size(); i += 3) {
    const double x = m.vertices[i], y = m.vertices[i + 1], z = m.vertices[i + 2] - width / 2;
    // Rotate +z onto +y: (x, y, z) -> (x, -z, y)... keeps the winding (a proper rotation).
    m.vertices[i] = static_cast<float>(c.x() + x);
    m.vertices[i + 1] = static_cast<float>(c.y() - z);
    m.vertices[i + 2] = static_cast<float>(c.z() + y);
  }
  return m;
}

map::Mesh Ellipsoid(const V3& c, const V3& r, int sides = 8, int rings = 5) {
  map::Mesh m;
  map::AddEllipsoid(m, c, r, sides, rings);
  return m;
}

map::Mesh Cylinder(const V3& base, double radius, double height, int sides = 6) {
  map::Mesh m;
  map::AddCylinder(m, base, radius, height, sides);
  return m;
}

enum class Kind { kCar, kOneBox, kTruck, kBus, kBike };
enum Extra { kNone = 0, kTaxiSign, kPoliceBar, kAmbulanceBar, kRoofRack, kSpoiler, kLadder, kBed };

struct Style {
  const char* name;
  Kind kind;
  double body_h;     // lower body height, fraction of total height
  double cabin_len;  // fraction of length
  double cabin_off;  // cabin centre offset, fraction of length (+ forward)
  double taper;      // cabin top length / bottom length
  double wheel_r;    // wheel radius, fraction of total height
  Extra extra;
  std::uint8_t tag;
};

const Style kStyles[] = {
    {"sedan", Kind::kCar, 0.5, 0.48, -0.05, 0.62, 0.22, kNone, tag::kCar},
    {"hatchback", Kind::kCar, 0.5, 0.55, -0.12, 0.7, 0.22, kNone, tag::kCar},
    {"suv", Kind::kCar, 0.55, 0.62, -0.1, 0.8, 0.24, kRoofRack, tag::kCar},
    {"van", Kind::kOneBox, 0.45, 0.82, -0.06, 0.9, 0.18, kNone, tag::kCar},
    {"truck", Kind::kTruck, 0.35, 0.22, 0.38, 0.9, 0.17, kNone, tag::kTruck},
    {"bus", Kind::kBus, 0.5, 1.0, 0.0, 1.0, 0.14, kNone, tag::kBus},
    {"motorbike", Kind::kBike, 0.45, 0.3, 0.0, 1.0, 0.22, kNone, tag::kMotorcycle},
    {"pickup", Kind::kCar, 0.55, 0.35, 0.12, 0.75, 0.24, kBed, tag::kTruck},
    {"coupe", Kind::kCar, 0.55, 0.4, -0.08, 0.5, 0.24, kNone, tag::kCar},
    {"wagon", Kind::kCar, 0.5, 0.62, -0.14, 0.85, 0.22, kRoofRack, tag::kCar},
    {"minivan", Kind::kOneBox, 0.45, 0.72, -0.08, 0.75, 0.2, kNone, tag::kCar},
    {"sportscar", Kind::kCar, 0.6, 0.36, -0.1, 0.45, 0.26, kSpoiler, tag::kCar},
    {"jeep", Kind::kCar, 0.55, 0.5, -0.12, 0.95, 0.27, kNone, tag::kCar},
    {"taxi", Kind::kCar, 0.5, 0.48, -0.05, 0.62, 0.22, kTaxiSign, tag::kCar},
    {"police", Kind::kCar, 0.5, 0.5, -0.05, 0.65, 0.22, kPoliceBar, tag::kCar},
    {"ambulance", Kind::kOneBox, 0.45, 0.85, -0.05, 0.95, 0.17, kAmbulanceBar, tag::kCar},
    {"firetruck", Kind::kTruck, 0.4, 0.25, 0.36, 0.9, 0.16, kLadder, tag::kTruck},
    {"bicycle", Kind::kBike, 0.35, 0.3, 0.0, 1.0, 0.2, kNone, tag::kBicycle},
    {"microcar", Kind::kCar, 0.45, 0.7, -0.05, 0.8, 0.2, kNone, tag::kCar},
    {"limousine", Kind::kCar, 0.5, 0.6, -0.05, 0.85, 0.18, kNone, tag::kCar},
};

const Style& FindStyle(const std::string& name) {
  for (const auto& s : kStyles) {
    if (name == s.name) return s;
  }
  return kStyles[0];
}

constexpr Rgb kTyre{25, 25, 25}, kGlass{40, 55, 70}, kChrome{170, 170, 175}, kHead{255, 250, 225}, kTail{200, 20, 20};

void AddWheels(Builder* b, double hx, double hy, double hz, double r, int axles, std::uint8_t tag) {
  const double w = std::min(0.35 * hy, 0.32);
  for (int a = 0; a < axles; ++a) {
    const double x = axles == 2 ? (a == 0 ? 0.68 * hx : -0.68 * hx) : (0.75 - 1.5 * a / (axles - 1)) * hx;
    for (int side : {-1, 1}) b->Add(Wheel(V3(x, side * (hy - w / 2), -hz + r), r, w), kTyre, kMatPlain, tag);
  }
}

void AddLights(Builder* b, const Style& s, double hx, double hy, double z) {
  for (int side : {-1, 1}) {
    b->Add(Box(V3(hx - 0.02, side * 0.68 * hy, z), V3(0.06, 0.22 * hy, 0.1)), kHead, kMatHeadlight, s.tag);
    b->Add(Box(V3(-hx + 0.02, side * 0.7 * hy, z), V3(0.06, 0.2 * hy, 0.1)), kTail, kMatTaillight, s.tag);
  }
}

void BuildCar(Builder* b, const Style& s, double hx, double hy, double hz) {
  const double H = 2 * hz, L = 2 * hx, r = s.wheel_r * H;
  const double z_body0 = -hz + 0.45 * r, z_body1 = -hz + s.body_h * H;
  const Rgb white{255, 255, 255};  // paint: the shader takes the actor's colour
  b->Add(Box(V3(0, 0, (z_body0 + z_body1) / 2), V3(L, 2 * hy, z_body1 - z_body0)), white, kMatPaint, s.tag);
  const double roof = 0.06 * H;
  const double cl = s.cabin_len * L, cx = s.cabin_off * L;
  b->Add(Prism(cx, 0.92 * hy, z_body1, hz - roof, cl, cl * s.taper, -0.08 * cl * (1 - s.taper)), kGlass, kMatGlass, s.tag);
  b->Add(Box(V3(cx - 0.08 * cl * (1 - s.taper), 0, hz - roof / 2), V3(cl * s.taper, 1.84 * hy, roof)), white, kMatPaint, s.tag);
  if (s.kind == Kind::kOneBox) {
    b->Add(Box(V3(0, 0, z_body1 + 0.02), V3(L * 0.98, 1.9 * hy, 0.04)), white, kMatPaint, s.tag);
  }
  AddWheels(b, hx, hy, hz, r, 2, s.tag);
  AddLights(b, s, hx, hy, z_body1 - 0.12 * H);
  switch (s.extra) {
    case kTaxiSign: b->Add(Box(V3(cx, 0, hz - 0.01), V3(0.25, 0.5 * hy, 0.02)), Rgb{250, 200, 20}, kMatPlain, s.tag); break;
    case kPoliceBar:
      b->Add(Box(V3(cx, 0.3 * hy, hz - 0.01), V3(0.18, 0.5 * hy, 0.02)), Rgb{30, 60, 255}, kMatHeadlight, s.tag);
      b->Add(Box(V3(cx, -0.3 * hy, hz - 0.01), V3(0.18, 0.5 * hy, 0.02)), Rgb{255, 30, 30}, kMatTaillight, s.tag);
      break;
    case kAmbulanceBar: b->Add(Box(V3(0.3 * hx, 0, hz - 0.015), V3(0.2, 1.2 * hy, 0.03)), Rgb{255, 40, 40}, kMatTaillight, s.tag); break;
    case kRoofRack:
      for (int side : {-1, 1}) b->Add(Box(V3(cx, side * 0.7 * hy, hz - 0.015), V3(0.6 * cl, 0.05, 0.03)), kChrome, kMatPlain, s.tag);
      break;
    case kSpoiler: b->Add(Box(V3(-0.92 * hx, 0, z_body1 + 0.06), V3(0.12 * L / 4, 1.8 * hy, 0.03)), Rgb{20, 20, 20}, kMatPlain, s.tag); break;
    case kBed:
      b->Add(Box(V3(-0.45 * hx, 0, z_body1 + 0.12), V3(0.02 * L + 0.05, 1.9 * hy, 0.02)), white, kMatPaint, s.tag);
      break;
    default: break;
  }
}

void BuildTruck(Builder* b, const Style& s, double hx, double hy, double hz) {
  const double H = 2 * hz, L = 2 * hx, r = s.wheel_r * H;
  const Rgb white{255, 255, 255};
  const double cab_len = s.cabin_len * L, cab_x = hx - cab_len / 2;
  const double z0 = -hz + 0.6 * r;
  b->Add(Box(V3(cab_x, 0, (z0 + 0.55 * hz) / 2), V3(cab_len, 2 * hy, 0.55 * hz - z0)), white, kMatPaint, s.tag);
  b->Add(Prism(cab_x, 0.95 * hy, 0.55 * hz, 0.78 * hz, cab_len * 0.98, cab_len * 0.85, -0.05 * cab_len), kGlass, kMatGlass, s.tag);
  const double box_len = L - cab_len - 0.15;
  const Rgb cargo = s.extra == kLadder ? Rgb{180, 20, 20} : Rgb{215, 215, 210};
  b->Add(Box(V3(-hx + box_len / 2, 0, (z0 + hz) / 2), V3(box_len, 2 * hy, hz - z0)), cargo, s.extra == kLadder ? kMatPaint : kMatPlain, s.tag);
  if (s.extra == kLadder) {
    b->Add(Box(V3(-hx + box_len / 2, 0, hz - 0.05), V3(box_len * 0.9, 0.5 * hy, 0.08)), kChrome, kMatPlain, s.tag);
  }
  AddWheels(b, hx, hy, hz, r, 3, s.tag);
  AddLights(b, s, hx, hy, -hz + 1.3 * r);
}

void BuildBus(Builder* b, const Style& s, double hx, double hy, double hz) {
  const double H = 2 * hz, L = 2 * hx, r = s.wheel_r * H;
  const Rgb white{255, 255, 255};
  const double z0 = -hz + 0.6 * r;
  b->Add(Box(V3(0, 0, (z0 + hz) / 2), V3(L, 2 * hy, hz - z0)), white, kMatPaint, s.tag);
  b->Add(Box(V3(0.02, 0, 0.35 * hz), V3(L * 0.96, 2 * hy + 0.02, 0.5 * hz)), kGlass, kMatGlass, s.tag);
  AddWheels(b, hx, hy, hz, r, 2, s.tag);
  AddLights(b, s, hx, hy, -hz + 1.4 * r);
}

void AddRider(Builder* b, double x, double hz) {
  const Rgb jacket{40, 40, 60}, skin{210, 170, 140}, helmet{230, 230, 230};
  b->Add(Box(V3(x, 0, 0.3 * hz), V3(0.3, 0.36, 0.55 * hz)), jacket, kMatPlain, tag::kRider);
  b->Add(Ellipsoid(V3(x + 0.05, 0, 0.78 * hz), V3(0.12, 0.11, 0.14), 6, 4), helmet, kMatPlain, tag::kRider);
  (void)skin;
}

void BuildBike(Builder* b, const Style& s, double hx, double hy, double hz) {
  const double H = 2 * hz, r = std::min(s.wheel_r * H, 0.9 * hx / 2);
  const Rgb white{255, 255, 255};
  const double w = std::min(0.12, hy);
  for (double x : {hx - r, -hx + r}) b->Add(Wheel(V3(x, 0, -hz + r), r, w), kTyre, kMatPlain, s.tag);
  b->Add(Box(V3(0, 0, -hz + r * 1.2), V3(2 * hx - 2 * r, 0.6 * hy, s.kind == Kind::kBike && s.tag == tag::kMotorcycle ? 0.35 : 0.06)),
         white, kMatPaint, s.tag);
  b->Add(Box(V3(hx - r, 0, -hz + 2.1 * r), V3(0.06, 1.6 * hy, 0.05)), kChrome, kMatPlain, s.tag);
  if (s.tag == tag::kMotorcycle) b->Add(Box(V3(hx - 0.03, 0, -hz + 1.7 * r), V3(0.05, 0.12, 0.1)), kHead, kMatHeadlight, s.tag);
  AddRider(b, -0.1 * hx, hz);
}

Rgb Pick(const Rgb* list, std::size_t n, std::uint64_t h) { return list[h % n]; }

}  // namespace

void AppendMesh(std::vector<Vertex>* out, const map::Mesh& mesh, const std::array<std::uint8_t, 3>& rgb, Material material,
                std::uint32_t label) {
  out->reserve(out->size() + mesh.indices.size());
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    Eigen::Vector3f p[3];
    for (int k = 0; k < 3; ++k) {
      const std::size_t i = mesh.indices[t + k] * 3;
      p[k] = Eigen::Vector3f(mesh.vertices[i], mesh.vertices[i + 1], mesh.vertices[i + 2]);
    }
    Eigen::Vector3f n = (p[1] - p[0]).cross(p[2] - p[0]);
    if (n.norm() < 1e-12f) continue;  // degenerate
    n.normalize();
    for (int k = 0; k < 3; ++k) {
      Vertex v;
      for (int c = 0; c < 3; ++c) {
        v.position[c] = p[k][c];
        v.normal[c] = n[c];
        v.rgba[c] = rgb[c];
      }
      v.rgba[3] = material;
      v.label = label;
      out->push_back(v);
    }
  }
}

const std::vector<std::string>& VehicleStyles() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& s : kStyles) v.emplace_back(s.name);
    return v;
  }();
  return names;
}

std::string VehicleStyleFor(const std::string& blueprint) {
  // Longest matching name first ("minivan" before "van", "firetruck" before "truck").
  std::string best;
  for (const auto& s : kStyles) {
    const std::string n = s.name;
    if (blueprint.find(n) != std::string::npos && n.size() > best.size()) best = n;
  }
  if (!best.empty()) return best;
  if (blueprint.find("bike") != std::string::npos || blueprint.find("cycle") != std::string::npos) return "motorbike";
  // Hash over the car styles only: an unknown id is most likely a car.
  static const char* cars[] = {"sedan", "hatchback", "suv", "coupe", "wagon", "sportscar", "jeep", "microcar", "limousine", "pickup"};
  return cars[Fnv(blueprint) % (sizeof(cars) / sizeof(cars[0]))];
}

std::uint8_t VehicleTag(const std::string& blueprint) { return FindStyle(VehicleStyleFor(blueprint)).tag; }

Model BuildVehicle(const std::string& style, const Vec3& he) {
  const Style& s = FindStyle(style);
  Builder b;
  const double hx = std::max(0.2, he.x()), hy = std::max(0.1, he.y()), hz = std::max(0.2, he.z());
  switch (s.kind) {
    case Kind::kCar:
    case Kind::kOneBox: BuildCar(&b, s, hx, hy, hz); break;
    case Kind::kTruck: BuildTruck(&b, s, hx, hy, hz); break;
    case Kind::kBus: BuildBus(&b, s, hx, hy, hz); break;
    case Kind::kBike: BuildBike(&b, s, hx, hy, hz); break;
  }
  b.model.half_extents = Vec3(hx, hy, hz);
  return b.model;
}

int WalkerVariant(const std::string& blueprint) {
  const auto dot = blueprint.find_last_of('.');
  if (dot != std::string::npos && dot + 1 < blueprint.size()) {
    char* end = nullptr;
    const long n = std::strtol(blueprint.c_str() + dot + 1, &end, 10);
    if (end && *end == '\0' && n >= 0) return static_cast<int>(n % kWalkerVariants);
  }
  return static_cast<int>(Fnv(blueprint) % kWalkerVariants);
}

Model BuildWalker(int variant, const Vec3& he) {
  static const Rgb skins[] = {{236, 200, 170}, {210, 160, 120}, {170, 120, 85}, {120, 80, 55}, {90, 60, 40}, {245, 215, 190}};
  static const Rgb shirts[] = {{200, 30, 30}, {30, 90, 200}, {240, 240, 240}, {30, 30, 30}, {40, 150, 60}, {240, 190, 30},
                               {130, 60, 160}, {250, 120, 30}, {90, 90, 100}, {20, 140, 150}, {230, 120, 160}};
  static const Rgb trousers[] = {{30, 40, 80}, {20, 20, 20}, {110, 90, 60}, {80, 80, 85}, {160, 150, 120}, {60, 30, 20}, {40, 70, 40}};
  static const Rgb hairs[] = {{20, 15, 10}, {90, 60, 30}, {200, 170, 90}, {150, 150, 150}, {120, 40, 20}};
  const std::uint64_t h = static_cast<std::uint64_t>(variant) * 2654435761ull + 97;
  const Rgb skin = Pick(skins, 6, h), shirt = Pick(shirts, 11, h / 7), pants = Pick(trousers, 7, h / 83), hair = Pick(hairs, 5, h / 577);
  const bool skirt = (variant % 5) == 2, backpack = (variant % 4) == 1, hat = (variant % 7) == 3, child = (variant % 11) == 10;
  const double build = 0.85 + 0.3 * ((variant * 37) % 10) / 9.0;  // slim .. broad
  const double hx = std::max(0.1, he.x()), hy = std::max(0.1, he.y()), hz = std::max(0.3, he.z());
  const double H = 2 * hz, z0 = -hz;
  const double shoulder = std::min(2 * hy, 0.42 * build * (child ? 0.8 : 1.0));
  const double leg_h = 0.47 * H, torso_h = 0.33 * H, head_r = 0.065 * H;
  Builder b;
  const std::uint8_t t = tag::kPedestrian;
  if (skirt) {
    map::Mesh m;
    map::AddCone(m, V3(0, 0, z0 + 0.22 * H), 0.6 * shoulder, 0.5 * leg_h + 0.05 * H, 8);
    b.Add(m, pants, kMatPlain, t);
    for (int side : {-1, 1}) b.Add(Box(V3(0, side * 0.1 * shoulder, z0 + 0.12 * H), V3(0.1, 0.08, 0.24 * H)), skin, kMatPlain, t);
  } else {
    for (int side : {-1, 1}) {
      b.Add(Box(V3(0, side * 0.22 * shoulder, z0 + leg_h / 2), V3(0.14 * build, 0.35 * shoulder, leg_h)), pants, kMatPlain, t);
    }
  }
  b.Add(Box(V3(0.03, 0, z0 + 0.02), V3(std::min(2 * hx, 0.28), 0.8 * shoulder, 0.04)), Rgb{30, 25, 20}, kMatPlain, t);  // shoes
  b.Add(Box(V3(0, 0, z0 + leg_h + torso_h / 2), V3(0.22 * build, shoulder * 0.85, torso_h)), shirt, kMatPlain, t);
  for (int side : {-1, 1}) {
    b.Add(Box(V3(0, side * (shoulder * 0.5 - 0.03), z0 + leg_h + torso_h - 0.19 * H), V3(0.09, 0.08, 0.38 * H)), shirt,
          kMatPlain, t);
    b.Add(Box(V3(0, side * (shoulder * 0.5 - 0.03), z0 + leg_h + torso_h - 0.4 * H), V3(0.07, 0.07, 0.06 * H)), skin, kMatPlain, t);
  }
  const double head_z = hz - head_r - 0.02 * H;
  b.Add(Cylinder(V3(0, 0, z0 + leg_h + torso_h), 0.04, head_z - head_r - (z0 + leg_h + torso_h) + 0.01, 5), skin, kMatPlain, t);
  b.Add(Ellipsoid(V3(0, 0, head_z), V3(head_r * 0.9, head_r * 0.85, head_r), 7, 4), skin, kMatPlain, t);
  b.Add(Ellipsoid(V3(-0.01, 0, head_z + 0.3 * head_r), V3(head_r * 0.95, head_r * 0.9, head_r * 0.75), 7, 3), hair, kMatPlain, t);
  if (hat) b.Add(Cylinder(V3(0, 0, hz - 0.045 * H), head_r * 1.1, 0.04 * H, 8), Pick(shirts, 11, h / 13), kMatPlain, t);
  if (backpack) b.Add(Box(V3(-0.11 * build - 0.07, 0, z0 + leg_h + 0.55 * torso_h), V3(0.14, shoulder * 0.6, 0.6 * torso_h)),
                      Pick(shirts, 11, h / 31), kMatPlain, t);
  b.model.half_extents = Vec3(hx, hy, hz);
  return b.model;
}

Model BuildDrone(const DroneShape& d) {
  Builder b;
  const Rgb body{50, 50, 55}, arm{30, 30, 30}, motor{120, 120, 125}, prop{200, 200, 200};
  const std::uint8_t t = tag::kOther;  // CARLA has no drone class; AirSim's drones read as Other
  b.Add(Box(V3::Zero(), d.body_box), body, kMatPlain, t);
  b.Add(Box(V3(d.body_box.x() / 2, 0, 0), V3(0.02, 0.04, 0.015)), Rgb{30, 220, 60}, kMatHeadlight, t);
  std::vector<double> angles;
  if (d.frame == "quad_plus") angles = {0, 90, 180, 270};
  else if (d.frame == "hexa_x") angles = {30, 90, 150, 210, 270, 330};
  else angles = {45, 135, 225, 315};
  const double arm_w = 0.02;
  for (std::size_t i = 0; i < angles.size(); ++i) {
    const double a = angles[i] * M_PI / 180;
    const V3 hub(d.arm_length * std::cos(a), d.arm_length * std::sin(a), d.rotor_z);
    b.Add(Box(hub / 2, V3(d.arm_length, arm_w, arm_w), a), arm, kMatPlain, t);
    b.Add(Cylinder(hub - V3(0, 0, 0.02), 0.018, 0.035, 6), motor, kMatPlain, t);
  }
  for (std::size_t i = 0; i < angles.size(); ++i) {
    const double a = angles[i] * M_PI / 180;
    Model::Rotor r;
    r.hub = V3(d.arm_length * std::cos(a), d.arm_length * std::sin(a), d.rotor_z + 0.02);
    r.clockwise = (i % 2) == 1;
    r.first = b.model.vertices.size();
    // Two blades around the hub origin; the renderer spins and moves them.
    b.Add(Box(V3(0, 0, 0), V3(d.propeller_diameter, 0.025, 0.006)), prop, kMatRotor, t);
    r.count = b.model.vertices.size() - r.first;
    b.model.rotors.push_back(r);
  }
  const double reach = d.arm_length + d.propeller_diameter / 2;
  b.model.half_extents = Vec3(std::max(reach, d.body_box.x() / 2), std::max(reach, d.body_box.y() / 2), std::max(0.04, d.body_box.z() / 2 + 0.03));
  return b.model;
}

std::array<std::uint8_t, 3> DefaultPaint(std::uint32_t actor) {
  static const Rgb paints[] = {{180, 20, 20}, {20, 60, 170}, {230, 230, 230}, {25, 25, 25}, {130, 130, 135}, {200, 170, 30},
                               {30, 110, 50}, {100, 20, 30}, {60, 140, 190}, {210, 100, 20}, {90, 60, 40}, {170, 170, 160}};
  return paints[(static_cast<std::uint64_t>(actor) * 2654435761ull >> 8) % 12];
}

}  // namespace lockstep::render
