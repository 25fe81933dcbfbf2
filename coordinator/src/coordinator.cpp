#include "lockstep/coordinator/coordinator.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>

#include "lockstep/coordinator/command_processor.h"
#include "lockstep/coordinator/membership.h"
#include "lockstep/coordinator/outbox.h"
#include "lockstep/coordinator/tick_barrier.h"
#include "lockstep/runtime/actor_list.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/messages.h"
#include "lockstep/runtime/tick_log.h"
#include "actor_roster.h"
#include "map_source.h"
#include "playback.h"
#include "run_status.h"
#include "scenario.h"
#include "weather_defaults.h"

namespace lockstep {

using Clock = std::chrono::steady_clock;
using msg::RunState;

// Services announce themselves every 100 ms; silence this long means failure.
constexpr auto kHeartbeatTimeout = std::chrono::milliseconds(600);
// A process on this host that still runs but was not heard (its heartbeat thread starved
// on an overloaded machine) gets this long before it counts as hung.
constexpr auto kStarvedTimeout = std::chrono::seconds(5);

struct Coordinator::Impl {
  Impl(Bus& b, LaunchConfig c) : bus(b), config(std::move(c)) {
    members.SetProcessProbe(ProbeLocalProcess, kStarvedTimeout);
  }

  Bus& bus;
  LaunchConfig config;
  CommandProcessor commands;
  TickBarrier barrier;

  mutable std::mutex mu;
  std::condition_variable cv;
  const std::vector<std::string> required_services = config.RequiredServices();
  Membership members{required_services, kHeartbeatTimeout};
  std::deque<msg::Command> inbox;

  // Run state, touched by the main loop only (under mu).
  RunState state = RunState::RUN_WAITING_FOR_SERVICES;
  uint32_t run = 1;
  uint64_t frame = 0;          // last completed frame
  double sim_time = 0;         // s, of the last completed frame
  uint64_t seed = 0;
  msg::WorldSettings settings;
  msg::WeatherParameters weather;
  msg::Tick open_tick;         // the tick in flight (barrier open)
  Clock::time_point tick_sent;
  Clock::time_point tick_deadline;
  Clock::time_point next_tick_at;  // pacing for real_time_factor > 0
  uint64_t ticks_requested = 0;    // synchronous mode: ticks asked for and not yet started
  std::string map_name;
  std::string map_opendrive;
  std::string map_scene;
  size_t map_traffic_lights = 0;
  std::string failed_service;
  std::string failure_reason;
  Scenario scenario{config.scenario};         // the config's scheduled commands (scenario.cpp)
  Playback playback{OpenRecordedLog, RecordedLogPath};  // CARLA's replay_file: the log's actors follow it
  uint64_t playback_sequence = 0;

  // Statistics.
  std::deque<Clock::time_point> recent_done;
  double barrier_us_sum = 0;
  std::vector<double> barrier_samples;
  uint64_t barrier_count = 0;
  Clock::time_point last_status;
  std::optional<Clock::time_point> first_tick;  // wall time the run's first tick went out
  bool status_dirty = true;

  Writer<msg::Tick> tick_writer;
  Writer<msg::TickLog> tick_log_writer;
  std::vector<msg::Tick> log;  // completed ticks a replay cannot infer (see TickLog in clock.idl)
  uint64_t log_first_frame = 0;  // ticks up to this frame are forgotten (TrimLog)
  std::set<std::string> tick_logs_sent;  // services failed in this fault whose log went out
  std::map<std::string, msg::ServiceSnapshot> snapshots;  // latest of each service (for its replacement)
  Writer<msg::ServiceSnapshot> snapshot_writer;
  Reader<msg::ServiceSnapshot> snapshot_reader;
  Writer<msg::WorldInfo> world_writer;
  Writer<msg::MapData> map_writer;
  Writer<msg::RunStatus> status_writer;
  Writer<msg::FrameDone> done_writer;
  Writer<msg::CommandReply> reply_writer;
  Writer<msg::SpawnCheck> check_writer;
  Writer<msg::ActorList> actors_writer;
  std::map<uint64_t, msg::SpawnCheckReply> check_replies;  // by request id
  uint64_t next_check = 0;
  bool checking = false;                       // the main loop waits for an owner's spawn check
  std::unique_lock<std::mutex>* main_lock = nullptr;  // the main loop's lock on `mu`, while it runs
  // DDS writes happen with `mu` released: a middleware thread may be waiting on
  // `mu` in a callback while a write needs that thread's progress.
  OrderedOutbox outbox;
  template <class T>
  void Post(Writer<T>& w, T sample) {
    outbox.Post([&w, s = std::move(sample)] { w.Write(s); });
  }
  void Flush(std::unique_lock<std::mutex>& lock) { outbox.Flush(lock); }

