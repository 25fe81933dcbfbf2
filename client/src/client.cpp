#include "lockstep/client/client.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cxxabi.h>
#include <cstdlib>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <thread>
#include <tuple>

#include "lockstep/map/map.h"
#include "lockstep/runtime/actor_list.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/hash.h"
#include "lockstep/client/sample_pool.h"

namespace lockstep::client {

namespace {

using Clock = std::chrono::steady_clock;
using RunFrame = std::pair<uint32_t, uint64_t>;

// a * b of two poses (b given in a's frame).
msg::Quaternion QMul(const msg::Quaternion& a, const msg::Quaternion& b) {
  msg::Quaternion q;
  q.w(a.w() * b.w() - a.x() * b.x() - a.y() * b.y() - a.z() * b.z());
  q.x(a.w() * b.x() + a.x() * b.w() + a.y() * b.z() - a.z() * b.y());
  q.y(a.w() * b.y() - a.x() * b.z() + a.y() * b.w() + a.z() * b.x());
  q.z(a.w() * b.z() + a.x() * b.y() - a.y() * b.x() + a.z() * b.w());
  return q;
}
msg::Vector3 QRotate(const msg::Quaternion& q, double x, double y, double z) {
  msg::Quaternion v;
  v.w(0), v.x(x), v.y(y), v.z(z);
  msg::Quaternion c;
  c.w(q.w()), c.x(-q.x()), c.y(-q.y()), c.z(-q.z());
  const msg::Quaternion r = QMul(QMul(q, v), c);
  msg::Vector3 out;
  out.x(r.x()), out.y(r.y()), out.z(r.z());
  return out;
}
msg::Pose Compose(const msg::Pose& a, const msg::Pose& b) {
  const msg::Vector3 p = QRotate(a.orientation(), b.position().x(), b.position().y(), b.position().z());
  msg::Pose out;
  msg::Vector3 pos;
  pos.x(a.position().x() + p.x()), pos.y(a.position().y() + p.y()), pos.z(a.position().z() + p.z());
  out.position(pos);
  out.orientation(QMul(a.orientation(), b.orientation()));
  return out;
}

Clock::time_point Deadline(double seconds) {
  if (seconds < 0) return Clock::time_point::max();
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string HostName() {
  char buf[256] = {0};
  gethostname(buf, sizeof(buf) - 1);
  return buf;
}

std::string DefaultName() {
  static std::atomic<int> counter{0};
  return "client-" + HostName() + "-" + std::to_string(getpid()) + "-" + std::to_string(++counter);
}

msg::ActorKind KindOfBlueprint(const std::string& id, const BlueprintLibrary& library) {
  if (auto d = library.Find(id)) return d->kind();
  auto starts = [&](const char* p) { return id.rfind(p, 0) == 0; };
  if (starts("vehicle.")) return msg::ActorKind::ACTOR_VEHICLE;
  if (starts("walker.")) return msg::ActorKind::ACTOR_WALKER;
  if (starts("drone.")) return msg::ActorKind::ACTOR_DRONE;
  if (starts("sensor.")) return msg::ActorKind::ACTOR_SENSOR;
  if (starts("traffic.traffic_light")) return msg::ActorKind::ACTOR_TRAFFIC_LIGHT;
  if (starts("traffic.")) return msg::ActorKind::ACTOR_TRAFFIC_SIGN;
  if (starts("controller.")) return msg::ActorKind::ACTOR_CONTROLLER;
  if (starts("static.")) return msg::ActorKind::ACTOR_PROP;
  return msg::ActorKind::ACTOR_OTHER;
}

bool Terminal(msg::DroneCommandStatus s) {
  return s == msg::DroneCommandStatus::DRONE_CMD_COMPLETED || s == msg::DroneCommandStatus::DRONE_CMD_TIMED_OUT ||
         s == msg::DroneCommandStatus::DRONE_CMD_CANCELLED || s == msg::DroneCommandStatus::DRONE_CMD_REJECTED;
}

const char* ActorPhysicsName(msg::ActorPhysicsKind k) {
  switch (k) {
    case msg::ActorPhysicsKind::PHYSICS_SET_TARGET_VELOCITY: return "set_target_velocity";
    case msg::ActorPhysicsKind::PHYSICS_SET_TARGET_ANGULAR_VELOCITY: return "set_target_angular_velocity";
    case msg::ActorPhysicsKind::PHYSICS_ADD_IMPULSE: return "add_impulse";
    case msg::ActorPhysicsKind::PHYSICS_SET_SIMULATE_PHYSICS: return "set_simulate_physics";
    case msg::ActorPhysicsKind::PHYSICS_SET_LIGHT_STATE: return "set_light_state";
  }
  return "actor physics command";
}

const char* WalkerAIName(msg::WalkerAIKind k) {
  switch (k) {
    case msg::WalkerAIKind::WALKER_AI_START: return "WalkerAIController.start";
    case msg::WalkerAIKind::WALKER_AI_STOP: return "WalkerAIController.stop";
    case msg::WalkerAIKind::WALKER_AI_GO_TO_LOCATION: return "WalkerAIController.go_to_location";
    case msg::WalkerAIKind::WALKER_AI_SET_MAX_SPEED: return "WalkerAIController.set_max_speed";
  }
  return "walker AI controller command";
}

std::string Fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%g", v);
  return b;
}

// What every client of this process learned from spawn replies and ticks, so a client
// created later (an airsim client after a carla one spawned the drones) knows the
// attributes (role_name) of actors spawned before it joined even before the
// coordinator's actor list (lockstep/actors) reaches it.
struct SharedActors {
  std::mutex mu;
  std::map<std::pair<int, uint32_t>, std::map<uint32_t, ActorInfo>> by_run;  // (domain, run) -> actors
};
SharedActors& Shared() {
  static SharedActors s;
  return s;
}

}  // namespace

int DefaultDomain() {
  const char* env = std::getenv("LOCKSTEP_DOMAIN");
  if (env == nullptr || *env == '\0') return 0;
  char* end = nullptr;
  const long d = std::strtol(env, &end, 10);
  if (*end != '\0' || d < 0 || d > 232) {
    throw ClientError(std::string("LOCKSTEP_DOMAIN='") + env + "' is not a DDS domain id (0..232)");
  }
  return static_cast<int>(d);
}

struct Client::Impl {
  ClientOptions options;
  std::unique_ptr<Bus> owned_bus;  // a DDS participant of our own, unless options.bus was given
  Bus* bus = nullptr;

  mutable std::mutex mu;
  // Every change notifies `cv`. The waits of a tick (reply, FrameDone, frame state,
  // sensor deliveries) use `frame_cv`, which only those changes notify: the run status
  // and tick messages of every frame do not wake a tick() twice more on a busy machine.
  mutable std::condition_variable cv;
  mutable std::condition_variable frame_cv;
  std::condition_variable inbox_cv;  // the dispatch thread's: sensor samples arrived

  std::optional<msg::WorldInfo> world;
  std::optional<msg::RunStatus> status;
  std::optional<msg::MapData> map_data;
  RunFrame done{0, 0};  // latest FrameDone
  double done_sim_time = 0;
  std::map<uint64_t, msg::CommandReply> replies;
  std::map<std::string, std::vector<msg::BlueprintDeclaration>> declarations;
  std::map<uint32_t, ActorInfo> actors;  // current run
  uint32_t actors_run = 0;
  std::map<uint64_t, msg::SpawnActor> pending_spawns;  // our spawn requests by sequence number
  std::set<std::pair<uint32_t, uint32_t>> removed;     // (run, actor) destroyed: a late actor list must not revive it
  uint32_t listed_run = 0;                              // run of the latest lockstep/actors list
  uint64_t listed_frame = 0;                            // its frame
  std::set<uint32_t> listed;                            // its actors
  std::map<RunFrame, std::shared_ptr<const msg::GroundState>> ground;
  std::map<RunFrame, std::shared_ptr<const msg::AirState>> air;
  std::map<std::pair<uint32_t, uint64_t>, msg::DroneCommandStatus> drone_finished;  // (actor, command id)
  std::map<uint32_t, std::pair<uint64_t, msg::DroneCommandStatus>> drone_last;     // actor -> (id, status)
  std::map<uint32_t, std::deque<std::string>> drone_failures;  // actor -> air_sim's latest EVENT_COMMAND_FAILED messages
  // Watched commands (SubmitWatched) and the services' failures, by (run, frame, actor).
  struct Watched {
    uint32_t run = 0;
    uint64_t frame = 0;
    uint32_t actor = 0;
    std::string call;
  };
  std::deque<Watched> watched;
  std::map<std::tuple<uint32_t, uint64_t, uint32_t>, std::string> service_failures;
  uint64_t next_seq = 1;
  uint64_t quiet_reply = 0;
  uint64_t pings_upto = 0;   // replies to our connection pings (sequence numbers up to this) are dropped  // tick() waits for this reply and the FrameDone it names: the reply alone need not wake it
  uint64_t next_drone_command = 1;
  uint64_t drone_id_base = 0;

