// bench_client: what the client adds on top of the tick barrier, in one run.
// A coordinator (this process) in synchronous mode over the generated town, one no-op
// service (a process) as the empty world, and a camera service (this process) that
// publishes a 1280x720 BGRA image per tick for each camera it owns, stamped with its
// publication time. Then:
//   tick_roundtrip_us_cpp     median of Client::tick() over DDS (C++)
//   barrier_median_us         the coordinator's median tick-to-last-ack time meanwhile
//   tick_roundtrip_us_python  median of lockstep.Client.tick() from Python (client_bench.py)
//   barrier_median_us_during_python  the barrier's median over those same Python ticks
//   python_to_barrier         tick_roundtrip_us_python / barrier_median_us_during_python
//   get_waypoint_us_python    carla Map.get_waypoint from Python, mean per call
//   image_720p_to_numpy_ms    median from the camera's write to a numpy view in a Python callback
// Prints JSON lines; the last is the summary.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "lockstep/client/client.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/domain_lock.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/service.h"

namespace {

using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string BinDir() { return std::filesystem::canonical("/proc/self/exe").parent_path().string(); }

pid_t Spawn(const std::vector<std::string>& argv, const std::string& out_file = "") {
  pid_t pid = fork();
  if (pid == 0) {
    if (!out_file.empty()) {
      FILE* f = std::fopen(out_file.c_str(), "w");
      if (f) dup2(fileno(f), 1);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

// A camera service: declares sensor.camera.rgb and publishes one 720p frame per tick per
// camera, with the steady-clock publication time (s) in sensor_pose.position.x (bench only).
class BenchCamera final : public lockstep::ServiceCore {
 public:
  explicit BenchCamera(lockstep::Bus& bus) : bus_(bus) {}
  std::vector<lockstep::msg::BlueprintDeclaration> Blueprints() const override {
    namespace bp = lockstep::blueprint;
    return {bp::Make("sensor.camera.rgb", lockstep::msg::ActorKind::ACTOR_SENSOR,
                     {bp::String("role_name", ""), bp::Int("image_size_x", 1280, 1, 3840), bp::Int("image_size_y", 720, 1, 2160)})};
  }
  void BeginRun(const lockstep::msg::WorldInfo&) override { images_.clear(); }
  bool StepNeverWaits() const override { return true; }
  void Step(const lockstep::msg::Tick& tick) override {
    for (const auto& c : tick.commands()) {
      if (c.body()._d() == lockstep::msg::CommandKind::CMD_SPAWN_ACTOR) {
        const uint32_t id = c.body().spawn_actor().actor();
        const std::string topic = lockstep::topics::ImageTopicName(id);  // one topic per camera
        images_.emplace(id, lockstep::Writer<lockstep::msg::Image>(
                                bus_, lockstep::Topic<lockstep::msg::Image>{topic.c_str(), lockstep::QosKind::kImage}));
      }
    }
    for (auto& [id, writer] : images_) {
      lockstep::msg::Image im;
      im.sensor(id);
      im.stamp().run(tick.run());
      im.stamp().frame(tick.frame());
      im.stamp().sim_time(tick.sim_time());
      im.width(1280);
      im.height(720);
      im.step(1280 * 4);
      im.encoding(static_cast<uint32_t>(lockstep::msg::ImageEncoding::IMAGE_BGRA8));
      im.data().assign(1280 * 720 * 4, static_cast<uint8_t>(tick.frame()));
      im.sensor_pose().position().x(std::chrono::duration<double>(Clock::now().time_since_epoch()).count());
      writer.Write(im);
    }
  }

 private:
  lockstep::Bus& bus_;
  std::map<uint32_t, lockstep::Writer<lockstep::msg::Image>> images_;
};

}  // namespace

int main(int argc, char** argv) {
  setenv("LOCKSTEP_LOG", "warn", 0);
  lockstep::InitLogging("bench");
  const int ticks = argc > 1 ? std::atoi(argv[1]) : 2000;
  const int domain = lockstep::LockFreeDdsDomain();  // none shared with tests or other benchmarks running now
  const std::string dom = std::to_string(domain);

  lockstep::LaunchConfig config;
  config.domain_id = domain;
  config.map = LOCKSTEP_BENCH_TOWN;
  config.world = lockstep::DefaultWorldSettings();
  config.world.synchronous_mode(true);
  config.world.service_timeout(30);
  config.services.push_back({"noop", "noop", "", {}, true, false, "never"});
  config.services.push_back({"camera", "bench_camera", "", {}, true, true, "never"});
  const pid_t noop = Spawn({BinDir() + "/lockstep_noop", "--name", "noop", "--domain", dom});

  auto coordinator_bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-coordinator"});
  auto camera_bus = lockstep::CreateDdsBus({domain, "", "lockstep.participant", "bench-camera"});
  lockstep::Coordinator coordinator(*coordinator_bus, config);
  BenchCamera camera_core(*camera_bus);
  lockstep::ServiceRunner camera(*camera_bus, lockstep::ServiceOptions{"camera", "bench_camera", true}, camera_core);
  std::atomic<bool> stop{false};
  std::thread coordinator_thread([&] { coordinator.Run(stop); });
  std::thread camera_thread([&] { camera.Run(stop); });

  double cpp_us = 0, barrier_us = 0;
  try {
    lockstep::client::ClientOptions o;
    o.domain = domain;
    o.timeout_s = 30;
    lockstep::client::Client client(o);
    client.wait_ready(30);
    for (int i = 0; i < 100; ++i) client.tick();  // warm-up
    const size_t before = coordinator.stats().barrier_us.size();
    std::vector<double> rt;
    for (int i = 0; i < ticks; ++i) {
      const auto t0 = Clock::now();
      client.tick();
      rt.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    }
    const auto all = coordinator.stats().barrier_us;
    barrier_us = Median(std::vector<double>(all.begin() + std::min(before, all.size()), all.end()));
    cpp_us = Median(rt);
    std::printf("{\"bench\":\"client_tick_cpp\",\"ticks\":%d,\"median_us\":%.1f,\"barrier_median_us\":%.1f}\n", ticks, cpp_us,
                barrier_us);
    std::fflush(stdout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_client: the C++ part failed: %s\n", e.what());
    stop = true;
    coordinator_thread.join();
    camera_thread.join();
    kill(noop, SIGTERM);
    waitpid(noop, nullptr, 0);
    return 1;
  }

  // Python: ticks, waypoints, 720p images (client_bench.py prints one JSON line).
  const std::string out = std::filesystem::temp_directory_path() / ("bench-client-" + std::to_string(getpid()) + ".json");
  setenv("PYTHONPATH", LOCKSTEP_BENCH_PYTHONPATH, 1);
  // The barrier side by side with the Python ticks: in synchronous mode only the client
  // ticks, so after its 100 warm-up ticks the next `ticks` samples are its measured ones.
  const size_t py_before = coordinator.stats().barrier_us.size();
  const pid_t py = Spawn({"/usr/bin/python3", LOCKSTEP_BENCH_SCRIPT, dom, std::to_string(ticks)}, out);
  int status = 0;
  waitpid(py, &status, 0);
  double barrier_py_us = 0;
  {
    const auto all = coordinator.stats().barrier_us;
    const size_t from = std::min(py_before + 100, all.size()), to = std::min(from + ticks, all.size());
    barrier_py_us = Median(std::vector<double>(all.begin() + from, all.begin() + to));
  }
  std::string line;
  if (FILE* f = std::fopen(out.c_str(), "r")) {
    char buf[4096];
    while (std::fgets(buf, sizeof(buf), f)) line = buf;
    std::fclose(f);
  }
  std::filesystem::remove(out);
  stop = true;
  coordinator_thread.join();
  camera_thread.join();
  kill(noop, SIGTERM);
  waitpid(noop, nullptr, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || line.empty()) {
    std::fprintf(stderr, "bench_client: the Python part failed (exit %d)\n", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    return 1;
  }
  std::map<std::string, double> py_values;
  // The script prints {"tick_us":..,"waypoint_us":..,"image_ms":..}
  for (const char* key : {"tick_us", "waypoint_us", "image_ms"}) {
    const auto at = line.find(std::string("\"") + key + "\":");
    py_values[key] = at == std::string::npos ? -1 : std::atof(line.c_str() + at + std::strlen(key) + 3);
  }
  std::printf("{\"bench\":\"client_python\",\"tick_us\":%.1f,\"get_waypoint_us\":%.2f,\"image_720p_to_numpy_ms\":%.3f}\n",
              py_values["tick_us"], py_values["waypoint_us"], py_values["image_ms"]);
  std::printf("{\"bench\":\"client\",\"tick_roundtrip_us_cpp\":%.1f,\"tick_roundtrip_us_python\":%.1f,\"get_waypoint_us_python\":%.2f,"
              "\"image_720p_to_numpy_ms\":%.3f,\"barrier_median_us\":%.1f,\"barrier_median_us_during_python\":%.1f,"
              "\"python_to_barrier\":%.2f}\n",
              cpp_us, py_values["tick_us"], py_values["waypoint_us"], py_values["image_ms"], barrier_us, barrier_py_us,
              barrier_py_us > 0 ? py_values["tick_us"] / barrier_py_us : 0.0);
  return 0;
}
