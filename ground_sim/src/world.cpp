// The ground world: ODE setup, actors, commands, the step and its events.
#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

#include "internal.h"

namespace lockstep::ground {
namespace {

std::once_flag g_ode_init;

constexpr double kWalkerMass = 80.0;   // kg, for impulses with kinematic walkers
constexpr int kMaxContacts = 8;

void InitOde() {
  std::call_once(g_ode_init, [] { dInitODE2(0); });
  dAllocateODEDataForThread(dAllocateMaskAll);
}

bool IsGroundTag(uint8_t t) {
  return t == map::semantic::kRoads || t == map::semantic::kSideWalks || t == map::semantic::kTerrain ||
         t == map::semantic::kRoadLine || t == map::semantic::kGround;
}

const GeomTag* TagOf(dGeomID g) { return static_cast<const GeomTag*>(dGeomGetData(g)); }

struct RayQuery {
  double best = 1e30;
  Vec3 normal = Vec3::UnitZ();
  uint8_t tag = 0;
  bool hit = false;
};

void RayCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* q = static_cast<RayQuery*>(data);
  dContactGeom c[4];
  const int n = dCollide(o1, o2, 4, c, sizeof(dContactGeom));
  for (int i = 0; i < n; ++i) {
    if (c[i].depth < q->best) {
      q->best = c[i].depth;
      q->normal = Vec3(c[i].normal[0], c[i].normal[1], c[i].normal[2]);
      const GeomTag* t = TagOf(o2) ? TagOf(o2) : TagOf(o1);
      q->tag = t ? t->semantic : 0;
      q->hit = true;
    }
  }
}

}  // namespace

uint64_t MixSeed(uint64_t seed, uint64_t id) {
  Rng r{seed ^ (id * 0xD1B54A32D192ED03ull)};
  r.Next();
  return r.Next();
}

double Pose::Yaw() const {
  const Vec3 f = orientation * Vec3::UnitX();
  return std::atan2(f.y(), f.x());
}
Pose Pose::FromYaw(const Vec3& p, double yaw) {
  Pose out;
  out.position = p;
  out.orientation = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
  return out;
}

Vec3 ToVec(const dReal* v) { return Vec3(v[0], v[1], v[2]); }
double Wrap(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}
Pose BodyPose(dBodyID b) {
  Pose p;
  p.position = ToVec(dBodyGetPosition(b));
  const dReal* q = dBodyGetQuaternion(b);
  p.orientation = Quat(q[0], q[1], q[2], q[3]);
  return p;
}
void SetBodyPose(dBodyID b, const Pose& p) {
  dBodySetPosition(b, p.position.x(), p.position.y(), p.position.z());
  const Quat q = p.orientation.normalized();
  dQuaternion dq = {q.w(), q.x(), q.y(), q.z()};
  dBodySetQuaternion(b, dq);
}

World::Impl::Impl(std::shared_ptr<const Town> t, uint64_t s, PhysicsSettings ps)
    : town(std::move(t)), seed(s), settings(ps) {
  InitOde();
  world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -9.81);
  dWorldSetQuickStepNumIterations(world, 20);
  dWorldSetAutoDisableFlag(world, 0);
  dWorldSetContactSurfaceLayer(world, 0.001);
  // A quadtree over the town: single-geom queries (wheel rays, walkers) visit only the
  // cells they touch (a hash space's collide2 tests every static geom).
  {
    const auto lo = town->Map().BoundsMin(), hi = town->Map().BoundsMax();
    const dVector3 centre = {(lo.x() + hi.x()) / 2, (lo.y() + hi.y()) / 2, 0, 0};
    const dVector3 extents = {(hi.x() - lo.x()) / 2 + 100, (hi.y() - lo.y()) / 2 + 100, 200, 0};
    static_space = dQuadTreeSpaceCreate(nullptr, centre, extents, 6);
  }
  actor_space = dHashSpaceCreate(nullptr);
  dHashSpaceSetLevels(actor_space, -1, 5);
  contacts = dJointGroupCreate(0);
  tm.random_seed = 0;
  tm_rng.s = MixSeed(seed, 0x7E4D);
  BuildStatics();
  InitLights();
}

World::Impl::~Impl() {
  for (auto& [id, v] : vehicles) DestroyBody(v->body, v->geom);
  for (auto& [id, w] : walkers) DestroyBody(w->body, w->geom);
  for (auto& e : externals) DestroyBody(e->ode_body, e->geom);
  dJointGroupDestroy(contacts);
  dSpaceDestroy(actor_space);
  dSpaceDestroy(static_space);  // destroys the static geoms it holds
  for (auto d : mesh_data) dGeomTriMeshDataDestroy(d);
  dWorldDestroy(world);
}

