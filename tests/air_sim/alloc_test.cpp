// Step() must not allocate in steady flight (no commands, no events): counts global operator
// new calls around Step. In its own executable because it replaces operator new.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "lockstep/air/air.h"

namespace {
std::atomic<long> g_allocs{0};
}

void* operator new(std::size_t n) {
  g_allocs.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace lockstep::air {
namespace {

TEST(air_alloc, SteadyFlightStepDoesNotAllocate) {
  World model;
  WorldState state;
  std::vector<float> v = {-50, -50, 0, 50, -50, 0, 50, 50, 0, -50, 50, 0, 0, 0, 30};
  std::vector<std::uint32_t> idx = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
  model.statics.mesh = StaticMesh::Build(v, idx, 5.0);
  for (DroneId id = 1; id <= 3; ++id) {
    Pose spawn;
    spawn.position = Vec3(10.0 * id - 40, -40, 0.06);
    AddDrone(&model, &state, id, MultirotorParams{}, spawn);
  }
  Environment env;
  env.wind = Vec3(1, 2, 0);
  env.turbulence_sigma = 0.5;
  VehicleBox car;
  car.pose.position = Vec3(-30, -30, 0.75);
  car.velocity = Vec3(1, 0, 0);
  env.vehicles.push_back(car);
  Commands cmds;
  for (DroneId id = 1; id <= 3; ++id) {
    cmds.push_back({id * 10, id, cmd::Arm{}});
    cmds.push_back({id * 10 + 1, id, cmd::MoveOnPath{{Vec3(10.0 * id - 40, -40, 3), Vec3(10.0 * id - 40, 0, 6)}, 2.0}});
  }
  const long at_start = g_allocs.load();
  Step(model, &state, cmds, env, 0.05);
  EXPECT_GT(g_allocs.load(), at_start);  // the counter works: starting paths allocates
  const Commands none;
  for (int i = 0; i < 60; ++i) Step(model, &state, none, env, 0.05);  // warm up: take-off events
  ASSERT_EQ(state.drones[0].landed, LandedState::kFlying);
  const long before = g_allocs.load();
  for (int i = 0; i < 40; ++i) {
    Step(model, &state, none, env, 0.05);
    ASSERT_TRUE(state.events.empty());
  }
  EXPECT_EQ(g_allocs.load() - before, 0);
}

}  // namespace
}  // namespace lockstep::air
