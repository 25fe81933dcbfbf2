#pragma once
// Procedural low-poly models of the dynamic actors, built in the actor's body frame
// (x forward, y left, z up) around the centre of its bounding box, so that they fill
// the blueprint's box exactly: 20 vehicle styles, 50+ pedestrian variants, multirotors
// whose rotors are separate parts that spin.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "lockstep/map/mesh.h"
#include "lockstep/render/types.h"

namespace lockstep::render {

// Surface behaviour, stored in the vertex colour's alpha.
enum Material : std::uint8_t {
  kMatPlain = 0,
  kMatPaint = 1,      // takes the actor's colour
  kMatGlass = 2,
  kMatHeadlight = 3,  // lit at night
  kMatTaillight = 4,
  kMatRoad = 5,       // wet and puddles
  kMatLamp = 6,       // street lamp bulb, lit at night
  kMatLightRed = 7,   // traffic light lamps: bright when the light shows that colour
  kMatLightYellow = 8,
  kMatLightGreen = 9,
  kMatWindow = 10,    // building windows: some lit at night
  kMatRotor = 11,
};

struct Vertex {
  float position[3];
  float normal[3];
  std::uint8_t rgba[4];  // colour, material in alpha
  std::uint32_t label;   // semantic tag in the low byte, instance id << 8 (0: the draw's own)
};
static_assert(sizeof(Vertex) == 32);

struct Model {
  std::vector<Vertex> vertices;  // triangle list, flat normals
  Vec3 half_extents = Vec3::Zero();
  // Rotors: each one a separate vertex range drawn with its own spin.
  struct Rotor {
    Vec3 hub;                    // body frame
    bool clockwise = true;       // seen from above
    std::size_t first = 0, count = 0;  // vertex range in `vertices`
  };
  std::vector<Rotor> rotors;
  std::size_t TriangleCount() const { return vertices.size() / 3; }
};

// Appends a map mesh's triangles with flat normals. label: tag | (instance << 8).
void AppendMesh(std::vector<Vertex>* out, const map::Mesh& mesh, const std::array<std::uint8_t, 3>& rgb,
                Material material, std::uint32_t label);

// Vehicle style names (at least 16); the style of a blueprint is the first name its id
// contains, else one picked by a hash of the id.
const std::vector<std::string>& VehicleStyles();
std::string VehicleStyleFor(const std::string& blueprint);
// Semantic tag of a vehicle blueprint (Car, Truck, Bus, Motorcycle, Bicycle).
std::uint8_t VehicleTag(const std::string& blueprint);
Model BuildVehicle(const std::string& style, const Vec3& half_extents);

// Pedestrian variant of a blueprint id ("walker.pedestrian.0007" -> 7), and its model.
int WalkerVariant(const std::string& blueprint);
inline constexpr int kWalkerVariants = 64;
Model BuildWalker(int variant, const Vec3& half_extents);

struct DroneShape {
  std::string frame = "quad_x";  // quad_x | quad_plus | hexa_x
  double arm_length = 0.2275;    // m
  Vec3 body_box{0.18, 0.11, 0.04};  // m, full extents
  double propeller_diameter = 0.2286;  // m
  double rotor_z = 0.0;
};
Model BuildDrone(const DroneShape& shape);

// A default paint colour for an actor (used when its blueprint has no colour attribute).
std::array<std::uint8_t, 3> DefaultPaint(std::uint32_t actor);

}  // namespace lockstep::render
