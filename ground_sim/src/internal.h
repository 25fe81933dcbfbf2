#pragma once
// Shared internals of the ground world (ODE handles, per-actor state).
#include <array>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include <ode/ode.h>

#include "lockstep/ground/world.h"

namespace lockstep::ground {

// splitmix64: a tiny seeded generator whose whole state is one word (saved with the world).
struct Rng {
  uint64_t s = 0;
  uint64_t Next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  bool Percent(double p) { return p > 0 && Uniform() * 100.0 < p; }
};
uint64_t MixSeed(uint64_t seed, uint64_t id);

enum class GeomKind : uint8_t { kStatic, kVehicle, kWalker, kExternal };

// User data of every ODE geom: who it belongs to.
struct GeomTag {
  GeomKind kind = GeomKind::kStatic;
  uint32_t actor = 0;
  uint8_t semantic = 0;
  ObjectKind object = ObjectKind::kStatic;
};

struct TmState {
  std::deque<map::Waypoint> path;        // lane-centre points ahead (path[0] at or behind the car)
  std::deque<map::Waypoint> planned;     // set_path / lane-change points still to append
  std::vector<int> route;                // set_route: options for the next junctions (1 L, 2 R, 3 S)
  Rng rng;
  double speed = 0;                      // m/s, kinematic mode speed
  double blocked = 0;                    // s below 0.1 m/s
  int committed_junction = -1;           // junction it may cross
  double waiting = 0;                    // s waiting at a junction entry
  int lane_change = 0;                   // forced: -1 left, +1 right
  double lane_change_cooldown = 0;       // s
  double random_draw_timer = 0;
  uint64_t ignore_draw_key = 0;          // unused (kept in the saved state's layout)
  bool ignore_light = false;             // this tick's ignore-lights draw (CARLA: every tick at red / yellow)
  bool ignore_sign = false;              // this tick's ignore-signs draw, before a stop sign
  double sign_wait = 0;                  // s stopped at the stop sign ahead
  uint64_t sign_done_key = 0;            // junction entry whose stop sign it has stopped at
  uint64_t entry_key = 0;                // junction entry ahead (lane key) last step
  double front_to_line = -1;             // m from the front bumper to its stop line last step
  Pose kin_target;                       // kinematic: pose at the end of this step
  TmVehicleParams params;
  std::set<uint32_t> ignore_collision;   // collision_detection(this, other, False): others it does not avoid
  // Outputs of the last decision.
  double target_speed = 0;
  double steer_angle = 0;                // rad, bicycle, + left
  int light = -1;                        // light ahead governing it
  double light_distance = -1;
};

struct VehicleActor {
  uint32_t id = 0;
  std::string blueprint;
  const VehicleSpec* spec = nullptr;
  VehiclePhysics physics;
  SpawnAttributes attributes;
  GeomTag tag;
  dBodyID body = nullptr;
  dGeomID geom = nullptr;
  VehicleControl control;
  bool use_ackermann = false;
  AckermannControl ackermann;
  double ackermann_integral = 0;
  double steer_angle = 0;                // rad, current front (bicycle) angle, + left
  bool simulate_physics = true;
  bool kinematic = false;                // moved kinematically this step
  int gear = 1;
  double gear_timer = 0;
  Vec3 prev_velocity = Vec3::Zero();
  Vec3 acceleration = Vec3::Zero();
  uint32_t light_state = 0;
  bool autopilot = false;
  TmState tm;
  map::Footprint footprint{};
  bool has_footprint = false;
  double speed_limit = 30 / 3.6;
  double opposite_lane = 0, sidewalk = 0, offroad = 0;  // footprint fractions
  Infractions infractions;
  bool hero() const { return attributes.role_name == "hero"; }
};

struct WalkerActor {
  uint32_t id = 0;
  std::string blueprint;
  const WalkerSpec* spec = nullptr;
  SpawnAttributes attributes;
  GeomTag tag;
  dBodyID body = nullptr;
  dGeomID geom = nullptr;
  WalkerControl control;
  double vertical_speed = 0;             // m/s, jumping
  bool airborne = false;
  Vec3 velocity = Vec3::Zero();
  uint32_t controller = 0;               // AI controller actor, 0 = none
};

struct ControllerActor {
  uint32_t id = 0;
  uint32_t walker = 0;
  bool running = false;
  double max_speed = 1.4;                // m/s
  bool has_goal = false;
  Vec3 goal = Vec3::Zero();
  bool planned = false;                  // the route to the goal is computed
  Vec3 goal_point = Vec3::Zero();        // where that route ends: the goal, or its nearest graph point
  std::deque<std::pair<int, int>> route; // graph nodes ahead, each with the crossing of the edge reaching it (-1: none)
  Rng rng;
  int at_node = -1;                      // last graph node reached
  int came_from = -1;                    // the node before it
  int drawn_node = -1;                   // node where the cross draw was made (once per arrival)
  int crossing = -1;                     // crossing (Town::Crosswalks index) it waits at or walks over
  int cross_end = 0;                     // the end it walks to
  bool cross_wait = false;               // at the kerb, waiting for the walk light and a free road
};

struct ExternalActor {
  ExternalBody body;
  GeomTag tag;
  dBodyID ode_body = nullptr;
  dGeomID geom = nullptr;
};

// A static box of another service's actor (a custom prop with the bounding box its
// blueprint declares): part of the town for collisions, named by its actor id.
struct PropActor {
  uint32_t id = 0;
  Pose pose;
  Vec3 half_extents = Vec3::Zero();
  GeomTag tag;
  dGeomID geom = nullptr;
};

// What the Traffic Manager sees of another actor at the start of a step.
struct Obstacle {
  uint32_t id = 0;
  Vec3 position = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  Eigen::Vector2d forward = Eigen::Vector2d(1, 0);
  double half_x = 0, half_y = 0;
  bool walker = false;
};

struct ContactRecord {
  uint32_t a = 0, b = 0;                 // actor ids (b = 0 for static)
  const GeomTag* ta = nullptr;
  const GeomTag* tb = nullptr;
  dContactGeom geom{};
};

// The walkers at the start of a step sorted by x (then id), for neighbour queries without
// an O(n^2) scan: a query near x looks at the entries whose start x is within its reach
// (walker_crowd.cpp).
struct WalkerSweep {
  struct Entry {
    double x = 0;                        // sort key: x at the start of the step
    uint32_t id = 0;
    Vec3 position = Vec3::Zero();        // StepWalkers moves it with the walker
    Vec3 velocity = Vec3::Zero();        // of the last step
    double radius = 0, half_height = 0;
  };
  std::vector<Entry> entries;            // by x, then id
  std::vector<uint32_t> ids;             // walker ids in order
  std::vector<size_t> slot;              // index in ids -> entry
  double max_radius = 0;
  void Build(const std::map<uint32_t, std::unique_ptr<WalkerActor>>& walkers);
  size_t Find(uint32_t id) const;        // the walker's entry
  std::pair<size_t, size_t> Range(double x, double reach) const;
  // Another capsule within the sum of radii + kWalkerGap of `to` that the move from `from`
  // brings closer blocks the move (not one it overlaps already: spawned so, Push parts them).
  bool Blocks(size_t self, const Vec3& from, const Vec3& to, double reach) const;
  // Walkers within kPersonalSpace of this one's capsule (or overlapping it) push it away
  // (at most push_speed x dt): a crowd spawned overlapping spreads out.
  Eigen::Vector2d Push(size_t self, double push_speed, double dt) const;
  // Another walker stands on `target` (within the sum of radii + 0.05 m).
  bool Occupied(size_t self, const Vec3& target) const;
};

struct World::Impl {
  std::shared_ptr<const Town> town;
  uint64_t seed = 0;
  uint64_t frame = 0;
  PhysicsSettings settings;
  TmGlobal tm;
  double cross_factor = 0.5;             // share of walkers that cross at a crosswalk they reach
  bool has_pedestrians_seed = false;     // a client sent set_pedestrians_seed
  uint64_t pedestrians_seed = 0;
  Rng tm_rng;                            // TM-wide draws (respawn points)
  std::vector<map::Waypoint> respawn_points;  // driving lane points every 5 m outside junctions (derived, not state)
  bool respawn_points_ready = false;
  LightWeather weather;                  // what the TM's vehicle lights follow (saved)