  std::shared_ptr<const map::Map> map_cache;
  uint64_t map_cache_hash = 0;
  std::mutex map_mu;

  // Sensors.
  struct Listener {
    SensorType type;
    SensorCallback callback;
    RunFrame start{0, 0};      // frames after this one are expected
    RunFrame delivered{0, 0};  // last frame delivered
    uint64_t count = 0;
    bool per_frame = true;     // checked by tick()
  };
  std::map<uint32_t, Listener> listeners;
  std::deque<SensorSample> inbox;   // arrival order: per sensor in frame order (one writer each)
  bool dispatching = false;         // a callback is running
  bool stopping = false;            // Shutdown() began: waits end with ClientError
  std::thread dispatcher;
  std::mutex reader_mu;             // creation of the sensor readers
  std::map<SensorType, std::shared_ptr<void>> sensor_readers;
  std::map<uint32_t, std::shared_ptr<void>> image_readers;  // cameras: one topic each
  std::map<uint32_t, std::shared_ptr<void>> large_image_readers;  // ... and their large_image topic
  // Images and point clouds change hands without a copy (sample_pool.h).
  std::shared_ptr<SamplePool<msg::Image>> image_pool = std::make_shared<SamplePool<msg::Image>>(4);
  std::shared_ptr<SamplePool<msg::PointCloud>> cloud_pool = std::make_shared<SamplePool<msg::PointCloud>>(4);

  Writer<msg::Command> commands;
  // Readers last: their callbacks use everything above.
  Reader<msg::WorldInfo> world_reader;
  Reader<msg::RunStatus> status_reader;
  Reader<msg::FrameDone> done_reader;
  Reader<msg::CommandReply> reply_reader;
  Reader<msg::BlueprintSet> blueprint_reader;
  Reader<msg::MapData> map_reader;
  Reader<msg::GroundState> ground_reader;
  Reader<msg::AirState> air_reader;
  Reader<msg::SimEvent> event_reader;
  Reader<msg::ActorList> actors_reader;

  explicit Impl(ClientOptions o) : options(std::move(o)) {
    if (options.domain < 0) options.domain = DefaultDomain();
    if (options.name.empty()) options.name = DefaultName();
    drone_id_base = (Fnv1a64().Add(std::string_view(options.name)).value() & 0xffffffULL) << 32;
    DdsOptions dds;
    dds.domain_id = options.domain;
    dds.participant_name = options.name;
    if (options.bus != nullptr) {
      bus = options.bus;
    } else {
      owned_bus = CreateDdsBus(dds);
      bus = owned_bus.get();
    }
    dispatcher = std::thread([this] { Dispatch(); });
    commands = Writer<msg::Command>(*bus, topics::kCommand);
    world_reader = Reader<msg::WorldInfo>(*bus, topics::kWorldInfo, [this](const msg::WorldInfo& w, const SampleInfo&) {
      Update([&] { world = w; });
    });
    status_reader = Reader<msg::RunStatus>(*bus, topics::kRunStatus, [this](const msg::RunStatus& s, const SampleInfo&) {
      Update([&] { status = s; });
    });
    done_reader = Reader<msg::FrameDone>(*bus, topics::kFrameDone, [this](const msg::FrameDone& d, const SampleInfo&) {
      Update(kFrame, [&] {
        if (RunFrame{d.run(), d.frame()} > done) {
          done = {d.run(), d.frame()};
          done_sim_time = d.sim_time();
        }
      });
    });
    reply_reader = Reader<msg::CommandReply>(*bus, topics::kCommandReply, [this](const msg::CommandReply& r, const SampleInfo&) {
      if (r.client().to_string() != options.name) return;
      bool wake_tick = true;
      {
        std::lock_guard<std::mutex> lock(mu);
        OnReply(r);
        // The tick() waiting for it needs the FrameDone too: that one wakes it (one wake
        // per tick, not two, on the machine the services step on).
        wake_tick = !(r.sequence_number() == quiet_reply && r.accepted() && done < RunFrame{r.run(), r.frame()});
      }
      cv.notify_all();
      if (wake_tick) frame_cv.notify_all();
    });
    blueprint_reader = Reader<msg::BlueprintSet>(*bus, topics::kBlueprints, [this](const msg::BlueprintSet& s, const SampleInfo&) {
      Update([&] { declarations[s.service().to_string()] = s.blueprints(); });
    });
    map_reader = Reader<msg::MapData>(*bus, topics::kMap, [this](const msg::MapData& m, const SampleInfo&) {
      Update([&] { map_data = m; });
    });
    ground_reader = Reader<msg::GroundState>(*bus, topics::kGroundState, [this](const msg::GroundState& g, const SampleInfo&) {
      auto p = std::make_shared<const msg::GroundState>(g);
      Update(kFrame, [&] { OnGround(std::move(p)); });
    });
    air_reader = Reader<msg::AirState>(*bus, topics::kAirState, [this](const msg::AirState& a, const SampleInfo&) {
      auto p = std::make_shared<const msg::AirState>(a);
      Update(kFrame, [&] { OnAir(std::move(p)); });
    });
    actors_reader = Reader<msg::ActorList>(*bus, topics::kActors, [this](const msg::ActorList& l, const SampleInfo&) {
      Update([&] { OnActorList(l); });
    });
    event_reader = Reader<msg::SimEvent>(*bus, topics::kEvent, [this](const msg::SimEvent& e, const SampleInfo&) {
      if (e.kind() != msg::EventKind::EVENT_COMMAND_FAILED) return;
      Update([&] {
        auto& q = drone_failures[e.actor()];
        q.push_back(e.message().to_string());
        while (q.size() > 8) q.pop_front();
        if (watched.empty()) return;
        std::string& f = service_failures[{e.stamp().run(), e.stamp().frame(), e.actor()}];
        f.append(f.empty() ? "" : "; ").append(e.service().to_string()).append(": ").append(e.message().to_string());
        while (service_failures.size() > 1024) service_failures.erase(service_failures.begin());
      });
    });
    try {
      Connect();
    } catch (...) {
      Shutdown();
      throw;
    }
  }

  ~Impl() { Shutdown(); }

  // close(): waits end, the dispatch thread ends. The readers and the writer stay (another
  // thread may be inside a call that uses them) until the destructor.
  void Stop() {
    {
      std::lock_guard<std::mutex> lock(mu);
      stopping = true;
    }
    inbox_cv.notify_all();
    cv.notify_all();        // waits in other threads end (WaitOn checks `stopping`)
    frame_cv.notify_all();
    if (dispatcher.joinable() && dispatcher.get_id() != std::this_thread::get_id()) dispatcher.join();
  }

  void Shutdown() {
    // Readers first, so no callback runs while the rest goes away.
    event_reader = {};
    actors_reader = {};
    air_reader = {};
    ground_reader = {};
    map_reader = {};
    blueprint_reader = {};
    reply_reader = {};
    done_reader = {};
    status_reader = {};
    world_reader = {};
    {
      std::lock_guard<std::mutex> lock(reader_mu);
      sensor_readers.clear();
      image_readers.clear();
      large_image_readers.clear();
    }
    Stop();
    if (commands && commands.MatchedReaders() > 0) commands.WaitForAcknowledgments(0.5);
  }

  enum Wakes { kAny, kFrame };  // kFrame: a change a tick() may wait for
  template <class F>
  void Update(F&& f) {
    Update(kAny, std::forward<F>(f));
  }
  template <class F>
  void Update(Wakes wakes, F&& f) {
    {
      std::lock_guard<std::mutex> lock(mu);
      f();
    }
    cv.notify_all();
    if (wakes == kFrame) frame_cv.notify_all();
  }

