// bench_recovery: how long a run stands still when a service dies. A coordinator and two
// no-op services run as processes at full speed; one is killed with SIGKILL and its
// replacement is started at once (what `lockstep up` does with restart: on-failure).
// Measured, per kill: kill -> the run reports the failure (detect_ms) and kill -> the
// first frame completed after it (kill_to_resume_ms). Prints one JSON line per kill, then
// {"bench":"recovery","kill_to_resume_ms":<median>,...}.
//
// bench_recovery --stack [rounds]: the full stack under `lockstep up` (ground_sim, air_sim,
// sensors, render, recorder, each `restart: on-failure`, snapshots every 200 frames; cars,
// a walker, a drone, a LiDAR, an IMU and a camera in the generated town), free-running
// for as long as it takes; each service in turn is killed with SIGKILL once the run is
// 150 frames further, `lockstep up` starts its replacement, and kill -> the first frame
// completed after it is measured per service (issue 21: at most 2 s in a run of any
// length). One JSON line per kill, then {"bench":"recovery_stack", "<service>_ms": ...}.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <mutex>
#include <string>
#include <vector>

#include "lockstep/runtime/domain_lock.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/messages.h"

namespace {

using Clock = std::chrono::steady_clock;

std::string BinDir() { return std::filesystem::canonical("/proc/self/exe").parent_path().string(); }

// Starts a process with its output in `log` (kept for a look when a kill goes slowly).
pid_t Spawn(std::vector<std::string> argv, const std::string& log) {
  pid_t pid = fork();
  if (pid == 0) {
    const int out = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, 1);
    dup2(out, 2);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

int StackMain(int rounds);

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--stack") return StackMain(argc > 2 ? std::atoi(argv[2]) : 1);
  const int kills = argc > 1 ? std::atoi(argv[1]) : 5;
  const int domain = lockstep::LockFreeDdsDomain();  // not one a test or another bench uses now
  lockstep::InitLogging("bench_recovery");
  spdlog::set_level(spdlog::level::warn);
  const std::string config = std::filesystem::temp_directory_path() / ("bench-recovery-" + std::to_string(getpid()) + ".yaml");
  std::ofstream(config) << "domain_id: " << domain
                        << "\nparticipant_profile: lockstep.participant.loopback\nworld:\n  service_timeout: 5\n"
                           "services:\n  - {name: alpha, kind: noop}\n  - {name: beta, kind: noop}\n";
  const std::string bin = BinDir();
  const std::string logs = std::filesystem::temp_directory_path() / ("bench-recovery-" + std::to_string(getpid()));
  std::filesystem::create_directories(logs);
  std::vector<pid_t> pids{Spawn({bin + "/lockstep_coordinator", config}, logs + "/coordinator.log"),
                          Spawn({bin + "/lockstep_noop", "--name", "alpha", "--config", config}, logs + "/alpha.log")};
  pid_t beta = Spawn({bin + "/lockstep_noop", "--name", "beta", "--config", config}, logs + "/beta-0.log");

  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant.loopback", "bench-recovery"});
  std::mutex mu;
  std::condition_variable cv;
  uint64_t last_frame = 0;
  bool faulted = false;
  lockstep::Reader<lockstep::msg::FrameDone> done(*bus, lockstep::topics::kFrameDone, [&](const lockstep::msg::FrameDone& d, const lockstep::SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    last_frame = std::max<uint64_t>(last_frame, d.frame());
    cv.notify_all();
  });
  lockstep::Reader<lockstep::msg::RunStatus> status(*bus, lockstep::topics::kRunStatus, [&](const lockstep::msg::RunStatus& s, const lockstep::SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    faulted = s.state() == lockstep::msg::RunState::RUN_FAULTED;
    cv.notify_all();
  });

  std::vector<double> resume_ms, detect_ms;
  int code = 0;
  for (int i = 0; i < kills && code == 0; ++i) {
    std::unique_lock<std::mutex> lock(mu);
    const uint64_t warm = last_frame + 100;
    if (!cv.wait_for(lock, std::chrono::seconds(60), [&] { return last_frame >= warm && !faulted; })) {
      std::fprintf(stderr, "bench_recovery: the run did not advance\n");
      code = 1;
      break;
    }
    const uint64_t at_kill = last_frame;
    lock.unlock();
    const auto t0 = Clock::now();
    kill(beta, SIGKILL);
    waitpid(beta, nullptr, 0);
    // The replacement waiting.
    beta = Spawn({bin + "/lockstep_noop", "--name", "beta", "--config", config}, logs + "/beta-" + std::to_string(i + 1) + ".log");
    lock.lock();
    // The frame in flight at the kill may still complete: resume means a frame beyond it.
    const bool seen_fault = cv.wait_for(lock, std::chrono::seconds(30), [&] { return faulted; });
    const auto t_fault = Clock::now();
    const bool resumed = cv.wait_for(lock, std::chrono::seconds(60), [&] { return last_frame > at_kill + 1; });
    const auto t1 = Clock::now();
    if (!resumed) {
      std::fprintf(stderr, "bench_recovery: no frame within 60 s of the kill (logs in %s)\n", logs.c_str());
      code = 1;
      break;
    }
    const double d = seen_fault ? std::chrono::duration<double, std::milli>(t_fault - t0).count() : -1;
    const double r = std::chrono::duration<double, std::milli>(t1 - t0).count();
    detect_ms.push_back(d);
    resume_ms.push_back(r);
    std::printf("{\"bench\":\"recovery_kill\",\"kill\":%d,\"detect_ms\":%.1f,\"kill_to_resume_ms\":%.1f}\n", i + 1, d, r);
    std::fflush(stdout);
  }
  pids.push_back(beta);
  for (pid_t p : pids) kill(p, SIGTERM);
  for (pid_t p : pids) waitpid(p, nullptr, 0);
  std::filesystem::remove(config);
  const bool slow = !resume_ms.empty() && *std::max_element(resume_ms.begin(), resume_ms.end()) > 5000;
  if (code == 0 && !slow) {
    std::filesystem::remove_all(logs);
  } else {
    std::fprintf(stderr, "bench_recovery: process logs kept in %s\n", logs.c_str());
  }
  if (code == 0) {
    std::printf("{\"bench\":\"recovery\",\"kills\":%d,\"kill_to_resume_ms\":%.1f,\"kill_to_resume_max_ms\":%.1f,\"detect_ms\":%.1f}\n",
                kills, Median(resume_ms), *std::max_element(resume_ms.begin(), resume_ms.end()), Median(detect_ms));
  }
  return code;
}

int StackMain(int rounds) {
  const int domain = lockstep::LockFreeDdsDomain();
  lockstep::InitLogging("bench_recovery");
  spdlog::set_level(spdlog::level::warn);
  const std::string bin = BinDir();
  const std::string build = std::filesystem::path(bin).parent_path().string();
  const std::string config = std::filesystem::temp_directory_path() / ("bench-recovery-stack-" + std::to_string(getpid()) + ".yaml");
  const std::vector<std::string> services{"ground_sim", "air_sim", "sensors", "render", "recorder"};
  std::ofstream(config)
      << "name: bench-recovery\ndomain_id: " << domain << "\nparticipant_profile: lockstep.participant.loopback\nseed: 7\n"
      << "map: " << build << "/maps/generated/LockstepTown1.xodr\n"
      << "world:\n  real_time_factor: 0\n  service_timeout: 20\n"
         "services:\n"
         "  - {name: ground_sim, kind: ground_sim, restart: on-failure}\n"
         "  - {name: air_sim, kind: air_sim, restart: on-failure}\n"
         "  - {name: sensors, kind: sensors, perception: true, restart: on-failure}\n"
         "  - {name: render, kind: render, perception: true, restart: on-failure}\n"
         "  - {name: recorder, kind: recorder, perception: true, restart: on-failure}\n"
         "scenario:\n"
         "  - {frame: 1, spawn: vehicle.tesla.model3, as: ego, at: [122.75, 1.75, 0.8], yaw: 3.1416, attributes: {role_name: hero}}\n"
         "  - {frame: 2, actor: ego, autopilot: true}\n"
         "  - {frame: 1, spawn: vehicle.audi.tt, as: car1, at: [207.75, 1.75, 0.8], yaw: 3.1416}\n"
         "  - {frame: 2, actor: car1, autopilot: true}\n"
         "  - {frame: 1, spawn: vehicle.nissan.micra, as: car2, at: [142.75, 18.25, 0.8], yaw: 1.5708}\n"
         "  - {frame: 2, actor: car2, autopilot: true}\n"
         "  - {frame: 1, spawn: drone.generic_quad, as: drone, at: [47.75, 1.75, 0]}\n"
         "  - {frame: 2, actor: drone, drone: arm}\n"
         "  - {frame: 3, actor: drone, drone: takeoff}\n"
         "  - {frame: 2, spawn: sensor.lidar.ray_cast, as: ego_lidar, parent: ego, at: [0, 0, 2.4], attributes: {range: 50}}\n"
         "  - {frame: 2, spawn: sensor.other.imu, as: ego_imu, parent: ego}\n"
         "  - {frame: 2, spawn: sensor.camera.rgb, as: ego_rgb, parent: ego, at: [1.5, 0, 2.4],"
         " attributes: {image_size_x: \"320\", image_size_y: \"240\"}}\n";
  const std::string logs = std::filesystem::temp_directory_path() / ("bench-recovery-stack-" + std::to_string(getpid()));
  std::filesystem::create_directories(logs);
  const pid_t up = Spawn({bin + "/lockstep", "up", config}, logs + "/lockstep-up.log");

  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant.loopback", "bench-recovery-stack"});
  std::mutex mu;
  std::condition_variable cv;
  uint64_t last_frame = 0;
  std::optional<lockstep::msg::RunStatus> status;
  lockstep::Reader<lockstep::msg::FrameDone> done(*bus, lockstep::topics::kFrameDone, [&](const lockstep::msg::FrameDone& d, const lockstep::SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    last_frame = std::max<uint64_t>(last_frame, d.frame());
    cv.notify_all();
  });
  lockstep::Reader<lockstep::msg::RunStatus> status_reader(*bus, lockstep::topics::kRunStatus, [&](const lockstep::msg::RunStatus& s, const lockstep::SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    status = s;
    cv.notify_all();
  });
  std::map<std::string, std::vector<double>> resume_ms;
  int code = 0;
  for (int round = 0; round < rounds && code == 0; ++round) {
    for (const std::string& service : services) {
      std::unique_lock<std::mutex> lock(mu);
      const uint64_t warm = last_frame + 150;
      auto running = [&] { return status && status->state() == lockstep::msg::RunState::RUN_RUNNING; };
      if (!cv.wait_for(lock, std::chrono::seconds(180), [&] { return last_frame >= warm && running(); })) {
        std::fprintf(stderr, "bench_recovery: the run did not advance (logs in %s)\n", logs.c_str());
        code = 1;
        break;
      }
      int32_t pid = 0;
      for (const auto& m : status->members()) {
        if (m.service().to_string() == service) pid = m.pid();
      }
      const uint64_t at_kill = last_frame;
      lock.unlock();
      const auto t0 = Clock::now();
      if (pid <= 0 || kill(pid, SIGKILL) != 0) {
        std::fprintf(stderr, "bench_recovery: no process of %s\n", service.c_str());
        code = 1;
        break;
      }
      lock.lock();
      const bool resumed = cv.wait_for(lock, std::chrono::seconds(60), [&] { return last_frame > at_kill + 1 && running(); });
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (!resumed) {
        std::fprintf(stderr, "bench_recovery: %s: no frame within 60 s of the kill (logs in %s)\n", service.c_str(), logs.c_str());
        code = 1;
        break;
      }
      resume_ms[service].push_back(ms);
      std::printf("{\"bench\":\"recovery_stack_kill\",\"service\":\"%s\",\"at_frame\":%llu,\"kill_to_resume_ms\":%.1f}\n",
                  service.c_str(), static_cast<unsigned long long>(at_kill), ms);
      std::fflush(stdout);
    }
  }
  kill(up, SIGINT);
  waitpid(up, nullptr, 0);
  std::filesystem::remove(config);
  if (code == 0) {
    std::filesystem::remove_all(logs);
    std::string line = "{\"bench\":\"recovery_stack\",\"rounds\":" + std::to_string(rounds);
    double worst = 0;
    for (const auto& s : services) {
      char v[64];
      std::snprintf(v, sizeof v, ",\"%s_ms\":%.1f", s.c_str(), Median(resume_ms[s]));
      line += v;
      worst = std::max(worst, *std::max_element(resume_ms[s].begin(), resume_ms[s].end()));
    }
    char v[64];
    std::snprintf(v, sizeof v, ",\"max_ms\":%.1f}", worst);
    std::printf("%s\n", (line + v).c_str());
  }
  return code;
}
