// bench/run recorder: the recorder on CARLA's Town01 with 100 Traffic Manager vehicles,
// 50 AI walkers, the town's traffic lights and 2 flying drones, the coordinator and the
// ground_sim, air_sim and recorder services on one in-process bus (the services' own
// code; no DDS transport), at dt 0.05 s:
//   - tick cost with and without recording, side by side in one run: blocks of ticks that
//     alternate not recording / recording (start_recorder and stop_recorder between them),
//     the barrier time per tick (publishing the tick to its last ack), the median of the
//     recording blocks' medians over that of the plain ones; and the recorder's writer
//     thread's time per frame (off the barrier);
//   - MB per simulated hour of a long log recorded after the blocks (goal: at most 100 MB/h,
//     half of CARLA's about 200 MB/h for about 150 actors);
//   - re-simulation speed: that log's ticks (with the run's earlier ticks it carries)
//     re-drive fresh services from frame 1 (x real time), every world hash compared;
//   - playback speed: after the long log is stopped, a block of ticks of the same world
//     without playback, then a client's replay_file of that log (CMD_RECORDER REPLAY_START
//     on the bus, as carla.Client.replay_file sends it): the coordinator puts the log's
//     actors (the run's own, reused) at their recorded poses tick by tick, free-running;
//     x real time of the ticks that show the log's frames, and its ratio to the plain block.
// JSON lines; the last one is the summary.
//
//   bench_recorder [--vehicles N] [--walkers N] [--block N] [--blocks N] [--long N] [--seed N] [--keep 1]
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <thread>
#include <vector>

#include "air_service.h"
#include "ground_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/map/map.h"
#include "lockstep/recorder/log_reader.h"
#include "lockstep/recorder/resimulate.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/log.h"
#include "recorder.h"

