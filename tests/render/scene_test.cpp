// Labels from the shared pass: semantic classes at known pixels, instance ids per actor,
// a drone in a car's camera, an imported OBJ with its class, the town with culling.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "lockstep/map/map.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/render/asset_import.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

std::uint8_t TagAt(const CameraFrame& f, const Camera& cam, const Vec3& p) {
  const auto uv = Project(cam, p);
  EXPECT_TRUE(uv);
  if (!uv) return 255;
  return f.Tag(static_cast<int>(uv->x()), static_cast<int>(uv->y()));
}

TEST(Semantic, KnownPixelsCarryTheirClasses) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.actors.push_back(Vehicle(r, 10, At(25, -1.5, 0.75)));
  w.actors.push_back(Walker(r, 11, At(18, 5.5, 0.15 + 0.9)));
  const Camera cam = Cam(200, 150, 90, At(0, 0, 2.0, 10, -3), kOutLabels | kOutColor);
  const auto f = r.RenderFrames({cam}, w)[0];
  EXPECT_EQ(TagAt(f, cam, Vec3(8, -2.5, 0)), tag::kRoads);
  EXPECT_EQ(TagAt(f, cam, Vec3(12, 6.0, 0.15)), tag::kSideWalks);
  EXPECT_EQ(TagAt(f, cam, Vec3(30, 9, 6)), tag::kBuilding);
  EXPECT_EQ(TagAt(f, cam, Vec3(25, -1.5, 0.9)), tag::kCar);
  EXPECT_EQ(TagAt(f, cam, Vec3(18, 5.5, 0.15 + 1.0)), tag::kPedestrian);
  EXPECT_EQ(TagAt(f, cam, Vec3(100, -40, 60)), tag::kSky);
}

TEST(Instance, IdsAreUniquePerActor) {
  Renderer& r = SharedRenderer();
  WorldView w;
  const std::vector<std::uint32_t> ids = {5, 6, 7, 300, 301};
  w.actors.push_back(Vehicle(r, 5, At(15, -2, 0.75)));
  w.actors.push_back(Vehicle(r, 6, At(22, 2, 0.75), "suv", Vec3(2.4, 1.05, 0.9)));
  w.actors.push_back(Vehicle(r, 7, At(30, -2, 0.75), "van", Vec3(2.6, 1.1, 1.1)));
  w.actors.push_back(Walker(r, 300, At(12, 5, 1.05), 3));
  w.actors.push_back(Walker(r, 301, At(13, 2.5, 0.9), 4));
  const Camera cam = Cam(240, 160, 90, At(0, 0, 3.0, 0, -5), kOutLabels);
  const auto f = r.RenderFrames({cam}, w)[0];
  std::map<std::uint32_t, std::set<std::uint8_t>> tags_of;
  for (int v = 0; v < f.height; ++v) {
    for (int u = 0; u < f.width; ++u) tags_of[f.Instance(u, v)].insert(f.Tag(u, v));
  }
  for (std::size_t i = 0; i < w.actors.size(); ++i) {
    const auto uv = Project(cam, w.actors[i].pose.position);
    ASSERT_TRUE(uv);
    EXPECT_EQ(f.Instance(static_cast<int>(uv->x()), static_cast<int>(uv->y())), ids[i]) << "actor " << ids[i];
    ASSERT_TRUE(tags_of.count(ids[i])) << "actor " << ids[i] << " not in the image";
    const std::uint8_t expected = ids[i] >= 300 ? tag::kPedestrian : tag::kCar;
    EXPECT_EQ(tags_of[ids[i]], std::set<std::uint8_t>{expected}) << "one id, one actor, one class";
  }
  // Static objects have ids of their own, above every actor id.
  EXPECT_TRUE(tags_of.count(kStaticInstanceBase + 2));  // the road
  EXPECT_EQ(tags_of[kStaticInstanceBase + 2], std::set<std::uint8_t>{tag::kRoads});
}