  // Waits (mu held by `lock`) until pred or the deadline; false on timeout. `on` is cv,
  // or frame_cv for a predicate over reply, FrameDone, state and delivery changes only.
  template <class P>
  bool WaitUntil(std::unique_lock<std::mutex>& lock, Clock::time_point deadline, P pred) {
    return WaitOn(cv, lock, deadline, pred);
  }
  // A closed client (or one closing) waits no more, and options.interrupted is polled
  // every kInterruptPoll with `mu` released (it may take the Python GIL).
  template <class P>
  bool WaitOn(std::condition_variable& on, std::unique_lock<std::mutex>& lock, Clock::time_point deadline, P pred) {
    auto next_poll = Clock::now() + kInterruptPoll;
    while (!pred()) {
      ThrowIfStopping();
      if (options.interrupted && Clock::now() >= next_poll) {  // also when notifications keep coming
        PollInterrupt(lock);
        next_poll = Clock::now() + kInterruptPoll;
        continue;
      }
      const auto until = options.interrupted ? std::min(deadline, next_poll) : deadline;
      if (until == Clock::time_point::max()) {
        on.wait(lock);
      } else if (on.wait_until(lock, until) == std::cv_status::timeout && until == deadline) {
        return pred();
      }
    }
    return true;
  }
  static constexpr auto kInterruptPoll = std::chrono::milliseconds(100);
  void ThrowIfStopping() const {
    if (stopping) throw ClientError("client " + options.name + " is closed");
  }
  // `lock` holds mu on entry and on return.
  void PollInterrupt(std::unique_lock<std::mutex>& lock) {
    if (!options.interrupted) return;
    lock.unlock();
    const bool stop = options.interrupted();
    lock.lock();
    if (stop) throw Interrupted("interrupted while waiting");
  }

  void Connect() {
    std::unique_lock<std::mutex> lock(mu);
    const auto deadline = Deadline(options.timeout_s);
    if (!WaitUntil(lock, deadline, [&] { return world.has_value(); })) {
      throw ClientError("no Lockstep simulation on DDS domain " + std::to_string(options.domain) + ": no world info within " +
                        Fmt(options.timeout_s) + " s (is `lockstep up` running on this domain? set LOCKSTEP_DOMAIN)");
    }
    // Commands are VOLATILE: wait until the coordinator reads ours and we read its replies.
    lock.unlock();
    while (commands.MatchedReaders() == 0 || reply_reader.MatchedWriters() == 0) {
      if (Clock::now() > deadline) {
        throw ClientError("the coordinator on DDS domain " + std::to_string(options.domain) +
                          " does not read commands (no matched command reader within " + Fmt(options.timeout_s) + " s)");
      }
      lock.lock();
      cv.wait_for(lock, std::chrono::milliseconds(5));
      ThrowIfStopping();
      lock.unlock();
      if (options.interrupted && options.interrupted()) throw Interrupted("interrupted while connecting");
    }
    // The shared, keyed sensor topics are read from now on, not from the first listen():
    // sensor topics are VOLATILE, and a reader made by listen() right before tick() could
    // be matched by the sensors service only after it wrote that frame (lost: the tick then
    // waited sensor_timeout_s and threw SensorLate). Made here, they are discovered with
    // the command writer the ping below proves. Cameras keep one TRANSIENT_LOCAL topic each.
    for (SensorType type : {SensorType::kPointCloud, SensorType::kRadar, SensorType::kImu, SensorType::kGnss,
                            SensorType::kBarometer, SensorType::kMagnetometer, SensorType::kCollision,
                            SensorType::kLaneInvasion, SensorType::kObstacle, SensorType::kDistance, SensorType::kV2X}) {
      EnsureSensorReader(type, 0);
    }
    // Each side discovers the other's endpoints on its own: our reader may see the
    // coordinator's reply writer before that writer sees our reader, and a reply written
    // before then is lost (VOLATILE). A reply proves both directions: ping (CMD_TICK with
    // count 0, answered in any mode, no effect) every 100 ms until one is answered.
    for (bool answered = false; !answered;) {
      msg::CommandBody ping;
      msg::TickRequest none;
      none.count(0);
      ping.tick_request(none);
      const uint64_t seq = Send(std::move(ping));
      lock.lock();
      answered = WaitOn(frame_cv, lock, std::min(deadline, Deadline(0.1)), [&] { return replies.count(seq) > 0; });
      if (answered) {
        pings_upto = seq;
        replies.erase(replies.begin(), replies.upper_bound(seq));
      }
      lock.unlock();
      if (!answered && Clock::now() > deadline) {
        throw ClientError("the coordinator on DDS domain " + std::to_string(options.domain) + " does not answer commands (no reply within " +
                          Fmt(options.timeout_s) + " s)");
      }
    }
    // The latest ground / air state is kept by their writers (TRANSIENT_LOCAL): wait for it,
    // so actors spawned before we joined are known at once (bounded: a stalled run has none).
    lock.lock();
    const auto state_deadline = std::min(deadline, Deadline(options.state_timeout_s));
    WaitUntil(lock, state_deadline, [&] { return status.has_value(); });
    if (status && status->frame() > 0) {
      // The states of the last completed frame (FrameDone is TRANSIENT_LOCAL too): the
      // writers replay several frames, and the newest must be in before we answer.
      const uint32_t run = world->run();
      auto has = [&](const auto& m) { return !m.empty() && m.rbegin()->first >= done; };
      WaitUntil(lock, state_deadline, [&] {
        return done.first == run && done.second > 0 && (!MemberOfKind("air_sim") || has(air)) &&
               (!MemberOfKind("ground_sim") || has(ground)) && listed_run >= run;
      });
    }
  }

  // --- callbacks (mu held) ---
  void OnReply(const msg::CommandReply& r) {
    if (r.sequence_number() <= pings_upto) return;  // a late answer to a connection ping
    replies[r.sequence_number()] = r;
    auto it = pending_spawns.find(r.sequence_number());
    if (it == pending_spawns.end()) return;
    if (r.accepted() && r.actor() != 0) AddActor(r.run(), r.frame(), it->second, r.actor());
    pending_spawns.erase(it);
  }

  void AddActor(uint32_t run, uint64_t frame, const msg::SpawnActor& s, uint32_t id) {
    if (run != actors_run) {
      if (run < actors_run) return;
      actors.clear();
      actors_run = run;
    }
    ActorInfo& a = actors[id];
    a.id = id;
    a.blueprint = s.blueprint().to_string();
    a.kind = KindOfBlueprint(a.blueprint, BlueprintLibrary(declarations));
    a.parent = s.parent();
    if (!s.owner().to_string().empty()) a.owner = s.owner().to_string();
    a.attributes.clear();
    for (const auto& at : s.attributes()) a.attributes.emplace_back(at.key().to_string(), at.value().to_string());
    a.spawn_pose = s.transform();
    a.spawn_frame = frame;
    auto& shared = Shared();
    std::lock_guard<std::mutex> lock(shared.mu);
    shared.by_run[{options.domain, run}][id] = a;
  }

  // Our registry completed with what other clients of this process learned (mu held).
  std::map<uint32_t, ActorInfo> MergedActors() const {
    std::map<uint32_t, ActorInfo> out;
    if (actors_run != world->run()) return out;
    out = actors;
    auto& shared = Shared();
    std::lock_guard<std::mutex> lock(shared.mu);
    auto it = shared.by_run.find({options.domain, actors_run});
    if (it == shared.by_run.end()) return out;
    for (const auto& [id, a] : it->second) {
      auto mine = out.find(id);
      if (mine == out.end()) {
        // Only if our states list it: the shared copy may describe a destroyed actor.
        continue;
      }
      if (mine->second.attributes.empty() && mine->second.blueprint == a.blueprint) mine->second = a;
    }
    return out;
  }