void World::Impl::BuildStatics() {
  ground_tag = GeomTag{GeomKind::kStatic, 0, map::semantic::kTerrain, ObjectKind::kGround};
  dGeomID plane = dCreatePlane(static_space, 0, 0, 1, -0.02);
  dGeomSetData(plane, &ground_tag);
  for (const auto& m : town->Meshes()) {
    if (m.indices.empty()) continue;
    dTriMeshDataID data = dGeomTriMeshDataCreate();
    static_assert(sizeof(dTriIndex) == sizeof(std::uint32_t));
    dGeomTriMeshDataBuildSingle(data, m.vertices.data(), 3 * sizeof(float), static_cast<int>(m.VertexCount()),
                                m.indices.data(), static_cast<int>(m.indices.size()), 3 * sizeof(std::uint32_t));
    mesh_data.push_back(data);
    dGeomID g = dCreateTriMesh(static_space, data, nullptr, nullptr, nullptr);
    auto tag = std::make_unique<GeomTag>();
    tag->kind = GeomKind::kStatic;
    tag->semantic = m.semantic_tag;
    tag->object = IsGroundTag(m.semantic_tag) ? ObjectKind::kGround : ObjectKind::kStatic;
    dGeomSetData(g, tag.get());
    static_tags.push_back(std::move(tag));
  }
}

void World::Impl::DestroyBody(dBodyID b, dGeomID g) {
  if (g) dGeomDestroy(g);
  if (b) dBodyDestroy(b);
}

VehicleActor* World::Impl::FindVehicle(uint32_t id) {
  auto it = vehicles.find(id);
  return it == vehicles.end() ? nullptr : it->second.get();
}
WalkerActor* World::Impl::FindWalker(uint32_t id) {
  auto it = walkers.find(id);
  return it == walkers.end() ? nullptr : it->second.get();
}

// Height of the first static surface below p + up (m), searching `up + down` metres.
double World::Impl::GroundHeight(const Vec3& p, double up, double down, bool* hit) const {
  dGeomID ray = dCreateRay(nullptr, up + down);
  dGeomRaySet(ray, p.x(), p.y(), p.z() + up, 0, 0, -1);
  dGeomRaySetClosestHit(ray, 1);
  RayQuery q;
  dSpaceCollide2(ray, reinterpret_cast<dGeomID>(static_space), &q, &RayCallback);
  dGeomDestroy(ray);
  if (hit) *hit = q.hit;
  return q.hit ? p.z() + up - q.best : p.z();
}

void World::Impl::CreateVehicleBody(VehicleActor* v, const Pose& pose) {
  const Vec3 h = v->spec->half_extents;
  v->body = dBodyCreate(world);
  dMass m;
  // Inertia of the box; the centre of mass offset is handled by where forces act.
  dMassSetBoxTotal(&m, v->physics.mass, 2 * h.x(), 2 * h.y(), 2 * h.z());
  dBodySetMass(v->body, &m);
  SetBodyPose(v->body, pose);
  dBodySetAngularDamping(v->body, 0.02);
  // The collision box starts ground_clearance above the bottom: curbs pass under it.
  const double clear = std::min(v->physics.ground_clearance, h.z());
  v->geom = dCreateBox(actor_space, 2 * h.x(), 2 * h.y(), 2 * h.z() - clear);
  dGeomSetBody(v->geom, v->body);
  dGeomSetOffsetPosition(v->geom, 0, 0, clear / 2);
  v->tag = GeomTag{GeomKind::kVehicle, v->id, 10, ObjectKind::kVehicle};
  v->tag.semantic = 14;  // Car (CARLA palette); refined below
  switch (v->spec->base_type) {
    case BaseType::kTruck: v->tag.semantic = 15; break;
    case BaseType::kBus: v->tag.semantic = 16; break;
    case BaseType::kMotorcycle: v->tag.semantic = 18; break;
    case BaseType::kBicycle: v->tag.semantic = 19; break;
    default: break;
  }
  dGeomSetData(v->geom, &v->tag);
}

void World::Impl::CreateWalkerBody(WalkerActor* w, const Pose& pose) {
  w->body = dBodyCreate(world);
  dMass m;
  dMassSetCapsuleTotal(&m, kWalkerMass, 3, w->spec->radius, std::max(0.1, w->spec->height - 2 * w->spec->radius));
  dBodySetMass(w->body, &m);
  Pose upright = Pose::FromYaw(pose.position, pose.Yaw());
  SetBodyPose(w->body, upright);
  dBodySetKinematic(w->body);
  // Capsule along z; its bottom 5 cm above the feet so standing on a curb is no contact.
  w->geom = dCreateCapsule(actor_space, w->spec->radius, std::max(0.1, w->spec->height - 2 * w->spec->radius - 0.05));
  dGeomSetBody(w->geom, w->body);
  dGeomSetOffsetPosition(w->geom, 0, 0, 0.025);
  w->tag = GeomTag{GeomKind::kWalker, w->id, 12, ObjectKind::kWalker};
  dGeomSetData(w->geom, &w->tag);
}

// ---- collisions ----

