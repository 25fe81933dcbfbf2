// lockstep: the command-line front end.
//   lockstep up <config.yaml>     start the coordinator and services of a simulation
//   lockstep serve [--map Town01] the simulator a CARLA user starts: every built service on a
//                                 map, free-running at real time, until Ctrl-C
//   lockstep status               members, frame and tick rate of a running simulation
//   lockstep map info <file>      statistics of an OpenDRIVE map (delegates to lockstep-map)
//   lockstep python <script> ...  runs a Python script with `lockstep`, `carla` and `airsim`
//                                 resolving to Lockstep's packages (docs/python.md)
#include <CLI/CLI.hpp>
#include <sys/ioctl.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <mutex>
#include <optional>

#include "lockstep/recorder/sensor_selection.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/domain_lock.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/launch_config.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/shm_sweep.h"
#include "hashes.h"
#include "log_command.h"
#include "progress.h"
#include "remote.h"
#include "serve.h"
#include "supervisor.h"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

std::string BinDir() { return std::filesystem::canonical("/proc/self/exe").parent_path().string(); }

// Frees what earlier runs killed with SIGKILL left in /dev/shm; says so when it did.
void SweepShm(bool quiet) {
  const auto r = lockstep::runtime::SweepStaleShm();
  if (!quiet || r.removed_files > 0)
    std::printf("lockstep: removed %d stale Fast DDS shared-memory file(s), %.1f MiB\n", r.removed_files,
                static_cast<double>(r.removed_bytes) / (1 << 20));
  std::fflush(stdout);
}

