// bench_client: what a client's tick costs on top of the bare barrier, in one run.
// The bare barrier is the coordinator's barrier with one no-op service (a process): the
// time from publishing a tick to its last ack, as the coordinator measures it. Here the
// coordinator (this process) runs in synchronous mode over the generated town with that
// one required no-op service, and every tick is one a client asked for, so each client
// tick has its own barrier sample.
//   1. A C++ client in this process (the coordinator's) ticks: the DDS messages between
//      them never leave the process (tick_roundtrip_us_cpp_in_process).
//   2. A C++ client and a Python client (lockstep.carla world.tick()), each in its own
//      process as a user's would be, tick in interleaved blocks of 500 (after 100
//      warm-up ticks each), alternating which goes first, so both see the same load; one
//      client process runs at a time, as each client adds readers to the tick's messages.
//      For each, the median round trip and the barrier median over its own ticks; the
//      ratios divide the two.
//   3. The Python process measures carla Map.get_waypoint, then, with a camera service
//      (this process, not required, joined only now) publishing a 1280x720 BGRA image
//      per tick, the delay from the camera's write to a numpy view in a listen callback
//      (the coordinator logs that the camera diverged: a newcomer without the run's past).
//   4. The empty world: a second simulation on the same DDS domain with the services of
//      the main job (air_sim, ground_sim, sensors, render; those built) as required
//      processes, the generated town, no actors. The C++ and the Python client process tick
//      it in interleaved blocks as in step 2, against the barrier of those services.
//   5. The coordinator in the Python process: a third simulation on the domain, with one
//      no-op service process, whose coordinator the Python process hosts
//      (lockstep.Coordinator, as a script started with `lockstep up --no-coordinator`
//      would); its world.tick() against that coordinator's barrier.
// Prints JSON lines; the last is the summary, whose python_to_barrier is exactly
// tick_roundtrip_us_python / barrier_median_us as printed (python_to_barrier_empty_world
// likewise for step 4).
// `bench_client --child DOMAIN` is the C++ client process of step 2.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_camera.h"
#include "child_process.h"
#include "lockstep/client/client.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/domain_lock.h"
#include "lockstep/runtime/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace {

using Clock = std::chrono::steady_clock;
using lockstep::bench::ChildProcess;

constexpr int kBlock = 500;

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double Round1(double v) { return std::round(v * 10) / 10; }

double LoadAverage() {
  std::ifstream f("/proc/loadavg");
  double l = -1;
  f >> l;
  return l;
}

std::string BinDir() { return std::filesystem::canonical("/proc/self/exe").parent_path().string(); }

lockstep::client::ClientOptions Options(int domain) {
  lockstep::client::ClientOptions o;
  o.domain = domain;
  o.timeout_s = 30;
  return o;
}

pid_t Spawn(const std::vector<std::string>& argv) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