namespace {
struct CollideContext {
  World::Impl* impl;
};

bool KinematicGeom(dGeomID g) {
  dBodyID b = dGeomGetBody(g);
  return !b || dBodyIsKinematic(b);
}

void NearCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* impl = static_cast<CollideContext*>(data)->impl;
  const GeomTag* t1 = TagOf(o1);
  const GeomTag* t2 = TagOf(o2);
  if (!t1 || !t2) return;
  if (t1->kind == GeomKind::kStatic && t2->kind == GeomKind::kStatic) return;
  // Against the town only dynamic vehicles collide: kinematic vehicles follow lanes and
  // walkers are kept off walls by their own step.
  for (auto [a, b, ga] : {std::tuple{t1, t2, o1}, std::tuple{t2, t1, o2}}) {
    if (b->kind == GeomKind::kStatic && (a->kind != GeomKind::kVehicle || KinematicGeom(ga))) return;
  }
  dContactGeom c[kMaxContacts];
  const int n = dCollide(o1, o2, kMaxContacts, c, sizeof(dContactGeom));
  for (int i = 0; i < n; ++i) {
    ContactRecord r;
    r.ta = t1;
    r.tb = t2;
    r.a = t1->actor;
    r.b = t2->actor;
    r.geom = c[i];
    impl->contact_buffer.push_back(r);
  }
}

double ReducedMass(dBodyID a, dBodyID b) {
  auto mass = [](dBodyID x) {
    if (!x) return 1e12;
    dMass m;
    dBodyGetMass(x, &m);
    return m.mass;
  };
  const double ma = mass(a), mb = mass(b);
  return ma * mb / (ma + mb);
}
}  // namespace

void World::Impl::Collide(bool) {
  contact_buffer.clear();
  CollideContext ctx{this};
  dSpaceCollide(actor_space, &ctx, &NearCallback);
  // Against the town only vehicles with physics: kinematic ones follow lanes, walkers are
  // kept off walls by their own step (one query per dynamic vehicle, not per actor).
  for (auto& [id, v] : vehicles) {
    if (!v->kinematic && v->simulate_physics) dSpaceCollide2(v->geom, reinterpret_cast<dGeomID>(static_space), &ctx, &NearCallback);
  }
  // Deterministic order whatever the spaces' internal lists look like (a restored world
  // builds them in another order): the solver's result depends on the joint order.
  std::sort(contact_buffer.begin(), contact_buffer.end(), [](const ContactRecord& x, const ContactRecord& y) {
    const auto kx = std::make_tuple(x.a, x.b, x.ta->semantic, x.tb->semantic, x.geom.pos[0], x.geom.pos[1], x.geom.pos[2], x.geom.depth);
    const auto ky = std::make_tuple(y.a, y.b, y.ta->semantic, y.tb->semantic, y.geom.pos[0], y.geom.pos[1], y.geom.pos[2], y.geom.depth);
    return kx < ky;
  });
}

void World::Impl::RecordCollision(uint32_t actor, uint32_t other, ObjectKind kind, uint8_t tag, const Vec3& impulse) {
  auto key = std::make_pair(actor, other == 0 ? 0x80000000u + tag : other);
  auto it = pending_collisions.find(key);
  if (it == pending_collisions.end()) {
    Collision c;
    c.actor = actor;
    c.other_actor = other;
    c.other_kind = kind;
    c.other_semantic_tag = tag;
    c.normal_impulse = impulse;
    pending_collisions.emplace(key, c);
  } else {
    it->second.normal_impulse += impulse;
  }
}

