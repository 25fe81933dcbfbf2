// bench/run ground_wheels: the two wheel models issue 10 asks to measure, on the same flat
// trimesh (a 1 km x 100 m grid of 5 m quads, as a road mesh is) with 100 cars at full
// throttle from rest, CARLA's 10 ms sub-steps, dt 0.05 s:
//   raycast  ground_sim's model (one body, four suspension rays), the whole World::Step
//   jointed  a chassis and four sphere wheels on ODE hinge-2 joints (suspension by the
//            joint's ERP/CFM, a motor on every wheel, friction-pyramid contacts), at
//            10 ms and at 2 ms sub-steps
// It prints the CPU time per tick, the speed reached after 10 s, how many cars stayed
// upright and on course, and the chassis height jitter at rest. JSON lines.
//
//   bench_ground_wheels [--cars N] [--seconds S]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include <ode/ode.h>

#include "lockstep/ground/world.h"
#include "lockstep/map/map.h"
#include "lockstep/map/mesh.h"

namespace {

using lockstep::ground::Vec3;
constexpr double kDt = 0.05, kSub = 0.01;  // s
constexpr double kHalfX = 2.09, kHalfY = 0.9, kHalfZ = 0.69;  // vehicle.audi.tt's box
constexpr double kMass = 1500, kWheelR = 0.35, kWheelMass = 20;

lockstep::map::Mesh Grid() {
  lockstep::map::Mesh m;
  m.name = "road";
  m.semantic_tag = lockstep::map::semantic::kRoads;
  for (double x = -100; x < 900; x += 5) {
    for (double y = -50; y < 50; y += 5) {
      m.AddQuad(Vec3(x, y, 0), Vec3(x + 5, y, 0), Vec3(x + 5, y + 5, 0), Vec3(x, y + 5, 0), Vec3::UnitZ());
    }
  }
  return m;
}

Vec3 Start(int k) { return Vec3(-80 + 14.0 * (k / 10), -45 + 10.0 * (k % 10), 0); }

double Cpu() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

struct Figures {
  double cpu_ms = 0, speed_kmh = 0, jitter_mm = 0;
  int upright = 0, on_course = 0;
};

// ---- ray-cast: ground_sim's World ----
Figures RayCast(int cars, double seconds) {
  const std::string xodr = R"(<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="4" name="flat"/>
<road name="r" length="1000" id="1" junction="-1"><planView><geometry s="0" x="-100" y="0" hdg="0" length="1000"><line/></geometry></planView>
<lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center><right><lane id="-1" type="driving" level="false">
<width sOffset="0" a="100" b="0" c="0" d="0"/></lane></right></laneSection></lanes></road></OpenDRIVE>)";
  auto town = std::make_shared<const lockstep::ground::Town>(lockstep::map::Map::FromString(xodr, "flat"),
                                                             std::vector<lockstep::map::Mesh>{Grid()});
  lockstep::ground::World w(town, 1);
  for (int k = 0; k < cars; ++k) {
    w.AddVehicle(static_cast<uint32_t>(k + 1), "vehicle.audi.tt", {}, lockstep::ground::Pose::FromYaw(Start(k) + Vec3(0, 0, kHalfZ + 0.02), 0));
  }
  Figures f;
  std::vector<double> z;
  for (int i = 0; i < 40; ++i) {  // settle, then sample the height at rest
    w.Step(kDt);
    if (i >= 20) z.push_back(w.Vehicle(1)->pose.position.z());
  }
  const auto [lo, hi] = std::minmax_element(z.begin(), z.end());
  f.jitter_mm = (*hi - *lo) * 1000;
  lockstep::ground::VehicleControl c;
  c.throttle = 1;
  for (int k = 0; k < cars; ++k) w.ApplyControl(static_cast<uint32_t>(k + 1), c);
  const int ticks = static_cast<int>(seconds / kDt);
  const double t0 = Cpu();
  for (int i = 0; i < ticks; ++i) w.Step(kDt);
  f.cpu_ms = (Cpu() - t0) * 1000 / ticks;
  for (const auto& v : w.Vehicles()) {
    f.speed_kmh += v.velocity.norm() * 3.6 / cars;
    f.upright += (v.pose.orientation * Vec3::UnitZ()).z() > 0.9;
    f.on_course += std::abs(v.pose.position.y() - Start(static_cast<int>(v.id) - 1).y()) < 1.0;
  }
  return f;
}

