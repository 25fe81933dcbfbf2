#pragma once
// Walker-walker spacing and local avoidance parameters (walker_crowd.cpp, walkers.cpp).
namespace lockstep::ground {

constexpr double kWalkerGap = 0.02;     // m kept between two capsules (no contact events)
constexpr double kPushSpeed = 1.0;      // m/s: overlapping walkers (spawned so) move apart
constexpr double kPersonalSpace = 0.1;  // m: walkers nearer than the sum of radii + this push apart
constexpr double kAvoidRange = 1.5;     // m between the capsules: a walker ahead this near is avoided
constexpr double kPassGap = 0.3;        // m to the side of the other capsule when passing
constexpr double kMaxTurn = 1.0472;     // rad (60 deg): sharpest avoidance turn
constexpr double kSide = 0.1;           // m: a walker this far right of the heading is passed on the left
constexpr double kOffRoadProbe = 0.8;   // m ahead on the new heading that must not be a driving lane
constexpr double kQueue = 1.5;          // m: a target another walker stands on counts as reached this near

}  // namespace lockstep::ground