void World::Impl::Substep(double h, bool) {
  Collide(false);
  feedback.assign(contact_buffer.size(), dJointFeedback{});
  for (size_t i = 0; i < contact_buffer.size(); ++i) {
    const ContactRecord& r = contact_buffer[i];
    dBodyID b1 = dGeomGetBody(r.geom.g1), b2 = dGeomGetBody(r.geom.g2);
    const bool dyn1 = b1 && !dBodyIsKinematic(b1), dyn2 = b2 && !dBodyIsKinematic(b2);
    if (dyn1 || dyn2) {
      dContact c{};
      c.surface.mode = dContactBounce | dContactSoftCFM | dContactApprox1;
      c.surface.mu = 0.6;
      c.surface.bounce = 0.1;
      c.surface.bounce_vel = 0.5;
      c.surface.soft_cfm = 1e-5;
      c.geom = r.geom;
      dJointID j = dJointCreateContact(world, contacts, &c);
      dJointAttach(j, b1, b2);
      dJointSetFeedback(j, &feedback[i]);
    }
  }
  for (auto& [id, v] : vehicles) {
    if (!v->kinematic && v->simulate_physics) {
      if (v->use_ackermann) AckermannToControl(v.get(), h);
      UpdateGear(v.get(), h);
      ApplyWheelForces(v.get(), h);
    }
  }
  dRandSetSeed(0);  // the quick-step solver shuffles constraints with ODE's global generator
  dWorldQuickStep(world, h);
  // Events: every pair found, with the impulse the solver applied (or, between two
  // kinematic bodies, the momentum the contact would have to exchange).
  for (size_t i = 0; i < contact_buffer.size(); ++i) {
    const ContactRecord& r = contact_buffer[i];
    dBodyID b1 = dGeomGetBody(r.geom.g1), b2 = dGeomGetBody(r.geom.g2);
    const Vec3 n(r.geom.normal[0], r.geom.normal[1], r.geom.normal[2]);  // points into g1
    Vec3 imp1 = ToVec(feedback[i].f1) * h, imp2 = ToVec(feedback[i].f2) * h;
    if (imp1.isZero() && imp2.isZero()) {
      Vec3 va = b1 ? ToVec(dBodyGetLinearVel(b1)) : Vec3::Zero();
      Vec3 vb = b2 ? ToVec(dBodyGetLinearVel(b2)) : Vec3::Zero();
      const double closing = std::max(0.0, (vb - va).dot(n));
      imp1 = n * (ReducedMass(b1, b2) * closing / kMaxContacts);
      imp2 = -imp1;
    }
    imp1 = n * imp1.dot(n);
    imp2 = n * imp2.dot(n);
    auto actor_kind = [](const GeomTag* t) { return t->object; };
    if (r.ta->kind != GeomKind::kStatic && r.ta->kind != GeomKind::kExternal)
      RecordCollision(r.a, r.b, actor_kind(r.tb), r.tb->semantic, imp1);
    if (r.tb->kind != GeomKind::kStatic && r.tb->kind != GeomKind::kExternal)
      RecordCollision(r.b, r.a, actor_kind(r.ta), r.ta->semantic, imp2);
  }
  dJointGroupEmpty(contacts);
}

void World::Impl::FinishEvents() {
  collisions.clear();
  std::set<std::pair<uint32_t, uint32_t>> touching;
  for (auto& [key, c] : pending_collisions) {
    collisions.push_back(c);
    touching.insert(key);
    // The event every step in contact (like CARLA's collision sensor); the infraction
    // once per contact (not while the car keeps touching the same object).
    if (last_contacts.count(key)) continue;
    if (auto* v = FindVehicle(c.actor)) {
      switch (c.other_kind) {
        case ObjectKind::kVehicle: ++v->infractions.vehicle_collisions; break;
        case ObjectKind::kWalker: ++v->infractions.walker_collisions; break;
        default: ++v->infractions.static_collisions; break;
      }
    }
  }
  pending_collisions.clear();
  last_contacts = std::move(touching);
}

// Speed limit, footprint measures and lane invasions after the step.
void World::Impl::UpdateMeasurements(double dt) {
  invasions.clear();
  const map::Map& m = town->Map();
  for (auto& [id, vp] : vehicles) {
    VehicleActor& v = *vp;
    const Pose p = BodyPose(v.body);
    const Vec3 vel = ToVec(dBodyGetLinearVel(v.body));
    v.acceleration = dt > 0 ? Vec3((vel - v.prev_velocity) / dt) : Vec3::Zero();
    v.prev_velocity = vel;
    const double yaw = p.Yaw();
    const Vec3 h = v.spec->half_extents;
    const map::Footprint fp = map::MakeFootprint(p.position.head<2>(), yaw, h.x(), h.y());
    // Traffic-Manager cars follow lane centres: their measures come from the TM's lane;
    // every other vehicle is measured against the map (the costly part).
    if (!v.autopilot || v.hero()) {
      if (v.has_footprint) {
        auto crossed = map::CrossedLaneMarkings(m, v.footprint, fp);
        if (!crossed.empty()) {
          LaneInvasion inv;
          inv.actor = v.id;
          for (const auto& c : crossed) inv.crossed.push_back(c.marking);
          invasions.push_back(std::move(inv));
          ++v.infractions.lane_invasions;
        }
      }
      const auto overlap = map::ComputeFootprintOverlap(m, fp, yaw, 4);
      if (overlap.opposite_lane > kOppositeLaneThreshold && !(v.opposite_lane > kOppositeLaneThreshold))
        ++v.infractions.opposite_lane;
      if (overlap.offroad > kOffroadThreshold && !(v.offroad > kOffroadThreshold)) ++v.infractions.offroad;
      v.opposite_lane = overlap.opposite_lane;
      v.sidewalk = overlap.sidewalk;
      v.offroad = overlap.offroad;
      // The last speed sign passed on the lane it drives (CARLA's sticky vehicle limit).
      if (auto wp = m.NearestWaypoint(p.position); wp) {
        if (std::abs(Wrap(wp->transform.yaw - yaw)) > M_PI / 2) {
          if (auto other = m.LeftLane(*wp); other && std::abs(Wrap(other->transform.yaw - yaw)) < M_PI / 2) wp = other;
        }
        if (const double sign = town->SignSpeedLimit(*wp); std::isfinite(sign)) v.speed_limit = sign;
      }
    }
    if (v.has_footprint) v.infractions.distance += ((fp[0] + fp[2]) - (v.footprint[0] + v.footprint[2])).norm() / 2;
    v.footprint = fp;
    v.has_footprint = true;
  }
}