  // Where actor `id` carries what is attached to it, in its newest state of this run (the
  // services' mount: a vehicle's or walker's box bottom, a drone's centre); none without a state.
  std::optional<msg::Pose> LastMount(uint32_t id) const {
    for (auto r = ground.rbegin(); r != ground.rend(); ++r) {
      if (r->first.first != actors_run) continue;
      auto bottom = [](const auto& s) {
        msg::Pose down;
        msg::Vector3 v;
        v.z(-s.half_extents().z());
        down.position(v);
        msg::Quaternion one;
        one.w(1);
        down.orientation(one);
        return Compose(s.transform(), down);
      };
      for (const auto& v : r->second->vehicles()) if (v.actor() == id) return bottom(v);
      for (const auto& w : r->second->walkers()) if (w.actor() == id) return bottom(w);
      break;
    }
    for (auto r = air.rbegin(); r != air.rend(); ++r) {
      if (r->first.first != actors_run) continue;
      for (const auto& d : r->second->drones()) if (d.actor() == id) return d.transform();
      break;
    }
    return std::nullopt;
  }

  // A destroyed actor. What was attached to it stays, detached at its last world pose, as
  // CARLA's (only the actor is destroyed; Unreal detaches its children keeping their world
  // transform). A destroyed sensor delivers no more data: a tick() stops waiting for it.
  void RemoveActor(uint32_t id) {
    const std::optional<msg::Pose> mount = LastMount(id);
    actors.erase(id);
    listeners.erase(id);
    removed.insert({actors_run, id});
    auto& shared = Shared();
    std::lock_guard<std::mutex> lock(shared.mu);
    auto it = shared.by_run.find({options.domain, actors_run});
    if (it != shared.by_run.end()) it->second.erase(id);
    for (auto& [child, a] : actors) {
      if (a.parent != id) continue;
      a.parent = 0;
      if (mount) a.spawn_pose = Compose(*mount, a.spawn_pose);
      if (it != shared.by_run.end() && it->second.count(child)) it->second[child] = a;
    }
  }

  // The coordinator's list of live actors with their spawns: what a client that joined
  // after the spawn knows of its blueprint and attributes.
  // A list is the truth up to its frame: an actor it leaves out that was spawned by then
  // (or seen only in a state, which a late joiner receives several frames of) is gone.
  void OnActorList(const msg::ActorList& l) {
    if (l.run() < listed_run || (l.run() == listed_run && l.frame() < listed_frame)) return;
    if (l.run() < actors_run) return;
    listed_run = l.run();
    listed_frame = l.frame();
    listed.clear();
    for (const auto& a : l.actors()) {
      const uint32_t id = a.spawn().actor();
      listed.insert(id);
      if (removed.count({l.run(), id})) continue;
      auto it = l.run() == actors_run ? actors.find(id) : actors.end();
      // New, or seen in a state only; not one we detached from its destroyed parent.
      const bool detached = it != actors.end() && it->second.parent == 0 && a.spawn().parent() != 0;
      if (it == actors.end() || (it->second.owner.empty() && !detached)) AddActor(l.run(), a.frame(), a.spawn(), id);
    }
    if (l.run() != actors_run) return;
    std::vector<uint32_t> gone;
    for (const auto& [id, a] : actors) {
      if (!listed.count(id) && a.kind != msg::ActorKind::ACTOR_TRAFFIC_LIGHT && a.spawn_frame <= l.frame()) gone.push_back(id);
    }
    for (uint32_t id : gone) RemoveActor(id);
  }

  // Whether a state of (run, frame) may add actor `id` we have not heard of: not if it was
  // destroyed, or the actor list of a later frame leaves it out.
  bool MayAddFromState(uint32_t run, uint64_t frame, uint32_t id) const {
    if (removed.count({run, id})) return false;
    return !(listed_run == run && frame <= listed_frame && !listed.count(id));
  }

  template <class State>
  static void Keep(std::map<RunFrame, std::shared_ptr<const State>>& m, std::shared_ptr<const State> s) {
    m[RunFrame{s->stamp().run(), s->stamp().frame()}] = std::move(s);
    while (m.size() > 8) m.erase(m.begin());
  }

  void OnGround(std::shared_ptr<const msg::GroundState> g) {
    const uint32_t run = g->stamp().run();
    if (run > actors_run) {
      actors.clear();
      actors_run = run;
    }
    if (run == actors_run) {
      auto known = [&](uint32_t id, const std::string& bp, msg::ActorKind kind) {
        if (actors.count(id)) return;
        if (kind != msg::ActorKind::ACTOR_TRAFFIC_LIGHT && !MayAddFromState(run, g->stamp().frame(), id)) return;
        ActorInfo& a = actors[id];
        a.id = id;
        a.blueprint = bp;
        a.kind = kind;
        a.spawn_frame = g->stamp().frame();  // spawned by then
      };
      for (const auto& v : g->vehicles()) known(v.actor(), v.blueprint().to_string(), msg::ActorKind::ACTOR_VEHICLE);
      for (const auto& w : g->walkers()) known(w.actor(), w.blueprint().to_string(), msg::ActorKind::ACTOR_WALKER);
      for (const auto& l : g->traffic_lights()) known(l.actor(), "traffic.traffic_light", msg::ActorKind::ACTOR_TRAFFIC_LIGHT);
    }
    Keep(ground, std::move(g));
  }

  void OnAir(std::shared_ptr<const msg::AirState> a) {
    const uint32_t run = a->stamp().run();
    if (run > actors_run) {
      actors.clear();
      actors_run = run;
    }
    for (const auto& d : a->drones()) {
      if (run == actors_run && !actors.count(d.actor()) && MayAddFromState(run, a->stamp().frame(), d.actor())) {
        ActorInfo& info = actors[d.actor()];
        info.id = d.actor();
        info.blueprint = d.blueprint().to_string();
        info.kind = msg::ActorKind::ACTOR_DRONE;
        info.spawn_frame = a->stamp().frame();  // spawned by then
      }
      // Command completion: the latest status of each command, and a command replaced
      // by a newer one before it finished counts as cancelled.
      auto& last = drone_last[d.actor()];
      if (last.first != 0 && last.first != d.command_id() && !Terminal(last.second)) {
        drone_finished[{d.actor(), last.first}] = msg::DroneCommandStatus::DRONE_CMD_CANCELLED;
      }
      last = {d.command_id(), d.command_status()};
      if (d.command_id() != 0 && Terminal(d.command_status())) drone_finished[{d.actor(), d.command_id()}] = d.command_status();
    }
    while (drone_finished.size() > 4096) drone_finished.erase(drone_finished.begin());
    Keep(air, std::move(a));
  }

  // --- commands ---
  uint64_t Send(msg::CommandBody body) {
    msg::Command c;
    c.client(options.name);
    {
      std::lock_guard<std::mutex> lock(mu);
      c.sequence_number(next_seq++);
      if (body._d() == msg::CommandKind::CMD_SPAWN_ACTOR) pending_spawns[c.sequence_number()] = body.spawn_actor();
    }
    c.body(std::move(body));
    commands.Write(c);
    return c.sequence_number();
  }

  msg::CommandReply WaitReply(uint64_t seq, const char* what) {
    std::unique_lock<std::mutex> lock(mu);
    if (!WaitOn(frame_cv, lock, Deadline(options.timeout_s), [&] { return replies.count(seq) > 0; })) {
      throw ClientError(std::string(what) + ": no reply from the coordinator within " + Fmt(options.timeout_s) + " s");
    }
    msg::CommandReply r = replies.at(seq);
    replies.erase(seq);
    return r;
  }

  // --- sensors ---
  void Dispatch() {
    std::unique_lock<std::mutex> lock(mu);
    while (true) {
      inbox_cv.wait(lock, [&] { return stopping || !inbox.empty(); });
      if (stopping) return;
      SensorSample s = std::move(inbox.front());
      inbox.pop_front();
      auto it = listeners.find(s.sensor);
      const RunFrame rf{s.stamp.run(), s.stamp.frame()};
      if (it == listeners.end() || rf <= it->second.delivered) continue;  // stopped, or a duplicate
      SensorCallback cb = it->second.callback;
      dispatching = true;
      lock.unlock();
      try {
        cb(s);
      } catch (const abi::__forced_unwind&) {
        throw;  // the thread is being ended (pthread_exit): let it end
      } catch (...) {
        // A callback's exception must not kill the dispatcher; the Python layer reports its own.
      }
      lock.lock();
      dispatching = false;
      it = listeners.find(s.sensor);
      if (it != listeners.end()) {
        it->second.delivered = std::max(it->second.delivered, rf);
        ++it->second.count;
      }
      cv.notify_all();
      frame_cv.notify_all();
    }
  }