  dWorldID world = nullptr;
  dSpaceID static_space = nullptr;
  dSpaceID actor_space = nullptr;
  dJointGroupID contacts = nullptr;
  std::vector<dTriMeshDataID> mesh_data;
  std::vector<std::unique_ptr<GeomTag>> static_tags;
  GeomTag ground_tag;

  std::map<uint32_t, std::unique_ptr<VehicleActor>> vehicles;
  std::map<uint32_t, std::unique_ptr<WalkerActor>> walkers;
  std::map<uint32_t, ControllerActor> controllers;
  std::vector<std::unique_ptr<ExternalActor>> externals;
  std::map<uint32_t, std::unique_ptr<PropActor>> props;
  WalkerSweep crowd;                     // rebuilt at each walker step, not state
  std::vector<LightState> lights;
  std::vector<int> group_current;        // per group: index into its lights of the green one
  std::vector<std::vector<int>> group_lights;
  std::vector<bool> group_all_red;       // the group is in its all-red gap

  std::vector<Collision> collisions;
  std::vector<LaneInvasion> invasions;
  std::map<std::pair<uint32_t, uint32_t>, Collision> pending_collisions;  // (actor, other) -> sum
  std::set<std::pair<uint32_t, uint32_t>> last_contacts;  // (actor, other) in contact last step (saved)
  std::vector<ContactRecord> contact_buffer;
  std::vector<dJointFeedback> feedback;
  std::vector<std::pair<size_t, size_t>> feedback_owner;  // feedback index -> contact index

