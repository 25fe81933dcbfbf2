#include "log_command.h"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "lockstep/coordinator/coordinator.h"
#include "lockstep/recorder/carla_text.h"
#include "lockstep/recorder/log_reader.h"
#include "lockstep/recorder/log_writer.h"
#include "lockstep/recorder/resimulate.h"
#include "lockstep/recorder/sensor_export.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/launch_config.h"
#include "progress.h"
#include "supervisor.h"

namespace lockstep::launcher {
namespace {

using recorder::LogReader;

std::string BinDir() { return std::filesystem::canonical("/proc/self/exe").parent_path().string(); }

const char* KindName(msg::ActorKind k) {
  switch (k) {
    case msg::ActorKind::ACTOR_VEHICLE: return "vehicle";
    case msg::ActorKind::ACTOR_WALKER: return "walker";
    case msg::ActorKind::ACTOR_DRONE: return "drone";
    case msg::ActorKind::ACTOR_SENSOR: return "sensor";
    case msg::ActorKind::ACTOR_TRAFFIC_LIGHT: return "traffic_light";
    case msg::ActorKind::ACTOR_TRAFFIC_SIGN: return "traffic_sign";
    case msg::ActorKind::ACTOR_CONTROLLER: return "controller";
    case msg::ActorKind::ACTOR_PROP: return "prop";
    default: return "other";
  }
}

std::string Hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

int Info(const std::string& name, bool carla, bool all) {
  if (carla) {
    std::fputs(recorder::ShowRecorderFileInfo(name, all).c_str(), stdout);
    return 0;
  }
  LogReader log(recorder::ResolveLogPath(name));
  const auto& h = log.header();
  std::printf("log        %s\n", log.path().c_str());
  std::printf("map        %s (digest %s)\n", h.map_name.c_str(), Hex(h.map_digest).c_str());
  std::printf("seed       %llu, run %u\n", static_cast<unsigned long long>(h.seed), h.run);
  std::printf("config     %s\n", h.config_source.empty() ? "(none)" : h.config_source.c_str());
  std::printf("frames     %llu..%llu (%llu frames, %.2f s of simulated time)%s\n", static_cast<unsigned long long>(log.first_frame()),
              static_cast<unsigned long long>(log.last_frame()), static_cast<unsigned long long>(log.frame_count()), log.duration(),
              log.truncated() ? ", truncated: no footer (a crash or still recording)" : "");
  if (!log.truncated()) std::printf("stopped    %s\n", log.stop_reason().c_str());
  if (h.prelude_frames > 0) {
    std::printf("prelude    frames 1..%llu (%zu ticks with commands)\n", static_cast<unsigned long long>(h.prelude_frames), h.prelude.size());
  }
  const double mb = static_cast<double>(log.file_size()) / 1e6;
  std::printf("size       %.3f MB (%.1f MB per simulated hour)\n", mb, log.duration() > 0 ? mb * 3600 / log.duration() : 0.0);
  std::printf("services  ");
  for (const auto& s : h.services) std::printf(" %s (%s%s)", s.name.c_str(), s.kind.empty() ? "?" : s.kind.c_str(), s.required ? "" : ", optional");
  std::printf("\n");
  std::map<std::string, int> kinds;
  for (const auto& [id, a] : log.actors()) ++kinds[KindName(a.kind)];
  std::printf("actors    ");
  for (const auto& [k, n] : kinds) std::printf(" %d %s", n, k.c_str());
  std::printf("\n");
  // The recorded sensor outputs: per sensor, then per message type, with their size.
  const auto& stats = log.sensor_stats();
  const double hours = log.duration() > 0 ? log.duration() / 3600 : 0;
  auto per_hour = [&](uint64_t bytes) { return hours > 0 ? static_cast<double>(bytes) / 1e6 / hours : 0.0; };
  if (h.sensor_selection.empty() && stats.empty()) {
    std::printf("sensors    none recorded\n");
    return 0;
  }
  uint64_t total = 0;
  for (const auto& st : stats) total += st.bytes;
  std::printf("sensors    selection '%s': %zu sensors with outputs, %.3f MB (%.1f MB per simulated hour)\n", h.sensor_selection.c_str(),
              stats.size(), static_cast<double>(total) / 1e6, per_hour(total));
  std::map<std::string, std::array<uint64_t, 3>> types;  // type -> sensors, samples, bytes
  for (const auto& st : stats) {
    auto it = log.actors().find(st.sensor);
    std::printf("  sensor %u %s (%s): %llu samples, frames %llu..%llu, %.3f MB, %.1f kB per sample\n", st.sensor,
                it == log.actors().end() ? "?" : it->second.blueprint.c_str(), st.type.c_str(), static_cast<unsigned long long>(st.samples),
                static_cast<unsigned long long>(st.first_frame), static_cast<unsigned long long>(st.last_frame),
                static_cast<double>(st.bytes) / 1e6, st.samples ? static_cast<double>(st.bytes) / 1e3 / static_cast<double>(st.samples) : 0.0);
    auto& t = types[st.type];
    ++t[0];
    t[1] += st.samples;
    t[2] += st.bytes;
  }
  for (const auto& [type, t] : types) {
    std::printf("  %s: %llu sensors, %llu samples, %.3f MB, %.1f kB per sample, %.1f MB per simulated hour\n", type.c_str(),
                static_cast<unsigned long long>(t[0]), static_cast<unsigned long long>(t[1]), static_cast<double>(t[2]) / 1e6,
                t[1] ? static_cast<double>(t[2]) / 1e3 / static_cast<double>(t[1]) : 0.0, per_hour(t[2]));
  }
  return 0;
}

void WriteCsv(LogReader& log, const std::string& dir) {
  std::filesystem::create_directories(dir);
  std::ofstream frames(dir + "/frames.csv"), actors(dir + "/actors.csv"), air(dir + "/air_state.csv"), events(dir + "/events.csv");
  if (!frames || !actors || !air || !events) throw InputError("lockstep log export: cannot write into " + dir);
  frames << "tick,sim_time,commands,shown_frame,world_hash\n";
  actors << "frame,sim_time,actor,kind,blueprint,x,y,z,roll,pitch,yaw,vx,vy,vz\n";
  air << "frame,sim_time,actor,x,y,z,qw,qx,qy,qz,vx,vy,vz,landed,armed,command_id,command_status\n";
  events << "frame,sim_time,kind,actor,other_actor,detail\n";
  const auto& infos = log.actors();
  WorkProgress progress("export", log.frame_count());
  char buf[512];
  log.ForEach(
      0, UINT64_MAX,
      [&](const recorder::LogFrame& f) {
        std::snprintf(buf, sizeof buf, "%llu,%.3f,%zu,%llu,%s\n", static_cast<unsigned long long>(f.frame), f.sim_time,
                      f.tick.commands().size(), static_cast<unsigned long long>(f.state_frame),
                      f.hashes ? Hex(f.hashes->world_hash).c_str() : "");
        frames << buf;
        for (const auto& s : f.actors) {
          auto it = infos.find(s.id);
          std::snprintf(buf, sizeof buf, "%llu,%.3f,%u,%s,%s,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f,%.3f,%.3f,%.3f\n",
                        static_cast<unsigned long long>(f.frame), f.sim_time, s.id, KindName(s.kind),
                        it == infos.end() ? "" : it->second.blueprint.c_str(), s.x, s.y, s.z, s.roll, s.pitch, s.yaw, s.vx, s.vy, s.vz);
          actors << buf;
          if (s.kind != msg::ActorKind::ACTOR_DRONE) continue;
          const msg::Pose p = s.pose();
          const auto& q = p.orientation();
          std::snprintf(buf, sizeof buf, "%llu,%.3f,%u,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%d,%d,%llu,%u\n",
                        static_cast<unsigned long long>(f.state_frame), f.sim_time, s.id, s.x, s.y, s.z, q.w(), q.x(), q.y(), q.z(),
                        s.vx, s.vy, s.vz, s.landed ? 1 : 0, s.armed ? 1 : 0, static_cast<unsigned long long>(s.command_id),
                        s.command_status);
          air << buf;
        }
        for (const auto& c : f.collisions) {
          std::snprintf(buf, sizeof buf, "%llu,%.3f,collision,%u,%u,impulse %.3f %.3f %.3f\n", static_cast<unsigned long long>(f.frame),
                        f.sim_time, c.actor, c.other_actor, c.impulse[0], c.impulse[1], c.impulse[2]);
          events << buf;
        }
        for (const auto& l : f.lane_invasions) {
          std::snprintf(buf, sizeof buf, "%llu,%.3f,lane_invasion,%u,0,%zu markings\n", static_cast<unsigned long long>(f.frame),
                        f.sim_time, l.actor, l.crossed.size());
          events << buf;
        }
        static const char* infraction[] = {"red_light", "stop_sign", "collision", "opposite_lane", "offroad"};
        for (const auto& i : f.infractions) {
          std::snprintf(buf, sizeof buf, "%llu,%.3f,infraction,%u,0,%s x%u\n", static_cast<unsigned long long>(f.frame), f.sim_time,
                        i.actor, infraction[static_cast<int>(i.kind)], i.count);
          events << buf;
        }
        return true;
      },
      [&](uint64_t done, uint64_t) { progress.Update(done, 0); });
  progress.Done();
}

// The first frame where two logs differ: ticks, then hashes, then actor states.
int Diff(const std::string& a_name, const std::string& b_name) {
  LogReader a(recorder::ResolveLogPath(a_name)), b(recorder::ResolveLogPath(b_name));
  const uint64_t from = std::max(a.first_frame(), b.first_frame());
  const uint64_t to = std::min(a.last_frame(), b.last_frame());
  if (a.empty() || b.empty() || from > to) {
    std::printf("the logs share no frame (%llu..%llu and %llu..%llu)\n", static_cast<unsigned long long>(a.first_frame()),
                static_cast<unsigned long long>(a.last_frame()), static_cast<unsigned long long>(b.first_frame()),
                static_cast<unsigned long long>(b.last_frame()));
    return 1;
  }
  std::vector<std::pair<std::string, std::optional<recorder::FrameHashes>>> bt;
  b.ForEachTick(from, to, [&](uint64_t, const std::string& t, const std::optional<recorder::FrameHashes>& h) {
    bt.emplace_back(t, h);
    return true;
  });
  WorkProgress progress("diff", to - from + 1);
  std::string why;
  uint64_t at = 0;
  a.ForEachTick(from, to, [&](uint64_t k, const std::string& t, const std::optional<recorder::FrameHashes>& h) {
    const auto& [t2, h2] = bt[k - from];
    if ((k - from) % 256 == 0) progress.Update(k - from + 1, 0);
    if (t != t2) {
      at = k;
      why = "the ticks differ (commands or settings)";
      return false;
    }
    if (h && h2 && h->world_hash != h2->world_hash) {
      at = k;
      why = "world hash " + Hex(h->world_hash) + " vs " + Hex(h2->world_hash);
      std::map<std::string, uint64_t> other(h2->services.begin(), h2->services.end());
      for (const auto& [s, v] : h->services) {
        if (other.count(s) && other[s] != v) {
          why += "; service '" + s + "' " + Hex(v) + " vs " + Hex(other[s]);
          break;
        }
      }
      return false;
    }
    return true;
  });
  if (at == 0) {
    // Same ticks and hashes: compare the recorded states too.
    b.ForEach(from, to, [&](const recorder::LogFrame& fb) {
      const recorder::LogFrame fa = a.Read(fb.frame);
      if (fa.actors.size() != fb.actors.size()) {
        at = fb.frame;
        why = std::to_string(fa.actors.size()) + " actors vs " + std::to_string(fb.actors.size());
        return false;
      }
      for (size_t i = 0; i < fa.actors.size(); ++i) {
        const auto& x = fa.actors[i];
        const auto& y = fb.actors[i];
        if (x.id != y.id || x.x != y.x || x.y != y.y || x.z != y.z || x.yaw != y.yaw || x.pitch != y.pitch || x.roll != y.roll) {
          at = fb.frame;
          why = "actor " + std::to_string(x.id) + " is elsewhere";
          return false;
        }
      }
      progress.Update(fb.frame - from + 1, 0);
      return true;
    });
  }
  progress.Done();
  if (at == 0) {
    std::printf("the logs agree on frames %llu..%llu (ticks, world hashes and states)\n", static_cast<unsigned long long>(from),
                static_cast<unsigned long long>(to));
    return 0;
  }
  std::printf("first difference at frame %llu: %s\n", static_cast<unsigned long long>(at), why.c_str());
  return 1;
}

// The launch config a log was recorded with: --config if given, else its source file when
// it still holds the recorded text, else the recorded text written beside where it was.
std::string ConfigFileFor(const LogReader& log, const std::string& given) {
  if (!given.empty()) return given;
  const auto& h = log.header();
  if (h.config_text.empty()) throw InputError("the log carries no launch config: give one with --config");
  if (std::ifstream in(h.config_source); in) {
    std::stringstream text;
    text << in.rdbuf();
    if (text.str() == h.config_text) return h.config_source;
  }
  std::filesystem::path dir = std::filesystem::path(h.config_source).parent_path();
  if (dir.empty() || !std::filesystem::is_directory(dir) || access(dir.c_str(), W_OK) != 0) dir = std::filesystem::temp_directory_path();
  const std::string file = (dir / (".lockstep-resimulate-" + std::to_string(getpid()) + ".yaml")).string();
  std::ofstream(file) << h.config_text;
  return file;
}

int Resimulate(const std::string& name, const std::string& config_given, int domain, double timeout_s, const std::atomic<bool>& stop) {
  LogReader log(recorder::ResolveLogPath(name));
  const std::string config_file = ConfigFileFor(log, config_given);
  // The recorder the log's run had from `lockstep up`, and one that writes nothing.
  setenv("LOCKSTEP_DEFAULT_RECORDER", "1", 1);
  setenv("LOCKSTEP_RECORDER_READ_ONLY", "1", 1);
  LaunchConfig config = LoadLaunchConfig(config_file);
  if (domain >= 0) config.domain_id = domain;
  if (const std::string why = recorder::ResimulationRefusal(log, config); !why.empty()) {
    std::fprintf(stderr, "lockstep log replay: refused: %s\n", why.c_str());
    return 3;
  }
  const LaunchConfig plan = recorder::ResimulationConfig(log, config);
  const std::string bin = BinDir();
  const std::string dom = std::to_string(config.domain_id);
  std::vector<ChildSpec> children;
  for (const auto& s : config.services) {
    std::string exe = s.executable.empty() ? bin + "/lockstep_" + s.kind : s.executable;
    if (exe.find('/') == std::string::npos) exe = bin + "/" + exe;
    std::vector<std::string> argv{exe, "--name", s.name, "--config", config_file, "--domain", dom};
    argv.insert(argv.end(), s.args.begin(), s.args.end());
    children.push_back({s.name, argv, false, false});
  }
  std::printf("lockstep log replay: re-simulating %s (frames %llu..%llu) with %s on DDS domain %d\n", log.path().c_str(),
              static_cast<unsigned long long>(log.first_frame()), static_cast<unsigned long long>(log.last_frame()),
              config_file.c_str(), config.domain_id);
  std::fflush(stdout);
  auto bus = CreateDdsBus({config.domain_id, config.qos_file, config.participant_profile, "lockstep-resimulate"});
  recorder::ResimulationCheck check(*bus, log);
  Supervisor supervisor(std::move(children));
  std::atomic<bool> services_stop{false}, coordinator_stop{false};
  std::thread services([&] { supervisor.Run(services_stop); });
  Coordinator coordinator(*bus, plan);
  std::thread coordinator_thread([&] { coordinator.Run(coordinator_stop); });
  WorkProgress progress("re-simulation", log.frame_count());
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = check.Wait(timeout_s, stop, [&](uint64_t done, uint64_t) { progress.Update(done, 0); });
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.Done();
  coordinator_stop = true;
  coordinator_thread.join();
  services_stop = true;
  services.join();
  if (config_file != config_given && config_file != log.header().config_source) std::filesystem::remove(config_file);
  if (r.ok()) {
    std::printf("re-simulation of frames %llu..%llu: every world hash equal (%llu frames compared, %llu without a hash); "
                "%.2f s of simulated time in %.2f s (%.1f x real time)\n",
                static_cast<unsigned long long>(log.first_frame()), static_cast<unsigned long long>(log.last_frame()),
                static_cast<unsigned long long>(r.frames_checked), static_cast<unsigned long long>(r.frames_unchecked), log.duration(),
                wall, wall > 0 ? log.duration() / wall : 0.0);
    return 0;
  }
  if (r.first_differing != 0) {
    std::printf("re-simulation differs first at frame %llu%s: %s\n", static_cast<unsigned long long>(r.first_differing),
                r.service.empty() ? "" : (" (service '" + r.service + "')").c_str(), r.reason.c_str());
  } else {
    std::printf("re-simulation incomplete: %s\n", r.reason.c_str());
  }
  return 1;
}

}  // namespace

int LogCommand(const std::vector<std::string>& args, const std::atomic<bool>& stop) {
  CLI::App app{"lockstep log: read, query, export, re-simulate and compare Lockstep logs (docs/recorder.md)", "lockstep log"};
  app.require_subcommand(1);
  std::string name, other, csv_dir, config;
  bool carla = false, all = false, resimulate = false;
  char type1 = 'a', type2 = 'a';
  double min_time = 30, min_distance = 10, timeout_s = 60;
  int domain = -1;
  auto* info = app.add_subcommand("info", "what a log holds (--carla: CARLA's show_recorder_file_info text)");
  info->add_option("log", name, "log file (relative: in the recordings folder)")->required();
  info->add_flag("--carla", carla, "CARLA's show_recorder_file_info text");
  info->add_flag("-a,--all", all, "with --carla: every frame's positions, lights and animations");
  auto* collisions = app.add_subcommand("collisions", "CARLA's show_recorder_collisions text");
  collisions->add_option("log", name, "log file")->required();
  std::string types = "aa";
  collisions->add_option("-t,--types", types, "two categories: h hero, v vehicle, w walker, t traffic light, o other, a any")
      ->capture_default_str();
  auto* blocked = app.add_subcommand("blocked", "CARLA's show_recorder_actors_blocked text");
  blocked->add_option("log", name, "log file")->required();
  blocked->add_option("--min-time", min_time, "s an actor must stand")->capture_default_str();
  blocked->add_option("--min-distance", min_distance, "cm it may move meanwhile")->capture_default_str();
  auto* exp = app.add_subcommand("export", "the log as CSV files (frames, actors, air_state, events) and its recorded sensor outputs as files");
  exp->add_option("log", name, "log file")->required();
  exp->add_option("--csv", csv_dir, "folder for the CSV files");
  std::string sensors_dir, points_format = "ply";
  std::vector<uint32_t> sensor_ids;
  exp->add_option("--sensors", sensors_dir, "folder for the recorded sensor outputs (camera PNG/npy, LiDAR PLY/npy, CSV)");
  exp->add_option("--points", points_format, "LiDAR files: ply or npy")->check(CLI::IsMember({"ply", "npy"}))->capture_default_str();
  exp->add_option("--sensor", sensor_ids, "only these sensor ids (repeat the option)");
  auto* replay = app.add_subcommand("replay", "re-simulate a log: its ticks re-drive the services, every world hash compared");
  replay->add_option("log", name, "log file")->required();
  replay->add_flag("--resimulate", resimulate, "re-drive the real services (playback: carla.Client.replay_file)");
  replay->add_option("--config", config, "launch config to run (default: the log's); refused if its map, seed or services differ");
  replay->add_option("--domain", domain, "DDS domain id (default: the config's)");
  replay->add_option("--timeout", timeout_s, "s without a new frame before giving up")->capture_default_str();
  auto* diff = app.add_subcommand("diff", "the first frame where two logs differ");
  diff->add_option("a", name, "first log")->required();
  diff->add_option("b", other, "second log")->required();
  std::vector<std::string> rev(args.rbegin(), args.rend());
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (info->parsed()) return Info(name, carla, all);
    if (collisions->parsed()) {
      if (types.size() != 2 || std::string("hvwtoa").find(types[0]) == std::string::npos ||
          std::string("hvwtoa").find(types[1]) == std::string::npos) {
        std::fprintf(stderr, "lockstep log collisions: --types takes two of h v w t o a, got '%s'\n", types.c_str());
        return 2;
      }
      type1 = types[0];
      type2 = types[1];
      std::fputs(recorder::ShowRecorderCollisions(name, type1, type2).c_str(), stdout);
      return 0;
    }
    if (blocked->parsed()) {
      std::fputs(recorder::ShowRecorderActorsBlocked(name, min_time, min_distance).c_str(), stdout);
      return 0;
    }
    if (exp->parsed()) {
      if (csv_dir.empty() && sensors_dir.empty()) {
        std::fprintf(stderr, "lockstep log export: give --csv DIR, --sensors DIR or both\n");
        return 2;
      }
      LogReader log(recorder::ResolveLogPath(name));
      if (!csv_dir.empty()) {
        WriteCsv(log, csv_dir);
        std::printf("wrote frames.csv, actors.csv, air_state.csv and events.csv of %llu frames into %s\n",
                    static_cast<unsigned long long>(log.frame_count()), csv_dir.c_str());
      }
      if (!sensors_dir.empty()) {
        recorder::SensorExportOptions eo;
        eo.points = points_format;
        eo.sensors = sensor_ids;
        WorkProgress progress("export sensors", log.frame_count());
        const auto r = recorder::ExportSensors(log, sensors_dir, eo, [&](uint64_t done, uint64_t) { progress.Update(done, 0); });
        progress.Done();
        std::string by;
        for (const auto& [type, n] : r.by_type) {
          if (!by.empty()) by += ", ";
          by += std::to_string(n);
          by += ' ';
          by += type;
        }
        std::printf("wrote %llu sensor samples (%s) into %llu files under %s\n", static_cast<unsigned long long>(r.samples),
                    by.empty() ? "the log has none" : by.c_str(), static_cast<unsigned long long>(r.files), sensors_dir.c_str());
      }
      return 0;
    }
    if (replay->parsed()) {
      if (!resimulate) {
        std::fprintf(stderr, "lockstep log replay: only --resimulate from the command line; playback (actors following "
                             "their recorded states) is carla.Client.replay_file in a running simulation\n");
        return 2;
      }
      return Resimulate(name, config, domain, timeout_s, stop);
    }
    if (diff->parsed()) return Diff(name, other);
  } catch (const recorder::LogError& e) {
    std::fprintf(stderr, "lockstep log: %s\n", e.what());
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "lockstep log: %s\n", e.what());
    return 2;
  }
  return 2;
}

}  // namespace lockstep::launcher