int Up(const std::string& config_file, int domain, bool with_coordinator) {
  SweepShm(true);
  // A recorder service joins unless the config says `recorder: false` (docs/recorder.md);
  // the children inherit this, so the coordinator requires the recorder it starts. A
  // coordinator a script hosts read its config without it and is already ticking: a
  // recorder added here would join late, without the run's past, so none is added then.
  if (with_coordinator) setenv("LOCKSTEP_DEFAULT_RECORDER", "1", 1);
  lockstep::LaunchConfig config = lockstep::LoadLaunchConfig(config_file);
  if (domain >= 0) config.domain_id = domain;
  // One simulation per domain on this host: a second `lockstep up` is refused with who holds it.
  lockstep::HoldSimulationDomain(config.domain_id, "lockstep up " + config_file + " ('" + config.name + "')");
  const std::string bin = BinDir();
  const std::string dom = std::to_string(config.domain_id);
  std::vector<lockstep::ChildSpec> children;
  // Without it, a script hosts the coordinator (lockstep.Coordinator); the services run
  // until Ctrl-C (or until one of them exits).
  if (with_coordinator) {
    children.push_back({"coordinator", {bin + "/lockstep_coordinator", config_file, "--domain", dom}, false, true});
  }
  size_t local_services = 0;
  for (const auto& s : config.services) {
    if (config.HostOf(s.name) != nullptr) continue;  // started where it runs: printed below
    ++local_services;
    std::string exe = s.executable.empty() ? bin + "/lockstep_" + s.kind : s.executable;
    if (exe.find('/') == std::string::npos) exe = bin + "/" + exe;
    if (!std::filesystem::exists(exe)) {
      throw lockstep::InputError(config_file + ": service '" + s.name + "' of kind '" + s.kind + "': no program " + exe);
    }
    std::vector<std::string> argv{exe, "--name", s.name, "--config", config_file, "--domain", dom};
    argv.insert(argv.end(), s.args.begin(), s.args.end());
    children.push_back({s.name, argv, s.restart == "on-failure", false});
  }
  std::printf("lockstep: starting '%s' on DDS domain %d: %s%zu service(s)\n", config.name.c_str(), config.domain_id,
              with_coordinator ? "coordinator + " : "no coordinator (a script hosts it), ", local_services);
  // The services of other hosts: the exact command that starts each where it runs.
  const auto remote = lockstep::launcher::RemoteCommands(config, config_file, std::filesystem::path(bin).parent_path().string());
  if (!remote.empty()) {
    std::printf("lockstep: %zu service(s) run on other hosts; start each there (the run waits for the required ones):\n", remote.size());
    for (const auto& line : remote) std::printf("  %s\n", line.c_str());
    if (config.participant_profile == "lockstep.participant.loopback") {
      std::printf("lockstep: warning: participant_profile lockstep.participant.loopback keeps DDS on this machine; "
                  "other hosts will not find it (docs/deployment.md#several-machines)\n");
    }
  }
  std::fflush(stdout);
  // A member the run reports failed while its process still runs is hung (stopped, or a
  // step stuck while its heartbeat thread goes on): the supervisor replaces it.
  auto bus = lockstep::CreateDdsBus({config.domain_id, config.qos_file, config.participant_profile, "lockstep-up"});
  std::mutex mu;
  std::optional<lockstep::msg::RunStatus> status;
  lockstep::Reader<lockstep::msg::RunStatus> reader(*bus, lockstep::topics::kRunStatus,
                                                     [&](const lockstep::msg::RunStatus& s, const lockstep::SampleInfo&) {
                                                       std::lock_guard<std::mutex> lock(mu);
                                                       status = s;
                                                     });
  auto hung = [&](const std::string& name, pid_t pid) -> std::optional<std::string> {
    std::lock_guard<std::mutex> lock(mu);
    if (!status) return std::nullopt;
    for (const auto& m : status->members()) {
      if (m.service().to_string() == name && m.pid() == pid && !m.alive() && !m.failure().to_string().empty()) {
        return m.failure().to_string();
      }
    }
    return std::nullopt;
  };
  lockstep::Supervisor supervisor(std::move(children), hung);
  // Progress: wall time counts from the first tick; the frame and rate are the run's.
  namespace ll = lockstep::launcher;
  const bool terminal = isatty(STDOUT_FILENO) != 0;
  std::optional<std::chrono::steady_clock::time_point> ticking_since;
  uint64_t last_plain = 0;
  uint64_t last_frame = 0;
  std::chrono::steady_clock::time_point last_frame_at;  // when the frame last advanced: the summary's end of ticking
  auto wall_s = [&](std::chrono::steady_clock::time_point until) {
    return ticking_since ? std::chrono::duration<double>(until - *ticking_since).count() : 0.0;
  };
  supervisor.SetStatusLine(
      [&]() -> std::string {
        std::lock_guard<std::mutex> lock(mu);
        if (!status || status->frame() == 0) return "";
        if (!ticking_since) {  // first seen mid-run (status comes twice a second): back-date by the ticks done
          const double done_s = status->tick_rate_hz() > 0 ? static_cast<double>(status->frame()) / status->tick_rate_hz() : 0;
          ticking_since = std::chrono::steady_clock::now() -
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(done_s));
        }
        const auto now = std::chrono::steady_clock::now();
        if (status->frame() != last_frame) {
          last_frame = status->frame();
          last_frame_at = now;
        }
        ll::Progress p{status->frame(), config.ticks, status->sim_time(), wall_s(now), status->tick_rate_hz(),
                       lockstep::RunStateName(status->state())};
        if (!terminal) {
          if (!ll::PlainLineDue(p.frame, p.total, last_plain)) return "";
          last_plain = p.frame;
          return ll::FormatProgress(p, false, 200);
        }
        winsize ws{};
        const size_t width = ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 20 ? ws.ws_col - 1 : 100;
        return ll::FormatProgress(p, true, width);
      },
      terminal);
  const int rc = supervisor.Run(g_stop);
  SweepShm(true);  // what a hung service killed with SIGKILL left behind

  ll::Summary summary;
  summary.name = config.name;
  summary.wall_s = wall_s(last_frame_at);
  {
    std::lock_guard<std::mutex> lock(mu);
    if (status) {
      summary.state = lockstep::RunStateName(status->state());
      summary.frames = status->frame();
      summary.sim_time = status->sim_time();
      if (status->failed_service().size() > 0)
        summary.failure = status->failed_service().to_string() + ": " + status->reason().to_string();
      for (const auto& m : status->members())
        summary.members.push_back({m.service().to_string(), m.kind().to_string(), m.last_frame(), m.last_step_wall_us()});
    } else {
      summary.state = "never started";
    }
  }
  if (!config.output_dir.empty() && std::filesystem::exists(config.output_dir)) {
    summary.output_dir = config.output_dir;
    summary.outputs = ll::ScanOutputs(config.output_dir);
    // Each service's own summary (summary.txt in its output folder), as it wrote it.
    std::error_code ec;
    for (auto it = std::filesystem::recursive_directory_iterator(config.output_dir, ec);
         !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
      if (it->path().filename() != "summary.txt") continue;
      std::ifstream in(it->path());
      std::stringstream text;
      text << in.rdbuf();
      summary.service_summaries.emplace_back(std::filesystem::relative(it->path(), config.output_dir).string(), text.str());
    }
    std::sort(summary.service_summaries.begin(), summary.service_summaries.end());
  }
  std::fputs(ll::FormatSummary(summary).c_str(), stdout);
  std::fflush(stdout);
  return rc;
}