TEST(Scene, ADroneIsVisibleInACarsCameraAndACarInTheDronesCamera) {
  Renderer& r = SharedRenderer();
  WorldView w;
  const Pose car = At(10, -2, 0.75, 0);
  w.actors.push_back(Vehicle(r, 20, car));
  const Pose drone = At(20, -2, 4.0, 180);
  w.actors.push_back(Drone(r, 21, drone));
  // CARLA's usual dash camera: 1.5 m forward, 2.4 m up, attached to the car; the drone's
  // camera under its body looks back and down at the car.
  const Camera car_cam = Cam(320, 240, 90, car * At(1.5, 0, 1.65, 0, 0), kOutLabels);
  const Camera drone_cam = Cam(320, 240, 90, drone * At(0, 0, -0.1, 0, -30), kOutLabels);
  auto frames = r.RenderFrames({car_cam, drone_cam}, w);
  int drone_px = 0, car_px = 0;
  for (int v = 0; v < 240; ++v) {
    for (int u = 0; u < 320; ++u) {
      drone_px += frames[0].Instance(u, v) == 21;
      car_px += frames[1].Instance(u, v) == 20;
    }
  }
  EXPECT_GT(drone_px, 10) << "the drone 8.5 m ahead of the camera";
  EXPECT_GT(car_px, 100) << "the car in front of and below the drone";
}

TEST(Scene, RotorsSpin) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.actors.push_back(Drone(r, 30, At(5, 0, 3)));
  const Camera cam = Cam(96, 96, 20, At(5, 0, 6, 0, -90), kOutLabels);
  const auto a = r.RenderFrames({cam}, w)[0];
  w.actors[0].rotor_angles = {1.0, 2.0, 0.5, 0.1};
  const auto b = r.RenderFrames({cam}, w)[0];
  EXPECT_NE(a.labels, b.labels) << "rotor blades at other angles cover other pixels";
}

TEST(CustomAsset, AnImportedObjAppearsWithItsClass) {
  const auto dir = std::filesystem::temp_directory_path() / ("lockstep_render_obj_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = (dir / "crate.obj").string();
  {
    std::ofstream obj(path);
    // A 1 x 1 x 1 cube (Y up), faces counter-clockwise from outside.
    obj << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
           "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  }
  AssetSpec spec;
  spec.name = "crate";
  spec.path = path;
  spec.tag = static_cast<std::uint8_t>(ClassFromName("Dynamic"));
  const Model m = ImportAsset(spec);
  EXPECT_EQ(m.TriangleCount(), 12u);
  EXPECT_NEAR(m.half_extents.x(), 0.5, 1e-6);
  Renderer& r = SharedRenderer();
  r.AddModel("custom.crate", m);
  WorldView w;
  ActorDraw a;
  a.id = 40;
  a.model = "custom.crate";
  a.pose = At(8, 0, 0.5);
  a.cull_faces = false;
  w.actors.push_back(a);
  const Camera cam = Cam(64, 48, 60, At(0, 0, 1.0), kOutLabels);
  const auto f = r.RenderFrames({cam}, w)[0];
  const auto uv = Project(cam, Vec3(7.5, 0, 0.5));
  EXPECT_EQ(f.Tag(static_cast<int>(uv->x()), static_cast<int>(uv->y())), tag::kDynamic);
  EXPECT_EQ(f.Instance(static_cast<int>(uv->x()), static_cast<int>(uv->y())), 40u);
  spec.path = (dir / "missing.obj").string();
  try {
    ImportAsset(spec);
    FAIL() << "a missing file must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.obj"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(Town, CullingAndDetailLevelsDrawFewerTrianglesThanTheTown) {
  const auto town = map::Map::Load(std::string(LOCKSTEP_TEST_TOWN_DIR) + "/LockstepTown1.xodr");
  const auto scene = map::LoadSceneFile(std::string(LOCKSTEP_TEST_TOWN_DIR) + "/LockstepTown1.scene.yaml");
  Renderer r;
  const auto meshes = map::BuildWorldMeshes(town, scene);
  r.SetStaticScene(meshes, StreetLamps(scene));
  ASSERT_FALSE(scene.vehicle_spawn_points.empty());
  const auto& sp = scene.vehicle_spawn_points.front();
  const Camera cam = Cam(128, 96, 90, At(sp.x, sp.y, sp.z + 2.0, sp.yaw * 180 / M_PI), kOutLabels);
  const auto f = r.RenderFrames({cam}, WorldView{})[0];
  std::set<std::uint8_t> tags;
  for (std::size_t i = 0; i < f.labels.size(); i += 4) tags.insert(f.labels[i]);
  EXPECT_TRUE(tags.count(tag::kRoads));
  EXPECT_TRUE(tags.count(tag::kSky));
  EXPECT_GT(r.stats().static_triangles, 0u);
  EXPECT_LT(r.stats().triangles, r.stats().static_triangles / 2) << "frustum culling and LOD";
  EXPECT_FALSE(r.device().name.empty());
}

}  // namespace
}  // namespace lockstep::render