// ---- World ----

World::World(std::shared_ptr<const Town> town, uint64_t seed, PhysicsSettings settings)
    : impl_(std::make_unique<Impl>(std::move(town), seed, settings)) {}
World::~World() = default;

const Town& World::town() const { return *impl_->town; }
uint64_t World::seed() const { return impl_->seed; }
uint64_t World::frame() const { return impl_->frame; }
void World::SetPhysicsSettings(const PhysicsSettings& s) { impl_->settings = s; }
const TmGlobal& World::TrafficManager() const { return impl_->tm; }

bool SpawnOverlaps(const Pose& pose, const Vec3& half, const Pose& q, const Vec3& qh) {
  // Separating axes of two yawed rectangles, with a 0.2 m margin; z overlap within 2 m.
  if (std::abs(q.position.z() - pose.position.z()) > 2.0 + qh.z() + half.z()) return false;
  const double yaw = pose.Yaw(), qy = q.Yaw();
  const Eigen::Vector2d d = q.position.head<2>() - pose.position.head<2>();
  const Eigen::Vector2d axes[4] = {{std::cos(yaw), std::sin(yaw)}, {-std::sin(yaw), std::cos(yaw)},
                                   {std::cos(qy), std::sin(qy)}, {-std::sin(qy), std::cos(qy)}};
  const Eigen::Vector2d a0 = axes[0], a1 = axes[1], b0 = axes[2], b1 = axes[3];
  for (const auto& ax : axes) {
    const double ra = std::abs(a0.dot(ax)) * half.x() + std::abs(a1.dot(ax)) * half.y() + 0.2;
    const double rb = std::abs(b0.dot(ax)) * qh.x() + std::abs(b1.dot(ax)) * qh.y();
    if (std::abs(d.dot(ax)) > ra + rb) return false;
  }
  return true;
}

std::string World::CheckFree(const Pose& pose, const Vec3& half) const {
  for (const auto& [id, v] : impl_->vehicles) {
    if (SpawnOverlaps(pose, half, BodyPose(v->body), v->spec->half_extents)) return "spawn point occupied by vehicle " + std::to_string(id);
  }
  for (const auto& [id, w] : impl_->walkers) {
    if (SpawnOverlaps(pose, half, BodyPose(w->body), Vec3(w->spec->radius, w->spec->radius, w->spec->height / 2)))
      return "spawn point occupied by walker " + std::to_string(id);
  }
  return {};
}

std::string World::AddVehicle(uint32_t id, const std::string& blueprint, const std::map<std::string, std::string>& attributes,
                              const Pose& pose) {
  if (Has(id)) return "actor " + std::to_string(id) + " exists already";
  const VehicleSpec* spec = FindVehicle(blueprint);
  if (!spec) return "unknown vehicle blueprint '" + blueprint + "'";
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) return "spawn pose is not finite";
  auto v = std::make_unique<VehicleActor>();
  try {
    v->attributes = ParseSpawnAttributes(attributes);
  } catch (const std::exception& e) {
    return e.what();
  }
  v->id = id;
  v->blueprint = blueprint;
  v->spec = spec;
  v->physics = spec->physics;
  v->tm.rng.s = MixSeed(impl_->seed, id);
  impl_->CreateVehicleBody(v.get(), pose);
  impl_->vehicles.emplace(id, std::move(v));
  return {};
}

std::string World::AddWalker(uint32_t id, const std::string& blueprint, const std::map<std::string, std::string>& attributes,
                             const Pose& pose) {
  if (Has(id)) return "actor " + std::to_string(id) + " exists already";
  const WalkerSpec* spec = FindWalker(blueprint);
  if (!spec) return "unknown walker blueprint '" + blueprint + "'";
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) return "spawn pose is not finite";
  auto w = std::make_unique<WalkerActor>();
  try {
    w->attributes = ParseSpawnAttributes(attributes);
  } catch (const std::exception& e) {
    return e.what();
  }
  w->id = id;
  w->blueprint = blueprint;
  w->spec = spec;
  impl_->CreateWalkerBody(w.get(), pose);
  impl_->walkers.emplace(id, std::move(w));
  return {};
}

std::string World::AddWalkerController(uint32_t id, uint32_t walker) {
  if (Has(id)) return "actor " + std::to_string(id) + " exists already";
  WalkerActor* w = impl_->FindWalker(walker);
  if (!w) return "controller.ai.walker needs a walker parent; actor " + std::to_string(walker) + " is not a walker here";
  if (w->controller) return "walker " + std::to_string(walker) + " has controller " + std::to_string(w->controller) + " already";
  ControllerActor c;
  c.id = id;
  c.walker = walker;
  c.max_speed = w->attributes.walker_speed > 0 ? w->attributes.walker_speed : w->spec->walk_speed;
  c.rng.s = impl_->ControllerSeed(id);
  w->controller = id;
  impl_->controllers.emplace(id, std::move(c));
  return {};
}

