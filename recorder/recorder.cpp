#include "recorder.h"

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "lockstep/runtime/actor_list.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/log.h"

namespace lockstep {

namespace {

using Ms = std::chrono::milliseconds;

// Samples of (run, frame) from several writers (one per physics service).
template <class T>
class FrameSet {
 public:
  FrameSet(Bus& bus, const Topic<T>& topic)
      : reader_(bus, topic, [this](T& s, const SampleInfo& info) { Push(s, info.writer_id); }) {}

  // The samples of (run, frame) once `count` writers sent theirs; nullopt on timeout.
  std::optional<std::vector<T>> WaitFor(uint32_t run, uint64_t frame, size_t count, Ms timeout) {
    std::unique_lock<std::mutex> lock(mu_);
    const Key key{run, frame};
    if (!cv_.wait_for(lock, timeout, [&] { return samples_.count(key) && samples_[key].size() >= count; })) return std::nullopt;
    std::vector<T> out;
    for (auto& [writer, s] : samples_[key]) out.push_back(std::move(s));
    // Older frames are no longer needed.
    samples_.erase(samples_.begin(), samples_.lower_bound(key));
    return out;
  }

 private:
  using Key = std::pair<uint32_t, uint64_t>;
  // Takes the sample (no copy of a large state): the bus reads the next one into `s`.
  void Push(T& s, uint64_t writer) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      const Key key{s.stamp().run(), s.stamp().frame()};
      std::swap(samples_[key][writer], s);
      while (samples_.size() > 16) samples_.erase(samples_.begin());
    }
    cv_.notify_all();
  }
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<Key, std::map<uint64_t, T>> samples_;
  TakingReader<T> reader_;  // last: its callback uses the members above
};

std::vector<std::string> Union(std::vector<std::string> a, const std::vector<std::string>& b) {
  for (const auto& s : b) {
    if (std::find(a.begin(), a.end(), s) == a.end()) a.push_back(s);
  }
  return a;
}

}  // namespace

// FrameDone and the acks: read all the time (small samples, the last frames kept), so that
// the first recorded frame has every service's hash and, over DDS, no reader has to match
// its writers when recording starts.
struct Recorder::Hashes {
  std::atomic<uint32_t> run{0};
  std::mutex mu;
  std::condition_variable cv;
  std::map<uint64_t, recorder::FrameHashes> done;                 // FrameDone by frame
  std::map<uint64_t, std::map<std::string, uint64_t>> acks;       // frame -> service -> hash
  Reader<msg::FrameDone> done_reader;
  Reader<msg::Ack> ack_reader;

  explicit Hashes(Bus& bus)
      : done_reader(bus, topics::kFrameDone,
                    [this](const msg::FrameDone& d, const SampleInfo&) {
                      if (d.run() != run) return;
                      {
                        std::lock_guard<std::mutex> lock(mu);
                        auto& h = done[d.frame()];
                        h.world_hash = d.world_hash();
                        h.diverged = d.diverged();
                        done_max = std::max(done_max, d.frame());
                        while (done.size() > 64) done.erase(done.begin());
                      }
                      cv.notify_all();
                    }),
        ack_reader(bus, topics::kAck, [this](const msg::Ack& a, const SampleInfo&) {
          if (a.run() != run) return;
          {
            std::lock_guard<std::mutex> lock(mu);
            acks[a.frame()][a.service().to_string()] = a.state_hash();
            while (acks.size() > 64) acks.erase(acks.begin());
          }
          cv.notify_all();
        }) {}

  // A new run: what was kept belongs to the one before.
  void NewRun(uint32_t r, size_t required) {
    std::lock_guard<std::mutex> lock(mu);
    done.clear();
    acks.clear();
    done_max = 0;
    run = r;
    expected = required;
  }
  size_t expected = 0;  // acks per frame: the required services
  uint64_t done_max = 0;  // the latest FrameDone of the run (Take keeps no record of it)

  // Waits (bounded) until FrameDone of `frame` or a later one came: every member acked it,
  // so every sensor output of that tick has been published.
  void WaitDoneAtLeast(uint64_t frame, Ms timeout) {
    std::unique_lock<std::mutex> lock(mu);
    cv.wait_for(lock, timeout, [&] { return done_max >= frame; });
  }

