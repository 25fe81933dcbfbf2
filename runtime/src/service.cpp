#include "lockstep/runtime/service.h"

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>

#include "lockstep/runtime/error.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/tick_log.h"

namespace lockstep {

using Clock = std::chrono::steady_clock;

namespace {
// Thrown when the runner is told to stop while it waits for the coordinator.
struct Stopped {};
}  // namespace

struct ServiceRunner::Impl {
  Impl(Bus& b, ServiceOptions o, ServiceCore& c) : bus(b), options(std::move(o)), core(c) {}

  Bus& bus;
  ServiceOptions options;
  ServiceCore& core;
  const std::string host = [] {
    char h[64] = {};
    gethostname(h, sizeof h - 1);
    return std::string(h);
  }();

  std::mutex mu;
  std::mutex step_mu;                    // one step at a time, whichever thread runs it
  std::condition_variable cv;            // ticks and world info arrived
  std::condition_variable heartbeat_cv;  // wakes the heartbeat thread to stop
  std::deque<msg::Tick> ticks;
  std::optional<msg::WorldInfo> world;
  std::optional<msg::ServiceSnapshot> snapshot;  // our own last snapshot, for a replacement
  std::optional<msg::TickLog> tick_log;          // the run's ticks, published when we failed
  std::optional<msg::RunStatus> status;          // the coordinator's latest run status
  std::deque<msg::SpawnCheck> checks;            // spawn checks for us, answered between steps
  const std::vector<msg::BlueprintDeclaration> blueprints = core.Blueprints();

  std::atomic<uint32_t> run{0};
  std::atomic<uint64_t> last_frame{0};
  uint64_t last_hash = 0;
  bool can_snapshot = true;
  uint64_t snapshot_frame = 0;  // frame of our latest snapshot reported in acks (published or restored)
  uint64_t published_snapshot = 0;  // our latest published snapshot: reported from the next ack on, so
                                    // replay_from equals last_frame only for a service with no state
  std::string divergence;       // why our state is not the one the tick stream defines (this run)
  std::string failure;          // why the service stopped, if a step failed (guarded by mu)
  std::atomic<bool> joined{false};

  Writer<msg::Ack> ack;
  Writer<msg::ServiceAnnounce> announce;
  Writer<msg::ServiceSnapshot> snapshot_writer;
  Writer<msg::BlueprintSet> blueprint_writer;
  Writer<msg::SpawnCheckReply> check_reply_writer;
  Reader<msg::SpawnCheck> check_reader;
  Reader<msg::Tick> tick_reader;
  Reader<msg::WorldInfo> world_reader;
  Reader<msg::ServiceSnapshot> snapshot_reader;
  Reader<msg::TickLog> tick_log_reader;
  Reader<msg::RunStatus> status_reader;

  void Announce(msg::ServiceState state) {
    msg::ServiceAnnounce a;
    a.service(options.name);
    a.kind(options.kind);
    a.perception(options.perception);
    a.state(state);
    a.pid(static_cast<int32_t>(getpid()));
    a.host(host);
    a.last_frame(last_frame);
    a.blueprints(static_cast<uint32_t>(blueprints.size()));
    if (state == msg::ServiceState::SERVICE_STOPPING) {
      std::lock_guard<std::mutex> lock(mu);
      a.reason(failure.substr(0, 255));
    }
    announce.Write(a);
  }

  void PublishBlueprints() {
    msg::BlueprintSet set;
    set.service(options.name);
    set.blueprints(blueprints);
    set.checks_spawns(!blueprints.empty());
    blueprint_writer.Write(set);
  }

  // Answers the spawn checks queued for us (called with step_mu held, never during a step).
  void AnswerChecks() {
    for (;;) {
      msg::SpawnCheck c;
      {
        std::lock_guard<std::mutex> lock(mu);
        if (checks.empty()) return;
        c = std::move(checks.front());
        checks.pop_front();
      }
      std::string why;
      try {
        why = core.CheckSpawn(c.spawn());
      } catch (const std::exception& e) {
        why = std::string("the spawn check threw: ") + e.what();
      }
      msg::SpawnCheckReply r;
      r.service(options.name);
      r.request(c.request());
      r.accepted(why.empty());
      r.reason(why.substr(0, 511));
      check_reply_writer.Write(r);
    }
  }

  void SendAck(uint64_t frame, double wall_us) {
    msg::Ack a;
    a.service(options.name);
    a.run(run);
    a.frame(frame);
    a.state_hash(last_hash);
    a.step_wall_us(wall_us);
    a.divergence(divergence.substr(0, 255));
    // What a replacement would replay: after our snapshot; nothing if we keep no state.
    a.replay_from(snapshot_frame != 0 ? snapshot_frame : (!can_snapshot && last_hash == 0 ? last_frame.load() : 0));
    ack.Write(a);
  }