std::string World::AddProp(uint32_t id, const Pose& pose, const Vec3& half_extents) {
  auto& I = *impl_;
  if (id == 0) return "prop: actor id 0";
  if (Has(id) || I.props.count(id)) return "actor " + std::to_string(id) + " already exists";
  if (!half_extents.allFinite() || (half_extents.array() <= 0).any())
    return "prop " + std::to_string(id) + ": bounding box half extents must be finite and > 0";
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite() || pose.orientation.norm() < 1e-9)
    return "prop " + std::to_string(id) + ": pose must be finite";
  auto p = std::make_unique<PropActor>();
  p->id = id;
  p->pose = pose;
  p->half_extents = half_extents;
  p->tag = GeomTag{GeomKind::kStatic, id, map::semantic::kStatic, ObjectKind::kStatic};
  p->geom = dCreateBox(I.static_space, 2 * half_extents.x(), 2 * half_extents.y(), 2 * half_extents.z());
  dGeomSetPosition(p->geom, pose.position.x(), pose.position.y(), pose.position.z());
  const Quat q = pose.orientation.normalized();
  const dQuaternion dq = {q.w(), q.x(), q.y(), q.z()};
  dGeomSetQuaternion(p->geom, dq);
  dGeomSetData(p->geom, &p->tag);
  I.props.emplace(id, std::move(p));
  return {};
}

bool World::IsProp(uint32_t id) const { return impl_->props.count(id) > 0; }

bool World::Remove(uint32_t id) {
  auto& I = *impl_;
  if (auto it = I.props.find(id); it != I.props.end()) {
    dGeomDestroy(it->second->geom);
    I.props.erase(it);
    return true;
  }
  if (auto it = I.vehicles.find(id); it != I.vehicles.end()) {
    I.DestroyBody(it->second->body, it->second->geom);
    I.vehicles.erase(it);
    return true;
  }
  if (auto it = I.walkers.find(id); it != I.walkers.end()) {
    if (it->second->controller) I.controllers.erase(it->second->controller);
    I.DestroyBody(it->second->body, it->second->geom);
    I.walkers.erase(it);
    return true;
  }
  if (auto it = I.controllers.find(id); it != I.controllers.end()) {
    if (auto* w = I.FindWalker(it->second.walker)) w->controller = 0;
    I.controllers.erase(it);
    return true;
  }
  return false;
}

bool World::Has(uint32_t id) const { return IsVehicle(id) || IsWalker(id) || IsController(id); }
bool World::IsVehicle(uint32_t id) const { return impl_->vehicles.count(id) > 0; }
bool World::IsWalker(uint32_t id) const { return impl_->walkers.count(id) > 0; }
bool World::IsController(uint32_t id) const { return impl_->controllers.count(id) > 0; }

namespace {
std::string NotA(uint32_t id, const char* what) { return "actor " + std::to_string(id) + " is not a " + what + " of ground_sim"; }
}  // namespace

std::string World::SetTransform(uint32_t id, const Pose& pose) {
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) return "transform is not finite";
  if (auto* v = impl_->FindVehicle(id)) {
    SetBodyPose(v->body, pose);
    dBodySetLinearVel(v->body, 0, 0, 0);
    dBodySetAngularVel(v->body, 0, 0, 0);
    v->has_footprint = false;  // a teleport crosses no marking
    v->tm.path.clear();
    v->tm.speed = 0;
    v->tm.committed_junction = -1;
    return {};
  }
  if (auto* w = impl_->FindWalker(id)) {
    SetBodyPose(w->body, Pose::FromYaw(pose.position, pose.Yaw()));
    return {};
  }
  return NotA(id, "vehicle or walker");
}

std::string World::ApplyControl(uint32_t id, const VehicleControl& c) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  if (!(c.throttle >= 0 && c.throttle <= 1 && c.brake >= 0 && c.brake <= 1 && c.steer >= -1 && c.steer <= 1))
    return "vehicle control out of range (throttle, brake in 0..1, steer in -1..1)";
  if (v->autopilot) return "vehicle " + std::to_string(id) + " is on autopilot: the Traffic Manager drives it";
  v->control = c;
  v->use_ackermann = false;
  return {};
}

std::string World::ApplyAckermann(uint32_t id, const AckermannControl& c) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  if (!std::isfinite(c.steer) || !std::isfinite(c.speed) || !std::isfinite(c.acceleration) || c.acceleration < 0 ||
      c.steer_speed < 0)
    return "ackermann control needs finite steer and speed, acceleration >= 0 and steer_speed >= 0";
  if (v->autopilot) return "vehicle " + std::to_string(id) + " is on autopilot: the Traffic Manager drives it";
  v->ackermann = c;
  v->use_ackermann = true;
  return {};
}