// ---- jointed wheels on plain ODE ----
struct JointedCar {
  dBodyID chassis = nullptr;
  dBodyID wheel[4] = {};
  dJointID joint[4] = {};
};

struct JointedWorld {
  dWorldID world = dWorldCreate();
  dSpaceID statics = dHashSpaceCreate(nullptr);
  dSpaceID actors = dHashSpaceCreate(nullptr);
  dJointGroupID contacts = dJointGroupCreate(0);
  dTriMeshDataID data = dGeomTriMeshDataCreate();
  lockstep::map::Mesh mesh = Grid();
  std::vector<JointedCar> cars;
  ~JointedWorld() {
    dJointGroupDestroy(contacts);
    dSpaceDestroy(actors);
    dSpaceDestroy(statics);
    dGeomTriMeshDataDestroy(data);
    dWorldDestroy(world);
  }
};

void NearCallback(void* data, dGeomID a, dGeomID b) {
  auto* w = static_cast<JointedWorld*>(data);
  dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
  if (ba && bb && dAreConnected(ba, bb)) return;
  dContact c[4];
  const int n = dCollide(a, b, 4, &c[0].geom, sizeof(dContact));
  for (int i = 0; i < n; ++i) {
    c[i].surface.mode = dContactSoftCFM | dContactSoftERP | dContactApprox1;
    c[i].surface.mu = 1.0;
    c[i].surface.soft_cfm = 1e-5;
    c[i].surface.soft_erp = 0.5;
    dJointAttach(dJointCreateContact(w->world, w->contacts, &c[i]), ba, bb);
  }
}

Figures Jointed(int cars, double seconds, double sub) {
  JointedWorld w;
  dWorldSetGravity(w.world, 0, 0, -9.81);
  dWorldSetQuickStepNumIterations(w.world, 20);
  dWorldSetAutoDisableFlag(w.world, 0);
  dGeomTriMeshDataBuildSingle(w.data, w.mesh.vertices.data(), 3 * sizeof(float), static_cast<int>(w.mesh.VertexCount()),
                              w.mesh.indices.data(), static_cast<int>(w.mesh.indices.size()), 3 * sizeof(std::uint32_t));
  dCreateTriMesh(w.statics, w.data, nullptr, nullptr, nullptr);
  // Suspension of ~50 kN/m and ~3.5 kN s/m per wheel, as the ray-cast model's.
  const double k = 50000, d = 3500, erp = sub * k / (sub * k + d), cfm = 1 / (sub * k + d);
  for (int n = 0; n < cars; ++n) {
    JointedCar car;
    const Vec3 p = Start(n) + Vec3(0, 0, kWheelR + 0.3);
    car.chassis = dBodyCreate(w.world);
    dMass m;
    dMassSetBoxTotal(&m, kMass - 4 * kWheelMass, 2 * kHalfX, 2 * kHalfY, 0.6);
    dBodySetMass(car.chassis, &m);
    dBodySetPosition(car.chassis, p.x(), p.y(), p.z());
    dGeomSetBody(dCreateBox(w.actors, 2 * kHalfX, 2 * kHalfY, 0.6), car.chassis);
    for (int i = 0; i < 4; ++i) {
      const Vec3 at = p + Vec3(i < 2 ? 1.3 : -1.3, i % 2 ? 0.8 : -0.8, -0.3);
      car.wheel[i] = dBodyCreate(w.world);
      dMassSetSphereTotal(&m, kWheelMass, kWheelR);
      dBodySetMass(car.wheel[i], &m);
      dBodySetPosition(car.wheel[i], at.x(), at.y(), at.z());
      dGeomSetBody(dCreateSphere(w.actors, kWheelR), car.wheel[i]);
      car.joint[i] = dJointCreateHinge2(w.world, nullptr);
      dJointAttach(car.joint[i], car.chassis, car.wheel[i]);
      dJointSetHinge2Anchor(car.joint[i], at.x(), at.y(), at.z());
      const dReal up[3] = {0, 0, 1}, axle[3] = {0, 1, 0};
      dJointSetHinge2Axes(car.joint[i], up, axle);
      dJointSetHinge2Param(car.joint[i], dParamSuspensionERP, erp);
      dJointSetHinge2Param(car.joint[i], dParamSuspensionCFM, cfm);
      dJointSetHinge2Param(car.joint[i], dParamLoStop, 0);  // straight ahead
      dJointSetHinge2Param(car.joint[i], dParamHiStop, 0);
    }
    w.cars.push_back(car);
  }
  auto step = [&] {
    for (int s = 0; s < static_cast<int>(std::lround(kDt / sub)); ++s) {
      dSpaceCollide2(reinterpret_cast<dGeomID>(w.actors), reinterpret_cast<dGeomID>(w.statics), &w, &NearCallback);
      dSpaceCollide(w.actors, &w, &NearCallback);
      dWorldQuickStep(w.world, sub);
      dJointGroupEmpty(w.contacts);
    }
  };
  Figures f;
  std::vector<double> z;
  for (int i = 0; i < 40; ++i) {
    step();
    if (i >= 20) z.push_back(dBodyGetPosition(w.cars[0].chassis)[2]);
  }
  const auto [lo, hi] = std::minmax_element(z.begin(), z.end());
  f.jitter_mm = (*hi - *lo) * 1000;
  // Full throttle: a wheel motor towards 100 km/h with the ray-cast car's first-gear
  // wheel torque (~ 400 N m x 3.5 x 4.0 / 4 wheels).
  for (auto& car : w.cars) {
    for (int i = 0; i < 4; ++i) {
      dJointSetHinge2Param(car.joint[i], dParamVel2, 100 / 3.6 / kWheelR);
      dJointSetHinge2Param(car.joint[i], dParamFMax2, 1400);
    }
  }
  const int ticks = static_cast<int>(seconds / kDt);
  const double t0 = Cpu();
  for (int i = 0; i < ticks; ++i) step();
  f.cpu_ms = (Cpu() - t0) * 1000 / ticks;
  for (size_t n = 0; n < w.cars.size(); ++n) {
    const dReal* v = dBodyGetLinearVel(w.cars[n].chassis);
    const dReal* r = dBodyGetRotation(w.cars[n].chassis);
    f.speed_kmh += std::hypot(v[0], v[1]) * 3.6 / cars;
    f.upright += r[10] > 0.9;  // body z axis up
    f.on_course += std::abs(dBodyGetPosition(w.cars[n].chassis)[1] - Start(static_cast<int>(n)).y()) < 1.0;
  }
  return f;
}