  void OnSensor(SensorType type, uint32_t sensor, const msg::FrameStamp& stamp, std::shared_ptr<const void> message) {
    {
      std::lock_guard<std::mutex> lock(mu);
      auto it = listeners.find(sensor);
      if (it == listeners.end()) return;
      // Camera topics keep their last images for late readers (TRANSIENT_LOCAL): frames up
      // to the one the listener started after are not expected, so not delivered.
      if (RunFrame{stamp.run(), stamp.frame()} <= it->second.start) return;
      SensorSample s;
      s.type = type;
      s.sensor = sensor;
      s.stamp = stamp;
      s.message = std::move(message);
      inbox.push_back(std::move(s));
    }
    inbox_cv.notify_one();
  }

  // Large payloads: the received sample is taken, not copied.
  template <class T>
  std::shared_ptr<void> MakeTakingReader(SensorType type, const Topic<T>& topic, std::shared_ptr<SamplePool<T>> pool) {
    return std::make_shared<TakingReader<T>>(*bus, topic, [this, type, pool](T& m, const SampleInfo&) {
      std::shared_ptr<const T> taken = pool->Take(m);
      const uint32_t sensor = taken->sensor();
      const msg::FrameStamp stamp = taken->stamp();
      OnSensor(type, sensor, stamp, std::move(taken));
    });
  }

  template <class T>
  void MakeSensorReader(SensorType type, const Topic<T>& topic) {
    auto reader = std::make_shared<Reader<T>>(*bus, topic, [this, type](const T& m, const SampleInfo&) {
      OnSensor(type, m.sensor(), m.stamp(), std::make_shared<const T>(m));
    });
    sensor_readers[type] = reader;
  }

  // A camera's images come on its image topic, or on its large_image topic when they exceed
  // Image's bound (8294400 bytes): a camera of more than 8294400 / 8 pixels (8 bytes per pixel
  // at most, optical flow) or of unknown size (pixels 0) is read on both.
  void EnsureSensorReader(SensorType type, uint32_t sensor, std::size_t pixels = 0) {
    std::lock_guard<std::mutex> lock(reader_mu);
    if (type == SensorType::kImage) {
      if (image_readers.count(sensor)) return;
      const std::string name = topics::ImageTopicName(sensor);
      image_readers[sensor] = MakeTakingReader(SensorType::kImage, Topic<msg::Image>{name.c_str(), QosKind::kImage}, image_pool);
      if (pixels == 0 || pixels * 8 > 8294400) {
        const std::string large = topics::LargeImageTopicName(sensor);
        // Delivered as the msg::Image it would have been (the bound is the wire's, not the type's).
        large_image_readers[sensor] = std::make_shared<TakingReader<msg::LargeImage>>(
            *bus, Topic<msg::LargeImage>{large.c_str(), QosKind::kLargeImage}, [this](msg::LargeImage& m, const SampleInfo&) {
              auto img = std::make_shared<msg::Image>();
              img->sensor(m.sensor());
              img->stamp(m.stamp());
              img->sensor_pose(m.sensor_pose());
              img->width(m.width());
              img->height(m.height());
              img->step(m.step());
              img->encoding(m.encoding());
              img->fov(m.fov());
              img->data().swap(m.data());
              const uint32_t id = img->sensor();
              const msg::FrameStamp stamp = img->stamp();
              OnSensor(SensorType::kImage, id, stamp, std::move(img));
            });
      }
      return;
    }
    if (sensor_readers.count(type)) return;
    switch (type) {
      case SensorType::kImage: break;
      case SensorType::kPointCloud: sensor_readers[type] = MakeTakingReader(type, topics::kPointCloud, cloud_pool); break;
      case SensorType::kRadar: MakeSensorReader(type, topics::kRadar); break;
      case SensorType::kImu: MakeSensorReader(type, topics::kImu); break;
      case SensorType::kGnss: MakeSensorReader(type, topics::kGnss); break;
      case SensorType::kBarometer: MakeSensorReader(type, topics::kBarometer); break;
      case SensorType::kMagnetometer: MakeSensorReader(type, topics::kMagnetometer); break;
      case SensorType::kCollision: MakeSensorReader(type, topics::kCollision); break;
      case SensorType::kLaneInvasion: MakeSensorReader(type, topics::kLaneInvasion); break;
      case SensorType::kObstacle: MakeSensorReader(type, topics::kObstacle); break;
      case SensorType::kDistance: MakeSensorReader(type, topics::kDistance); break;
      case SensorType::kV2X: MakeSensorReader(type, topics::kV2X); break;
    }
  }

  // After frame k of `run` completed: the ground / air state of k (from the services
  // that publish one), then every listened per-frame sensor's data of its frame.
  void AwaitFrameOutputs(uint32_t run, uint64_t k) {
    // A state topic counts when its writer is matched, or (right after connecting, before
    // discovery finished) when a member of the run is the service kind that publishes it.
    // The matched counts are read before taking `mu`: Fast DDS holds a reader's lock while
    // it calls our callback, which takes `mu` (asking under `mu` deadlocked against an
    // AirState arriving at that moment).
    const bool ground_matched = ground_reader.MatchedWriters() > 0;
    const bool air_matched = air_reader.MatchedWriters() > 0;
    std::unique_lock<std::mutex> lock(mu);
    const bool has_ground = ground_matched || MemberOfKind("ground_sim");
    const bool has_air = air_matched || MemberOfKind("air_sim");
    const auto state_deadline = Deadline(options.state_timeout_s);
    WaitOn(frame_cv, lock, state_deadline, [&] {
      return (!has_ground || ground.count({run, k})) && (!has_air || air.count({run, k}));
    });
    const msg::PerceptionMode mode = world ? world->settings().perception_mode() : msg::PerceptionMode::PERCEPTION_STRICT;
    const uint64_t pk = PerceptionFrame(mode, k);
    auto late = [&] {
      std::vector<uint32_t> out;
      for (const auto& [id, l] : listeners) {
        if (!l.per_frame || pk == 0 || l.start.first != run) continue;  // a sensor of an earlier run is gone
        const RunFrame want{run, pk};
        if (want <= l.start) continue;  // spawned or listened after that frame
        if (l.delivered < want) out.push_back(id);
      }
      return out;
    };
    if (!WaitOn(frame_cv, lock, Deadline(options.sensor_timeout_s), [&] { return late().empty(); })) {
      std::vector<uint32_t> ids = late();
      std::string list;
      for (uint32_t id : ids) {
        auto a = actors.find(id);
        list += (list.empty() ? "" : ", ") + std::to_string(id) + (a != actors.end() ? " (" + a->second.blueprint + ")" : "");
      }
      throw SensorLate("tick(): frame " + std::to_string(k) + " is complete but sensor(s) " + list + " delivered no data for frame " +
                           std::to_string(pk) + " within " + Fmt(options.sensor_timeout_s) +
                           " s (is the service that owns them running?)",
                       ids, pk);
    }
  }

  // The first watched command whose failure arrived (mu held); watched commands older
  // than two completed frames without one were applied and are forgotten.
  std::optional<CommandRejected> TakeFailure() {
    for (auto it = watched.begin(); it != watched.end();) {
      auto f = service_failures.find({it->run, it->frame, it->actor});
      if (f != service_failures.end()) {
        CommandRejected e(it->call + " (actor " + std::to_string(it->actor) + ", frame " + std::to_string(it->frame) +
                              ") failed in " + f->second,
                          f->second);
        service_failures.erase(f);
        watched.erase(it);
        return e;
      }
      const bool old = it->run < done.first || (it->run == done.first && done.second >= it->frame + 2);
      it = old ? watched.erase(it) : std::next(it);
    }
    if (watched.empty()) service_failures.clear();
    return std::nullopt;
  }

  bool MemberOfKind(const std::string& kind) const {
    if (!status) return false;
    for (const auto& m : status->members()) {
      if (m.alive() && m.kind().to_string() == kind) return true;
    }
    return false;
  }

  std::string FaultReason() const {
    if (status && (status->state() == msg::RunState::RUN_FAULTED || status->state() == msg::RunState::RUN_STOPPED)) {
      return std::string(" (run ") + RunStateName(status->state()) +
             (status->reason().to_string().empty() ? "" : ": " + status->reason().to_string()) + ")";
    }
    return "";
  }
};

// ---------------------------------------------------------------------------

Client::Client(ClientOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
Client::~Client() = default;

void Client::close() { impl_->Stop(); }

bool Client::closed() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->stopping;
}

int Client::domain() const { return impl_->options.domain; }
const std::string& Client::name() const { return impl_->options.name; }
const ClientOptions& Client::options() const { return impl_->options; }

msg::WorldInfo Client::world_info() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return *impl_->world;
}

