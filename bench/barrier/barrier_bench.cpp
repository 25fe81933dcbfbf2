// bench_barrier: what the tick barrier costs on one machine.
// 1. floor: a plain Fast DDS round trip between two processes (this one and an echo
//    child), same QoS as ticks and acks;
// 2. for 1, 2, 4 and 8 no-op services (separate processes): the wall time from the
//    coordinator publishing tick k to its last ack, over many ticks.
// Prints one JSON object per line; the last is the 4-service summary the issue names.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <sys/wait.h>
#include <thread>
#include <vector>

#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/domain_lock.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/messages.h"

namespace {

using Clock = std::chrono::steady_clock;

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5))];
}

std::string BinDir() { return std::filesystem::canonical("/proc/self/exe").parent_path().string(); }

pid_t Spawn(std::vector<std::string> argv) {
  pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

void Reap(const std::vector<pid_t>& pids) {
  for (pid_t p : pids) kill(p, SIGTERM);
  for (pid_t p : pids) waitpid(p, nullptr, 0);
}

// Echo side of the floor measurement: Tick in, Ack out, from the listener thread.
int Echo(int domain) {
  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-echo"});
  lockstep::Writer<lockstep::msg::Ack> out(*bus, {"bench/pong", lockstep::QosKind::kAck});
  lockstep::Reader<lockstep::msg::Tick> in(*bus, {"bench/ping", lockstep::QosKind::kClock},
                                           [&](const lockstep::msg::Tick& t, const lockstep::SampleInfo&) {
                                             lockstep::msg::Ack a;
                                             a.service("echo");
                                             a.frame(t.frame());
                                             out.Write(a);
                                           });
  // Until the parent's SIGTERM (at most 30 s); then the participant goes cleanly: one
  // killed by a signal leaves its shared-memory port rings behind in /dev/shm.
  sigset_t term;
  sigemptyset(&term);
  sigaddset(&term, SIGTERM);
  sigprocmask(SIG_BLOCK, &term, nullptr);
  const timespec limit{30, 0};
  sigtimedwait(&term, nullptr, &limit);
  return 0;
}

// Ping-pong chained in the listener callbacks (no thread hand-off on either side):
// the cheapest round trip DDS gives between two processes here.
double FloorRtt(int domain, int rounds) {
  pid_t child = Spawn({BinDir() + "/bench_barrier", "--echo", std::to_string(domain)});
  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-ping"});
  std::mutex mu;
  std::condition_variable cv;
  std::vector<double> rtt;
  rtt.reserve(rounds + 100);
  Clock::time_point sent;
  bool done = false;
  lockstep::Writer<lockstep::msg::Tick> out(*bus, {"bench/ping", lockstep::QosKind::kClock});
  auto ping = [&](uint64_t i) {
    lockstep::msg::Tick t;
    t.frame(i);
    sent = Clock::now();
    out.Write(t);
  };
  lockstep::Reader<lockstep::msg::Ack> in(*bus, {"bench/pong", lockstep::QosKind::kAck},
                                          [&](const lockstep::msg::Ack& a, const lockstep::SampleInfo&) {
                                            const double us = std::chrono::duration<double, std::micro>(Clock::now() - sent).count();
                                            if (a.frame() > 100) rtt.push_back(us);  // the first 100 warm up
                                            if (a.frame() < static_cast<uint64_t>(rounds + 100)) {
                                              ping(a.frame() + 1);
                                              return;
                                            }
                                            std::lock_guard<std::mutex> lock(mu);
                                            done = true;
                                            cv.notify_all();
                                          });
  // Wait for discovery (both directions matched) before timing.
  while (out.MatchedReaders() < 1 || in.MatchedWriters() < 1) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the echo's reader match too
  ping(1);
  {
    std::unique_lock<std::mutex> lock(mu);
    if (!cv.wait_for(lock, std::chrono::seconds(60), [&] { return done; })) std::fprintf(stderr, "floor: ping-pong stalled\n");
  }
  Reap({child});
  return Percentile(rtt, 0.5);
}

struct Result {
  int services;
  size_t ticks;
  double median, p99, tick_rate;
};

Result Barrier(int domain, int services, uint64_t ticks) {
  lockstep::LaunchConfig config;
  config.domain_id = domain;
  config.ticks = ticks;
  config.world = lockstep::DefaultWorldSettings();
  std::vector<pid_t> pids;
  for (int i = 0; i < services; ++i) {
    const std::string name = "noop" + std::to_string(i);
    config.services.push_back({name, "noop", "", {}, true, false, "never"});
    pids.push_back(Spawn({BinDir() + "/lockstep_noop", "--name", name, "--domain", std::to_string(domain)}));
  }
  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-coordinator"});
  lockstep::CoordinatorStats stats;
  {
    lockstep::Coordinator coordinator(*bus, config);
    // A run that cannot finish (a service that never joined) ends after 120 s, named.
    std::atomic<bool> stop{false};
    std::mutex mu;
    std::condition_variable cv;
    bool finished = false;
    std::thread watchdog([&] {
      std::unique_lock<std::mutex> lock(mu);
      if (!cv.wait_for(lock, std::chrono::seconds(120), [&] { return finished; })) stop = true;
    });
    coordinator.Run(stop);
    {
      std::lock_guard<std::mutex> lock(mu);
      finished = true;
    }
    cv.notify_all();
    watchdog.join();
    stats = coordinator.stats();
    if (stats.frames < ticks) std::fprintf(stderr, "barrier: %d services: only %llu of %llu ticks within 120 s\n", services,
                                           static_cast<unsigned long long>(stats.frames), static_cast<unsigned long long>(ticks));
  }
  Reap(pids);
  // The first ticks include discovery settling: skip 10%.
  std::vector<double> v(stats.barrier_us.begin() + stats.barrier_us.size() / 10, stats.barrier_us.end());
  return Result{services, v.size(), Percentile(v, 0.5), Percentile(v, 0.99), stats.tick_rate_hz};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--echo") return Echo(std::atoi(argv[2]));
  setenv("LOCKSTEP_LOG", "warn", 0);
  lockstep::InitLogging("bench");
  const uint64_t ticks = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 3000;
  const int domain = lockstep::LockFreeDdsDomain();  // not one a test or another bench uses now
  const double floor_us = FloorRtt(domain, 2000);
  std::printf("{\"bench\":\"barrier_floor\",\"floor_rtt_us\":%.1f}\n", floor_us);
  std::fflush(stdout);
  Result four{};
  for (int n : {1, 2, 8, 4}) {
    Result r = Barrier(domain, n, ticks);
    const bool summary = n == 4;
    if (summary) four = r;
    std::printf("{\"bench\":\"barrier\",\"services\":%d,\"ticks\":%zu,\"median_us\":%.1f,\"p99_us\":%.1f,\"floor_rtt_us\":%.1f,"
                "\"ratio_to_floor\":%.2f,\"tick_rate_hz\":%.0f}\n",
                r.services, r.ticks, r.median, r.p99, floor_us, floor_us > 0 ? r.median / floor_us : 0, r.tick_rate);
    std::fflush(stdout);
  }
  (void)four;
  return 0;
}