  Reader<msg::Ack> ack_reader;
  Reader<msg::ServiceAnnounce> service_reader;
  Reader<msg::Command> command_reader;
  Reader<msg::BlueprintSet> blueprint_reader;
  Reader<msg::SpawnCheckReply> check_reply_reader;

  // --- callbacks (middleware threads) ---
  void OnAck(const msg::Ack& a) {
    bool wake = false;
    bool chained = false;
    {
      std::lock_guard<std::mutex> lock(mu);
      const std::string name = a.service().to_string();
      if (members.OnAck(name, run, a, open_tick.frame())) status_dirty = true;
      wake = barrier.OnAck(name, a.run(), a.frame(), a.state_hash()) == TickBarrier::AckResult::kCounted &&
             barrier.Complete();
      if (wake && CanChainSynchronous()) {
        // Synchronous: complete the tick here and start the next one a client asked for,
        // so FrameDone (and the next tick) leave without a hand-off to the main loop.
        const auto now = Clock::now();
        CompleteTick(now);
        StartRequestedTick(now);
        PostDone();
        wake = status_dirty;  // the main loop publishes the status, after FrameDone
        chained = true;
      } else if (wake && CanChainTick()) {
        // Free-running at full speed with nothing else to do: start the next tick from
        // this thread, saving a hand-off to the main loop on every tick.
        const auto now = Clock::now();
        CompleteTick(now);
        StartTick(now);
        PostDone();
        wake = false;
        chained = true;
      }
    }
    if (wake) cv.notify_one();
    if (chained) FlushFromCallback();
  }

  // Synchronous mode, nothing but ticks to do: what the main loop would do next is
  // complete the tick and start the next requested one (or wait for a request).
  bool CanChainSynchronous() const {
    return settings.synchronous_mode() && (state == RunState::RUN_RUNNING || state == RunState::RUN_READY) &&
           inbox.empty() && !checking && !ScheduledDue(open_tick.frame() + 1) && !playback.Busy() && AllAlive();
  }
  bool AllAlive() const {
    for (const auto& name : required_services) {
      const Member* m = members.Find(name);
      if (m == nullptr || !m->alive) return false;
    }
    return true;
  }
  // Synchronous mode with no tick in flight: start one if a client asked for it.
  void StartRequestedTick(Clock::time_point now) {
    SetState(ticks_requested > 0 ? RunState::RUN_RUNNING : RunState::RUN_READY);
    if (ticks_requested > 0) {
      --ticks_requested;
      StartTick(now);
    }
  }

  // The main loop's decisions would be "complete this tick, start the next one".
  bool CanChainTick() const {
    return state == RunState::RUN_RUNNING && !settings.synchronous_mode() && settings.real_time_factor() == 0 &&
           inbox.empty() && !status_dirty && !checking && !ScheduledDue(open_tick.frame() + 1) && !playback.Busy() &&
           (config.ticks == 0 || open_tick.frame() + 1 < config.ticks);
  }

  // The scenario has commands for `for_frame`: its tick starts on the main loop, which
  // may wait for an owner's spawn check.
  bool ScheduledDue(uint64_t for_frame) const { return scenario.Due(for_frame); }

  void FlushFromCallback() {
    std::unique_lock<std::mutex> lock(mu);
    Flush(lock);
  }

  void OnAnnounce(const msg::ServiceAnnounce& a) {
    {
      std::lock_guard<std::mutex> lock(mu);
      if (members.OnAnnounce(a, Clock::now())) status_dirty = true;
    }
    cv.notify_one();
  }

  void OnBlueprints(const msg::BlueprintSet& set) {
    {
      std::lock_guard<std::mutex> lock(mu);
      const std::string name = set.service().to_string();
      if (const Member* m = members.Find(name); m && m->alive && m->blueprints != set.blueprints().size()) {
        // A live member declares once, the count it announces: another set under its name
        // is a second process or a participant that is not it (issue 21, hostile input).
        spdlog::warn("blueprints of '{}' with {} declaration(s) while the live member announced {}: ignored", name,
                     set.blueprints().size(), m->blueprints);
        return;
      }
      commands.library().Declare(set);
      spdlog::info("service '{}' declares {} blueprint(s)", name, set.blueprints().size());
      if (members.OnBlueprints(name, static_cast<long>(set.blueprints().size()))) status_dirty = true;
    }
    cv.notify_one();
  }

