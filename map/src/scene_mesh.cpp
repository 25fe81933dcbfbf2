#include "lockstep/map/scene_mesh.h"

#include <cmath>

#include "lockstep/map/buildings.h"

namespace lockstep::map {
namespace {

Mesh NewMesh(const std::string& name, std::uint8_t tag, std::uint32_t* next_id) {
  Mesh m;
  m.name = name;
  m.semantic_tag = tag;
  m.instance_id = (*next_id)++;
  return m;
}

void AddProp(const PropInstance& p, std::size_t index, std::uint32_t* id, std::vector<Mesh>* out) {
  const Eigen::Vector3d base(p.x, p.y, p.z);
  const Eigen::Vector3d fwd(std::cos(p.yaw), std::sin(p.yaw), 0);
  const std::string name = p.kind + "_" + std::to_string(index);
  if (p.kind == "fence" || p.kind == "wall") {
    Mesh m = NewMesh(name, p.kind == "wall" ? semantic::kWall : semantic::kFence, id);
    const double h = p.height > 0 ? p.height : (p.kind == "wall" ? 2.2 : 1.4);
    AddBox(m, base, std::max(0.5, p.length), p.kind == "wall" ? 0.3 : 0.08, h, p.yaw);
    out->push_back(std::move(m));
    return;
  }
  const double h = p.height > 0 ? p.height : 3.0;
  Mesh pole = NewMesh(name + "_pole", semantic::kPole, id);
  AddCylinder(pole, base, p.kind == "street_light" ? 0.12 : 0.08, h, 6);
  if (p.kind == "street_light") {
    AddBox(pole, base + Eigen::Vector3d(0, 0, h - 0.1) + 0.9 * fwd, 1.8, 0.12, 0.1, p.yaw);
    AddBox(pole, base + Eigen::Vector3d(0, 0, h - 0.25) + 1.7 * fwd, 0.6, 0.3, 0.15, p.yaw);
    out->push_back(std::move(pole));
    return;
  }
  out->push_back(std::move(pole));
  if (p.kind == "traffic_light") {
    Mesh head = NewMesh(name + "_head", semantic::kTrafficLight, id);
    AddBox(head, base + Eigen::Vector3d(0, 0, h), 0.35, 0.35, 1.0, p.yaw);
    out->push_back(std::move(head));
  } else {
    Mesh plate = NewMesh(name + "_plate", semantic::kTrafficSign, id);
    // Thin plate facing along yaw (towards the traffic it serves).
    AddBox(plate, base + Eigen::Vector3d(0, 0, h - 0.3), 0.05, 0.7, 0.7, p.yaw);
    out->push_back(std::move(plate));
  }
}

}  // namespace

std::vector<Mesh> BuildSceneMeshes(const Scene& scene, std::uint32_t first_instance_id) {
  std::vector<Mesh> out;
  std::uint32_t id = first_instance_id;
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const BuildingInstance& b = scene.buildings[i];
    Mesh m = NewMesh("building_" + std::to_string(i) + "_" + DescribeBuildingDesign(b.design).Name(), semantic::kBuilding, &id);
    AddBuilding(m, b);
    out.push_back(std::move(m));
  }
  for (std::size_t i = 0; i < scene.vegetation.size(); ++i) {
    const VegetationInstance& v = scene.vegetation[i];
    Mesh m = NewMesh(v.kind + "_" + std::to_string(i), semantic::kVegetation, &id);
    const Eigen::Vector3d base(v.x, v.y, v.z);
    if (v.kind == "bush") {
      AddEllipsoid(m, base + Eigen::Vector3d(0, 0, 0.5 * v.height), {v.radius, v.radius, 0.5 * v.height}, 6, 3);
    } else if (v.kind == "conifer") {
      AddCylinder(m, base, 0.15, 0.3 * v.height, 5);
      AddCone(m, base + Eigen::Vector3d(0, 0, 0.25 * v.height), v.radius, 0.75 * v.height, 7);
    } else {
      AddCylinder(m, base, 0.18, 0.55 * v.height, 5);
      AddEllipsoid(m, base + Eigen::Vector3d(0, 0, 0.65 * v.height), {v.radius, v.radius, 0.4 * v.height}, 7, 4);
    }
    out.push_back(std::move(m));
  }
  for (std::size_t i = 0; i < scene.props.size(); ++i) AddProp(scene.props[i], i, &id, &out);
  return out;
}

std::vector<Mesh> BuildWorldMeshes(const Map& map, const Scene& scene, const RoadMeshOptions& options) {
  std::vector<Mesh> out;
  Mesh ground;
  ground.name = "ground";
  ground.semantic_tag = semantic::kTerrain;
  ground.instance_id = 1;
  const double pad = 60.0, z = -0.02;  // just under the road surface
  const Eigen::Vector2d lo = map.BoundsMin() - Eigen::Vector2d(pad, pad), hi = map.BoundsMax() + Eigen::Vector2d(pad, pad);
  ground.AddQuad({lo.x(), lo.y(), z}, {hi.x(), lo.y(), z}, {hi.x(), hi.y(), z}, {lo.x(), hi.y(), z}, Eigen::Vector3d::UnitZ());
  out.push_back(std::move(ground));
  std::vector<Mesh> roads = BuildRoadMeshes(map, options, 2);
  const std::uint32_t next = roads.empty() ? 2 : roads.back().instance_id + 1;
  for (Mesh& m : roads) out.push_back(std::move(m));
  for (Mesh& m : BuildSceneMeshes(scene, next)) out.push_back(std::move(m));
  return out;
}

}  // namespace lockstep::map