void Print(const char* model, int cars, double seconds, const Figures& f) {
  std::printf("{\"bench\":\"ground_wheels\",\"model\":\"%s\",\"cars\":%d,\"seconds\":%.0f,\"cpu_ms\":%.3f,\"ticks_per_s\":%.1f,"
              "\"speed_kmh\":%.1f,\"upright\":%d,\"on_course\":%d,\"rest_jitter_mm\":%.2f}\n",
              model, cars, seconds, f.cpu_ms, 1000 / f.cpu_ms, f.speed_kmh, f.upright, f.on_course, f.jitter_mm);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int cars = 100;
  double seconds = 10;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--cars") cars = std::atoi(argv[i + 1]);
    else if (a == "--seconds") seconds = std::atof(argv[i + 1]);
    else {
      std::fprintf(stderr, "bench ground_wheels: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  if (cars < 1 || cars > 100 || !(seconds > 0)) {
    std::fprintf(stderr, "bench ground_wheels: --cars 1..100, --seconds > 0\n");
    return 2;
  }
  dInitODE2(0);
  dAllocateODEDataForThread(dAllocateMaskAll);
  const Figures ray = RayCast(cars, seconds);
  Print("raycast", cars, seconds, ray);
  const Figures joint = Jointed(cars, seconds, kSub);
  Print("jointed", cars, seconds, joint);
  const Figures joint2 = Jointed(cars, seconds, 0.002);  // 2 ms sub-steps
  Print("jointed_2ms", cars, seconds, joint2);
  std::printf("{\"bench\":\"ground_wheels\",\"cars\":%d,\"raycast_cpu_ms\":%.3f,\"jointed_cpu_ms\":%.3f,\"jointed_2ms_cpu_ms\":%.3f,"
              "\"jointed_over_raycast\":%.2f,\"jointed_2ms_over_raycast\":%.2f}\n",
              cars, ray.cpu_ms, joint.cpu_ms, joint2.cpu_ms, joint.cpu_ms / ray.cpu_ms, joint2.cpu_ms / ray.cpu_ms);
  dCloseODE();
  return 0;
}
