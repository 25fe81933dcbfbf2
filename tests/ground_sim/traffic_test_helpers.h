#pragma once
// Helpers of the Traffic Manager tests (traffic, TM conventions, TM features).
#include <gtest/gtest.h>

#include "lockstep/ground/town.h"
#include "lockstep/ground/types.h"

namespace lockstep::ground::testing {

inline constexpr double kDt = 0.05;  // s, the tests' tick

// The lane of light `index`'s first stop waypoint, `back` metres before the line, the box
// centre `half_z` (+2 cm) above it.
inline Pose BeforeLight(const Town& town, size_t index, double back, double half_z) {
  const auto& stop = town.Lights().at(index).info.stop_waypoints.at(0);
  auto before = town.Map().Previous(stop, back);
  EXPECT_FALSE(before.empty());
  const auto& wp = before.front();
  return Pose::FromYaw(wp.transform.location + Vec3(0, 0, half_z + 0.02), wp.transform.yaw);
}

}  // namespace lockstep::ground::testing