  // FrameDone of `frame` is here with every required service's ack (an ack may reach this
  // reader after FrameDone reached the other: different writers).
  bool Complete(uint64_t frame) const {
    if (!done.count(frame)) return false;
    auto a = acks.find(frame);
    return a != acks.end() && a->second.size() >= expected;
  }
  // Recording starts at `frame`: the hashes of earlier frames are not the log's.
  void StartAt(uint64_t frame) {
    std::lock_guard<std::mutex> lock(mu);
    done.erase(done.begin(), done.lower_bound(frame));
  }

  // Waits (bounded) for FrameDone of `frame`: it comes after the recorder acked it.
  void WaitDone(uint64_t frame, Ms timeout) {
    std::unique_lock<std::mutex> lock(mu);
    cv.wait_for(lock, timeout, [&] { return Complete(frame); });
  }

  // The hashes of the frames before `before` that FrameDone completed, with the acks.
  std::vector<std::pair<uint64_t, recorder::FrameHashes>> Take(uint64_t before) {
    std::lock_guard<std::mutex> lock(mu);
    std::vector<std::pair<uint64_t, recorder::FrameHashes>> out;
    for (auto it = done.begin(); it != done.end() && it->first < before;) {
      recorder::FrameHashes h = it->second;
      if (auto a = acks.find(it->first); a != acks.end()) {
        for (const auto& [service, hash] : a->second) h.services.emplace_back(service, hash);
      }
      out.emplace_back(it->first, std::move(h));
      acks.erase(acks.begin(), acks.upper_bound(it->first));
      it = done.erase(it);
    }
    return out;
  }
};

// The state readers of a recording: created when it starts, gone when it stops, so a
// recorder that does not record reads no state topic.
struct Recorder::Inputs {
  uint32_t run = 0;
  size_t ground_count = 0, air_count = 0, events_count = 0;
  std::map<std::string, msg::ActorKind> kinds;  // blueprint -> kind, from the declarations
  std::mutex mu;
  std::map<uint32_t, msg::SpawnActor> listed;   // the coordinator's actor list
  FrameSet<msg::GroundState> ground;
  FrameSet<msg::AirState> air;
  FrameSet<msg::PhysicsEvents> events;
  Reader<msg::ActorList> actor_reader;

  Inputs(Bus& bus, uint32_t r)
      : run(r),
        ground(bus, topics::kGroundState),
        air(bus, topics::kAirState),
        events(bus, topics::kPhysicsEvents),
        actor_reader(bus, topics::kActors, [this](const msg::ActorList& l, const SampleInfo&) {
          std::lock_guard<std::mutex> lock(mu);
          if (l.run() != run) return;
          listed.clear();  // the list is every live actor
          for (const auto& a : l.actors()) listed[a.spawn().actor()] = a.spawn();
        }) {}
};

namespace {

std::string Attribute(const msg::SpawnActor& s, const char* key) {
  for (const auto& a : s.attributes()) {
    if (a.key().to_string() == key) return a.value().to_string();
  }
  return {};
}
std::string RoleName(const msg::SpawnActor& s) { return Attribute(s, "role_name"); }

// Sensors that publish only when something happens (a collision, a crossed marking, an
// obstacle, a V2X message): never waited for.
bool EventType(const std::string& type) {
  return type == "CollisionEvent" || type == "LaneInvasionEvent" || type == "ObstacleDetection" || type == "V2XData";
}

}  // namespace