namespace {

using namespace lockstep;

struct Options {
  std::string map = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr";
  int vehicles = 100, walkers = 50, block = 50, blocks = 10, warmup = 60, long_block = 400;
  uint64_t seed = 2017;
  bool keep = false;  // --keep 1: leave the logs in /tmp
};

ScheduledCommand Step(uint64_t frame, msg::CommandBody body, const std::string& alias = "", const std::string& actor_alias = "") {
  ScheduledCommand s;
  s.frame = frame;
  s.alias = alias;
  s.actor_alias = actor_alias;
  s.command.client("bench");
  s.command.sequence_number(frame);
  s.command.body(body);
  return s;
}

// (std::string(1, c) + std::to_string(i): GCC 12's -Wrestrict misfires on "c" + std::string at -O3.)
std::string Alias(char c, int i) {
  std::string s(1, c);
  s += std::to_string(i);
  return s;
}

// The frame whose tick stops the long recording; the plain block of the playback
// comparison follows it (frames LongEnd + 1 .. LongEnd + long_block), then the playback.
uint64_t LongEnd(const Options& o) { return static_cast<uint64_t>(o.warmup + o.blocks * o.block + o.long_block) + 1; }

LaunchConfig Config(const Options& o, const std::string& dir, uint64_t ticks) {
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.service_timeout(120);
  c.map = o.map;
  c.seed = o.seed;
  c.ticks = ticks;
  c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
  c.services.push_back({"ground_sim", "ground_sim", "", {}, true, false, "never"});
  c.services.push_back({"recorder", "recorder", "", {}, true, true, "never"});
  const map::Map town = map::Map::Load(o.map);
  const auto sp = town.SpawnPoints(8.0);
  for (int i = 0; i < o.vehicles && i < static_cast<int>(sp.size()); ++i) {
    const auto& p = sp[static_cast<size_t>(i) * sp.size() / static_cast<size_t>(o.vehicles)];
    const std::string a = Alias('v', i);
    c.scenario.push_back(Step(1, SpawnBody("vehicle.tesla.model3", MakePose(p.location.x(), p.location.y(), p.location.z() + 0.27, p.yaw)), a));
    c.scenario.push_back(Step(2, AutopilotBody(0, true), "", a));  // the alias names the actor
  }
  const auto wp = town.PedestrianSpawnPoints(6.0);
  for (int i = 0; i < o.walkers && i < static_cast<int>(wp.size()); ++i) {
    const auto& p = wp[static_cast<size_t>(i) * wp.size() / static_cast<size_t>(o.walkers)];
    const std::string w = Alias('w', i), ctl = Alias('c', i);
    c.scenario.push_back(Step(1, SpawnBody("walker.pedestrian.0001", MakePose(p.location.x(), p.location.y(), p.location.z() + 0.42, 0)), w));
    c.scenario.push_back(Step(2, SpawnBody("controller.ai.walker", MakePose(0, 0, 0)), ctl, w));
    msg::WalkerAICommand ai;
    ai.kind(msg::WalkerAIKind::WALKER_AI_START);
    msg::CommandBody b;
    b.walker_ai(ai);
    c.scenario.push_back(Step(3, b, "", ctl));
  }
  for (int i = 0; i < 2; ++i) {
    const std::string d = Alias('d', i);
    const auto& p = sp.at(static_cast<size_t>(i) * 3 + 1);
    // On the ground, armed, then a takeoff once it has settled (AirSim refuses a takeoff
    // while the drone moves).
    c.scenario.push_back(Step(1, SpawnBody("drone.generic_quad", MakePose(p.location.x() + 3, p.location.y() + 3, p.location.z() + 0.3, 0)), d));
    for (auto [frame, kind] : {std::pair{5ull, msg::DroneCommandKind::DRONE_ARM}, std::pair{30ull, msg::DroneCommandKind::DRONE_TAKEOFF}}) {
      msg::DroneCommand dc;
      dc.kind(kind);
      dc.yaw().is_rate(true);
      msg::CommandBody b;
      b.drone(dc);
      c.scenario.push_back(Step(frame, b, "", d));
    }
  }
  // Alternating blocks after the warm-up: even blocks plain, odd blocks recording.
  for (int k = 0; k < o.blocks; ++k) {
    if (k % 2 == 0) continue;
    const uint64_t start = static_cast<uint64_t>(o.warmup + k * o.block) + 1;
    c.scenario.push_back(Step(start, RecorderBody(msg::RecorderAction::RECORDER_START, dir + "/block" + std::to_string(k) + ".lslog")));
    c.scenario.push_back(Step(start + static_cast<uint64_t>(o.block), RecorderBody(msg::RecorderAction::RECORDER_STOP)));
  }
  // Then one long recording (the log size per hour, the re-simulation and the playback),
  // stopped at LongEnd(o): its frames are LongEnd(o) - long_block .. LongEnd(o) - 1.
  c.scenario.push_back(Step(static_cast<uint64_t>(o.warmup + o.blocks * o.block) + 1, RecorderBody(msg::RecorderAction::RECORDER_START, dir + "/long.lslog")));
  c.scenario.push_back(Step(LongEnd(o), RecorderBody(msg::RecorderAction::RECORDER_STOP)));
  std::stable_sort(c.scenario.begin(), c.scenario.end(), [](const auto& a, const auto& b) { return a.frame < b.frame; });
  return c;
}

struct RunResult {
  std::vector<double> barrier_us;  // per completed tick
  uint64_t frames_written = 0;     // by the recorder
  double write_us = 0;             // the recorder's time writing them (inputs at hand)
};

// Runs the services' cores and the coordinator on one in-process bus.
RunResult Run(const LaunchConfig& c, bool read_only, const std::function<void(Bus&)>& watch = {}) {
  auto bus = CreateInProcessBus();
  if (watch) watch(*bus);
  Coordinator coordinator(*bus, c);
  AirService air(*bus, "air_sim");
  GroundService ground(*bus, "ground_sim");
  RecorderOptions ro;
  ro.read_only = read_only;
  ro.input_timeout_s = 60;
  Recorder recorder(*bus, ro);
  ServiceRunner ra(*bus, ServiceOptions{"air_sim", "air_sim", false}, air);
  ServiceRunner rg(*bus, ServiceOptions{"ground_sim", "ground_sim", false}, ground);
  ServiceRunner rr(*bus, ServiceOptions{"recorder", "recorder", true}, recorder);
  std::atomic<bool> stop{false};
  std::thread ta([&] { ra.Run(stop); }), tg([&] { rg.Run(stop); }), tr([&] { rr.Run(stop); });
  coordinator.Run(stop);
  stop = true;
  ta.join();
  tg.join();
  tr.join();
  return RunResult{coordinator.stats().barrier_us, recorder.frames_written(), recorder.write_us()};
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const char* v = argv[i + 1];
    if (k == "--vehicles") o.vehicles = std::atoi(v);
    else if (k == "--walkers") o.walkers = std::atoi(v);
    else if (k == "--block") o.block = std::atoi(v);
    else if (k == "--blocks") o.blocks = std::atoi(v);
    else if (k == "--long") o.long_block = std::atoi(v);
    else if (k == "--seed") o.seed = std::strtoull(v, nullptr, 10);
    else if (k == "--keep") o.keep = std::atoi(v) != 0;
    else {
      std::fprintf(stderr, "bench_recorder: unknown option %s\n", k.c_str());
      return 2;
    }
  }
  if (o.blocks < 2) o.blocks = 2;
  InitLogging("bench_recorder");
  spdlog::set_level(spdlog::level::warn);
  const std::string dir = (std::filesystem::temp_directory_path() / ("lockstep-bench-recorder-" + std::to_string(getpid()))).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  // After the long log: a plain block, then the playback of that log (its frames and the
  // tick that ends it) with room for the reply to land a few frames later.
  const uint64_t plain_end = LongEnd(o) + static_cast<uint64_t>(o.long_block);
  const uint64_t ticks = plain_end + static_cast<uint64_t>(o.long_block) + 40;
  const LaunchConfig c = Config(o, dir, ticks);
  const std::string last_log = dir + "/long.lslog";
  // Playback: FrameDone wall times, and a client's replay_file once the plain block is done.
  using Clock = std::chrono::steady_clock;
  std::mutex mu;
  std::condition_variable cv;
  std::map<uint64_t, Clock::time_point> done_at;
  std::optional<msg::CommandReply> replay_reply;
  std::unique_ptr<Reader<msg::FrameDone>> done_reader;
  std::unique_ptr<Reader<msg::CommandReply>> reply_reader;
  std::unique_ptr<Writer<msg::Command>> command_writer;
  std::atomic<bool> run_over{false};
  std::thread client;
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult run = Run(c, false, [&](Bus& bus) {
    done_reader = std::make_unique<Reader<msg::FrameDone>>(bus, topics::kFrameDone, [&](const msg::FrameDone& d, const SampleInfo&) {
      const auto now = Clock::now();
      std::lock_guard<std::mutex> lock(mu);
      done_at.emplace(d.frame(), now);
      cv.notify_all();
    });
    reply_reader = std::make_unique<Reader<msg::CommandReply>>(bus, topics::kCommandReply, [&](const msg::CommandReply& r, const SampleInfo&) {
      if (r.client().to_string() != "bench-player") return;
      std::lock_guard<std::mutex> lock(mu);
      replay_reply = r;
      cv.notify_all();
    });
    command_writer = std::make_unique<Writer<msg::Command>>(bus, topics::kCommand);
    client = std::thread([&] {
      std::unique_lock<std::mutex> lock(mu);
      if (!cv.wait_for(lock, std::chrono::minutes(30), [&] { return run_over || done_at.count(plain_end); }) || run_over) return;
      lock.unlock();
      msg::Command cmd;
      cmd.client("bench-player");
      cmd.sequence_number(1);
      cmd.body(RecorderBody(msg::RecorderAction::REPLAY_START, last_log));
      command_writer->Write(cmd);
    });
  });
  {
    std::lock_guard<std::mutex> lock(mu);
    run_over = true;
  }
  cv.notify_all();
  client.join();
  const std::vector<double>& barrier = run.barrier_us;
  const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Block by block: median barrier time of the plain blocks and of the recording ones.
  std::vector<double> plain, recording;
  for (int k = 0; k < o.blocks; ++k) {
    std::vector<double> b;
    // Frame f's tick is entry f - 1; skip each block's first and last ticks (start, stop).
    for (int f = o.warmup + k * o.block + 2; f < o.warmup + (k + 1) * o.block; ++f) {
      if (static_cast<size_t>(f - 1) < barrier.size()) b.push_back(barrier[static_cast<size_t>(f - 1)]);
    }
    const double m = Median(b);
    (k % 2 ? recording : plain).push_back(m);
    std::printf("{\"block\":%d,\"recording\":%s,\"ticks\":%zu,\"median_tick_us\":%.1f}\n", k, k % 2 ? "true" : "false", b.size(), m);
  }
  const double plain_us = Median(plain);
  const double rec_us = Median(recording);
  const double write_us = run.frames_written ? run.write_us / static_cast<double>(run.frames_written) : 0;
  // Log sizes per simulated hour.
  // The long log: its frames and footer per simulated hour (the header is once per log).
  double mb_per_hour = 0;
  {
    recorder::LogReader log(last_log);
    const double sim_s = log.duration() + c.world.fixed_delta_seconds();
    const uint64_t bytes = log.file_size() - log.header_bytes();
    mb_per_hour = static_cast<double>(bytes) / 1e6 * 3600 / sim_s;
    std::printf("{\"log\":\"%s\",\"frames\":%llu,\"frame_and_footer_bytes\":%llu,\"bytes_per_frame\":%.0f,\"header_bytes\":%llu,"
                "\"mb_per_sim_hour\":%.1f}\n",
                last_log.c_str(), static_cast<unsigned long long>(log.frame_count()), static_cast<unsigned long long>(bytes),
                static_cast<double>(bytes) / static_cast<double>(log.frame_count()), static_cast<unsigned long long>(log.header_bytes()),
                mb_per_hour);
  }
  std::fflush(stdout);
  // Playback against the same world without it: x real time of the plain block's ticks and
  // of the ticks that showed the log's frames (the reply's frame F shows the first, F + n - 1
  // the last; F + n ends the replay).
  double plain_x = 0, playback_x = 0;
  {
    recorder::LogReader log(last_log);
    const uint64_t n = log.frame_count();
    const double dt = c.world.fixed_delta_seconds();
    std::lock_guard<std::mutex> lock(mu);
    auto span = [&](uint64_t from, uint64_t to) -> double {  // wall s from FrameDone(from) to FrameDone(to)
      if (!done_at.count(from) || !done_at.count(to)) return 0;
      return std::chrono::duration<double>(done_at[to] - done_at[from]).count();
    };
    const double plain_s = span(LongEnd(o), plain_end);
    plain_x = plain_s > 0 ? static_cast<double>(plain_end - LongEnd(o)) * dt / plain_s : 0;
    std::string why;
    if (!replay_reply) {
      why = "no reply to replay_file";
    } else if (!replay_reply->accepted()) {
      why = "replay_file refused: " + replay_reply->reason().to_string();
    } else {
      const uint64_t f = replay_reply->frame();
      const double s = span(f - 1, f + n - 1);
      if (s > 0) playback_x = static_cast<double>(n) * dt / s;
      else why = "the run ended before the replay's frames " + std::to_string(f) + ".." + std::to_string(f + n - 1);
    }
    std::printf("{\"playback\":\"%s\",\"frames\":%llu,\"reply_frame\":%llu,\"plain_ticks\":%llu,\"plain_x_real_time\":%.2f,"
                "\"playback_x_real_time\":%.2f,\"playback_over_plain\":%.3f,\"error\":\"%s\"}\n",
                last_log.c_str(), static_cast<unsigned long long>(n),
                static_cast<unsigned long long>(replay_reply ? replay_reply->frame() : 0),
                static_cast<unsigned long long>(plain_end - LongEnd(o)), plain_x, playback_x, plain_x > 0 ? playback_x / plain_x : 0,
                why.c_str());
    std::fflush(stdout);
  }
  // Re-simulation of the last log.
  recorder::LogReader log(last_log);
  const LaunchConfig plan = recorder::ResimulationConfig(log, c);
  recorder::ResimulationResult result;
  std::unique_ptr<recorder::ResimulationCheck> check;
  std::thread waiter;
  std::atomic<bool> never{false};
  const auto r0 = std::chrono::steady_clock::now();
  Run(plan, true, [&](Bus& bus) {
    check = std::make_unique<recorder::ResimulationCheck>(bus, log);
    waiter = std::thread([&] { result = check->Wait(300, never); });
  });
  waiter.join();
  const double resim_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
  const double resim_sim_s = static_cast<double>(log.last_frame()) * c.world.fixed_delta_seconds();
  std::printf("{\"resimulation\":\"%s\",\"frames_compared\":%llu,\"hashes_equal\":%s,\"reason\":\"%s\",\"wall_s\":%.2f,\"x_real_time\":%.2f}\n",
              last_log.c_str(), static_cast<unsigned long long>(result.frames_checked), result.ok() ? "true" : "false",
              result.reason.c_str(), resim_s, resim_sim_s / resim_s);
  std::printf("{\"summary\":\"recorder\",\"vehicles\":%d,\"walkers\":%d,\"drones\":2,\"dt\":0.05,\"run_wall_s\":%.1f,"
              "\"median_tick_us_plain\":%.1f,\"median_tick_us_recording\":%.1f,\"tick_cost_ratio\":%.3f,"
              "\"writer_thread_us_per_frame\":%.1f,"
              "\"mb_per_sim_hour\":%.1f,\"resimulation_x_real_time\":%.2f,\"resimulation_hashes_equal\":%s,"
              "\"plain_x_real_time\":%.2f,\"playback_x_real_time\":%.2f,\"playback_over_plain\":%.3f}\n",
              o.vehicles, o.walkers, run_s, plain_us, rec_us, plain_us > 0 ? rec_us / plain_us : 0, write_us, mb_per_hour,
              resim_sim_s / resim_s,
              result.ok() ? "true" : "false", plain_x, playback_x, plain_x > 0 ? playback_x / plain_x : 0);
  if (!o.keep) std::filesystem::remove_all(dir);
  return result.ok() ? 0 : 1;
}