// Writes the server's launch config into a folder of its own and runs it as `up` does.
int Serve(lockstep::launcher::ServeOptions o) {
  namespace ll = lockstep::launcher;
  const std::string build = std::filesystem::path(BinDir()).parent_path().string();
  if (o.domain < 0) {
    const char* env = std::getenv("LOCKSTEP_DOMAIN");
    o.domain = env && *env ? std::atoi(env) : 0;
  }
  const std::string map_file = ll::FindMap(o.map, ll::MapSearchPath(build));
  const auto services = ll::BuiltServices(build);
  char dir_template[] = "/tmp/lockstep-serve-XXXXXX";
  if (!mkdtemp(dir_template)) throw lockstep::InputError("lockstep serve: cannot create a folder in /tmp for the config");
  const std::string config = std::string(dir_template) + "/serve.yaml";
  {
    std::ofstream out(config);
    out << ll::ServeConfig(o, map_file, services);
    if (!out) throw lockstep::InputError("lockstep serve: cannot write " + config);
  }
  std::string list;
  for (const auto& s : services) list += (list.empty() ? "" : ", ") + s;
  std::printf("lockstep serve: %s on DDS domain %d with %s; free-running at real time (dt %.3f s)\n", map_file.c_str(), o.domain,
              list.c_str(), o.fixed_delta_seconds);
  std::printf("lockstep serve: run CARLA or AirSim scripts with `LOCKSTEP_DOMAIN=%d lockstep python script.py`; Ctrl-C stops\n",
              o.domain);
  std::fflush(stdout);
  const int rc = Up(config, o.domain, true);
  std::error_code ec;
  std::filesystem::remove_all(dir_template, ec);
  return rc;
}

int Status(int domain, const std::string& profile, double wait_s, bool json) {
  auto bus = lockstep::CreateDdsBus({domain, "", profile, "lockstep-status"});
  std::mutex mu;
  std::condition_variable cv;
  std::optional<lockstep::msg::RunStatus> status;
  lockstep::Reader<lockstep::msg::RunStatus> reader(*bus, lockstep::topics::kRunStatus,
                                                     [&](const lockstep::msg::RunStatus& s, const lockstep::SampleInfo&) {
                                                       std::lock_guard<std::mutex> lock(mu);
                                                       status = s;
                                                       cv.notify_all();
                                                     });
  std::unique_lock<std::mutex> lock(mu);
  if (!cv.wait_for(lock, std::chrono::duration<double>(wait_s), [&] { return status.has_value(); })) {
    std::fprintf(stderr, "lockstep status: no simulation answered on DDS domain %d within %.1f s\n", domain, wait_s);
    return 1;
  }
  const auto& s = *status;
  if (json) {
    std::printf("{\"run\":%u,\"state\":\"%s\",\"frame\":%llu,\"sim_time\":%.6f,\"tick_rate_hz\":%.2f,\"real_time_factor\":%.3f,\"members\":[",
                s.run(), lockstep::RunStateName(s.state()), static_cast<unsigned long long>(s.frame()), s.sim_time(), s.tick_rate_hz(),
                s.real_time_factor());
    for (size_t i = 0; i < s.members().size(); ++i) {
      const auto& m = s.members()[i];
      std::printf("%s{\"service\":\"%s\",\"kind\":\"%s\",\"alive\":%s,\"required\":%s,\"last_frame\":%llu,\"step_us\":%.1f}",
                  i ? "," : "", m.service().c_str(), m.kind().c_str(), m.alive() ? "true" : "false",
                  m.required() ? "true" : "false", static_cast<unsigned long long>(m.last_frame()), m.last_step_wall_us());
    }
    std::printf("],\"failed_service\":\"%s\",\"reason\":\"%s\"}\n", s.failed_service().c_str(), s.reason().c_str());
    return 0;
  }
  std::printf("run %u: %s, frame %llu, sim time %.2f s, %.1f ticks/s (real-time factor %.2f)\n", s.run(), lockstep::RunStateName(s.state()),
              static_cast<unsigned long long>(s.frame()), s.sim_time(), s.tick_rate_hz(), s.real_time_factor());
  if (s.failed_service().size() > 0) std::printf("failed: %s: %s\n", s.failed_service().c_str(), s.reason().c_str());
  std::printf("%-20s %-14s %-6s %-9s %-12s %s\n", "SERVICE", "KIND", "ALIVE", "REQUIRED", "LAST FRAME", "STEP (us)");
  for (const auto& m : s.members()) {
    std::printf("%-20s %-14s %-6s %-9s %-12llu %.1f\n", m.service().c_str(), m.kind().c_str(), m.alive() ? "yes" : "NO",
                m.required() ? "yes" : "no", static_cast<unsigned long long>(m.last_frame()), m.last_step_wall_us());
  }
  return 0;
}

