// The saved state and its hash are the state and nothing else: built on memory full of
// different garbage, the same world gives the same bytes; a restored world steps on
// exactly like the one it was saved from.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>

#include "lockstep/ground/world.h"
#include "test_towns.h"

// While scribbling, every heap block starts filled with a byte that changes per
// allocation (as freed memory would), so struct padding differs between two worlds.
namespace {
bool g_scribble = false;
unsigned char g_pattern = 0x5A;
}  // namespace

void* operator new(std::size_t n) {
  void* p = std::malloc(n == 0 ? 1 : n);
  if (!p) throw std::bad_alloc();
  if (g_scribble) std::memset(p, g_pattern += 0x3B, n);
  return p;
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace lockstep::ground {
namespace {

constexpr double kDt = 0.05;

// Offset of the first byte where two snapshots differ, -1 if they are equal.
long FirstDifference(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  const size_t n = std::min(a.size(), b.size());
  for (size_t i = 0; i < n; ++i) {
    if (a[i] != b[i]) return static_cast<long>(i);
  }
  return a.size() == b.size() ? -1 : static_cast<long>(n);
}

// A world that exercises every saved struct: physics settings, global and per-vehicle
// Traffic Manager parameters, light states, manual and Ackermann controls, walkers.
std::unique_ptr<World> Busy(std::shared_ptr<const Town> town) {
  PhysicsSettings ps;
  ps.max_substeps = 8;
  auto w = std::make_unique<World>(town, 77, ps);
  EXPECT_EQ(w->SetTrafficManager(TmParam::kDistanceToLeadingVehicle, 0, 3.0), "");
  const auto& sp = town->SpawnPoints();
  for (uint32_t k = 0; k < 4; ++k) {
    const auto& p = sp.at(3 * k);
    const Vec3 half = FindVehicle("vehicle.audi.tt")->half_extents;
    EXPECT_EQ(w->AddVehicle(10 + k, "vehicle.audi.tt", {}, Pose::FromYaw(p.location + Vec3(0, 0, half.z() - 0.48), p.yaw)), "");
  }
  EXPECT_EQ(w->SetAutopilot(10, true), "");
  EXPECT_EQ(w->SetAutopilot(11, true), "");
  EXPECT_EQ(w->SetTrafficManager(TmParam::kPercentageSpeedDifference, 11, -20), "");
  VehicleControl c;
  c.throttle = 0.4;
  c.steer = 0.05;
  c.manual_gear_shift = true;
  c.gear = 1;
  EXPECT_EQ(w->ApplyControl(12, c), "");
  AckermannControl a;
  a.speed = 3;
  a.steer = 0.1;
  EXPECT_EQ(w->ApplyAckermann(13, a), "");
  EXPECT_EQ(w->SetTrafficLight(2, LightColor::kGreen, 12, 4, 3, std::nullopt), "");
  const auto rep = Populate(w.get(), 0, 4, 77, 100);
  EXPECT_EQ(rep.walkers.size(), 4u);
  return w;
}

TEST(GroundState, TheSameStateGivesTheSameBytesWhateverTheMemoryHeld) {
  auto town = testing::Town01();
  g_scribble = true;
  auto a = Busy(town);
  auto b = Busy(town);
  g_scribble = false;
  EXPECT_EQ(FirstDifference(a->Save(), b->Save()), -1);
  EXPECT_EQ(a->StateHash(), b->StateHash());
  for (int i = 0; i < 40; ++i) {
    a->Step(kDt);
    b->Step(kDt);
  }
  EXPECT_EQ(a->StateHash(), b->StateHash());
}

TEST(GroundState, SaveRestoreStepEqualsStep) {
  auto town = testing::Town01();
  auto a = Busy(town);
  for (int i = 0; i < 60; ++i) a->Step(kDt);
  const std::vector<uint8_t> saved = a->Save();
  auto b = World::Restore(town, saved);
  EXPECT_EQ(FirstDifference(b->Save(), saved), -1) << "of " << saved.size() << " bytes";
  for (int i = 0; i < 100; ++i) {
    a->Step(kDt);
    b->Step(kDt);
    ASSERT_EQ(FirstDifference(a->Save(), b->Save()), -1) << "diverged at step " << i;
  }
  // The state moved (the test compares something that changes).
  EXPECT_NE(a->Save(), saved);
}

TEST(GroundState, ACorruptSnapshotIsRefusedWithAReason) {
  auto town = testing::Town01();
  auto a = Busy(town);
  std::vector<uint8_t> saved = a->Save();
  saved.resize(saved.size() / 2);
  EXPECT_THROW(World::Restore(town, saved), std::runtime_error);
  saved = a->Save();
  saved.push_back(0);
  EXPECT_THROW(World::Restore(town, saved), std::runtime_error);
}

}  // namespace
}  // namespace lockstep::ground