  void PublishSnapshot() {
    if (!can_snapshot || options.snapshot_period == 0 || last_frame % options.snapshot_period != 0) return;
    std::vector<uint8_t> state = core.SaveState();
    if (state.empty()) {
      can_snapshot = false;  // stateless or not restorable: stop trying
      return;
    }
    msg::ServiceSnapshot s;
    s.service(options.name);
    s.run(run);
    s.frame(last_frame);
    s.state_hash(last_hash);
    s.state(std::move(state));
    snapshot_writer.Write(s);
    published_snapshot = last_frame;
  }

  bool failed() {
    std::lock_guard<std::mutex> lock(mu);
    return !failure.empty();
  }
  void Fail(const std::string& why) {
    {
      std::lock_guard<std::mutex> lock(mu);
      if (failure.empty()) failure = "step failed at frame " + std::to_string(last_frame.load() + 1) + ": " + why;
    }
    cv.notify_all();
  }

  void Diverge(const std::string& why) {
    spdlog::error("diverged: {}", why);
    if (divergence.empty()) divergence = why;
  }

  void NewRun(const msg::WorldInfo& w) {
    run = w.run();
    core.BeginRun(w);
    last_frame = 0;
    last_hash = 0;
    can_snapshot = true;
    snapshot_frame = 0;
    published_snapshot = 0;
    divergence.clear();
  }