// The chosen sensors' outputs of one log. Readers on the shared sensor topics that the
// selection may need exist from the log's start (a sample of a sensor this recorder has
// not sorted yet is kept until it is); a chosen camera gets readers on its own image
// topics when it is sorted (they keep the last images, so its first one comes too). Each
// sample is kept as published until the writer thread takes it for the frame it shows;
// samples of sensors not chosen are dropped unread.
//
// The bus may deliver a sample after the frame's FrameDone (another topic, another
// thread), so the writer waits, bounded, for the samples due: a chosen sensor that
// publishes every frame (sensor_tick 0) is due in every frame after the one it was
// sorted in; one with a sensor_tick, from its third sample on, at its last frame plus the
// frames between its last two. A sensor that misses its due frame is not waited for again
// until it published twice more; event sensors never are.
struct Recorder::SensorTaps {
  using Key = std::tuple<uint64_t, uint32_t, std::string>;  // frame, sensor, type
  Bus& bus;
  const uint32_t run;
  const uint64_t first_frame;  // the log's first state frame: older samples are not the log's
  const recorder::SensorSelection selection;
  std::mutex mu;
  std::condition_variable cv;
  std::set<uint32_t> chosen, ignored;
  std::set<uint32_t> alive;  // sensors alive in the frame the Step thread last saw
  std::map<Key, std::function<std::vector<uint8_t>()>> pending;  // the sample's CDR, made off the bus thread
  std::map<std::pair<uint32_t, std::string>, uint64_t> last_taken;  // per stream: no sample twice
  struct Due {
    uint64_t previous = 0, last = 0;  // frames of its last two samples (last: or when it was sorted)
    uint64_t period = 0;              // frames between its samples; 0: not waited for
    bool events = false;
  };
  std::map<uint32_t, Due> due;  // chosen sensors
  uint64_t newest = 0;
  std::vector<std::shared_ptr<void>> readers;  // Step thread only

  SensorTaps(Bus& b, uint32_t r, uint64_t first, recorder::SensorSelection s)
      : bus(b), run(r), first_frame(first), selection(std::move(s)) {}
  ~SensorTaps() { readers.clear(); }  // no callback after this

  template <class T>
  void Keep(const T& s, const char* type) {
    if (s.stamp().run() != run || s.stamp().frame() < first_frame) return;
    const uint32_t id = s.sensor();
    {
      std::lock_guard<std::mutex> lock(mu);
      if (ignored.count(id)) return;
    }
    auto copy = std::make_shared<T>(s);
    std::lock_guard<std::mutex> lock(mu);
    const uint64_t frame = s.stamp().frame();
    pending[Key{frame, id, type}] = [copy] { return recorder::ToCdr(*copy); };
    newest = std::max(newest, frame);
    // A sample nobody takes (its sensor never sorted) does not stay for long.
    while (!pending.empty() && std::get<0>(pending.begin()->first) + 64 < newest) pending.erase(pending.begin());
    cv.notify_all();
  }

  template <class T>
  void Subscribe(const std::string& topic, QosKind qos, const char* type) {
    readers.push_back(std::make_shared<Reader<T>>(bus, Topic<T>{topic.c_str(), qos},
                                                  [this, type](const T& s, const SampleInfo&) { Keep(s, type); }));
  }
  template <class T>
  void Subscribe(const Topic<T>& topic, const char* type) {
    Subscribe<T>(topic.name, topic.qos, type);
  }

  // The shared topics of these message types (SensorMessageType).
  void SubscribeShared(const std::set<std::string>& types) {
    auto want = [&](const char* t) { return types.count(t) > 0; };
    if (want("PointCloud")) Subscribe(topics::kPointCloud, "PointCloud");
    if (want("RadarScan")) Subscribe(topics::kRadar, "RadarScan");
    if (want("Imu")) Subscribe(topics::kImu, "Imu");
    if (want("Gnss")) Subscribe(topics::kGnss, "Gnss");
    if (want("Barometer")) Subscribe(topics::kBarometer, "Barometer");
    if (want("Magnetometer")) Subscribe(topics::kMagnetometer, "Magnetometer");
    if (want("CollisionEvent")) Subscribe(topics::kCollision, "CollisionEvent");
    if (want("LaneInvasionEvent")) Subscribe(topics::kLaneInvasion, "LaneInvasionEvent");
    if (want("ObstacleDetection")) Subscribe(topics::kObstacle, "ObstacleDetection");
    if (want("DistanceMeasurement")) Subscribe(topics::kDistance, "DistanceMeasurement");
    if (want("V2XData")) Subscribe(topics::kV2X, "V2XData");
  }

