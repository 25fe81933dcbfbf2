#pragma once
// A small synthetic street for render tests: a road along +x, a sidewalk on its left,
// a building wall beyond the sidewalk, and helpers to place actors and cameras.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>

#include "lockstep/render/renderer.h"

namespace lockstep::render::testing {

// yaw: CARLA-like, counter-clockwise seen from above in ENU; pitch: nose up positive.
inline Pose At(double x, double y, double z, double yaw_deg = 0, double pitch_deg = 0) {
  Pose p;
  p.position = Vec3(x, y, z);
  p.orientation = Eigen::AngleAxisd(yaw_deg * M_PI / 180, Vec3::UnitZ()) * Eigen::AngleAxisd(-pitch_deg * M_PI / 180, Vec3::UnitY());
  return p;
}

inline map::Mesh Quad(const std::string& name, std::uint8_t tag, std::uint32_t id, double x0, double y0, double x1, double y1, double z) {
  map::Mesh m;
  m.name = name;
  m.semantic_tag = tag;
  m.instance_id = id;
  m.AddQuad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, Vec3::UnitZ());
  return m;
}

inline map::Mesh BoxMesh(const std::string& name, std::uint8_t tag, std::uint32_t id, const Vec3& base, double l, double w, double h) {
  map::Mesh m;
  m.name = name;
  m.semantic_tag = tag;
  m.instance_id = id;
  map::AddBox(m, base, l, w, h, 0, true);
  return m;
}

// Road y in [-4, 4], sidewalk y in [4, 7] (raised 0.15 m), building front at y = 9.
inline std::vector<map::Mesh> Street() {
  return {Quad("ground", tag::kTerrain, 1, -200, -200, 400, 200, -0.02), Quad("road", tag::kRoads, 2, -50, -4, 300, 4, 0),
          Quad("sidewalk", tag::kSideWalks, 3, -50, 4, 300, 7, 0.15),
          BoxMesh("building", tag::kBuilding, 4, Vec3(40, 14, 0), 40, 10, 12)};
}

// One renderer per test process (EGL context start-up is the slow part).
inline Renderer& SharedRenderer() {
  static std::unique_ptr<Renderer> r = [] {
    auto p = std::make_unique<Renderer>(DevicePreference::kAuto);
    p->SetStaticScene(Street());
    return p;
  }();
  return *r;
}

inline std::string VehicleKey(const std::string& style, const Vec3& he) {
  return "vehicle:" + style + ":" + std::to_string(he.x()) + "," + std::to_string(he.y()) + "," + std::to_string(he.z());
}

inline ActorDraw Vehicle(Renderer& r, std::uint32_t id, const Pose& pose, const std::string& style = "sedan",
                         const Vec3& he = Vec3(2.3, 1.0, 0.75)) {
  const std::string key = VehicleKey(style, he);
  if (!r.HasModel(key)) r.AddModel(key, BuildVehicle(style, he));
  ActorDraw a;
  a.id = id;
  a.model = key;
  a.pose = pose;
  a.paint = DefaultPaint(id);
  return a;
}

inline ActorDraw Walker(Renderer& r, std::uint32_t id, const Pose& pose, int variant = 1) {
  const Vec3 he(0.25, 0.25, 0.9);
  const std::string key = "walker:" + std::to_string(variant);
  if (!r.HasModel(key)) r.AddModel(key, BuildWalker(variant, he));
  ActorDraw a;
  a.id = id;
  a.model = key;
  a.pose = pose;
  return a;
}

inline ActorDraw Drone(Renderer& r, std::uint32_t id, const Pose& pose) {
  if (!r.HasModel("drone:quad_x")) r.AddModel("drone:quad_x", BuildDrone(DroneShape{}));
  ActorDraw a;
  a.id = id;
  a.model = "drone:quad_x";
  a.pose = pose;
  a.rotor_angles = {0.3, 1.2, 2.0, 2.9};
  return a;
}

inline Camera Cam(int w, int h, double fov, const Pose& pose, std::uint32_t outputs) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fov_deg = fov;
  c.pose = pose;
  c.outputs = outputs;
  return c;
}

inline double MeanLuma(const CameraFrame& f) {
  double s = 0;
  for (std::size_t i = 0; i < f.color.size(); i += 4) s += 0.114 * f.color[i] + 0.587 * f.color[i + 1] + 0.299 * f.color[i + 2];
  return s / (f.color.size() / 4);
}

inline double MeanAbsDiff(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += std::abs(int(a[i]) - int(b[i]));
  return s / a.size();
}

}  // namespace lockstep::render::testing
