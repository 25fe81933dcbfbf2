#include "lockstep/sensors/types.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>

namespace lockstep::sensors {

Pose MakePose(double x, double y, double z, double yaw, double pitch, double roll) {
  // yaw about +z (ENU heading), pitch nose-up positive, roll right-side-down positive.
  const Quat q = Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(-pitch, Vec3::UnitY()) *
                 Eigen::AngleAxisd(roll, Vec3::UnitX());
  return Pose{Vec3(x, y, z), q.normalized()};
}

Pose MountPose(const Actor& a) {
  if (a.kind != ActorKind::kVehicle && a.kind != ActorKind::kWalker) return a.pose;
  return Pose{a.pose.Apply(Vec3(0, 0, -a.half_extents.z())), a.pose.orientation};
}

uint8_t ActorTag(const Actor& a) {
  if (a.tag) return a.tag;
  auto has = [&](const char* s) { return a.blueprint.find(s) != std::string::npos; };
  switch (a.kind) {
    case ActorKind::kWalker: return 12;  // Pedestrian
    case ActorKind::kDrone: return 21;   // Dynamic
    case ActorKind::kVehicle:
      if (has("truck") || has("van") || has("firetruck")) return 15;
      if (has("bus")) return 16;
      if (has("motorbike") || has("motorcycle") || has("harley") || has("yamaha") || has("kawasaki") || has("vespa")) return 18;
      if (has("bicycle") || has("bike") || has("bh.crossbike") || has("diamondback") || has("gazelle")) return 19;
      return 14;  // Car
    case ActorKind::kOther: return 22;  // Other
  }
  return 0;
}

int TagFromClassName(const std::string& name) {
  // CARLA 0.9.14+ classes, ids 0..28 (as the renderer's palette).
  static const char* const kNames[] = {"Unlabeled", "Roads",      "SideWalks", "Building",  "Wall",      "Fence",     "Pole",
                                       "TrafficLight", "TrafficSign", "Vegetation", "Terrain", "Sky",      "Pedestrian", "Rider",
                                       "Car",       "Truck",      "Bus",       "Train",     "Motorcycle", "Bicycle", "Static",
                                       "Dynamic",   "Other",      "Water",     "RoadLine",  "Ground",    "Bridge",    "RailTrack",
                                       "GuardRail"};
  auto lower = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
  };
  for (int i = 0; i < static_cast<int>(std::size(kNames)); ++i) {
    if (lower(kNames[i]) == lower(name)) return i;
  }
  return -1;
}

HitKind ActorHitKind(ActorKind k) {
  switch (k) {
    case ActorKind::kVehicle: return HitKind::kVehicle;
    case ActorKind::kWalker: return HitKind::kWalker;
    case ActorKind::kDrone: return HitKind::kDrone;
    case ActorKind::kOther: return HitKind::kStatic;
  }
  return HitKind::kNone;
}

const Actor* WorldFrame::Find(uint32_t id) const {
  auto it = std::lower_bound(actors.begin(), actors.end(), id, [](const Actor& a, uint32_t v) { return a.id < v; });
  return it != actors.end() && it->id == id ? &*it : nullptr;
}

namespace {
uint64_t SplitMix(uint64_t& x) {
  uint64_t z = (x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
uint64_t Rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
}  // namespace

Rng::Rng(uint64_t seed) {
  for (auto& s : s_) s = SplitMix(seed);
}

uint64_t Rng::Next() {
  const uint64_t result = Rotl(s_[1] * 5, 7) * 9;
  const uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = Rotl(s_[3], 45);
  return result;
}

double Rng::Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

double Rng::Normal(double mean, double stddev) {
  if (has_spare_) {
    has_spare_ = false;
    return mean + stddev * spare_;
  }
  double u1 = Uniform();
  while (u1 <= 0) u1 = Uniform();
  const double u2 = Uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * M_PI * u2;
  spare_ = r * std::sin(a);
  has_spare_ = true;
  return mean + stddev * r * std::cos(a);
}

uint64_t Rng::Fingerprint() const { return s_[0] ^ Rotl(s_[1], 13) ^ Rotl(s_[2], 29) ^ Rotl(s_[3], 47); }

uint64_t MixSeed(uint64_t a, uint64_t b, uint64_t c) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (uint64_t v : {a, b, c}) {
    for (int i = 0; i < 8; ++i) {
      h ^= (v >> (8 * i)) & 0xff;
      h *= 0x100000001b3ull;
    }
  }
  return h;
}

}  // namespace lockstep::sensors