// The packages live in build/python (lockstep) and build/python/dropin (carla, airsim).
int RunPython(std::vector<std::string> args) {
  const std::string root = std::filesystem::path(BinDir()).parent_path().string() + "/python";
  std::string path = root + ":" + root + "/dropin";
  if (const char* old = std::getenv("PYTHONPATH"); old && *old) path += std::string(":") + old;
  setenv("PYTHONPATH", path.c_str(), 1);
  const char* python = std::getenv("LOCKSTEP_PYTHON") ? std::getenv("LOCKSTEP_PYTHON") : "/usr/bin/python3";
  std::vector<char*> argv{const_cast<char*>(python)};
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv(python, argv.data());
  std::fprintf(stderr, "lockstep python: cannot run %s\n", python);
  return 127;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Lockstep: a lock-step urban driving and drone co-simulator"};
  app.require_subcommand(1);

  auto* up = app.add_subcommand("up", "start a simulation from a launch config");
  std::string config_file;
  int domain = -1;
  up->add_option("config", config_file, "launch config (YAML)")->required()->check(CLI::ExistingFile);
  up->add_option("--domain", domain, "DDS domain id (overrides the config)");
  bool no_coordinator = false;
  up->add_flag("--no-coordinator", no_coordinator, "start the services only: a script hosts the coordinator (lockstep.Coordinator)");
  bool ros2 = false;
  up->add_flag("--ros2", ros2, "also publish the ROS 2 topics of CARLA's native interface (adds the ros2_bridge service; "
                               "as `ros2: true` in the config)");
  std::string record_sensors;
  up->add_option("--record-sensors", record_sensors,
                 "the recorder also logs these sensors' outputs: all, actor ids, role_name=NAME or blueprint "
                 "patterns (sensor.camera.*), comma-separated (docs/recorder.md)");

  auto* serve = app.add_subcommand("serve", "the simulator a CARLA user starts: every built service on a map, "
                                             "free-running at real time, until Ctrl-C");
  lockstep::launcher::ServeOptions serve_options;
  serve_options.domain = -1;
  serve->add_option("--map", serve_options.map, "map name (<name>.xodr on the map path) or .xodr file")->capture_default_str();
  serve->add_option("--domain", serve_options.domain, "DDS domain id (default $LOCKSTEP_DOMAIN, else 0)");
  serve->add_option("--seed", serve_options.seed, "run seed")->capture_default_str();
  serve->add_option("--fixed-delta-seconds", serve_options.fixed_delta_seconds, "s of simulated time per tick")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  serve->add_flag("--ros2", ros2, "also publish the ROS 2 topics of CARLA's native interface, as CARLA's server with --ros2");
  serve->add_option("--record-sensors", record_sensors, "the recorder also logs these sensors' outputs (as lockstep up)");

  auto* status = app.add_subcommand("status", "show a running simulation");
  int status_domain = 0;
  double wait_s = 3;
  bool json = false;
  std::string profile = "lockstep.participant";
  status->add_option("--domain", status_domain, "DDS domain id");
  status->add_option("--wait", wait_s, "seconds to wait for an answer");
  status->add_option("--participant-profile", profile, "Fast DDS participant profile");
  status->add_flag("--json", json, "one JSON object");

  auto* hashes = app.add_subcommand("hashes", "print each completed frame's world hash of a running simulation "
                                             "(compare two deployments of one config)");
  lockstep::launcher::HashesOptions hashes_options;
  hashes->add_option("--domain", hashes_options.domain, "DDS domain id")->capture_default_str();
  hashes->add_option("--participant-profile", hashes_options.participant_profile, "Fast DDS participant profile")
      ->capture_default_str();
  hashes->add_option("--until", hashes_options.until, "stop after this frame (0: until Ctrl-C)")->capture_default_str();
  hashes->add_option("--timeout", hashes_options.timeout_s, "give up after this many seconds without a frame")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);

  auto* map = app.add_subcommand("map", "map tools (see lockstep-map --help)");
  map->prefix_command();

  auto* log_cmd = app.add_subcommand("log", "Lockstep logs: info, collisions, blocked, export --csv, replay --resimulate, diff A B "
                                        "(lockstep log --help)");
  log_cmd->prefix_command();

  auto* clean_shm = app.add_subcommand(
      "clean-shm", "remove the shared-memory files of Fast DDS participants that died without cleaning up");

  auto* python = app.add_subcommand("python", "run a Python script with the lockstep, carla and airsim packages");
  python->prefix_command();

  auto* bench = app.add_subcommand("bench", "driving benchmarks and CARLA-Air workloads: lockstep bench corl2017 --agent "
                                            "autopilot --episodes N (= lockstep python -m lockstep.benchmarks ...)");
  bench->prefix_command();
  bench->set_help_flag();  // --help goes on to the benchmarks' own help

  CLI11_PARSE(app, argc, argv);
  lockstep::InitLogging("lockstep");
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  // The coordinator and every service read the config: the flag reaches them through the
  // environment, as the default recorder does.
  if (ros2) setenv("LOCKSTEP_ROS2", "1", 1);
  if (!record_sensors.empty()) {
    try {
      lockstep::recorder::SensorSelection::Parse(record_sensors);  // refuse a bad selection before starting anything
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lockstep: --record-sensors: %s\n", e.what());
      return 2;
    }
    setenv("LOCKSTEP_RECORD_SENSORS", record_sensors.c_str(), 1);
  }
  try {
    if (*up) return Up(config_file, domain, !no_coordinator);
    if (*serve) return Serve(serve_options);
    if (*status) return Status(status_domain, profile, wait_s, json);
    if (*hashes) return lockstep::launcher::PrintFrameHashes(hashes_options, g_stop);
    if (*log_cmd) return lockstep::launcher::LogCommand(log_cmd->remaining(), g_stop);
    if (*map) {
      const std::string tool = BinDir() + "/lockstep-map";
      // lockstep-map reads its positionals by place: pass options (anywhere on our
      // command line) after them. Every option but --json takes a value.
      std::vector<std::string> rest, options;
      const std::vector<std::string> given = map->remaining();
      for (size_t i = 0; i < given.size(); ++i) {
        if (given[i].rfind("--", 0) != 0) {
          rest.push_back(given[i]);
          continue;
        }
        options.push_back(given[i]);
        if (given[i] != "--json" && i + 1 < given.size()) options.push_back(given[++i]);
      }
      rest.insert(rest.end(), options.begin(), options.end());
      std::vector<char*> args{const_cast<char*>(tool.c_str())};
      for (auto& r : rest) args.push_back(r.data());
      args.push_back(nullptr);
      execv(tool.c_str(), args.data());
      std::fprintf(stderr, "lockstep map: cannot run %s\n", tool.c_str());
      return 127;
    }
    if (*clean_shm) {
      SweepShm(false);
      return 0;
    }
    if (*python) return RunPython(python->remaining());
    if (*bench) {
      std::vector<std::string> args{"-m", "lockstep.benchmarks"};
      for (const auto& a : bench->remaining()) args.push_back(a);
      return RunPython(args);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lockstep: %s\n", e.what());
    return 2;
  }
  return 0;
}
