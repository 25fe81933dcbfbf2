#pragma once
// Plain types of the sensors core: poses, the actors a frame shows, a seeded random
// stream. World frame ENU (x east, y north, z up), metres; bodies and sensors FLU
// (x forward, y left, z up). No DDS here.
#include <cstdint>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lockstep::sensors {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;

struct Pose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();  // body to parent

  Vec3 Apply(const Vec3& p) const { return position + orientation * p; }
  // This pose followed by `child` (a pose given in this pose's frame).
  Pose Compose(const Pose& child) const { return Pose{Apply(child.position), (orientation * child.orientation).normalized()}; }
};

Pose MakePose(double x, double y, double z, double yaw = 0, double pitch = 0, double roll = 0);

enum class ActorKind { kVehicle, kWalker, kDrone, kOther };
// What a ray hit: the kinds of ObjectKind on the wire.
enum class HitKind { kNone, kGround, kStatic, kVehicle, kWalker, kDrone };

// One moving actor as the physics services published it for a frame.
struct Actor {
  uint32_t id = 0;
  ActorKind kind = ActorKind::kOther;
  std::string blueprint;
  Pose pose;                                   // world, centre of the bounding box
  Vec3 half_extents = Vec3(0.5, 0.5, 0.5);     // m, box half sizes along body x, y, z
  Vec3 velocity = Vec3::Zero();                // m/s, world
  Vec3 angular_velocity = Vec3::Zero();        // rad/s, world
  uint8_t tag = 0;                             // CARLA semantic tag if set (custom props); 0: from kind and blueprint
  uint32_t light_state = 0;                    // vehicles: carla.VehicleLightState bits
  std::string special_type;                    // vehicles: the blueprint's special_type ("emergency", ...)
};

// CARLA semantic tag of an actor (Car, Truck, Bus, Motorcycle, Bicycle, Pedestrian; drones
// have no CARLA class: Dynamic).
uint8_t ActorTag(const Actor& a);
// The frame an attached sensor's or prop's transform is relative to, as the render service
// draws cameras: vehicles and walkers, the bottom centre of their box (CARLA's vehicle
// origin); drones and others, their pose.
Pose MountPose(const Actor& a);
// CARLA's semantic tag of a class name ("Static", "Vehicles" is not one: "Car"), case
// insensitive; -1 if unknown.
int TagFromClassName(const std::string& name);
HitKind ActorHitKind(ActorKind k);

// The actors of one frame, sorted by id.
struct WorldFrame {
  uint32_t run = 0;
  uint64_t frame = 0;      // the frame these states belong to
  double sim_time = 0;     // s
  std::vector<Actor> actors;
  const Actor* Find(uint32_t id) const;
};

// Physics events of one frame (PhysicsEvents on the wire), for the event sensors.
struct CollisionEvent {
  uint32_t actor = 0;
  uint32_t other_actor = 0;      // 0 = static geometry
  HitKind other_kind = HitKind::kNone;
  uint8_t other_tag = 0;
  Vec3 normal_impulse = Vec3::Zero();  // N s, world
  Vec3 location = Vec3::Zero();        // m, world
};
struct LaneMarking {
  int type = 0;                  // msg::LaneMarkingType value
  std::string color;
  float width = 0;
  bool lane_change_left = false;
  bool lane_change_right = false;
};
struct LaneInvasionEvent {
  uint32_t actor = 0;
  std::vector<LaneMarking> crossed;
};
struct FrameEvents {
  std::vector<CollisionEvent> collisions;
  std::vector<LaneInvasionEvent> lane_invasions;
};

// Weather that attenuates LiDAR returns (CARLA's WeatherParameters ranges, 0..100).
struct Weather {
  double precipitation = 0;
  double fog_density = 0;
};

// A snapshot of sensor state (a replacement process restores it): values in order, as
// their bytes (one machine's representation: snapshots stay within one build).
class StateOut {
 public:
  template <class T>
  void Put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "Put: a plain value");
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof v);
  }
  void Put(const Vec3& v) {
    for (int i = 0; i < 3; ++i) Put(v[i]);
  }
  void Put(const Quat& q) {
    for (double c : {q.w(), q.x(), q.y(), q.z()}) Put(c);
  }
  void Put(const Pose& p) {
    Put(p.position);
    Put(p.orientation);
  }
  void Put(const std::string& s) {
    Put(static_cast<uint64_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  void Put(const std::map<std::string, std::string>& m) {
    Put(static_cast<uint64_t>(m.size()));
    for (const auto& [k, v] : m) {
      Put(k);
      Put(v);
    }
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

class StateIn {
 public:
  explicit StateIn(const std::vector<uint8_t>& bytes, size_t at = 0) : bytes_(bytes), at_(at) {}
  template <class T>
  void Get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "Get: a plain value");
    Need(sizeof v);
    std::memcpy(&v, bytes_.data() + at_, sizeof v);
    at_ += sizeof v;
  }
  void Get(Vec3& v) {
    for (int i = 0; i < 3; ++i) Get(v[i]);
  }
  void Get(Quat& q) {
    double w = 0, x = 0, y = 0, z = 0;
    Get(w), Get(x), Get(y), Get(z);
    q = Quat(w, x, y, z);
  }
  void Get(Pose& p) {
    Get(p.position);
    Get(p.orientation);
  }
  void Get(std::string& s) {
    uint64_t n = 0;
    Get(n);
    Need(n);
    s.assign(reinterpret_cast<const char*>(bytes_.data() + at_), n);
    at_ += n;
  }
  void Get(std::map<std::string, std::string>& m) {
    uint64_t n = 0;
    Get(n);
    m.clear();
    for (uint64_t i = 0; i < n; ++i) {
      std::string k, v;
      Get(k);
      Get(v);
      m.emplace(std::move(k), std::move(v));
    }
  }
  size_t at() const { return at_; }
  bool done() const { return at_ == bytes_.size(); }

 private:
  void Need(uint64_t n) const {
    if (n > bytes_.size() - at_) throw std::runtime_error("sensor snapshot: truncated");
  }
  const std::vector<uint8_t>& bytes_;
  size_t at_;
};

// Deterministic random stream (splitmix64 seeding, xoshiro256**), identical on every
// platform: std::normal_distribution is not specified bit for bit, this is.
class Rng {
 public:
  explicit Rng(uint64_t seed = 0);
  uint64_t Next();
  double Uniform();                          // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  double Normal(double mean = 0, double stddev = 1);  // Box-Muller, both halves used
  uint64_t Fingerprint() const;              // for state hashes
  void Save(StateOut& out) const {
    for (uint64_t v : s_) out.Put(v);
    out.Put(has_spare_);
    out.Put(spare_);
  }
  void Load(StateIn& in) {
    for (uint64_t& v : s_) in.Get(v);
    in.Get(has_spare_);
    in.Get(spare_);
  }

 private:
  uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0;
};

// FNV-1a 64 of a few integers: per-sensor seeds from the run seed.
uint64_t MixSeed(uint64_t a, uint64_t b, uint64_t c = 0);

}  // namespace lockstep::sensors