  // Sorts a sensor once, in the Step of `frame` (its state frame): chosen or not. A
  // chosen camera gets its image readers.
  void Sort(uint32_t id, const msg::SpawnActor& spawn, uint64_t frame) {
    const std::string blueprint = spawn.blueprint().to_string();
    const bool choose = selection.Chooses(id, blueprint, RoleName(spawn));
    const std::string type = recorder::SensorMessageType(blueprint);
    {
      std::lock_guard<std::mutex> lock(mu);
      if (chosen.count(id) || ignored.count(id)) return;
      (choose ? chosen : ignored).insert(id);
      if (choose) {
        Due& d = due[id];
        d.events = EventType(type);
        d.last = std::max(first_frame, frame);
        const std::string tick = Attribute(spawn, "sensor_tick");
        if (!d.events && (tick.empty() || std::strtod(tick.c_str(), nullptr) <= 0)) d.period = 1;
      }
    }
    // Outside the lock: a new reader may deliver kept images at once.
    if (choose && type == "Image") {
      Subscribe<msg::Image>(topics::ImageTopicName(id), QosKind::kImage, "Image");
      Subscribe<msg::LargeImage>(topics::LargeImageTopicName(id), QosKind::kLargeImage, "LargeImage");
    }
  }

  void SetAlive(std::set<uint32_t> ids) {
    std::lock_guard<std::mutex> lock(mu);
    alive = std::move(ids);
  }

  // The chosen sensors due by `up_to` whose sample is not here yet (mu held).
  std::vector<uint32_t> Missing(uint64_t up_to) const {
    std::vector<uint32_t> out;
    for (const auto& [id, d] : due) {
      if (d.period == 0 || !alive.count(id) || d.last + d.period > up_to) continue;
      bool here = false;
      for (auto it = pending.lower_bound(Key{d.last + 1, 0, std::string()}); it != pending.end() && std::get<0>(it->first) <= up_to && !here; ++it) {
        here = std::get<1>(it->first) == id;
      }
      if (!here) out.push_back(id);
    }
    return out;
  }

  // Waits until the samples due by `up_to` are here, or `deadline`.
  void WaitDue(uint64_t up_to, std::chrono::steady_clock::time_point deadline) {
    std::unique_lock<std::mutex> lock(mu);
    if (cv.wait_until(lock, deadline, [&] { return Missing(up_to).empty(); })) return;
    for (uint32_t id : Missing(up_to)) {
      spdlog::warn("recorder: sensor {} published nothing for frame {}: not waited for until it publishes twice more", id, up_to);
      due[id].period = 0;
      due[id].previous = 0;
    }
  }

  // The samples of chosen sensors that show frames up to `up_to`, as CDR, in (frame,
  // sensor) order; one that came after its frame was written comes with a later frame.
  std::vector<recorder::SensorRecord> Take(uint64_t up_to) {
    std::vector<std::pair<Key, std::function<std::vector<uint8_t>()>>> ready;
    {
      std::lock_guard<std::mutex> lock(mu);
      for (auto it = pending.begin(); it != pending.end() && std::get<0>(it->first) <= up_to;) {
        const auto& [frame, id, type] = it->first;
        auto last = last_taken.find({id, type});
        if (ignored.count(id) || (last != last_taken.end() && frame <= last->second)) {
          it = pending.erase(it);
          continue;
        }
        if (!chosen.count(id)) {  // its spawn has not been sorted yet: it may still be
          ++it;
          continue;
        }
        last_taken[{id, type}] = frame;
        Due& d = due[id];
        if (frame > d.last) {
          if (!d.events && d.period == 0 && d.previous != 0) d.period = frame - d.last;  // learnt from two samples
          d.previous = d.last;
          d.last = frame;
        }
        ready.emplace_back(it->first, std::move(it->second));
        it = pending.erase(it);
      }
    }
    std::vector<recorder::SensorRecord> out;
    out.reserve(ready.size());
    for (auto& [key, cdr] : ready) out.push_back(recorder::SensorRecord{std::get<1>(key), std::get<2>(key), cdr(), std::get<0>(key)});
    return out;
  }
};