  void OnCheckReply(const msg::SpawnCheckReply& r) {
    {
      std::lock_guard<std::mutex> lock(mu);
      check_replies[r.request()] = r;
    }
    cv.notify_one();
  }

  // The library counts the declarations of alive members only.
  void SyncLibrary() {
    commands.library().UpdateAlive([&](const std::string& service) {
      const Member* m = members.Find(service);
      return m != nullptr && m->alive;
    });
    std::vector<std::string> recorders;
    for (const auto& [name, m] : members.members()) {
      if (m.alive && m.kind == "recorder") recorders.push_back(name);
    }
    commands.SetRecorders(std::move(recorders));
  }

  // Asks the owner of `spawn` to check it (blueprint.idl: SpawnCheck) and waits for the
  // answer, at most service_timeout. Runs on the main loop only: `mu` is released while
  // it waits, and `checking` keeps the ack callbacks from starting ticks meanwhile.
  std::string AskOwner(const msg::SpawnActor& spawn) {
    const std::string owner = spawn.owner().to_string();
    if (!commands.library().ChecksSpawns(owner) || main_lock == nullptr) return {};
    msg::SpawnCheck c;
    c.service(owner);
    c.request(++next_check);
    c.run(run);
    c.spawn(spawn);
    const uint64_t id = c.request();
    checking = true;
    Post(check_writer, std::move(c));
    Flush(*main_lock);
    const double timeout = settings.service_timeout();
    const bool answered = cv.wait_until(*main_lock, Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout)),
                                        [&] { return check_replies.count(id) > 0; });
    checking = false;
    if (!answered) return "no answer to the spawn check within " + std::to_string(timeout) + " s";
    const msg::SpawnCheckReply r = check_replies[id];
    check_replies.erase(id);
    return r.accepted() ? std::string() : r.reason().to_string();
  }

  void OnCommand(const msg::Command& c) {
    bool wake = true;
    bool started = false;
    {
      std::lock_guard<std::mutex> lock(mu);
      inbox.push_back(c);
      if (c.body()._d() == msg::CommandKind::CMD_TICK && inbox.size() == 1 && CanChainSynchronous() && !barrier.open()) {
        // A client's tick request while the run waits for one: start the tick from this
        // thread, as the main loop would, without waking it first; the reply goes after
        // the tick, which is on every service's critical path.
        inbox.clear();
        const msg::CommandReply reply = commands.Submit(c, run, frame + 1, true);
        if (reply.accepted()) {
          ticks_requested += c.body().tick_request().count();
        } else {
          spdlog::warn("rejected command {} from '{}': {}", c.sequence_number(), c.client().to_string(), reply.reason().to_string());
        }
        StartRequestedTick(Clock::now());
        Post(reply_writer, reply);
        started = true;
        wake = status_dirty;
      }
    }
    if (wake) cv.notify_one();
    if (started) FlushFromCallback();
  }

  // --- main loop helpers (called with mu held) ---
  void PublishWorld() {
    msg::WorldInfo w;
    w.run(run);
    w.map_name(map_name);
    w.map_hash(MapHash());
    w.settings(settings);
    w.weather(weather);
    w.seed(seed);
    std::vector<msg::ServiceName> required;
    for (const auto& s : config.RequiredServices()) required.emplace_back(s);
    w.required_services(required);
    Post(world_writer, w);
  }

  void PublishMap() {
    msg::MapData m;
    m.run(run);
    m.name(map_name);
    m.opendrive(map_opendrive);
    m.scene(map_scene);
    m.content_hash(MapHash());
    Post(map_writer, m);
  }

  void UseMap(MapContent m) {
    map_name = std::move(m.name);
    map_opendrive = std::move(m.opendrive);
    map_scene = std::move(m.scene);
    map_traffic_lights = m.traffic_lights;
  }

  // Actors every run starts with: the map's traffic lights, ids 1..n in signal order
  // (ground_sim derives the same order from the same map).
  void RegisterMapActors() {
    for (size_t i = 0; i < map_traffic_lights; ++i) commands.AddMapActor("traffic.traffic_light", msg::ACTOR_TRAFFIC_LIGHT);
  }

  void PublishStatus(Clock::time_point now) {
    RunFacts f;
    f.run = run;
    f.state = state;
    f.frame = frame;
    f.sim_time = sim_time;
    f.tick_rate_hz = TickRate(&recent_done, now);
    f.fixed_delta_seconds = settings.fixed_delta_seconds();
    f.diverged = Diverged(false);
    f.failed_service = failed_service;
    // A fault names who waits for the failed service's replacement (membership.cpp).
    f.reason = state == RunState::RUN_FAULTED && barrier.open()
                   ? members.FaultReason(failure_reason, failed_service, run, barrier.frame())
                   : failure_reason;
    Post(status_writer, MakeRunStatus(f, members));
    last_status = now;
    status_dirty = false;
  }

  // What a replacement of `service` needs to rebuild its state by replay.
  void PublishTickLog(const std::string& service) {
    msg::TickLog l;
    l.run(run);
    l.service(service);
    if (const Member* m = members.Find(service)) {
      l.last_frame(m->last_frame);
      l.last_hash(m->last_hash);
    }
    l.frames(frame);
    l.ticks(log);
    l.first_frame(log_first_frame);
    spdlog::info("tick log of {} frame(s) ({} kept, from frame {}) published for a replacement of '{}'", frame, log.size(),
                 log_first_frame + 1, service);
    Post(tick_log_writer, std::move(l));
    // The failed process's own snapshot went with it: give its replacement the copy.
    if (auto it = snapshots.find(service); it != snapshots.end() && it->second.run() == run) {
      Post(snapshot_writer, it->second);
    }
    tick_logs_sent.insert(service);
  }

  // A member of this run reported divergence (required ones only, for FrameDone).
  bool Diverged(bool required_only) const {
    for (const auto& [name, m] : members.members()) {
      if (m.run == run && !m.divergence.empty() && (m.required || !required_only)) return true;
    }
    return false;
  }

  // Forgets the logged ticks no replacement needs: those up to the smallest replay_from of
  // the required services (their latest snapshot; what the coordinator holds of it). The
  // first kept tick is then the one after, written out in full, so replay infers from it.
  void TrimLog() {
    if (frame == 0) return;
    uint64_t keep_after = frame - 1;  // the last completed tick stays: later ones are inferred from it
    for (const auto& name : required_services) {
      const Member* m = members.Find(name);
      uint64_t from = m && m->run == run ? m->replay_from : 0;
      if (m && m->last_hash != 0 && from != m->last_frame) {
        // It rebuilds from a snapshot: only from one the coordinator holds a copy of (its
        // newest may still be on the way here).
        auto it = snapshots.find(name);
        from = it != snapshots.end() && it->second.run() == run ? std::min(from, it->second.frame()) : 0;
      }
      keep_after = std::min(keep_after, from);
    }
    ticklog::Trim(&log, &log_first_frame, keep_after);  // the rule replay follows (runtime/tick_log.h)
  }

  void SetState(RunState next) {
    if (next == state) return;
    if (next == RunState::RUN_FAULTED && !failed_service.empty() && !tick_logs_sent.count(failed_service)) {
      PublishTickLog(failed_service);
    }
    // Synchronous mode goes ready -> running -> ready on every tick: keep that quiet.
    const bool routine = (state == RunState::RUN_READY && next == RunState::RUN_RUNNING) ||
                         (state == RunState::RUN_RUNNING && next == RunState::RUN_READY);
    spdlog::log(routine ? spdlog::level::debug : spdlog::level::info, "run {} frame {}: {} -> {}", run, frame,
                RunStateName(state), RunStateName(next));
    state = next;
    // The routine ones go out with the next periodic status (at most 500 ms later): two
    // statuses per tick went to every service and client.
    if (!routine) status_dirty = true;
  }

  // Starts a new run (reset or new map): actors gone, frame 0.
  void NewRun(uint64_t new_seed) {
    ++run;
    if (new_seed != 0) seed = new_seed;
    frame = 0;
    sim_time = 0;
    members.NewRun(run);
    log_first_frame = 0;
    tick_logs_sent.clear();
    barrier.Close();
    commands.ResetActors();
    RegisterMapActors();
    log.clear();
    ticks_requested = 0;
    scenario.Restart();
    playback.NewRun();
    PublishWorld();
    PublishMap();
    status_dirty = true;
    spdlog::info("run {} begins (map '{}', seed {})", run, map_name, seed);
  }

  void HandleCommands() {
    while (!inbox.empty()) {
      msg::Command c = std::move(inbox.front());
      inbox.pop_front();
      msg::CommandReply reply;
      const auto kind = c.body()._d();
      // A map must load and parse before the command is accepted.
      std::optional<MapContent> new_map;
      if (kind == msg::CommandKind::CMD_LOAD_MAP) {
        std::string why;
        try {
          new_map = MapToLoad(c.body().load_map(), map_name);
        } catch (const std::exception& e) {
          why = e.what();
        }
        if (!why.empty()) {
          reply.client(c.client());
          reply.sequence_number(c.sequence_number());
          reply.accepted(false);
          reply.reason(why.substr(0, 511));
          spdlog::warn("rejected load_map from '{}': {}", c.client().to_string(), why);
          Post(reply_writer, reply);
          continue;
        }
      }
      // replay_file: the log must open and be of this map before the command is accepted.
      if (kind == msg::CommandKind::CMD_RECORDER && c.body().recorder().action() == msg::RecorderAction::REPLAY_START &&
          CheckReplayCommand(c.body().recorder()).empty()) {
        std::string text;
        const std::string why = playback.Prepare(c.body().recorder(), map_name, MapHash(), &text);
        if (!why.empty()) {
          reply.client(c.client());
          reply.sequence_number(c.sequence_number());
          reply.run(run);
          reply.accepted(false);
          reply.reason(why.substr(0, 511));
          reply.text(text.substr(0, 1023));
          spdlog::warn("rejected replay_file from '{}': {}", c.client().to_string(), why);
          Post(reply_writer, reply);
          continue;
        }
      }
      SyncLibrary();
      reply = commands.Submit(c, run, frame + 1 + (barrier.open() ? 1 : 0), settings.synchronous_mode(),
                              [this](const msg::SpawnActor& s) { return AskOwner(s); });
      if (reply.accepted()) {
        switch (kind) {
          case msg::CommandKind::CMD_RECORDER: {
            const auto action = c.body().recorder().action();
            if (IsReplayAction(action)) {
              // CARLA's replay_file stops a recording in course first (ACarlaRecorder::ReplayFile).
              if (action == msg::RecorderAction::REPLAY_START && !commands.recording().empty()) {
                msg::Command stop;
                stop.client("playback");
                stop.sequence_number(++playback_sequence);
                msg::RecorderCommand r;
                r.action(msg::RecorderAction::RECORDER_STOP);
                stop.body().recorder(r);
                commands.Submit(stop, run, reply.frame(), settings.synchronous_mode());
              }
              reply.text(playback.Apply(c.body().recorder()).substr(0, 1023));
            } else if (action == msg::RecorderAction::RECORDER_START && playback.Busy()) {
              // CARLA's start_recorder stops the replayer first (ACarlaRecorder::Start: Replayer.Stop()).
              msg::RecorderCommand stop;
              stop.action(msg::RecorderAction::REPLAY_STOP);
              stop.flag(false);
              playback.Apply(stop);
            }
            break;
          }
          case msg::CommandKind::CMD_TICK:
            ticks_requested += c.body().tick_request().count();
            break;
          case msg::CommandKind::CMD_SET_WEATHER:
            weather = c.body().weather();
            PublishWorld();
            break;
          case msg::CommandKind::CMD_SET_WORLD_SETTINGS:
            settings = c.body().world_settings();
            PublishWorld();
            break;
          case msg::CommandKind::CMD_RESET:
            commands.TakePending();
            NewRun(c.body().reset().seed());
            reply.run(run);
            reply.frame(1);
            break;
          case msg::CommandKind::CMD_LOAD_MAP: {
            commands.TakePending();
            if (new_map) UseMap(std::move(*new_map));
            NewRun(0);
            reply.run(run);
            reply.frame(1);
            break;
          }
          default:
            break;
        }
      } else {
        spdlog::warn("rejected command {} from '{}': {}", c.sequence_number(), c.client().to_string(), reply.reason().to_string());
      }
      Post(reply_writer, reply);
    }
  }

  void StartTick(Clock::time_point now) {
    if (!first_tick) first_tick = now;
    msg::Tick t;
    t.run(run);
    t.frame(frame + 1);
    t.dt(settings.fixed_delta_seconds());
    t.sim_time(sim_time + settings.fixed_delta_seconds());
    t.seed(seed);
    std::vector<msg::Command> client = commands.TakePending();
    std::vector<msg::Command> batch = Scheduled(t.frame());
    batch.insert(batch.end(), client.begin(), client.end());
    std::vector<msg::Command> replayed = Replayed(t.frame(), t.dt());
    batch.insert(batch.end(), replayed.begin(), replayed.end());
    t.commands(std::move(batch));
    open_tick = t;
    ListActors(t);
    SendOpenTick(now);
  }

  // lockstep/actors: the spawns of the live actors, re-published when a tick changes them.
  ActorRoster roster;
  void ListActors(const msg::Tick& t) {
    if (auto list = roster.Apply(t)) Post(actors_writer, std::move(*list));
  }

  // Opens the barrier for open_tick and sends it. A re-send after a fault has the same
  // frame and commands: services that already did it ack again.
  void SendOpenTick(Clock::time_point now) {
    barrier.Open(run, open_tick.frame(), required_services);
    tick_sent = now;
    tick_deadline = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(settings.service_timeout()));
    Post(tick_writer, open_tick);
  }

  // The scenario's commands for `for_frame`, validated like a client's, aliases resolved.
  std::vector<msg::Command> Scheduled(uint64_t for_frame) {
    scenario.Submit(for_frame, [&](const msg::Command& c) {
      SyncLibrary();
      return commands.Submit(c, run, for_frame, settings.synchronous_mode(), [this](const msg::SpawnActor& s) { return AskOwner(s); });
    });
    return commands.TakePending();
  }

  // A replay's commands for `for_frame` (after the scenario's and the clients'), submitted
  // as a client's under the name "playback". Main loop only (Busy() stops the chaining).
  std::vector<msg::Command> Replayed(uint64_t for_frame, double dt) {
    if (!playback.Busy()) return {};
    SyncLibrary();
    playback.Tick(
        dt,
        [&](const msg::CommandBody& body) {
          msg::Command c;
          c.client("playback");
          c.sequence_number(++playback_sequence);
          c.body(body);
          msg::CommandReply r = commands.Submit(c, run, for_frame, settings.synchronous_mode(),
                                                [this](const msg::SpawnActor& s) { return AskOwner(s); });
          if (!r.accepted()) spdlog::debug("playback command refused: {}", r.reason().to_string());
          return r;
        },
        [this](uint32_t id) -> const std::string* {
          const auto& actors = commands.actors();
          auto it = actors.find(id);
          return it == actors.end() ? nullptr : &it->second.blueprint;
        });
    return commands.TakePending();
  }

  uint64_t MapHash() const { return Fnv1a64().Add(std::string_view(map_opendrive)).Add(std::string_view(map_scene)).value(); }

  // Before the process goes: the last FrameDone and RunStatus must reach their readers.
  void DrainWriters() {
    done_writer.WaitForAcknowledgments(1.0);
    status_writer.WaitForAcknowledgments(1.0);
    reply_writer.WaitForAcknowledgments(1.0);
  }

  // FrameDone goes out after the next Tick when both are due: the tick is on the
  // critical path of every service, the FrameDone only of clients.
  std::optional<msg::FrameDone> done_pending;
  void PostDone() {
    if (!done_pending) return;
    Post(done_writer, *done_pending);
    done_pending.reset();
  }

  void LogSummary(Clock::time_point now) const {
    if (!first_tick || frame == 0) return;
    const double wall = std::chrono::duration<double>(now - *first_tick).count();
    spdlog::info("finished {} ticks in {:.3f} s wall: {:.1f} ticks/s, real-time factor {:.2f}, mean barrier {:.1f} us",
                 frame, wall, frame / wall, sim_time / wall, barrier_count ? barrier_us_sum / barrier_count : 0.0);
  }

  void CompleteTick(Clock::time_point now) {
    frame = open_tick.frame();
    sim_time = open_tick.sim_time();
    msg::FrameDone d;
    d.run(run);
    d.frame(frame);
    d.sim_time(sim_time);
    d.world_hash(barrier.WorldHash());
    d.diverged(Diverged(true));
    barrier.Close();
    ticklog::Append(&log, open_tick);  // what a replay cannot infer (runtime/tick_log.h)
    TrimLog();
    done_pending = d;  // posted by PostDone, after the next tick when one follows at once
    const double us = std::chrono::duration<double, std::micro>(now - tick_sent).count();
    barrier_us_sum += us;
    if (barrier_samples.size() < 100000) barrier_samples.push_back(us);
    ++barrier_count;
    recent_done.push_back(now);
    while (recent_done.size() > 4096) recent_done.pop_front();
  }
};