std::string World::ApplyWalkerControl(uint32_t id, const WalkerControl& c) {
  auto* w = impl_->FindWalker(id);
  if (!w) return NotA(id, "walker");
  if (!c.direction.allFinite() || !(c.speed >= 0 && c.speed <= 10)) return "walker control needs a finite direction and speed in 0..10 m/s";
  if (w->controller && impl_->controllers.at(w->controller).running)
    return "walker " + std::to_string(id) + " is driven by AI controller " + std::to_string(w->controller);
  w->control = c;
  return {};
}

std::string World::SetTargetVelocity(uint32_t id, const Vec3& vel) {
  if (!vel.allFinite()) return "target velocity is not finite";
  if (auto* v = impl_->FindVehicle(id)) {
    dBodySetLinearVel(v->body, vel.x(), vel.y(), vel.z());
    v->tm.speed = vel.norm();
    return {};
  }
  if (auto* w = impl_->FindWalker(id)) {
    const double s = vel.head<2>().norm();
    w->control.speed = s;
    if (s > 0) w->control.direction = Vec3(vel.x() / s, vel.y() / s, 0);
    return {};
  }
  return NotA(id, "vehicle or walker");
}

std::string World::SetTargetAngularVelocity(uint32_t id, const Vec3& w) {
  if (!w.allFinite()) return "target angular velocity is not finite";
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  dBodySetAngularVel(v->body, w.x(), w.y(), w.z());
  return {};
}

std::string World::AddImpulse(uint32_t id, const Vec3& impulse) {
  if (!impulse.allFinite()) return "impulse is not finite";
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  if (v->kinematic || !v->simulate_physics) return "vehicle " + std::to_string(id) + " does not simulate physics now";
  dMass m;
  dBodyGetMass(v->body, &m);
  const Vec3 vel = ToVec(dBodyGetLinearVel(v->body)) + impulse / m.mass;
  dBodySetLinearVel(v->body, vel.x(), vel.y(), vel.z());
  return {};
}

std::string World::SetSimulatePhysics(uint32_t id, bool on) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  v->simulate_physics = on;
  if (on) {
    dBodySetDynamic(v->body);
  } else {
    dBodySetKinematic(v->body);
    dBodySetLinearVel(v->body, 0, 0, 0);
    dBodySetAngularVel(v->body, 0, 0, 0);
  }
  return {};
}

std::string World::SetVehiclePhysics(uint32_t id, const VehiclePhysics& p) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  if (!(p.mass > 0 && p.wheel_radius > 0.05 && p.max_rpm > 100 && p.wheelbase > 0.3 && p.track > 0.1 && p.tire_friction > 0 &&
        p.max_steer_angle > 0 && p.max_steer_angle < 1.5 && p.final_ratio > 0 && !p.forward_gears.empty() &&
        !p.torque_curve.empty() && p.suspension_stiffness > 0 && p.suspension_damping >= 0 && p.max_brake_torque >= 0))
    return "physics control rejected: mass, wheel radius, max rpm, wheelbase, track, friction, final ratio, stiffness "
           "must be > 0, max steer angle in (0, 1.5) rad, gears and torque curve non-empty";
  v->physics = p;
  dMass m;
  const Vec3 h = v->spec->half_extents;
  dMassSetBoxTotal(&m, p.mass, 2 * h.x(), 2 * h.y(), 2 * h.z());
  dBodySetMass(v->body, &m);
  return {};
}

std::optional<VehiclePhysics> World::GetVehiclePhysics(uint32_t id) const {
  auto it = impl_->vehicles.find(id);
  if (it == impl_->vehicles.end()) return std::nullopt;
  return it->second->physics;
}

std::string World::SetLightState(uint32_t id, uint32_t bits) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return NotA(id, "vehicle");
  v->light_state = bits;
  return {};
}

void World::SetExternalBodies(std::vector<ExternalBody> bodies) {
  auto& I = *impl_;
  for (auto& e : I.externals) I.DestroyBody(e->ode_body, e->geom);
  I.externals.clear();
  for (auto& b : bodies) {
    auto e = std::make_unique<ExternalActor>();
    e->body = b;
    e->tag = GeomTag{GeomKind::kExternal, b.id, 0, b.kind};
    e->ode_body = dBodyCreate(I.world);
    dMass m;
    dMassSetBoxTotal(&m, std::max(0.01, b.mass), 2 * b.half_extents.x(), 2 * b.half_extents.y(), 2 * b.half_extents.z());
    dBodySetMass(e->ode_body, &m);
    SetBodyPose(e->ode_body, b.pose);
    // A dynamic body of its own mass (not kinematic: an infinite mass would press a car's
    // suspension down under a drone resting on its roof); its motion here is dropped, the
    // owner simulates it. It meets vehicles and walkers only, never the town.
    dBodySetLinearVel(e->ode_body, b.velocity.x(), b.velocity.y(), b.velocity.z());
    e->geom = dCreateBox(I.actor_space, 2 * b.half_extents.x(), 2 * b.half_extents.y(), 2 * b.half_extents.z());
    dGeomSetBody(e->geom, e->ode_body);
    dGeomSetData(e->geom, &e->tag);
    I.externals.push_back(std::move(e));
  }
}