bool Client::wait_ready(double timeout_s) {
  std::unique_lock<std::mutex> lock(impl_->mu);
  return impl_->WaitUntil(lock, Deadline(timeout_s), [&] {
    const auto& s = impl_->status;
    return s && s->run() == impl_->world->run() &&
           (s->state() == msg::RunState::RUN_READY || s->state() == msg::RunState::RUN_RUNNING);
  });
}

std::optional<msg::RunStatus> Client::run_status() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->status;
}

uint32_t Client::run() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->world->run();
}

uint64_t Client::frame() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->done.first == impl_->world->run() ? impl_->done.second : 0;
}

msg::WorldSettings Client::settings() const { return world_info().settings(); }

uint64_t Client::apply_settings(const msg::WorldSettings& settings) {
  msg::CommandBody b;
  b.world_settings(settings);
  const msg::CommandReply r = Submit(std::move(b));
  // The coordinator publishes the new WorldInfo before its reply; wait until we have it.
  std::unique_lock<std::mutex> lock(impl_->mu);
  impl_->WaitUntil(lock, Deadline(impl_->options.timeout_s), [&] {
    const auto& s = impl_->world->settings();
    return s.synchronous_mode() == settings.synchronous_mode() && s.fixed_delta_seconds() == settings.fixed_delta_seconds() &&
           s.perception_mode() == settings.perception_mode();
  });
  return r.frame();
}

void Client::set_weather(const msg::WeatherParameters& weather) {
  msg::CommandBody b;
  b.weather(weather);
  Submit(std::move(b));
}

uint64_t Client::tick(double timeout_s) {
  auto& s = *impl_;
  const double frame_timeout = timeout_s < 0 ? s.options.tick_timeout_s : timeout_s;
  msg::CommandBody b;
  msg::TickRequest t;
  t.count(1);
  b.tick_request(t);
  const uint64_t seq = s.Send(std::move(b));
  msg::CommandReply r;
  {
    // One wait for the reply and the FrameDone it names (Impl::quiet_reply).
    std::unique_lock<std::mutex> lock(s.mu);
    s.quiet_reply = seq;
    auto done_for = [&](const msg::CommandReply& x) { return !x.accepted() || s.done >= RunFrame{x.run(), x.frame()}; };
    // The frame's time-out counts from the call, as CARLA's (the reply is part of it).
    const auto frame_deadline = Deadline(frame_timeout);
    const double reply_timeout = std::min(s.options.timeout_s, frame_timeout);
    const bool replied = s.WaitOn(s.frame_cv, lock, std::min(Deadline(s.options.timeout_s), frame_deadline), [&] {
      auto it = s.replies.find(seq);
      return it != s.replies.end() && done_for(it->second);
    }) || s.replies.count(seq) > 0;
    s.quiet_reply = 0;
    if (!replied) throw ClientError(std::string("tick: no reply from the coordinator within ") + Fmt(reply_timeout) + " s");
    r = s.replies.at(seq);
    s.replies.erase(seq);
    if (!r.accepted()) throw CommandRejected("tick rejected: " + r.reason().to_string(), r.reason().to_string());
    if (!s.WaitOn(s.frame_cv, lock, frame_deadline, [&] { return done_for(r); })) {
      throw ClientError("tick(): frame " + std::to_string(r.frame()) + " did not complete within " + Fmt(frame_timeout) +
                        " s" + s.FaultReason());
    }
  }
  s.AwaitFrameOutputs(r.run(), r.frame());
  check_failures();
  return r.frame();
}

uint64_t Client::wait_for_tick(double timeout_s) {
  auto& s = *impl_;
  std::unique_lock<std::mutex> lock(s.mu);
  const RunFrame from = s.done;
  if (!s.WaitUntil(lock, Deadline(timeout_s < 0 ? s.options.tick_timeout_s : timeout_s), [&] { return s.done > from; })) {
    throw ClientError("wait_for_tick(): no new frame after " + std::to_string(from.second) + " within " +
                      Fmt(timeout_s < 0 ? s.options.tick_timeout_s : timeout_s) + " s" + s.FaultReason());
  }
  const uint64_t frame = s.done.second;
  if (auto e = s.TakeFailure()) throw *e;
  return frame;
}

msg::CommandReply Client::SubmitWatched(msg::CommandBody body, const std::string& call) {
  const uint32_t actor = CommandActor(body);
  const uint64_t seq = impl_->Send(std::move(body));
  msg::CommandReply r = impl_->WaitReply(seq, call.c_str());
  if (!r.accepted()) throw CommandRejected(call + " rejected: " + r.reason().to_string(), r.reason().to_string());
  watch(actor, r.run(), r.frame(), call);
  return r;
}

void Client::watch(uint32_t actor, uint32_t run, uint64_t frame, const std::string& call) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->watched.push_back({run, frame, actor, call});
  while (impl_->watched.size() > 4096) impl_->watched.pop_front();
}

void Client::check_failures() {
  std::lock_guard<std::mutex> lock(impl_->mu);
  if (auto e = impl_->TakeFailure()) throw *e;
}

void Client::apply_ackermann_control(const msg::VehicleAckermannControl& control) {
  msg::CommandBody b;
  b.ackermann(control);
  SubmitWatched(std::move(b), "apply_ackermann_control");
}

void Client::apply_actor_physics(const msg::ActorPhysicsCommand& command) {
  msg::CommandBody b;
  b.actor_physics(command);
  SubmitWatched(std::move(b), ActorPhysicsName(command.kind()));
}

void Client::apply_physics_control(uint32_t actor, const msg::VehiclePhysicsControl& physics) {
  msg::VehiclePhysicsCommand c;
  c.actor(actor);
  c.physics(physics);
  msg::CommandBody b;
  b.vehicle_physics(c);
  SubmitWatched(std::move(b), "apply_physics_control");
}

std::optional<msg::VehiclePhysicsControl> Client::physics_control(uint32_t actor) const {
  const Snapshot s = snapshot();
  if (const msg::VehicleState* v = s.Vehicle(actor)) return v->physics();
  return std::nullopt;
}

void Client::walker_ai(const msg::WalkerAICommand& command) {
  msg::CommandBody b;
  b.walker_ai(command);
  SubmitWatched(std::move(b), WalkerAIName(command.kind()));
}

uint32_t Client::reset(uint64_t seed) {
  msg::CommandBody b;
  msg::ResetWorld r;
  r.seed(seed);
  b.reset(r);
  const uint32_t run = Submit(std::move(b)).run();
  std::unique_lock<std::mutex> lock(impl_->mu);
  impl_->WaitUntil(lock, Deadline(impl_->options.timeout_s), [&] { return impl_->world->run() >= run; });
  return run;
}

uint32_t Client::load_map(const std::string& name, const std::string& opendrive, const std::string& scene) {
  msg::CommandBody b;
  msg::LoadMap m;
  m.name(name);
  m.opendrive(opendrive);
  m.scene(scene);
  b.load_map(m);
  const uint32_t run = Submit(std::move(b)).run();
  std::unique_lock<std::mutex> lock(impl_->mu);
  impl_->WaitUntil(lock, Deadline(impl_->options.timeout_s), [&] {
    return impl_->world->run() >= run && impl_->map_data && impl_->map_data->run() >= run;
  });
  return run;
}

uint64_t Client::Send(msg::CommandBody body) { return impl_->Send(std::move(body)); }

msg::CommandReply Client::WaitReply(uint64_t sequence) { return impl_->WaitReply(sequence, "command"); }

msg::CommandReply Client::Submit(msg::CommandBody body, bool throw_if_rejected) {
  const msg::CommandKind kind = body._d();
  const uint64_t seq = impl_->Send(std::move(body));
  msg::CommandReply r = impl_->WaitReply(seq, CommandKindName(kind));
  if (!r.accepted() && throw_if_rejected) {
    throw CommandRejected(std::string(CommandKindName(kind)) + " rejected: " + r.reason().to_string(), r.reason().to_string());
  }
  return r;
}