Coordinator::Coordinator(Bus& bus, LaunchConfig config) : impl_(std::make_unique<Impl>(bus, std::move(config))) {
  auto& s = *impl_;
  ValidateWorldSettings(s.config.world, s.config.source + ": world");
  s.seed = s.config.seed;
  s.settings = s.config.world;
  s.weather = DefaultWeather();
  if (!s.config.map.empty()) s.UseMap(ReadMap(s.config.map));
  s.RegisterMapActors();
  s.tick_writer = Writer<msg::Tick>(bus, topics::kTick);
  s.tick_log_writer = Writer<msg::TickLog>(bus, topics::kTickLog);
  s.world_writer = Writer<msg::WorldInfo>(bus, topics::kWorldInfo);
  s.map_writer = Writer<msg::MapData>(bus, topics::kMap);
  s.status_writer = Writer<msg::RunStatus>(bus, topics::kRunStatus);
  s.done_writer = Writer<msg::FrameDone>(bus, topics::kFrameDone);
  s.reply_writer = Writer<msg::CommandReply>(bus, topics::kCommandReply);
  s.check_writer = Writer<msg::SpawnCheck>(bus, topics::kSpawnCheck);
  s.actors_writer = Writer<msg::ActorList>(bus, topics::kActors);
  s.snapshot_writer = Writer<msg::ServiceSnapshot>(bus, topics::kSnapshot);
  {
    std::unique_lock<std::mutex> lock(s.mu);
    s.PublishWorld();
    s.PublishMap();
    s.Flush(lock);
  }
  s.ack_reader = Reader<msg::Ack>(bus, topics::kAck, [&s](const msg::Ack& a, const SampleInfo&) { s.OnAck(a); });
  s.service_reader = Reader<msg::ServiceAnnounce>(bus, topics::kService,
                                                  [&s](const msg::ServiceAnnounce& a, const SampleInfo&) { s.OnAnnounce(a); });
  s.command_reader = Reader<msg::Command>(bus, topics::kCommand, [&s](const msg::Command& c, const SampleInfo&) { s.OnCommand(c); });
  s.snapshot_reader = Reader<msg::ServiceSnapshot>(bus, topics::kSnapshot, [&s](const msg::ServiceSnapshot& snap, const SampleInfo& info) {
    if (info.writer_id == s.snapshot_writer.id()) return;  // our own copy for a replacement
    std::unique_lock<std::mutex> lock(s.mu);
    if (snap.run() != s.run) return;
    s.snapshots[snap.service().to_string()] = snap;
    // A snapshot of a failed process that arrives after its tick log: pass it on too.
    if (s.tick_logs_sent.count(snap.service().to_string())) {
      s.Post(s.snapshot_writer, snap);
      s.Flush(lock);
    }
  });
  s.blueprint_reader = Reader<msg::BlueprintSet>(bus, topics::kBlueprints,
                                                 [&s](const msg::BlueprintSet& b, const SampleInfo&) { s.OnBlueprints(b); });
  s.check_reply_reader = Reader<msg::SpawnCheckReply>(bus, topics::kSpawnCheckReply,
                                                      [&s](const msg::SpawnCheckReply& r, const SampleInfo&) { s.OnCheckReply(r); });
}