void World::Step(double dt) {
  auto& I = *impl_;
  dAllocateODEDataForThread(dAllocateMaskAll);
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("ground step: dt must be > 0");
  ++I.frame;
  I.StepLights(dt);
  I.StepControllers(dt);
  I.StepTrafficManager(dt);  // sets the kinematic vehicles' motion and the TM cars' controls
  I.StepVehicleLights();
  I.StepWalkers(dt);
  bool any_dynamic = false;
  for (auto& [id, v] : I.vehicles) any_dynamic |= !v->kinematic && v->simulate_physics;
  int n = 1;
  if (any_dynamic && I.settings.substepping) {
    n = static_cast<int>(std::ceil(dt / I.settings.max_substep_delta_time - 1e-9));
    n = std::clamp(n, 1, std::max(1, I.settings.max_substeps));
  }
  const double h = dt / n;
  for (int i = 0; i < n; ++i) I.Substep(h, i == n - 1);
  // Kinematic vehicles end exactly on their lane (no integration drift).
  for (auto& [id, v] : I.vehicles) {
    if (v->kinematic && v->autopilot) I.AnchorPath(v.get());
  }
  I.FinishEvents();
  I.UpdateMeasurements(dt);
}

const std::vector<Collision>& World::Collisions() const { return impl_->collisions; }
const std::vector<LaneInvasion>& World::LaneInvasions() const { return impl_->invasions; }

namespace {
VehicleView View(const World::Impl& I, const VehicleActor& v) {
  VehicleView o;
  o.id = v.id;
  o.blueprint = v.blueprint;
  o.role_name = v.attributes.role_name;
  o.pose = BodyPose(v.body);
  o.half_extents = v.spec->half_extents;
  o.velocity = ToVec(dBodyGetLinearVel(v.body));
  o.angular_velocity = ToVec(dBodyGetAngularVel(v.body));
  o.acceleration = v.acceleration;
  o.control = v.control;
  o.autopilot = v.autopilot;
  o.kinematic = v.kinematic || !v.simulate_physics;
  o.speed_limit = v.speed_limit;
  o.traffic_light = v.tm.light >= 0 ? static_cast<uint32_t>(v.tm.light + 1) : 0;
  o.stop_line_distance = v.tm.light >= 0 ? v.tm.light_distance : -1;
  o.opposite_lane = v.opposite_lane;
  o.sidewalk = v.sidewalk;
  o.offroad = v.offroad;
  o.light_state = v.light_state;
  o.gear = v.gear;
  o.infractions = v.infractions;
  (void)I;
  return o;
}
WalkerView View(const WalkerActor& w, bool ai) {
  WalkerView o;
  o.id = w.id;
  o.blueprint = w.blueprint;
  o.pose = BodyPose(w.body);
  o.half_extents = Vec3(w.spec->radius, w.spec->radius, w.spec->height / 2);
  o.velocity = w.velocity;
  o.ai_controlled = ai;
  o.control = w.control;
  return o;
}
}  // namespace

std::vector<VehicleView> World::Vehicles() const {
  std::vector<VehicleView> out;
  out.reserve(impl_->vehicles.size());
  for (const auto& [id, v] : impl_->vehicles) out.push_back(View(*impl_, *v));
  return out;
}
std::optional<VehicleView> World::Vehicle(uint32_t id) const {
  auto it = impl_->vehicles.find(id);
  if (it == impl_->vehicles.end()) return std::nullopt;
  return View(*impl_, *it->second);
}
std::vector<WalkerView> World::Walkers() const {
  std::vector<WalkerView> out;
  for (const auto& [id, w] : impl_->walkers) {
    const bool ai = w->controller && impl_->controllers.at(w->controller).running;
    out.push_back(View(*w, ai));
  }
  return out;
}
std::optional<WalkerView> World::Walker(uint32_t id) const {
  auto it = impl_->walkers.find(id);
  if (it == impl_->walkers.end()) return std::nullopt;
  const bool ai = it->second->controller && impl_->controllers.at(it->second->controller).running;
  return View(*it->second, ai);
}
std::vector<LightView> World::Lights() const {
  std::vector<LightView> out;
  const auto& tl = impl_->town->Lights();
  for (size_t i = 0; i < impl_->lights.size(); ++i) {
    LightView l;
    l.id = static_cast<uint32_t>(i + 1);
    l.pose = tl[i].info.pose;
    l.state = impl_->lights[i];
    l.opendrive_id = tl[i].info.signal_id;
    out.push_back(l);
  }
  return out;
}

}  // namespace lockstep::ground