  // Waits for world info of `wanted_run` (0 = any).
  msg::WorldInfo WaitWorld(uint32_t wanted_run, const std::atomic<bool>& stop) {
    std::unique_lock<std::mutex> lock(mu);
    const Clock::time_point deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.world_info_timeout_s));
    while (!stop) {
      if (world && world->run() >= wanted_run) return *world;  // a newer run supersedes the one wanted
      if (cv.wait_until(lock, std::min<Clock::time_point>(deadline, Clock::now() + std::chrono::milliseconds(100))) ==
              std::cv_status::timeout &&
          Clock::now() >= deadline) {
        throw JoinTimeout("service '" + options.name + "': no world info from a coordinator within " +
                         std::to_string(options.world_info_timeout_s) + " s (is it running on this DDS domain?)");
      }
    }
    throw Stopped{};
  }

  // Join: restore from our last snapshot when the run is already under way.
  void Join(const std::atomic<bool>& stop) {
    NewRun(WaitWorld(0, stop));
    std::optional<msg::Tick> current;
    std::optional<msg::ServiceSnapshot> snap;
    bool replacing = true;
    {
      // World info and the current tick arrive on different topics: when the run is
      // under way (its status shows completed frames), wait until the tick is here too.
      std::unique_lock<std::mutex> lock(mu);
      const auto deadline = Clock::now() + std::chrono::seconds(5);
      auto status_known = [&] { return status && status->run() == run; };
      auto tick_known = [&] { return !ticks.empty() && ticks.back().run() == run; };
      cv.wait_until(lock, std::min<Clock::time_point>(deadline, Clock::now() + std::chrono::seconds(2)),
                    [&] { return stop || status_known(); });
      // Under way: frames done, or a first tick out (a status from before the latest may
      // still show frame 0 while running).
      if (status_known() && (status->frame() > 0 || status->state() == msg::RunState::RUN_RUNNING ||
                             status->state() == msg::RunState::RUN_FAULTED)) {
        cv.wait_until(lock, deadline, [&] { return stop || tick_known(); });
      }
      if (!ticks.empty() && ticks.back().run() == run) current = ticks.back();
      replacing = Predecessor();
    }
    if (current && current->frame() > 1) {
      // The run is under way: take over at our snapshot (the coordinator keeps a copy of
      // the last one of the process we replace), then replay the run's ticks after it
      // (published by the coordinator when that process failed). A newcomer (the run never
      // had a member of our name) has no log to wait for: it joins without the past.
      std::optional<msg::TickLog> log = replacing ? WaitTickLog(current->frame() - 1, stop) : std::nullopt;
      // Take over after the last completed frame: the open tick, or the one after the log's.
      uint64_t to = log ? std::max<uint64_t>(log->frames(), current->frame() - 1) : current->frame() - 1;
      // The process we replace may have stepped the open tick and sent its snapshot before
      // it died (the coordinator then holds that one): the state after the open tick is
      // as good, and the re-sent tick is then acked without stepping it again.
      const uint64_t newest_usable = std::max(to, current->frame());
      {
        // A log that forgot ticks needs a snapshot at least as new: wait for its copy.
        std::unique_lock<std::mutex> lock(mu);
        auto usable = [&] {
          return snapshot && snapshot->run() == run && snapshot->frame() <= newest_usable &&
                 (!log || snapshot->frame() >= log->first_frame());
        };
        // (Not for a service that keeps no state, hash 0: it has no snapshot to wait for.)
        if (log && log->first_frame() > 0 && log->last_hash() != 0) {
          cv.wait_for(lock, std::chrono::seconds(5), [&] { return stop || usable(); });
        }
        if (usable()) snap = snapshot;
      }
      uint64_t restored = 0;
      if (snap) {
        core.RestoreState(snap->state());
        restored = snap->frame();
        snapshot_frame = published_snapshot = restored;
        spdlog::info("restored the snapshot of frame {}", restored);
      }
      if (restored > to) {
        to = restored;  // the open tick's own snapshot: nothing to replay
      } else if (log && log->first_frame() <= restored) {
        restored = Replay(*log, restored, to);
      } else if (log && log->last_hash() == 0 && core.StateHash() == 0) {
        spdlog::info("keeps no state: took over at frame {}", to);  // nothing to rebuild
      } else if (log) {
        Diverge("the tick log starts after frame " + std::to_string(log->first_frame()) + " and no snapshot of frame " +
                std::to_string(log->first_frame()) + " or later is here: joined run " + std::to_string(run.load()) +
                " at frame " + std::to_string(to) + " without its past");
      } else if (restored < to) {
        Diverge(std::string(replacing ? "no tick log" : "a newcomer") + ": joined run " + std::to_string(run.load()) + " at frame " + std::to_string(to) +
                " without its past" + (restored ? " (snapshot of frame " + std::to_string(restored) + ")" : std::string()));
      }
      last_frame = to;
      last_hash = core.StateHash();
    } else if (current) {
      last_frame = current->frame() - 1;
    }
    // An ack before the first tick tells the coordinator where we stand.
    SendAck(last_frame, 0);
    Announce(msg::ServiceState::SERVICE_READY);
    joined = true;
  }

  // True unless the run status shows we are a newcomer: frames were done in this run while
  // no member of our name took part (none listed, or listed with no acked frame, no
  // failure, and no pid but ours: our own STARTING announcement). Only then the
  // coordinator publishes no tick log for us. A status from before any frame cannot tell:
  // then assume a predecessor (waiting for a log is the safe side). Call with mu held.
  bool Predecessor() const {
    if (!status || status->run() != run || status->frame() == 0) return true;
    for (const auto& m : status->members()) {
      if (m.service().to_string() != options.name) continue;
      return m.last_frame() > 0 || !m.failure().to_string().empty() || (m.pid() != 0 && m.pid() != static_cast<int32_t>(getpid()));
    }
    return false;
  }

  // The tick log of the current run covering `frame`, if the coordinator has one.
  std::optional<msg::TickLog> WaitTickLog(uint64_t frame, const std::atomic<bool>& stop) {
    std::unique_lock<std::mutex> lock(mu);
    const auto deadline = Clock::now() + std::chrono::seconds(5);
    auto ready = [&] {
      return tick_log && tick_log->run() == run && tick_log->service().to_string() == options.name &&
             !tick_log->ticks().empty() && tick_log->frames() >= frame;
    };
    while (!stop && !ready() && Clock::now() < deadline) cv.wait_until(lock, deadline);
    if (!ready()) return std::nullopt;
    return tick_log;
  }

  // Steps the core through the logged ticks after `from` up to `to` without publishing;
  // checks the state hash against what the failed service acknowledged.
  uint64_t Replay(const msg::TickLog& log, uint64_t from, uint64_t to) {
    core.replaying_ = true;
    uint64_t n = 0;
    ticklog::Cursor logged(log.ticks());
    for (uint64_t f = std::max<uint64_t>(from, log.first_frame()) + 1; f <= to; ++f) {
      core.Step(logged.At(f));
      ++n;
    }
    core.replaying_ = false;
    const uint64_t hash = core.StateHash();
    if (log.last_frame() == to && log.last_hash() != 0) {
      if (hash == log.last_hash()) {
        spdlog::info("rebuilt frame {} by replaying {} tick(s): state hash {:016x} matches", to, n, hash);
      } else {
        char why[200];
        std::snprintf(why, sizeof why, "replayed %llu tick(s) to frame %llu but the state hash %016llx differs from the acknowledged %016llx",
                      static_cast<unsigned long long>(n), static_cast<unsigned long long>(to), static_cast<unsigned long long>(hash),
                      static_cast<unsigned long long>(log.last_hash()));
        Diverge(why);
      }
    } else {
      spdlog::info("rebuilt frame {} by replaying {} tick(s)", to, n);
    }
    return to;
  }

  void Handle(const msg::Tick& tick, const std::atomic<bool>& stop) {
    if (tick.run() < run) return;  // a tick of a run already superseded
    if (tick.run() != run) {
      msg::WorldInfo w = WaitWorld(tick.run(), stop);
      if (w.run() != tick.run()) {
        // Two quick resets: this tick's run is over before it began here. Skip it; the
        // newest run's ticks follow.
        spdlog::info("skipping tick {} of run {}: run {} superseded it", tick.frame(), tick.run(), w.run());
        return;
      }
      NewRun(w);
    }
    if (tick.frame() <= last_frame) {
      SendAck(tick.frame(), 0);  // a re-sent tick we already did: ack again, idempotent
      return;
    }
    if (tick.frame() != last_frame + 1) {
      Diverge("tick " + std::to_string(tick.frame()) + " arrived after frame " + std::to_string(last_frame.load()) + ": " +
              std::to_string(tick.frame() - last_frame - 1) + " frame(s) missed");
    }
    const auto t0 = Clock::now();
    core.Step(tick);
    last_frame = tick.frame();
    last_hash = core.StateHash();
    snapshot_frame = published_snapshot;
    PublishSnapshot();
    const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    SendAck(tick.frame(), us);
  }
};