// The C++ client process: "tick N" -> N round trips (us) on one line; EOF ends it. The
// answers go to the original stdout; logging (stdout) goes to stderr instead.
int RunChild(int domain) {
  FILE* answers = fdopen(dup(1), "w");
  dup2(2, 1);
  lockstep::client::Client client(Options(domain));
  client.wait_ready(30);
  std::fprintf(answers, "ready\n");
  std::fflush(answers);
  char* line = nullptr;
  size_t cap = 0;
  while (getline(&line, &cap, stdin) > 0) {
    if (std::strncmp(line, "tick ", 5) != 0) break;
    const int n = std::atoi(line + 5);
    std::string out;
    for (int i = 0; i < n; ++i) {
      const auto t0 = Clock::now();
      client.tick();
      char b[32];
      std::snprintf(b, sizeof(b), "%s%.1f", i ? " " : "", std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
      out += b;
    }
    std::fprintf(answers, "%s\n", out.c_str());
    std::fflush(answers);
  }
  std::free(line);
  std::fclose(answers);
  return 0;
}

// One client's ticks and the barrier samples of those same ticks.
struct Series {
  std::vector<double> tick_us, barrier_us;
};

// `child` ticks `n` times; its round trips and the coordinator's barrier samples of those
// ticks (synchronous mode: only client requests start ticks) go into `into`.
void Block(ChildProcess& child, int n, const lockstep::Coordinator& coordinator, Series* into) {
  const size_t before = coordinator.stats().barrier_us.size();
  const std::vector<double> ticks = lockstep::bench::ParseNumbers(child.Ask("tick " + std::to_string(n)));
  const auto all = coordinator.stats().barrier_us;
  if (into == nullptr) return;
  into->tick_us.insert(into->tick_us.end(), ticks.begin(), ticks.end());
  into->barrier_us.insert(into->barrier_us.end(), all.begin() + static_cast<long>(std::min(before, all.size())), all.end());
}

// The C++ and the Python client process tick in interleaved blocks of kBlock (after 100
// warm-up ticks each), `rounds` each, alternating which goes first and ending with Python.
// `after_python_last` runs with the last Python process still alive (step 3).
void InterleavedClients(int rounds, const std::string& dom, const lockstep::Coordinator& coordinator, Series* cpp, Series* py,
                        const std::function<void(ChildProcess&)>& after_python_last = {}) {
  for (int b = 0; b < 2 * rounds; ++b) {
    const bool cpp_first = (rounds - 1 - b / 2) % 2 == 0;
    const bool python = cpp_first == (b % 2 == 1);
    ChildProcess child(python ? std::vector<std::string>{"/usr/bin/python3", LOCKSTEP_BENCH_SCRIPT}
                              : std::vector<std::string>{BinDir() + "/bench_client", "--child", dom});
    if (child.ReadLine() != "ready") throw std::runtime_error("a client did not start");
    Block(child, 100, coordinator, nullptr);  // warm-up
    Block(child, kBlock, coordinator, python ? py : cpp);
    if (python && b == 2 * rounds - 1 && after_python_last) after_python_last(child);
    if (child.Wait() != 0) throw std::runtime_error(python ? "the Python client failed" : "a client process failed");
  }
}

struct EmptyWorld {
  std::string services;  // comma-separated
  Series cpp, py;
};

// A run config (synchronous, the bench's town) in a temporary folder, and one process per
// service started with it; the processes end and the folder goes with this object.
class ServiceProcesses {
 public:
  // `services`: (kind, perception); each is named after its kind.
  ServiceProcesses(const std::string& name, int domain, const std::vector<std::pair<std::string, bool>>& services,
                   double service_timeout_s)
      : dir_(std::filesystem::temp_directory_path() / ("lockstep-bench-client-" + name + "-" + std::to_string(getpid()))),
        file_((dir_ / (name + ".yaml")).string()) {
    std::filesystem::create_directories(dir_);
    {
      std::ofstream f(file_);
      f << "name: bench_" << name << "\ndomain_id: " << domain << "\nseed: 1\nmap: " << LOCKSTEP_BENCH_TOWN
        << "\nworld: {synchronous_mode: true, fixed_delta_seconds: 0.05, service_timeout: " << service_timeout_s
        << "}\nservices:\n";
      for (const auto& [kind, perception] : services) {
        f << "  - {name: " << kind << ", kind: " << kind << ", perception: " << (perception ? "true" : "false") << "}\n";
      }
    }
    for (const auto& [kind, perception] : services) {
      pids_.push_back(Spawn({BinDir() + "/lockstep_" + kind, "--name", kind, "--config", file_, "--domain", std::to_string(domain)}));
    }
  }
  ~ServiceProcesses() {
    for (pid_t p : pids_) kill(p, SIGTERM);
    for (pid_t p : pids_) waitpid(p, nullptr, 0);
    std::filesystem::remove_all(dir_);
  }
  ServiceProcesses(const ServiceProcesses&) = delete;
  ServiceProcesses& operator=(const ServiceProcesses&) = delete;
  const std::string& config_file() const { return file_; }

 private:
  std::filesystem::path dir_;
  std::string file_;
  std::vector<pid_t> pids_;
};

// Step 4: the services of the main job, each a process, required; no actors.
EmptyWorld RunEmptyWorld(int domain, int rounds) {
  EmptyWorld out;
  std::vector<std::pair<std::string, bool>> kinds;  // (kind, perception)
  for (const auto& [kind, perception] : {std::pair{"air_sim", false}, {"ground_sim", false}, {"sensors", true}, {"render", true}}) {
    if (!std::filesystem::exists(BinDir() + "/lockstep_" + kind)) continue;
    kinds.emplace_back(kind, perception);
    if (!out.services.empty()) out.services += ',';
    out.services += kind;
  }
  ServiceProcesses services("empty_world", domain, kinds, 60);
  std::atomic<bool> stop{false};
  auto bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-coordinator-empty-world"});
  lockstep::Coordinator coordinator(*bus, lockstep::LoadLaunchConfig(services.config_file()));
  std::thread run([&] { coordinator.Run(stop); });
  try {
    InterleavedClients(rounds, std::to_string(domain), coordinator, &out.cpp, &out.py);
  } catch (...) {
    stop = true;
    run.join();
    throw;
  }
  stop = true;
  run.join();
  return out;
}

// Step 5: the Python process hosts the coordinator (lockstep.Coordinator) of a run with
// one no-op service process; its answer is {"tick_us":..,"barrier_us":..,...}.
std::string RunEmbedded(int domain, int ticks) {
  ServiceProcesses noop("embedded", domain, {{"noop", false}}, 30);
  ChildProcess python({"/usr/bin/python3", LOCKSTEP_BENCH_SCRIPT, "--embedded", noop.config_file(), std::to_string(ticks)});
  const std::string answer = python.ReadLine();
  if (python.Wait() != 0) throw std::runtime_error("the Python process hosting the coordinator failed");
  return answer;
}

// The number after "key": in a flat JSON line; -1 when the key is missing.
double JsonNumber(const std::string& json, const char* key) {
  std::string quoted = "\"";
  quoted.append(key).append("\":");
  const auto at = json.find(quoted);
  return at == std::string::npos ? -1.0 : std::atof(json.c_str() + at + std::strlen(key) + 3);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 2 && std::strcmp(argv[1], "--child") == 0) return RunChild(std::atoi(argv[2]));
  setenv("LOCKSTEP_LOG", "warn", 0);
  spdlog::set_default_logger(spdlog::stderr_color_mt("bench"));  // stdout carries the JSON lines only
  lockstep::InitLogging("bench");
  const int ticks = std::max(kBlock, argc > 1 ? std::atoi(argv[1]) / kBlock * kBlock : 2000);
  const int domain = lockstep::LockFreeDdsDomain();  // none shared with tests or other benchmarks running now
  const std::string dom = std::to_string(domain);
  const double load_start = LoadAverage();

  lockstep::LaunchConfig config;
  config.domain_id = domain;
  config.map = LOCKSTEP_BENCH_TOWN;
  config.world = lockstep::DefaultWorldSettings();
  config.world.synchronous_mode(true);
  config.world.service_timeout(30);
  config.services.push_back({"noop", "noop", "", {}, true, false, "never"});
  config.services.push_back({"camera", "bench_camera", "", {}, false, true, "never"});  // joins for step 3 only
  const pid_t noop = Spawn({BinDir() + "/lockstep_noop", "--name", "noop", "--domain", dom});

  auto coordinator_bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-coordinator"});
  auto coordinator_owner = std::make_unique<lockstep::Coordinator>(*coordinator_bus, config);
  lockstep::Coordinator& coordinator = *coordinator_owner;
  std::atomic<bool> stop{false};
  std::thread coordinator_thread([&] { coordinator.Run(stop); });
  std::unique_ptr<lockstep::Bus> camera_bus;
  std::unique_ptr<lockstep::bench::BenchCamera> camera_core;
  std::unique_ptr<lockstep::ServiceRunner> camera;
  std::thread camera_thread;
  auto finish = [&](int rc) {
    stop = true;
    coordinator_thread.join();
    if (camera_thread.joinable()) camera_thread.join();
    kill(noop, SIGTERM);
    waitpid(noop, nullptr, 0);
    return rc;
  };

  // 1. A C++ client in the coordinator's process.
  Series in_process;
  try {
    lockstep::client::Client client(Options(domain));
    client.wait_ready(30);
    for (int i = 0; i < 100; ++i) client.tick();  // warm-up
    const size_t before = coordinator.stats().barrier_us.size();
    for (int i = 0; i < ticks; ++i) {
      const auto t0 = Clock::now();
      client.tick();
      in_process.tick_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    }
    const auto all = coordinator.stats().barrier_us;
    in_process.barrier_us.assign(all.begin() + static_cast<long>(std::min(before, all.size())), all.end());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_client: the in-process C++ client failed: %s\n", e.what());
    return finish(1);
  }
  std::printf("{\"bench\":\"client_tick_cpp_in_process\",\"ticks\":%d,\"median_us\":%.1f,\"barrier_median_us\":%.1f}\n", ticks,
              Median(in_process.tick_us), Median(in_process.barrier_us));
  std::fflush(stdout);

  // 2. A C++ and a Python client process, interleaved.
  setenv("PYTHONPATH", LOCKSTEP_BENCH_PYTHONPATH, 1);
  setenv("LOCKSTEP_DOMAIN", dom.c_str(), 1);
  Series cpp, py;
  std::string py_summary;
  try {
    InterleavedClients(ticks / kBlock, dom, coordinator, &cpp, &py, [&](ChildProcess& child) {
      // 3. The camera joins (not required: the barrier still waits for the no-op only).
      camera_bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-camera"});
      camera_core = std::make_unique<lockstep::bench::BenchCamera>(*camera_bus);
      camera = std::make_unique<lockstep::ServiceRunner>(*camera_bus, lockstep::ServiceOptions{"camera", "bench_camera", true},
                                                         *camera_core);
      camera_thread = std::thread([&] { camera->Run(stop); });
      if (child.Ask("rest") != "spawned") throw std::runtime_error("the Python client did not spawn the camera");
      const auto until = Clock::now() + std::chrono::seconds(10);
      while (camera_core->cameras() == 0) {
        if (Clock::now() > until) throw std::runtime_error("the camera service did not step the camera's spawn frame in 10 s");
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      py_summary = child.Ask("go");
    });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_client: %s\n", e.what());
    return finish(1);
  }
  finish(0);
  // Step 1-3's participants leave the domain before the empty world starts on it.
  camera.reset();
  camera_core.reset();
  camera_bus.reset();
  coordinator_owner.reset();
  coordinator_bus.reset();

  // 4. The empty world.
  EmptyWorld empty;
  try {
    empty = RunEmptyWorld(domain, std::max(1, ticks / kBlock / 2));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_client: the empty world: %s\n", e.what());
    return 1;
  }
  // 5. The coordinator in the Python process.
  std::string embedded;
  try {
    embedded = RunEmbedded(domain, ticks / 2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_client: the embedded coordinator: %s\n", e.what());
    return 1;
  }
  const double em_py = Round1(JsonNumber(embedded, "tick_us")), em_barrier = Round1(JsonNumber(embedded, "barrier_us"));
  const double em_ratio = em_barrier > 0 ? em_py / em_barrier : 0.0;
  std::printf("{\"bench\":\"client_tick_embedded_coordinator\",\"ticks\":%.0f,\"tick_roundtrip_us_python\":%.1f,"
              "\"barrier_median_us\":%.1f,\"python_to_barrier\":%.2f}\n",
              JsonNumber(embedded, "ticks"), em_py, em_barrier, em_ratio);

  const double ew_py = Round1(Median(empty.py.tick_us)), ew_py_barrier = Round1(Median(empty.py.barrier_us));
  const double ew_cpp = Round1(Median(empty.cpp.tick_us)), ew_cpp_barrier = Round1(Median(empty.cpp.barrier_us));
  const double ew_ratio = ew_py_barrier > 0 ? ew_py / ew_py_barrier : 0.0;
  std::printf("{\"bench\":\"client_tick_empty_world\",\"services\":\"%s\",\"ticks\":%zu,\"tick_roundtrip_us_python\":%.1f,"
              "\"barrier_median_us\":%.1f,\"python_to_barrier\":%.2f,\"tick_roundtrip_us_cpp\":%.1f,"
              "\"barrier_median_us_during_cpp\":%.1f,\"cpp_to_barrier\":%.2f}\n",
              empty.services.c_str(), empty.py.tick_us.size(), ew_py, ew_py_barrier, ew_ratio, ew_cpp, ew_cpp_barrier,
              ew_cpp_barrier > 0 ? ew_cpp / ew_cpp_barrier : 0.0);

  // The Python process prints {"waypoint_us":..,"image_ms":..,"images":..}.
  const double waypoint_us = JsonNumber(py_summary, "waypoint_us"), image_ms = JsonNumber(py_summary, "image_ms");
  const double cpp_us = Round1(Median(cpp.tick_us)), cpp_barrier = Round1(Median(cpp.barrier_us));
  const double py_us = Round1(Median(py.tick_us)), py_barrier = Round1(Median(py.barrier_us));
  const double in_us = Round1(Median(in_process.tick_us));
  std::printf("{\"bench\":\"client_tick_cpp\",\"ticks\":%zu,\"median_us\":%.1f,\"barrier_median_us\":%.1f}\n", cpp.tick_us.size(),
              cpp_us, cpp_barrier);
  std::printf("{\"bench\":\"client_tick_python\",\"ticks\":%zu,\"median_us\":%.1f,\"barrier_median_us\":%.1f}\n", py.tick_us.size(),
              py_us, py_barrier);
  std::printf("{\"bench\":\"client_python\",\"get_waypoint_us\":%.2f,\"image_720p_to_numpy_ms\":%.3f,\"images\":%.0f}\n", waypoint_us,
              image_ms, JsonNumber(py_summary, "images"));
  std::printf("{\"bench\":\"client\",\"tick_roundtrip_us_cpp\":%.1f,\"tick_roundtrip_us_python\":%.1f,\"get_waypoint_us_python\":%.2f,"
              "\"image_720p_to_numpy_ms\":%.3f,\"barrier_median_us\":%.1f,\"python_to_barrier\":%.2f,"
              "\"barrier_median_us_during_cpp\":%.1f,\"cpp_to_barrier\":%.2f,\"tick_roundtrip_us_cpp_in_process\":%.1f,"
              "\"python_to_barrier_empty_world\":%.2f,\"python_to_barrier_embedded_coordinator\":%.2f,"
              "\"load_avg_1m\":[%.2f,%.2f]}\n",
              cpp_us, py_us, waypoint_us, image_ms, py_barrier, py_barrier > 0 ? py_us / py_barrier : 0.0, cpp_barrier,
              cpp_barrier > 0 ? cpp_us / cpp_barrier : 0.0, in_us, ew_ratio, em_ratio, load_start, LoadAverage());
  return 0;
}