Recorder::Recorder(Bus& bus, RecorderOptions options)
    : bus_(bus),
      options_(std::move(options)),
      declarations_(bus),
      hashes_(std::make_unique<Hashes>(bus)),
      announce_reader_(bus, topics::kService, [this](const msg::ServiceAnnounce& a, const SampleInfo&) {
        std::lock_guard<std::mutex> lock(announce_mu_);
        announced_[a.service().to_string()] = {a.kind().to_string(), a.perception()};
      }) {
  if (options_.record_run && options_.output_dir.empty()) {
    throw InputError("recorder: recording every run needs output_dir in the launch config");
  }
  try {
    sensor_selection_ = recorder::SensorSelection::Parse(options_.record_sensors);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("recorder: --record-sensors: ") + e.what());
  }
  writer_thread_ = std::thread([this] { WriterLoop(); });
}

Recorder::~Recorder() {
  closing_ = true;  // the writer waits for no FrameDone any more
  try {
    Stop("service stopped");
  } catch (const std::exception& e) {
    spdlog::error("recorder: {}", e.what());
  }
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    quit_ = true;
  }
  queue_cv_.notify_all();
  writer_thread_.join();
}

std::string Recorder::recording() const { return writer_ ? writer_->path() : std::string(); }

void Recorder::BeginRun(const msg::WorldInfo& world) {
  Stop("run ended");
  hashes_->NewRun(world.run(), world.required_services().size());
  world_ = world;
  mode_ = world.settings().perception_mode();
  alive_.clear();
  prelude_.clear();
  prelude_bytes_ = 0;
  prelude_complete_ = true;
  last_dt_ = -1;
  last_frame_ = 0;
}

void Recorder::Track(const msg::Tick& tick) {
  // The first tick this recorder sees after frame 1 means it joined mid-run: no prelude.
  if (last_frame_ == 0 && tick.frame() > 1) prelude_complete_ = false;
  if (prelude_complete_ && (!tick.commands().empty() || tick.dt() != last_dt_)) {
    prelude_bytes_ += msg::Tick::getCdrSerializedSize(tick);
    if (prelude_bytes_ > options_.prelude_limit_bytes) {
      prelude_complete_ = false;
      prelude_.clear();
      prelude_.shrink_to_fit();
    } else {
      prelude_.push_back(tick);
    }
  }
  last_dt_ = tick.dt();
  last_frame_ = tick.frame();
  for (const auto& c : tick.commands()) {
    const auto& b = c.body();
    if (b._d() == msg::CommandKind::CMD_SPAWN_ACTOR) {
      alive_[b.spawn_actor().actor()] = b.spawn_actor();
    } else if (b._d() == msg::CommandKind::CMD_DESTROY_ACTOR) {
      // Only the actor goes; what was attached to it stays, unattached (the coordinator's
      // rule, CARLA's).
      const uint32_t gone = b.destroy_actor().actor();
      alive_.erase(gone);
      for (auto& [id, s] : alive_) {
        if (s.parent() == gone) s.parent(0);
      }
    }
  }
}