ServiceRunner::ServiceRunner(Bus& bus, ServiceOptions options, ServiceCore& core)
    : impl_(std::make_unique<Impl>(bus, std::move(options), core)) {
  auto& s = *impl_;
  if (s.options.name.empty()) throw InputError("a service needs a name");
  if (s.options.snapshot_period > MaxSnapshotPeriod()) {
    throw InputError("service '" + s.options.name + "': snapshot period " + std::to_string(s.options.snapshot_period) +
                     " frames is longer than the " + std::to_string(MaxSnapshotPeriod()) +
                     " frames of inputs the state topics keep for a replay");
  }
  // AwaitInput holds while another service's failure stops the run (no cascade).
  core.run_faulted_by_ = [&s]() -> std::string {
    std::lock_guard<std::mutex> lock(s.mu);
    if (!s.status || s.status->run() != s.run || s.status->state() != msg::RunState::RUN_FAULTED) return {};
    const std::string failed = s.status->failed_service().to_string();
    if (failed == s.options.name) return {};
    return failed.empty() ? std::string("the run") : failed;
  };
  s.ack = Writer<msg::Ack>(bus, topics::kAck);
  s.announce = Writer<msg::ServiceAnnounce>(bus, topics::kService);
  s.snapshot_writer = Writer<msg::ServiceSnapshot>(bus, topics::kSnapshot);
  s.blueprint_writer = Writer<msg::BlueprintSet>(bus, topics::kBlueprints);
  s.check_reply_writer = Writer<msg::SpawnCheckReply>(bus, topics::kSpawnCheckReply);
  s.check_reader = Reader<msg::SpawnCheck>(bus, topics::kSpawnCheck, [&s](const msg::SpawnCheck& c, const SampleInfo&) {
    if (c.service() != s.options.name) return;
    {
      std::lock_guard<std::mutex> lock(s.mu);
      s.checks.push_back(c);
    }
    s.cv.notify_all();
  });
  s.snapshot_reader = Reader<msg::ServiceSnapshot>(bus, topics::kSnapshot, [&s](const msg::ServiceSnapshot& snap, const SampleInfo& info) {
    if (snap.service() != s.options.name || info.writer_id == s.snapshot_writer.id()) return;
    {
      std::lock_guard<std::mutex> lock(s.mu);
      s.snapshot = snap;
    }
    s.cv.notify_all();
  });
  s.status_reader = Reader<msg::RunStatus>(bus, topics::kRunStatus, [&s](const msg::RunStatus& st, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(s.mu);
      s.status = st;
    }
    s.cv.notify_all();
  });
  s.tick_log_reader = Reader<msg::TickLog>(bus, topics::kTickLog, [&s](const msg::TickLog& log, const SampleInfo&) {
    spdlog::debug("tick log of run {} for '{}': {} tick(s)", log.run(), log.service().to_string(), log.ticks().size());
    if (log.service() != s.options.name) return;  // another failed service's
    {
      std::lock_guard<std::mutex> lock(s.mu);
      s.tick_log = log;
    }
    s.cv.notify_all();
  });
  s.world_reader = Reader<msg::WorldInfo>(bus, topics::kWorldInfo, [&s](const msg::WorldInfo& w, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(s.mu);
      s.world = w;
    }
    s.cv.notify_all();
  });
  s.tick_reader = Reader<msg::Tick>(bus, topics::kTick, [&s](const msg::Tick& t, const SampleInfo&) {
    // Fast path: step right here when the core never waits and nothing is queued
    // before this tick (a new run needs world info: the main thread waits for it).
    if (s.joined && s.core.StepNeverWaits() && t.run() == s.run) {
      std::lock_guard<std::mutex> step(s.step_mu);
      bool queued;
      {
        std::lock_guard<std::mutex> lock(s.mu);
        queued = !s.ticks.empty();
      }
      if (!queued) {
        static const std::atomic<bool> never_stop{false};
        try {
          if (s.failed()) return;
          s.Handle(t, never_stop);
        } catch (const std::exception& e) {
          s.Fail(e.what());  // on the DDS thread: the main loop ends Run with the reason
        } catch (...) {
          s.Fail("unknown exception");
        }
        return;
      }
    }
    {
      std::lock_guard<std::mutex> lock(s.mu);
      s.ticks.push_back(t);
    }
    s.cv.notify_one();
  });
  // Declarations first: the announcement counts them, and the coordinator waits for them.
  s.PublishBlueprints();
  s.Announce(msg::ServiceState::SERVICE_STARTING);
}

