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
#include <fstream>
#include <sstream>
#include <string>
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

// What a set of processes has spent so far: CPU time (user + system, every thread) and
// voluntary context switches (every thread): the wake-ups. On a 2-core machine the barrier
// is mostly these two: the work per tick and the wake-ups it takes; both depend far less on
// the load of the machine than the latency does.
struct Spent {
  double cpu_us = 0;
  double switches = 0;
};

Spent ProcessSpent(pid_t pid) {
  Spent s;
  const std::string dir = "/proc/" + std::to_string(pid);
  std::ifstream stat(dir + "/stat");
  std::string line;
  if (std::getline(stat, line)) {
    const auto close = line.rfind(')');
    std::istringstream rest(line.substr(close + 2));
    std::string field;
    double utime = 0, stime = 0;
    for (int i = 3; i <= 15 && rest >> field; ++i) {  // fields 14 and 15: utime, stime (clock ticks)
      if (i == 14) utime = std::stod(field);
      if (i == 15) stime = std::stod(field);
    }
    s.cpu_us = (utime + stime) * 1e6 / static_cast<double>(sysconf(_SC_CLK_TCK));
  }
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator(dir + "/task", ec)) {
    std::ifstream status(task.path() / "status");
    while (std::getline(status, line)) {
      // Voluntary ones only: each is a thread that waits for something (a sample, a lock) and is
      // woken for it; involuntary ones count the load of the machine, not the barrier's work.
      if (line.rfind("voluntary_ctxt_switches:", 0) == 0) s.switches += std::stod(line.substr(line.find(':') + 1));
    }
  }
  return s;
}

struct Result {
  int services;
  size_t ticks;
  double median, p99, tick_rate;
  double cpu_us_per_tick = 0;       // coordinator and services together, over the timed ticks
  double coordinator_cpu_us_per_tick = 0;
  double switches_per_tick = 0;     // voluntary context switches (wake-ups) of those processes per tick
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
  Result spent{};
  {
    lockstep::Coordinator coordinator(*bus, config);
    // A run that cannot finish (a service that never joined) ends after 120 s, named.
    std::atomic<bool> stop{false};
    std::mutex mu;
    std::condition_variable cv;
    bool finished = false;
    // Counters from when the timed ticks begin (the first 10% are skipped below) to the end.
    Spent start_self, start_services;
    uint64_t start_frame = 0;
    std::thread watchdog([&] {
      const auto deadline = Clock::now() + std::chrono::seconds(120);
      std::unique_lock<std::mutex> lock(mu);
      while (!finished && Clock::now() < deadline) {
        if (start_frame == 0) {
          lock.unlock();
          const uint64_t f = coordinator.stats().frames;
          if (f >= ticks / 10 && f > 0) {
            start_self = ProcessSpent(getpid());
            for (pid_t p : pids) {
              const Spent x = ProcessSpent(p);
              start_services.cpu_us += x.cpu_us;
              start_services.switches += x.switches;
            }
            start_frame = f;
          }
          lock.lock();
        }
        cv.wait_for(lock, std::chrono::milliseconds(start_frame == 0 ? 2 : 100), [&] { return finished; });
      }
      if (!finished) stop = true;
    });
    coordinator.Run(stop);
    const Spent end_self = ProcessSpent(getpid());
    Spent end_services;
    for (pid_t p : pids) {
      const Spent x = ProcessSpent(p);
      end_services.cpu_us += x.cpu_us;
      end_services.switches += x.switches;
    }
    {
      std::lock_guard<std::mutex> lock(mu);
      finished = true;
    }
    cv.notify_all();
    watchdog.join();
    stats = coordinator.stats();
    if (stats.frames > start_frame && start_frame > 0) {
      const double n = static_cast<double>(stats.frames - start_frame);
      spent.coordinator_cpu_us_per_tick = (end_self.cpu_us - start_self.cpu_us) / n;
      spent.cpu_us_per_tick = spent.coordinator_cpu_us_per_tick + (end_services.cpu_us - start_services.cpu_us) / n;
      spent.switches_per_tick = (end_self.switches - start_self.switches + end_services.switches - start_services.switches) / n;
    }
    if (stats.frames < ticks) std::fprintf(stderr, "barrier: %d services: only %llu of %llu ticks within 120 s\n", services,
                                           static_cast<unsigned long long>(stats.frames), static_cast<unsigned long long>(ticks));
  }
  Reap(pids);
  // The first ticks include discovery settling: skip 10%.
  std::vector<double> v(stats.barrier_us.begin() + stats.barrier_us.size() / 10, stats.barrier_us.end());
  spent.services = services;
  spent.ticks = v.size();
  spent.median = Percentile(v, 0.5);
  spent.p99 = Percentile(v, 0.99);
  spent.tick_rate = stats.tick_rate_hz;
  return spent;
}

double LoadAverage() {
  double load = 0;
  std::ifstream("/proc/loadavg") >> load;
  return load;
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
  // bench_barrier [TICKS [SERVICES...]]: by default 1, 2, 8 and 4 services (the last line is 4).
  std::vector<int> counts{1, 2, 8, 4};
  if (argc > 2) {
    counts.clear();
    for (int i = 2; i < argc; ++i) counts.push_back(std::atoi(argv[i]));
  }
  for (int n : counts) {
    Result r = Barrier(domain, n, ticks);
    const bool summary = n == 4;
    if (summary) four = r;
    std::printf("{\"bench\":\"barrier\",\"services\":%d,\"ticks\":%zu,\"median_us\":%.1f,\"p99_us\":%.1f,\"floor_rtt_us\":%.1f,"
                "\"ratio_to_floor\":%.2f,\"tick_rate_hz\":%.0f,\"cpu_us_per_tick\":%.1f,\"coordinator_cpu_us_per_tick\":%.1f,"
                "\"switches_per_tick\":%.1f,\"load\":%.2f}\n",
                r.services, r.ticks, r.median, r.p99, floor_us, floor_us > 0 ? r.median / floor_us : 0, r.tick_rate, r.cpu_us_per_tick,
                r.coordinator_cpu_us_per_tick, r.switches_per_tick, LoadAverage());
    std::fflush(stdout);
  }
  (void)four;
  return 0;
}