void Recorder::Start(const msg::Tick& tick, const std::string& path, bool additional_data) {
  Stop("restarted");
  const std::vector<std::string> required = RequiredServices(world_);
  declarations_.WaitFor(required, Ms(static_cast<int>(options_.input_timeout_s * 1000)));
  auto inputs = std::make_unique<Inputs>(bus_, tick.run());
  const auto ground = Union(declarations_.Declaring(msg::ActorKind::ACTOR_VEHICLE, required),
                            declarations_.Declaring(msg::ActorKind::ACTOR_WALKER, required));
  const auto air = declarations_.Declaring(msg::ActorKind::ACTOR_DRONE, required);
  inputs->ground_count = ground.size();
  inputs->air_count = air.size();
  inputs->events_count = Union(ground, air).size();

  recorder::LogHeader h;
  h.name = path;
  h.config_text = options_.config_text;
  h.config_source = options_.config_source;
  h.map_name = world_.map_name().to_string();
  h.map_digest = world_.map_hash();
  h.seed = world_.seed();
  h.run = world_.run();
  h.world = world_;
  const auto live = declarations_.Live();
  std::map<std::string, std::pair<std::string, bool>> kinds = options_.service_kinds;
  {
    std::lock_guard<std::mutex> lock(announce_mu_);
    for (const auto& [name, k] : announced_) kinds[name] = k;
  }
  std::vector<std::string> names = required;
  for (const auto& [name, set] : live) {
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  for (const auto& name : names) {
    recorder::ServiceInfo s;
    s.name = name;
    s.required = std::find(required.begin(), required.end(), name) != required.end();
    if (auto k = kinds.find(name); k != kinds.end()) {
      s.kind = k->second.first;
      s.perception = k->second.second;
    }
    if (auto it = live.find(name); it != live.end()) {
      for (const auto& b : it->second.blueprints()) {
        s.blueprints.emplace_back(b.id().to_string(), b.kind());
        inputs->kinds[b.id().to_string()] = b.kind();
      }
      s.blueprint_set_cdr = recorder::ToCdr(it->second);
    }
    h.services.push_back(std::move(s));
  }
  h.first_frame = tick.frame();
  h.first_sim_time = tick.sim_time();
  h.start_unix_time = static_cast<int64_t>(std::time(nullptr));
  h.additional_data = additional_data;
  h.keyframe_period = options_.keyframe_period;
  // The sensors whose outputs it holds: the recorder's selection, else every sensor when
  // start_recorder asks for additional_data.
  const recorder::SensorSelection chosen =
      !sensor_selection_.empty() ? sensor_selection_ : (additional_data ? recorder::SensorSelection::All() : recorder::SensorSelection());
  h.sensor_selection = chosen.spec();
  std::shared_ptr<SensorTaps> taps;
  if (!chosen.empty()) {
    taps = std::make_shared<SensorTaps>(bus_, tick.run(), PerceptionFrame(mode_, tick.frame()), chosen);
    std::set<std::string> types;
    for (const auto& [bp, kind] : inputs->kinds) {
      if (kind == msg::ActorKind::ACTOR_SENSOR && chosen.MayChoose(bp)) types.insert(recorder::SensorMessageType(bp));
    }
    taps->SubscribeShared(types);
    for (const auto& [id, s] : alive_) {
      const std::string bp = s.blueprint().to_string();
      auto k = inputs->kinds.find(bp);
      if (k != inputs->kinds.end() && k->second == msg::ActorKind::ACTOR_SENSOR && chosen.Chooses(id, bp, RoleName(s))) h.sensors.push_back(id);
    }
  }
  if (prelude_complete_ && tick.frame() > 1) {
    h.prelude = prelude_;
    h.prelude_frames = tick.frame() - 1;
  }
  try {
    writer_ = std::make_unique<recorder::LogWriter>(path, h);
  } catch (const std::exception& e) {
    spdlog::error("recorder: not recording: {}", e.what());
    return;
  }
  inputs_ = std::move(inputs);
  taps_ = std::move(taps);
  described_.clear();
  queued_ = 0;
  hashes_->StartAt(tick.frame());
  spdlog::info("recording run {} from frame {} into {}", tick.run(), tick.frame(), path);
}

void Recorder::Stop(const std::string& reason) {
  if (!writer_) return;
  Drain();  // every queued frame written first
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    if (writer_error_) {
      spdlog::error("recorder: writing {} failed; the log ends at its last whole frame", writer_->path());
      writer_error_ = nullptr;
    }
  }
  // The last frame's FrameDone follows its ack; wait for it a little.
  if (writer_->frames() > 0) hashes_->WaitDone(writer_->last_frame(), Ms(reason == "service stopped" ? 1000 : 2000));
  auto late = hashes_->Take(UINT64_MAX);
  const std::string path = writer_->path();
  const uint64_t frames = writer_->frames();
  writer_->Close(reason, late);
  writer_.reset();
  inputs_.reset();
  taps_.reset();
  spdlog::info("recorder: {} ({} frames, {})", path, frames, reason);
}