std::vector<msg::CommandReply> Client::SubmitBatch(const std::vector<msg::CommandBody>& bodies) {
  // The command topic keeps 256 samples: send in windows so none is overwritten unread.
  constexpr size_t kWindow = 128;
  std::vector<msg::CommandReply> out;
  out.reserve(bodies.size());
  for (size_t begin = 0; begin < bodies.size(); begin += kWindow) {
    std::vector<uint64_t> seqs;
    for (size_t i = begin; i < std::min(bodies.size(), begin + kWindow); ++i) seqs.push_back(impl_->Send(bodies[i]));
    for (uint64_t seq : seqs) out.push_back(impl_->WaitReply(seq, "batch command"));
  }
  return out;
}

uint32_t Client::spawn(const std::string& blueprint, const msg::Pose& pose, const AttributeList& attributes, uint32_t parent) {
  const msg::CommandReply r = impl_->WaitReply(impl_->Send(SpawnBody(blueprint, pose, attributes, parent)), "spawn");
  if (!r.accepted()) {
    throw CommandRejected("spawn of '" + blueprint + "' rejected: " + r.reason().to_string(), r.reason().to_string());
  }
  return r.actor();
}

std::optional<uint32_t> Client::try_spawn(const std::string& blueprint, const msg::Pose& pose, const AttributeList& attributes,
                                          uint32_t parent, std::string* reason) {
  const msg::CommandReply r = impl_->WaitReply(impl_->Send(SpawnBody(blueprint, pose, attributes, parent)), "spawn");
  if (!r.accepted()) {
    if (reason) *reason = r.reason().to_string();
    return std::nullopt;
  }
  return r.actor();
}

void Client::destroy(uint32_t actor) {
  msg::CommandBody b;
  msg::DestroyActor d;
  d.actor(actor);
  b.destroy_actor(d);
  Submit(std::move(b));
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->RemoveActor(actor);
}

// The recorder's commands: RecorderBody (lockstep/runtime/command_builders.h).
std::string Client::start_recorder(const std::string& name, bool additional_data) {
  if (name.empty()) throw ClientError("start_recorder needs a file name");
  if (name.size() > 1024) throw ClientError("start_recorder: the file name is longer than 1024 characters");
  return Submit(RecorderBody(msg::RecorderAction::RECORDER_START, name, additional_data)).text().to_string();
}

void Client::stop_recorder() { Submit(RecorderBody(msg::RecorderAction::RECORDER_STOP)); }

std::string Client::replay_file(const std::string& name, double start, double duration, uint32_t follow_id,
                                bool replay_sensors) {
  if (name.size() > 1024) throw ClientError("replay_file: the file name is longer than 1024 characters");
  msg::CommandBody b = RecorderBody(msg::RecorderAction::REPLAY_START, name);
  b.recorder().start(start);
  b.recorder().duration(duration);
  b.recorder().follow_id(follow_id);
  b.recorder().replay_sensors(replay_sensors);
  const msg::CommandReply r = Submit(std::move(b), false);
  // CARLA answers a file it cannot replay with its text ("File ... not found on server").
  if (r.accepted() || !r.text().to_string().empty()) return r.text().to_string();
  throw CommandRejected("replay_file rejected: " + r.reason().to_string(), r.reason().to_string());
}

void Client::stop_replayer(bool keep_actors) { Submit(RecorderBody(msg::RecorderAction::REPLAY_STOP, "", keep_actors)); }

void Client::set_replayer_time_factor(double time_factor) {
  msg::CommandBody b = RecorderBody(msg::RecorderAction::REPLAY_TIME_FACTOR);
  b.recorder().value(time_factor);
  Submit(std::move(b));
}

void Client::set_replayer_ignore_hero(bool ignore_hero) {
  Submit(RecorderBody(msg::RecorderAction::REPLAY_IGNORE_HERO, "", ignore_hero));
}

void Client::set_replayer_ignore_spectator(bool ignore_spectator) {
  Submit(RecorderBody(msg::RecorderAction::REPLAY_IGNORE_SPECTATOR, "", ignore_spectator));
}

BlueprintLibrary Client::blueprints(double wait_s) const {
  auto& s = *impl_;
  std::unique_lock<std::mutex> lock(s.mu);
  // The union of what the live members declare: wait until every one of them has been
  // heard (each publishes its set, possibly empty, when it joins).
  auto live = [&] {
    std::vector<std::string> names;
    if (s.status) {
      for (const auto& m : s.status->members()) {
        if (m.alive()) names.push_back(m.service().to_string());
      }
    }
    return names;
  };
  s.WaitUntil(lock, Deadline(wait_s), [&] {
    if (!s.status) return false;
    for (const auto& n : live()) {
      if (!s.declarations.count(n)) return false;
    }
    return true;
  });
  std::map<std::string, std::vector<msg::BlueprintDeclaration>> current;
  const auto names = live();
  for (const auto& [service, list] : s.declarations) {
    if (!s.status || std::find(names.begin(), names.end(), service) != names.end()) current[service] = list;
  }
  return BlueprintLibrary(current);
}

std::vector<ActorInfo> Client::actors() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  std::vector<ActorInfo> out;
  for (const auto& [id, a] : impl_->MergedActors()) out.push_back(a);
  return out;
}

std::optional<ActorInfo> Client::actor(uint32_t id) const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  const auto all = impl_->MergedActors();
  auto it = all.find(id);
  if (it == all.end()) return std::nullopt;
  return it->second;
}

Snapshot Client::snapshot() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  Snapshot s;
  s.run = impl_->world->run();
  s.frame = impl_->done.first == s.run ? impl_->done.second : 0;
  s.sim_time = impl_->done_sim_time;
  // The state of the latest completed frame, else the newest of this run.
  auto pick = [&](const auto& m) -> decltype(m.begin()->second) {
    auto it = m.find({s.run, s.frame});
    if (it != m.end()) return it->second;
    for (auto r = m.rbegin(); r != m.rend(); ++r) {
      if (r->first.first == s.run) return r->second;
    }
    return nullptr;
  };
  if (auto g = pick(impl_->ground)) s.ground = *g;
  if (auto a = pick(impl_->air)) s.air = *a;
  return s;
}

std::optional<msg::MapData> Client::map_data() {
  std::unique_lock<std::mutex> lock(impl_->mu);
  impl_->WaitUntil(lock, Deadline(impl_->options.timeout_s), [&] { return impl_->map_data.has_value(); });
  return impl_->map_data;
}

std::shared_ptr<const map::Map> Client::map() {
  std::optional<msg::MapData> data;
  {
    std::unique_lock<std::mutex> lock(impl_->mu);
    impl_->WaitUntil(lock, Deadline(impl_->options.timeout_s), [&] { return impl_->map_data.has_value(); });
    data = impl_->map_data;
  }
  if (!data || data->opendrive().empty()) throw ClientError("get_map(): the simulation has no map loaded");
  std::lock_guard<std::mutex> lock(impl_->map_mu);
  if (!impl_->map_cache || impl_->map_cache_hash != data->content_hash()) {
    impl_->map_cache = std::make_shared<const map::Map>(map::Map::FromString(data->opendrive(), data->name().to_string()));
    impl_->map_cache_hash = data->content_hash();
  }
  return impl_->map_cache;
}

void Client::listen(uint32_t sensor, SensorCallback callback) {
  auto info = actor(sensor);
  if (!info) throw ClientError("listen(): no actor " + std::to_string(sensor) + " in the current run");
  SensorType type;
  if (!SensorTypeOf(info->blueprint, &type)) {
    throw ClientError("listen(): actor " + std::to_string(sensor) + " (" + info->blueprint + ") is not a sensor");
  }
  std::size_t pixels = 0;
  if (type == SensorType::kImage) {
    try {
      pixels = std::stoul(info->Attribute("image_size_x", "0")) * std::stoul(info->Attribute("image_size_y", "0"));
    } catch (const std::exception&) {
      pixels = 0;  // unknown: both topics
    }
  }
  impl_->EnsureSensorReader(type, sensor, pixels);
  std::lock_guard<std::mutex> lock(impl_->mu);
  Impl::Listener l;
  l.type = type;
  l.callback = std::move(callback);
  const uint32_t run = impl_->world->run();
  const uint64_t now = impl_->done.first == run ? impl_->done.second : 0;
  // Expected: the frames after the last completed one, from the frame whose tick carries
  // the spawn on (as in CARLA, the first world.tick() after spawn_actor() and listen()
  // brings the sensor's data of that very frame; synchronous_mode.py waits for it).
  l.start = {run, std::max(now, info->spawn_frame > 0 ? info->spawn_frame - 1 : 0)};
  l.delivered = {run, 0};
  const double sensor_tick = std::atof(info->Attribute("sensor_tick", "0").c_str());
  l.per_frame = IsPerFrame(type) && !(sensor_tick > impl_->world->settings().fixed_delta_seconds() + 1e-9);
  impl_->listeners[sensor] = std::move(l);
}