ServiceRunner::~ServiceRunner() {
  try {
    impl_->Announce(msg::ServiceState::SERVICE_STOPPING);
    if (impl_->failed()) impl_->announce.WaitForAcknowledgments(1.0);  // the reason must get out before we exit
  } catch (...) {
  }
}

uint64_t ServiceRunner::last_frame() const { return impl_->last_frame; }

void ServiceRunner::Run(const std::atomic<bool>& stop) {
  auto& s = *impl_;
  // Heartbeats come from their own thread, so a long step is not mistaken for a hang
  // (the coordinator's per-tick timeout covers that); a killed or stopped process
  // falls silent and is noticed within the coordinator's heartbeat timeout.
  std::atomic<bool> heartbeat_stop{false};
  std::thread heartbeat([&] {
    std::unique_lock<std::mutex> lock(s.mu);
    while (!heartbeat_stop && !stop) {
      lock.unlock();
      if (s.joined) s.Announce(msg::ServiceState::SERVICE_READY);
      lock.lock();
      s.heartbeat_cv.wait_for(lock, std::chrono::duration<double>(s.options.heartbeat_period_s));
    }
  });
  s.core.stopping_ = [&stop] { return stop.load(); };
  try {
    s.Join(stop);
    while (!stop) {
      std::optional<msg::Tick> tick;
      {
        std::unique_lock<std::mutex> lock(s.mu);
        s.cv.wait_for(lock, std::chrono::milliseconds(100),
                      [&] { return !s.ticks.empty() || !s.checks.empty() || !s.failure.empty() || stop; });
        if (!s.failure.empty()) throw ServiceFailed(s.failure);
        if (s.ticks.empty()) {
          if (s.checks.empty()) continue;
          lock.unlock();
          std::lock_guard<std::mutex> step(s.step_mu);
          s.AnswerChecks();
          continue;
        }
        tick = std::move(s.ticks.front());
        s.ticks.pop_front();
      }
      std::lock_guard<std::mutex> step(s.step_mu);
      try {
        s.Handle(*tick, stop);
      } catch (const Stopped&) {
        throw;
      } catch (const std::exception& e) {
        s.Fail(e.what());
        std::lock_guard<std::mutex> lock(s.mu);
        throw ServiceFailed(s.failure);
      }
      s.AnswerChecks();
    }
  } catch (const Stopped&) {
    // Asked to stop while waiting: a normal end.
  } catch (...) {
    s.core.stopping_ = nullptr;
    heartbeat_stop = true;
    s.heartbeat_cv.notify_all();
    heartbeat.join();
    // A failed step: SERVICE_STOPPING with the reason, so the run faults at once.
    if (s.failed()) s.Announce(msg::ServiceState::SERVICE_STOPPING);
    throw;
  }
  s.core.stopping_ = nullptr;
  heartbeat_stop = true;
  s.heartbeat_cv.notify_all();
  heartbeat.join();
}

uint64_t MaxSnapshotPeriod() { return static_cast<uint64_t>(QosHistoryDepth(QosKind::kState)) - 8; }

}  // namespace lockstep