void Recorder::Step(const msg::Tick& tick) {
  if (replaying()) {
    // A replacement cannot rebuild past frames (their inputs are gone); it learns the actors.
    Track(tick);
    return;
  }
  bool start = false, additional = false;
  std::string path;
  for (const auto& c : tick.commands()) {
    if (c.body()._d() != msg::CommandKind::CMD_RECORDER) continue;
    const auto& r = c.body().recorder();
    if (r.action() == msg::RecorderAction::RECORDER_START) {
      start = true;
      path = recorder::ResolveLogPath(r.name().to_string());
      additional = r.flag();
    } else if (r.action() == msg::RecorderAction::RECORDER_STOP) {
      start = false;
      Stop("stopped");
    }
  }
  if (!writer_ && options_.record_run && !options_.read_only && last_frame_ == 0) {
    start = true;
    path = options_.output_dir + "/run" + std::to_string(tick.run()) + "/" + options_.run_log_name;
  }
  if (start && !options_.read_only) Start(tick, path, additional);
  Track(tick);
  if (writer_) WriteFrame(tick);
}

void Recorder::WriteFrame(const msg::Tick& tick) {
  Inputs& in = *inputs_;
  const auto timeout = Ms(static_cast<int>(options_.input_timeout_s * 1000));
  const uint64_t state_frame = PerceptionFrame(mode_, tick.frame());
  std::vector<msg::GroundState> ground;
  std::vector<msg::AirState> air;
  std::vector<msg::PhysicsEvents> events;
  if (state_frame >= 1) {
    auto need = [&](auto& set, size_t count, const char* what, auto* out) {
      if (count == 0) return;
      auto got = set.WaitFor(tick.run(), state_frame, count, timeout);
      if (!got) {
        throw MissingInput("recorder: no " + std::string(what) + " of frame " + std::to_string(state_frame) + " from all " +
                           std::to_string(count) + " services within " + std::to_string(options_.input_timeout_s) + " s");
      }
      *out = std::move(*got);
    };
    need(in.ground, in.ground_count, "GroundState", &ground);
    need(in.air, in.air_count, "AirState", &air);
    need(in.events, in.events_count, "PhysicsEvents", &events);
  }
  // The frame before is done (its FrameDone came before this tick, on another topic).
  if (queued_ > 0) hashes_->WaitDone(tick.frame() - 1, Ms(1000));
  ++queued_;
  // The frame goes to the writer thread: its serialisation and write stay off the barrier.
  Job job;
  job.tick = tick;
  job.state_frame = state_frame;
  job.ground = std::move(ground);
  job.air = std::move(air);
  job.events = std::move(events);
  job.hashes = hashes_->Take(tick.frame());
  auto kind_of = [&](const std::string& blueprint) {
    auto it = in.kinds.find(blueprint);
    return it == in.kinds.end() ? msg::ActorKind::ACTOR_OTHER : it->second;
  };
  auto describe = [&](uint32_t id, const msg::SpawnActor& s) {
    recorder::ActorInfo a;
    a.id = id;
    a.blueprint = s.blueprint().to_string();
    a.kind = kind_of(a.blueprint);
    a.parent = s.parent();
    a.owner = s.owner().to_string();
    for (const auto& at : s.attributes()) a.attributes.emplace_back(at.key().to_string(), at.value().to_string());
    a.spawn_pose = s.transform();
    job.described[id] = std::move(a);
  };
  // Describe each actor once per log, when it first shows up (the writer decides which are
  // new to the frame): the spawns this recorder saw, else the coordinator's actor list.
  for (const auto& [id, s] : alive_) {
    const auto k = kind_of(s.blueprint().to_string());
    if (k != msg::ActorKind::ACTOR_VEHICLE && k != msg::ActorKind::ACTOR_WALKER && k != msg::ActorKind::ACTOR_DRONE) {
      job.stateless.push_back(id);
    }
    if (described_.insert(id).second) describe(id, s);
  }
  auto listed = [&](uint32_t id) {
    if (described_.count(id)) return;
    std::lock_guard<std::mutex> lock(in.mu);
    if (auto it = in.listed.find(id); it != in.listed.end()) {
      described_.insert(id);
      describe(id, it->second);
    }
  };
  for (const auto& g : job.ground) {
    for (const auto& v : g.vehicles()) listed(v.actor());
    for (const auto& w : g.walkers()) listed(w.actor());
  }
  for (const auto& a : job.air) {
    for (const auto& d : a.drones()) listed(d.actor());
  }
  if (taps_) {
    ChooseSensors(*taps_, state_frame);
    job.sensors = taps_;
  }
  Enqueue(std::move(job));
}

