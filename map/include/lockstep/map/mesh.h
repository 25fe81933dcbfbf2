#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace lockstep::map {

// Semantic tags: CARLA's palette ids (0.9.14+, ../shared/reference/carla_constants.json).
namespace semantic {
inline constexpr std::uint8_t kUnlabeled = 0, kRoads = 1, kSideWalks = 2, kBuilding = 3, kWall = 4, kFence = 5,
                              kPole = 6, kTrafficLight = 7, kTrafficSign = 8, kVegetation = 9, kTerrain = 10,
                              kStatic = 20, kRoadLine = 24, kGround = 25;
}

// Triangle mesh in the world frame (ENU, metres). Triangles are counter-clockwise seen
// from outside (top faces from above). Render, sensors and ground physics share these.
struct Mesh {
  std::string name;
  std::uint8_t semantic_tag = semantic::kUnlabeled;
  std::uint32_t instance_id = 0;   // unique per object in a world; 0 = none
  std::vector<float> vertices;     // x, y, z per vertex (m)
  std::vector<std::uint32_t> indices;  // 3 per triangle

  std::size_t VertexCount() const { return vertices.size() / 3; }
  std::size_t TriangleCount() const { return indices.size() / 3; }
  std::uint32_t AddVertex(const Eigen::Vector3d& p);
  void AddTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c);
  // Quad p0 p1 p2 p3 (in order around it) as two triangles, wound so that its normal
  // points along `outward` (for top faces use +z).
  void AddQuad(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
               const Eigen::Vector3d& p3, const Eigen::Vector3d& outward);
  void AddTriangleFacing(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& outward);
  void Append(const Mesh& other);
};

// Primitives (closed, outward-facing). yaw rotates about +z around the base centre.
void AddBox(Mesh& m, const Eigen::Vector3d& base_centre, double length, double width, double height, double yaw,
            bool bottom = false);
void AddCylinder(Mesh& m, const Eigen::Vector3d& base_centre, double radius, double height, int sides);
void AddCone(Mesh& m, const Eigen::Vector3d& base_centre, double radius, double height, int sides);
// Low-poly ellipsoid (latitude/longitude grid).
void AddEllipsoid(Mesh& m, const Eigen::Vector3d& centre, const Eigen::Vector3d& radii, int sides, int rings);

std::size_t TotalTriangles(const std::vector<Mesh>& meshes);

}  // namespace lockstep::map