Coordinator::~Coordinator() = default;

CoordinatorStats Coordinator::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  CoordinatorStats st;
  st.frames = impl_->frame;
  st.mean_barrier_us = impl_->barrier_count ? impl_->barrier_us_sum / impl_->barrier_count : 0;
  st.barrier_us = impl_->barrier_samples;
  const auto& r = impl_->recent_done;
  if (r.size() >= 2) {
    st.tick_rate_hz = (r.size() - 1) / std::chrono::duration<double>(r.back() - r.front()).count();
  }
  return st;
}

int Coordinator::Run(const std::atomic<bool>& stop) {
  auto& s = *impl_;
  std::unique_lock<std::mutex> lock(s.mu);
  s.main_lock = &lock;
  spdlog::info("coordinator on {}: waiting for {} required service(s)", s.bus.Describe(), s.config.RequiredServices().size());
  s.next_tick_at = Clock::now();
  while (!stop) {
    const auto now = Clock::now();
    s.HandleCommands();
    if (s.members.CheckHeartbeats(now)) s.status_dirty = true;

    std::string failed;
    const std::string why = s.members.FirstMissing(&failed);
    if (!why.empty()) {
      if (s.state == RunState::RUN_RUNNING || s.state == RunState::RUN_READY ||
          (s.state == RunState::RUN_FAULTED && failed != s.failed_service)) {
        s.failed_service = failed;
        s.failure_reason = "service '" + failed + "' " + why;
        spdlog::error("stopping the clock at frame {}: {}", s.frame, s.failure_reason);
        s.SetState(RunState::RUN_FAULTED);
      }
      if (s.state == RunState::RUN_FAULTED) {
        // Every required service that failed gets the log for its replacement, also one
        // that fails while the run is already faulted.
        for (const auto& [name, reason] : s.members.Missing()) {
          const Member* m = s.members.Find(name);
          if (m && !m->failure.empty() && !s.tick_logs_sent.count(name)) {
            spdlog::error("service '{}' {} (the run is already faulted)", name, reason);
            s.PublishTickLog(name);
          }
        }
      }
    } else if (s.state == RunState::RUN_WAITING_FOR_SERVICES || s.state == RunState::RUN_FAULTED) {
      if (s.state == RunState::RUN_FAULTED) spdlog::info("all required services are back: resuming at frame {}", s.frame + 1);
      s.failed_service.clear();
      s.failure_reason.clear();
      s.tick_logs_sent.clear();
      s.SetState(s.settings.synchronous_mode() ? RunState::RUN_READY : RunState::RUN_RUNNING);
      if (s.barrier.open()) s.SendOpenTick(now);
    }

    const bool active = s.state == RunState::RUN_RUNNING || s.state == RunState::RUN_READY;
    Clock::time_point wake = now + std::chrono::milliseconds(100);
    if (active && s.barrier.open()) {
      if (s.barrier.Complete()) {
        s.CompleteTick(now);
        if (s.config.ticks > 0 && s.frame >= s.config.ticks && !s.settings.synchronous_mode()) {
          s.SetState(RunState::RUN_STOPPED);
          s.PostDone();
          s.PublishStatus(now);
          s.Flush(lock);
          s.LogSummary(now);
          s.main_lock = nullptr;
          lock.unlock();
          s.DrainWriters();
          return 0;
        }
      } else if (now >= s.tick_deadline) {
        std::string missing;
        for (const auto& m : s.barrier.Missing()) missing += (missing.empty() ? "" : ", ") + m;
        s.failed_service = s.barrier.Missing().front();
        s.failure_reason = "service '" + s.failed_service + "' did not acknowledge frame " + std::to_string(s.barrier.frame()) +
                           " within " + std::to_string(s.settings.service_timeout()) + " s (missing: " + missing + ")";
        s.members.MarkStalled(s.failed_service, s.barrier.frame());
        spdlog::error("stopping the clock: {}", s.failure_reason);
        s.SetState(RunState::RUN_FAULTED);
        s.Flush(lock);
        continue;
      } else {
        wake = std::min(wake, s.tick_deadline);
      }
    }
    if (active && !s.barrier.open()) {
      if (s.settings.synchronous_mode()) {
        s.StartRequestedTick(now);
      } else {
        s.SetState(RunState::RUN_RUNNING);
        const double rtf = s.settings.real_time_factor();
        if (rtf > 0 && now < s.next_tick_at) {
          wake = std::min(wake, s.next_tick_at);
        } else {
          if (rtf > 0) {
            const auto period = std::chrono::duration_cast<Clock::duration>(
                std::chrono::duration<double>(s.settings.fixed_delta_seconds() / rtf));
            // Keep the pace without bursting after a stall.
            s.next_tick_at = std::max(s.next_tick_at + period, now);
          }
          s.StartTick(now);
        }
      }
    }

    s.PostDone();
    if (s.status_dirty || now - s.last_status > std::chrono::milliseconds(500)) s.PublishStatus(now);
    s.Flush(lock);
    if (s.barrier.open() && s.barrier.Complete()) continue;
    s.cv.wait_until(lock, wake, [&] {
      return stop || !s.inbox.empty() || s.status_dirty || (s.barrier.open() && s.barrier.Complete());
    });
  }
  s.SetState(RunState::RUN_STOPPED);
  s.PostDone();
  s.PublishStatus(Clock::now());
  s.Flush(lock);
  s.LogSummary(Clock::now());
  s.main_lock = nullptr;
  lock.unlock();
  s.DrainWriters();
  return 0;
}

}  // namespace lockstep