void Recorder::ChooseSensors(SensorTaps& taps, uint64_t state_frame) {
  Inputs& in = *inputs_;
  auto sort = [&](uint32_t id, const msg::SpawnActor& s) {
    const std::string bp = s.blueprint().to_string();
    auto k = in.kinds.find(bp);
    const bool sensor = k != in.kinds.end() ? k->second == msg::ActorKind::ACTOR_SENSOR : bp.rfind("sensor.", 0) == 0;
    if (sensor) taps.Sort(id, s, state_frame);
  };
  for (const auto& [id, s] : alive_) sort(id, s);
  std::map<uint32_t, msg::SpawnActor> listed;
  {
    std::lock_guard<std::mutex> lock(in.mu);
    for (const auto& [id, s] : in.listed) {
      if (!alive_.count(id)) listed.emplace(id, s);
    }
  }
  for (const auto& [id, s] : listed) sort(id, s);
  std::set<uint32_t> alive;
  for (const auto& [id, s] : alive_) alive.insert(id);
  for (const auto& [id, s] : listed) alive.insert(id);
  taps.SetAlive(std::move(alive));
}

void Recorder::Enqueue(Job job) {
  std::unique_lock<std::mutex> lock(queue_mu_);
  if (writer_error_) std::rethrow_exception(writer_error_);
  // At most kQueue frames behind: the run cannot outpace the disk.
  queue_cv_.wait(lock, [&] { return queue_.size() < kQueue; });
  queue_.push_back(std::move(job));
  queue_cv_.notify_all();
}

void Recorder::Drain() {
  std::unique_lock<std::mutex> lock(queue_mu_);
  queue_cv_.wait(lock, [&] { return queue_.empty() && !writing_; });
}

void Recorder::WriterLoop() {
  std::unique_lock<std::mutex> lock(queue_mu_);
  for (;;) {
    queue_cv_.wait(lock, [&] { return quit_ || !queue_.empty(); });
    if (queue_.empty()) return;  // quit_ and nothing left
    Job job = std::move(queue_.front());
    queue_.pop_front();
    writing_ = true;
    queue_cv_.notify_all();
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    try {
      recorder::FrameInputs f;
      f.tick = &job.tick;
      f.state_frame = job.state_frame;
      for (const auto& g : job.ground) f.ground.push_back(&g);
      for (const auto& a : job.air) f.air.push_back(&a);
      for (const auto& e : job.events) f.events.push_back(&e);
      f.hashes = std::move(job.hashes);
      f.stateless_actors = std::move(job.stateless);
      f.describe = [&](uint32_t id) -> std::optional<recorder::ActorInfo> {
        auto it = job.described.find(id);
        if (it == job.described.end()) return std::nullopt;
        return it->second;
      };
      if (job.sensors) {
        // FrameDone of the frame: every member acked it, so its sensors published their
        // outputs (the service loop publishes before it acks).
        const auto deadline = std::chrono::steady_clock::now() + Ms(closing_ ? 500 : 3000);
        if (!closing_) hashes_->WaitDoneAtLeast(job.tick.frame(), Ms(1000));
        job.sensors->WaitDue(job.state_frame, deadline);
        f.sensors = job.sensors->Take(job.state_frame);
      }
      writer_->WriteFrame(f);
      ++frames_written_;
      write_us_ = write_us_ + std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    } catch (...) {
      lock.lock();
      writer_error_ = std::current_exception();
      writing_ = false;
      queue_.clear();
      queue_cv_.notify_all();
      continue;
    }
    lock.lock();
    writing_ = false;
    queue_cv_.notify_all();
  }
}

}  // namespace lockstep
