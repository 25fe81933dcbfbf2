#include "town.h"

#include "lockstep/map/scene_mesh.h"

namespace lockstep::render::bench {

Town LoadTown(Renderer& r, int vehicles) {
  Town t{map::Map::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr"), {}, {}, {}, {}, 0};
  t.scene = map::GenerateScene(t.map, 42);
  r.SetStaticScene(map::BuildWorldMeshes(t.map, t.scene), StreetLamps(t.scene));
  const auto& styles = VehicleStyles();
  const auto& spawns = t.scene.vehicle_spawn_points;
  std::uint32_t id = 1;
  for (int i = 0; i < vehicles && i < static_cast<int>(spawns.size()); ++i) {
    const auto& sp = spawns[static_cast<std::size_t>(i)];
    const std::string style = styles[static_cast<std::size_t>(i) % styles.size()];
    Vec3 he(2.2, 0.95, 0.75);
    if (style == "truck" || style == "firetruck") he = Vec3(4.0, 1.2, 1.6);
    if (style == "bus") he = Vec3(5.5, 1.3, 1.6);
    if (style == "van" || style == "ambulance" || style == "minivan") he = Vec3(2.5, 1.0, 1.0);
    if (style == "motorbike" || style == "bicycle") he = Vec3(1.0, 0.4, 0.8);
    const std::string key = "vehicle:" + style + std::to_string(he.x());
    if (!r.HasModel(key)) r.AddModel(key, BuildVehicle(style, he));
    ActorDraw a;
    a.id = id++;
    a.model = key;
    a.pose.position = Vec3(sp.x, sp.y, sp.z + he.z());
    a.pose.orientation = Quat(Eigen::AngleAxisd(sp.yaw, Vec3::UnitZ()));
    a.paint = DefaultPaint(a.id);
    t.world.actors.push_back(a);
  }
  const auto& walks = t.scene.pedestrian_spawn_points;
  for (int i = 0; i < 30 && i < static_cast<int>(walks.size()); ++i) {
    const auto& sp = walks[static_cast<std::size_t>(i)];
    const std::string key = "walker:" + std::to_string(i);
    if (!r.HasModel(key)) r.AddModel(key, BuildWalker(i, Vec3(0.25, 0.25, 0.9)));
    ActorDraw a;
    a.id = id++;
    a.model = key;
    a.pose.position = Vec3(sp.x, sp.y, sp.z + 0.9);
    a.pose.orientation = Quat(Eigen::AngleAxisd(sp.yaw, Vec3::UnitZ()));
    t.world.actors.push_back(a);
  }
  t.ego = t.world.actors.front().pose;
  t.drone.position = t.ego.position + t.ego.orientation * Vec3(18, 0, 0) + Vec3(0, 0, 6);
  t.drone.orientation = t.ego.orientation * Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitZ()));
  if (!r.HasModel("drone")) r.AddModel("drone", BuildDrone(DroneShape{}));
  ActorDraw d;
  d.id = t.drone_id = id++;
  d.model = "drone";
  d.pose = t.drone;
  d.rotor_angles = {0.2, 1.1, 2.3, 0.7};
  t.world.actors.push_back(d);
  return t;
}

Pose DashCamera(const Town& t) {
  const double hz = 0.75;
  return t.ego * Pose{Vec3(1.5, 0, 2.4 - hz), Quat::Identity()};
}

}  // namespace lockstep::render::bench
