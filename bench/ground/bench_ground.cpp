// bench/run ground: ground_sim's step at dt 0.05 s in CARLA's Town01 with 100 Traffic
// Manager vehicles and 50 walkers, on one core, in two modes (every car on ODE physics
// with CARLA's 10 ms sub-steps; CARLA's hybrid mode, every car kinematic), and SUMO
// stepping the same network (netconvert from the same OpenDRIVE file), the same number of
// vehicles and the same simulated time. JSON lines; the last one is the summary.
//
//   bench_ground [--map FILE.xodr] [--vehicles N] [--walkers N] [--ticks N] [--seed N] [--no-sumo]
#include <chrono>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <sys/resource.h>

#include "lockstep/ground/world.h"

namespace {

using lockstep::ground::Populate;
using lockstep::ground::TmParam;
using lockstep::ground::Town;
using lockstep::ground::World;

constexpr double kDt = 0.05;

struct Options {
  std::string map = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr";
  int vehicles = 100, walkers = 50, ticks = 2000, warmup = 100;
  uint64_t seed = 2017;
  bool sumo = true;
};

struct Result {
  double tick_ms = 0, cpu_ms = 0, mean_speed_kmh = 0;
  int vehicles = 0, walkers = 0;
};

Result RunGround(const std::shared_ptr<const Town>& town, const Options& o, bool hybrid) {
  World w(town, o.seed);
  if (hybrid) w.SetTrafficManager(TmParam::kHybridPhysicsMode, 0, 1);  // no hero: every TM car kinematic
  const auto rep = Populate(&w, o.vehicles, o.walkers, o.seed, 1000);
  for (int i = 0; i < o.warmup; ++i) w.Step(kDt);
  double speed_sum = 0;
  long samples = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (int i = 0; i < o.ticks; ++i) {
    w.Step(kDt);
    if (i % 20 == 0) {
      for (const auto& v : w.Vehicles()) speed_sum += v.velocity.norm(), ++samples;
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Result r;
  r.tick_ms = s * 1000.0 / o.ticks;
  // CPU time too: on a shared machine the wall clock also counts other processes' turns.
  r.cpu_ms = static_cast<double>(std::clock() - c0) * 1000.0 / CLOCKS_PER_SEC / o.ticks;
  r.mean_speed_kmh = samples ? speed_sum / static_cast<double>(samples) * 3.6 : 0;
  r.vehicles = static_cast<int>(rep.vehicles.size());
  r.walkers = static_cast<int>(rep.walkers.size());
  return r;
}

// Runs a shell command, returns its exit status and output.
int Shell(const std::string& cmd, std::string* out) {
  out->clear();
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof buf, p)) out->append(buf, n);
  return pclose(p);
}

bool Have(const std::string& tool) {
  std::string out;
  return Shell("command -v " + tool, &out) == 0;
}

// SUMO's own timing of its simulation loop ("Duration: 8.42s" or "Duration: 842ms").
std::optional<double> DurationSeconds(const std::string& log) {
  const auto at = log.find(" Duration: ");
  if (at == std::string::npos) return std::nullopt;
  const double v = std::atof(log.c_str() + at + 11);
  const auto unit = log.find_first_not_of("0123456789.", at + 11);
  if (unit != std::string::npos && log.compare(unit, 2, "ms") == 0) return v / 1000.0;
  return v;
}

int Count(const std::string& log, const std::string& key) {
  const auto at = log.find(key);
  return at == std::string::npos ? -1 : std::atoi(log.c_str() + at + key.size());
}

// CPU seconds of the waited-for children (SUMO runs as one).
double ChildrenCpu() {
  rusage u{};
  getrusage(RUSAGE_CHILDREN, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

struct Sumo {
  double step_ms = 0, cpu_ms = 0;
  int running = 0;
  std::string error;
};

// SUMO (Debian's sumo; installed with apt-get here if missing, never by the tests).
Sumo RunSumo(const Options& o, int steps) {
  Sumo r;
  if (!Have("sumo") || !Have("netconvert")) {
    std::fprintf(stderr, "bench ground: SUMO missing, installing Debian's sumo and sumo-tools\n");
    std::string out;
    Shell("DEBIAN_FRONTEND=noninteractive apt-get install -y sumo sumo-tools", &out);
    if (!Have("sumo") || !Have("netconvert")) {
      r.error = "sumo not installed (apt-get install sumo sumo-tools failed)";
      return r;
    }
  }
  const char* home = std::getenv("SUMO_HOME");
  const std::string sumo_home = home && *home ? home : "/usr/share/sumo";
  const std::string dir = (std::filesystem::temp_directory_path() / ("bench_ground_sumo_" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(dir);
  const std::string env = "cd '" + dir + "' && export SUMO_HOME='" + sumo_home + "' && ";
  std::string out;
  // The same network from the same OpenDRIVE file; rerouters keep every vehicle driving
  // (a trip's end is a new start), so the number of vehicles stays as asked.
  if (Shell(env + "netconvert --opendrive-files '" + o.map + "' -o net.net.xml", &out) != 0) {
    r.error = "netconvert failed: " + out.substr(0, 200);
  } else if (Shell(env + "/usr/bin/python3 \"$SUMO_HOME/tools/generateContinuousRerouters.py\" -n net.net.xml -o rerouters.xml", &out) != 0) {
    r.error = "generateContinuousRerouters failed: " + out.substr(0, 200);
  } else if (Shell(env + "/usr/bin/python3 \"$SUMO_HOME/tools/randomTrips.py\" -n net.net.xml -o trips.xml -b 0 -e 1 -p " +
                       std::to_string(1.0 / o.vehicles) + " --seed " + std::to_string(o.seed) + " --validate",
                   &out) != 0) {
    r.error = "randomTrips failed: " + out.substr(0, 200);
  } else {
    // Twice: to the end, and to time 0 (loading only), whose CPU time is taken off.
    auto run = [&](int n, std::string* log) {
      char end[32];
      std::snprintf(end, sizeof end, "%.2f", n * kDt);
      const double c0 = ChildrenCpu();
      Shell(env + "sumo -n net.net.xml -r trips.xml -a rerouters.xml --step-length 0.05 --end " + std::string(end) +
                " --no-step-log --duration-log.statistics --no-warnings --seed " + std::to_string(o.seed),
            log);
      return ChildrenCpu() - c0;
    };
    std::string load_log;
    const double load_cpu = run(0, &load_log);
    const double cpu = run(steps, &out);
    const auto d = DurationSeconds(out);
    if (!d) {
      r.error = "no SUMO timing in its output: " + out.substr(0, 200);
    } else {
      r.step_ms = *d * 1000.0 / steps;
      r.cpu_ms = std::max(0.0, cpu - load_cpu) * 1000.0 / steps;
      r.running = Count(out, "Running: ");
    }
  }
  std::filesystem::remove_all(dir);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench ground: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--map") o.map = next();
    else if (a == "--vehicles") o.vehicles = std::atoi(next().c_str());
    else if (a == "--walkers") o.walkers = std::atoi(next().c_str());
    else if (a == "--ticks") o.ticks = std::atoi(next().c_str());
    else if (a == "--seed") o.seed = std::strtoull(next().c_str(), nullptr, 10);
    else if (a == "--no-sumo") o.sumo = false;
    else {
      std::fprintf(stderr, "bench ground: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  if (o.ticks <= 0 || o.vehicles < 0 || o.walkers < 0) {
    std::fprintf(stderr, "bench ground: --ticks must be > 0, --vehicles and --walkers >= 0\n");
    return 2;
  }
  const std::string town_name = std::filesystem::path(o.map).stem().string();
  std::shared_ptr<const Town> town;
  try {
    town = Town::Load(o.map, 42);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench ground: %s\n", e.what());
    return 1;
  }
  Result modes[2];
  for (int hybrid = 0; hybrid < 2; ++hybrid) {
    const Result r = RunGround(town, o, hybrid == 1);
    modes[hybrid] = r;
    std::printf("{\"bench\":\"ground\",\"mode\":\"%s\",\"town\":\"%s\",\"vehicles\":%d,\"walkers\":%d,\"ticks\":%d,\"tick_ms\":%.3f,"
                "\"cpu_ms\":%.3f,\"ticks_per_s\":%.1f,\"mean_speed_kmh\":%.2f}\n",
                hybrid ? "hybrid" : "physics", town_name.c_str(), r.vehicles, r.walkers, o.ticks, r.tick_ms, r.cpu_ms,
                1000.0 / r.tick_ms, r.mean_speed_kmh);
    std::fflush(stdout);
  }
  Sumo sumo;
  if (o.sumo) {
    sumo = RunSumo(o, o.warmup + o.ticks);
    if (sumo.error.empty()) {
      std::printf("{\"bench\":\"ground\",\"mode\":\"sumo\",\"town\":\"%s\",\"vehicles\":%d,\"running_at_end\":%d,\"steps\":%d,"
                  "\"step_ms\":%.4f,\"cpu_ms\":%.4f}\n",
                  town_name.c_str(), o.vehicles, sumo.running, o.warmup + o.ticks, sumo.step_ms, sumo.cpu_ms);
    } else {
      std::string why;
      for (char c : sumo.error) why += (c == '"' || c == '\\') ? '\'' : (c == '\n' ? ' ' : c);
      std::printf("{\"bench\":\"ground\",\"mode\":\"sumo\",\"error\":\"%s\"}\n", why.c_str());
    }
  }
  // The summary: the physics mode (100 cars on ODE, as CARLA's 15 FPS figure); wall
  // clock, and CPU time (cpu_*: what the step costs when the core is not shared).
  const Result& r = modes[0];
  const bool have_sumo = o.sumo && sumo.error.empty() && sumo.step_ms > 0;
  char sumo_ms[32] = "null", ratio[32] = "null", sumo_cpu[32] = "null", cpu_ratio[32] = "null";
  if (have_sumo) {
    std::snprintf(sumo_ms, sizeof sumo_ms, "%.4f", sumo.step_ms);
    std::snprintf(ratio, sizeof ratio, "%.2f", r.tick_ms / sumo.step_ms);
    std::snprintf(sumo_cpu, sizeof sumo_cpu, "%.4f", sumo.cpu_ms);
    if (sumo.cpu_ms > 0) std::snprintf(cpu_ratio, sizeof cpu_ratio, "%.2f", r.cpu_ms / sumo.cpu_ms);
  }
  std::printf("{\"bench\":\"ground\",\"town\":\"%s\",\"vehicles\":%d,\"walkers\":%d,\"tick_ms\":%.3f,\"ticks_per_s\":%.1f,"
              "\"sumo_step_ms\":%s,\"ratio_to_sumo\":%s,\"cpu_ms\":%.3f,\"cpu_ticks_per_s\":%.1f,\"sumo_cpu_ms\":%s,"
              "\"cpu_ratio_to_sumo\":%s,\"hybrid_tick_ms\":%.3f,\"hybrid_cpu_ms\":%.3f}\n",
              town_name.c_str(), r.vehicles, r.walkers, r.tick_ms, 1000.0 / r.tick_ms, sumo_ms, ratio, r.cpu_ms, 1000.0 / r.cpu_ms,
              sumo_cpu, cpu_ratio, modes[1].tick_ms, modes[1].cpu_ms);
  return 0;
}
