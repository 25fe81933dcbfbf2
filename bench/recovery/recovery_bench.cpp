// bench_recovery: how long a run stands still when a service dies. A coordinator and two
// no-op services run as processes at full speed; one is killed with SIGKILL and its
// replacement is started at once (what `lockstep up` does with restart: on-failure).
// Measured, per kill: kill -> the run reports the failure (detect_ms) and kill -> the
// first frame completed after it (kill_to_resume_ms). Prints one JSON line per kill, then
// {"bench":"recovery","kill_to_resume_ms":<median>,...}.
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

int main(int argc, char** argv) {
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