void Client::stop(uint32_t sensor) {
  {
    std::unique_lock<std::mutex> lock(impl_->mu);
    impl_->listeners.erase(sensor);
  }
  impl_->frame_cv.notify_all();  // a tick() waiting for it waits no more
}

bool Client::is_listening(uint32_t sensor) const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->listeners.count(sensor) > 0;
}

uint64_t Client::delivered(uint32_t sensor) const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  auto it = impl_->listeners.find(sensor);
  return it == impl_->listeners.end() ? 0 : it->second.count;
}

std::optional<msg::DroneState> Client::drone_state(uint32_t actor) const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  for (auto it = impl_->air.rbegin(); it != impl_->air.rend(); ++it) {
    for (const auto& d : it->second->drones()) {
      if (d.actor() == actor) return d;
    }
    break;  // only the newest state counts: an actor missing there is gone
  }
  return std::nullopt;
}

uint64_t Client::send_drone(msg::DroneCommand command) {
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    command.command_id(impl_->drone_id_base | impl_->next_drone_command++);
  }
  msg::CommandBody b;
  b.drone(command);
  Submit(std::move(b));
  return command.command_id();
}

msg::DroneCommandStatus Client::wait_drone(uint32_t actor, uint64_t command_id, double timeout_s) {
  auto& s = *impl_;
  const auto deadline = Deadline(timeout_s);
  auto next_poll = Clock::now() + s.kInterruptPoll;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(s.mu);
      if (Clock::now() >= next_poll) {  // synchronous mode: a tick() at a time may never wait 100 ms
        s.PollInterrupt(lock);
        next_poll = Clock::now() + s.kInterruptPoll;
      }
      auto done = s.drone_finished.find({actor, command_id});
      if (done != s.drone_finished.end()) return done->second;
      if (Clock::now() >= deadline) {
        throw ClientError("drone " + std::to_string(actor) + ": command " + std::to_string(command_id & 0xffffffffULL) +
                          " not finished within " + Fmt(timeout_s) + " s");
      }
      if (!s.world->settings().synchronous_mode()) {
        const size_t seen = s.air.empty() ? 0 : s.air.rbegin()->first.second;
        s.ThrowIfStopping();
        s.cv.wait_until(lock, std::min(deadline, Clock::now() + s.kInterruptPoll), [&] {
          return s.stopping || s.drone_finished.count({actor, command_id}) ||
                 (!s.air.empty() && s.air.rbegin()->first.second != seen);
        });
        s.ThrowIfStopping();
        if (!s.drone_finished.count({actor, command_id}) && (s.actors_run != s.world->run() || !s.actors.count(actor))) {
          throw ClientError("drone " + std::to_string(actor) + " is gone (destroyed, or a new run began)");
        }
        continue;
      }
    }
    tick();  // synchronous mode: this client drives the clock while it waits
    std::lock_guard<std::mutex> lock(s.mu);
    if (!s.drone_finished.count({actor, command_id}) && (s.actors_run != s.world->run() || !s.actors.count(actor))) {
      throw ClientError("drone " + std::to_string(actor) + " is gone (destroyed, or a new run began)");
    }
  }
}

std::string Client::drone_failure(uint32_t actor, uint64_t command_id, double wait_s) const {
  auto& s = *impl_;
  const std::string id = std::to_string(command_id);
  std::string found;
  auto find = [&] {
    auto it = s.drone_failures.find(actor);
    if (it == s.drone_failures.end()) return false;
    for (auto m = it->second.rbegin(); m != it->second.rend(); ++m) {
      if (m->find("command " + id) != std::string::npos) {
        found = *m;
        return true;
      }
    }
    return false;
  };
  std::unique_lock<std::mutex> lock(s.mu);
  if (!s.WaitUntil(lock, Deadline(wait_s), find)) {
    // A command refused before it ran (bad values) is reported without its id: the
    // actor's latest failure is the one.
    auto it = s.drone_failures.find(actor);
    if (it != s.drone_failures.end() && !it->second.empty()) found = it->second.back();
  }
  return found;
}

const char* CommandKindName(msg::CommandKind kind) {
  switch (kind) {
    case msg::CommandKind::CMD_SPAWN_ACTOR: return "spawn_actor";
    case msg::CommandKind::CMD_DESTROY_ACTOR: return "destroy_actor";
    case msg::CommandKind::CMD_SET_TRANSFORM: return "set_transform";
    case msg::CommandKind::CMD_VEHICLE_CONTROL: return "apply_control (vehicle)";
    case msg::CommandKind::CMD_WALKER_CONTROL: return "apply_control (walker)";
    case msg::CommandKind::CMD_DRONE: return "drone command";
    case msg::CommandKind::CMD_TRAFFIC_LIGHT: return "traffic light command";
    case msg::CommandKind::CMD_TRAFFIC_MANAGER: return "traffic manager command";
    case msg::CommandKind::CMD_SET_WEATHER: return "set_weather";
    case msg::CommandKind::CMD_SET_WORLD_SETTINGS: return "apply_settings";
    case msg::CommandKind::CMD_LOAD_MAP: return "load_world";
    case msg::CommandKind::CMD_RESET: return "reload_world";
    case msg::CommandKind::CMD_TICK: return "tick";
    case msg::CommandKind::CMD_VEHICLE_ACKERMANN: return "apply_ackermann_control";
    case msg::CommandKind::CMD_ACTOR_PHYSICS: return "actor physics command";
    case msg::CommandKind::CMD_VEHICLE_PHYSICS: return "apply_physics_control";
    case msg::CommandKind::CMD_WALKER_AI: return "walker AI controller command";
    case msg::CommandKind::CMD_PEDESTRIANS: return "set_pedestrians_cross_factor";
    case msg::CommandKind::CMD_DEBUG_DRAW: return "debug draw";
    case msg::CommandKind::CMD_RECORDER: return "recorder command";
    case msg::CommandKind::CMD_V2X_SEND: return "V2X send";
  }
  return "command";
}

uint32_t CommandActor(const msg::CommandBody& b) {
  using K = msg::CommandKind;
  switch (b._d()) {
    case K::CMD_DESTROY_ACTOR: return b.destroy_actor().actor();
    case K::CMD_SET_TRANSFORM: return b.set_transform().actor();
    case K::CMD_VEHICLE_CONTROL: return b.vehicle_control().actor();
    case K::CMD_WALKER_CONTROL: return b.walker_control().actor();
    case K::CMD_DRONE: return b.drone().actor();
    case K::CMD_TRAFFIC_LIGHT: return b.traffic_light().actor();
    case K::CMD_TRAFFIC_MANAGER: return b.traffic_manager().actor();
    case K::CMD_VEHICLE_ACKERMANN: return b.ackermann().actor();
    case K::CMD_ACTOR_PHYSICS: return b.actor_physics().actor();
    case K::CMD_VEHICLE_PHYSICS: return b.vehicle_physics().actor();
    case K::CMD_WALKER_AI: return b.walker_ai().actor();
    default: return 0;
  }
}

const char* DroneStatusName(msg::DroneCommandStatus status) {
  switch (status) {
    case msg::DroneCommandStatus::DRONE_CMD_NONE: return "none";
    case msg::DroneCommandStatus::DRONE_CMD_RUNNING: return "running";
    case msg::DroneCommandStatus::DRONE_CMD_COMPLETED: return "completed";
    case msg::DroneCommandStatus::DRONE_CMD_TIMED_OUT: return "timed_out";
    case msg::DroneCommandStatus::DRONE_CMD_CANCELLED: return "cancelled";
    case msg::DroneCommandStatus::DRONE_CMD_REJECTED: return "rejected";
  }
  return "?";
}

}  // namespace lockstep::client