  Impl(std::shared_ptr<const Town> t, uint64_t s, PhysicsSettings ps);
  ~Impl();

  // world.cpp
  void BuildStatics();
  void CreateVehicleBody(VehicleActor* v, const Pose& pose);
  void CreateWalkerBody(WalkerActor* w, const Pose& pose);
  void DestroyBody(dBodyID b, dGeomID g);
  VehicleActor* FindVehicle(uint32_t id);
  WalkerActor* FindWalker(uint32_t id);
  double GroundHeight(const Vec3& p, double up, double down, bool* hit) const;
  void Collide(bool record_only_kinematic);
  void Substep(double h, bool last);
  void RecordCollision(uint32_t actor, uint32_t other, ObjectKind kind, uint8_t tag, const Vec3& impulse);
  void FinishEvents();
  void UpdateMeasurements(double dt);
  void SyncExternals(double dt);

  // vehicle_dynamics.cpp
  void ApplyWheelForces(VehicleActor* v, double h);
  void UpdateGear(VehicleActor* v, double h);
  void AckermannToControl(VehicleActor* v, double h);

  // traffic_lights.cpp
  void InitLights();
  void StepLights(double dt);
  void ResetLightGroup(size_t group);
  double RedTimeLeft(int light) const;

  // traffic_manager.cpp
  void StepTrafficManager(double dt);
  void TmVehicle(VehicleActor* v, double dt, std::map<int, std::vector<const VehicleActor*>>* junction_users,
                 const std::vector<Obstacle>& obstacles);
  void FillPath(VehicleActor* v);
  bool ChangeLane(VehicleActor* v, bool left, const std::vector<Obstacle>* obstacles);
  void MoveKinematic(VehicleActor* v, double dt);
  void AnchorPath(VehicleActor* v);
  void Respawn(VehicleActor* v);
  bool HybridKinematic(const VehicleActor& v) const;
  // CARLA's dormant actors: farther than actor_active_distance from every hero (none
  // without a hero).
  bool Dormant(const VehicleActor& v) const;
  // CARLA's MotionPlanStage for a dormant vehicle with respawn_dormant_vehicles: to a free
  // lane point at a random distance within the respawn bounds of `hero`.
  void RespawnNearHero(VehicleActor* v, const Vec3& hero);
  void PlaceAt(VehicleActor* v, const Pose& pose);

  // vehicle_lights.cpp
  void StepVehicleLights();

  // walkers.cpp
  void StepWalkers(double dt);
  // walker_ai.cpp
  void StepControllers(double dt);
  void StepController(ControllerActor& c, WalkerActor& w, size_t self, double dt);
  Vec3 AvoidWalkers(size_t self, const Vec3& dir, double speed, bool on_road) const;
  bool MayCross(const TownCrosswalk& cw, double need_s) const;
  void PlanRoute(ControllerActor& c, const Vec3& pos);
  bool ExtendWander(ControllerActor& c, const Vec3& pos);
  uint64_t ControllerSeed(uint32_t id) const;
};

Pose BodyPose(dBodyID b);
void SetBodyPose(dBodyID b, const Pose& p);
Vec3 ToVec(const dReal* v);
double Wrap(double a);

}  // namespace lockstep::ground
