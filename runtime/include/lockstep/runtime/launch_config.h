#pragma once
// The launch config: which services make up a simulation and how the world runs.
// Loaded from YAML (deploy/configs/*.yaml); unknown keys and bad values are errors
// that name the key and line.
#include <map>
#include <string>
#include <vector>

#include "lockstep/runtime/messages.h"

namespace lockstep {

struct ServiceLaunch {
  std::string name;                 // unique service name
  std::string kind;                 // what to run: air_sim, noop, cyclone_c, ...
  std::string executable;           // program; empty = lockstep_<kind> next to the launcher
  std::vector<std::string> args;    // extra arguments
  bool required = true;             // the barrier waits for it
  bool perception = false;
  std::string restart = "never";    // never | on-failure (the launcher starts a replacement)
};

msg::WorldSettings DefaultWorldSettings();

// A command the coordinator itself issues at a given frame, so a scripted scenario is as
// deterministic as the run (it is sequenced before any client command of that frame).
struct ScheduledCommand {
  uint64_t frame = 1;          // applied in the tick that produces this frame
  std::string alias;           // spawn: a name later steps use in `actor`
  std::string actor_alias;     // the actor this command addresses (a spawn: its parent), by alias (filled in at run time)
  msg::Command command;        // client "scenario"
};

// A machine (or container engine) that runs some of the services (`hosts:`); a service
// names it in `host:`. `lockstep up` starts only the services of this machine and prints
// the command that starts each of the others where it runs (docs/deployment.md).
struct HostLaunch {
  std::string name;         // the key under `hosts:`
  std::string address;      // ssh destination ([user@]host): run the program there
  std::string build_dir;    // the build on that host (its bin/ holds the programs); default: this build's
  std::string config;       // the launch config's path on that host; default: this config's path
  std::string container;    // podman | docker: run the service as a container of its image instead
  std::string image_prefix = "localhost/lockstep/";  // the service's image is <image_prefix><kind>
  std::string network;      // container network (default: the engine's)
};

struct LaunchConfig {
  std::string source = "(built-in)";  // file it came from, for messages
  std::string name = "lockstep";
  int domain_id = 0;                  // DDS domain
  std::string participant_profile = "lockstep.participant";
  std::string qos_file;               // empty = the built-in deploy/qos/fastdds.xml
  uint64_t seed = 42;
  std::string map;                    // path to an .xodr file (scene beside it as .scene.yaml); empty = none
  uint64_t ticks = 0;                 // free-running: stop after this many ticks (0 = run until stopped)
  std::string output_dir;             // where services write outputs; empty = none
  uint64_t snapshot_period = 200;     // frames between each service's state snapshots: a replacement
                                      // replays at most this many ticks (1 .. MaxSnapshotPeriod())
  msg::WorldSettings world = DefaultWorldSettings();
  std::vector<ServiceLaunch> services;
  std::vector<ScheduledCommand> scenario;  // sorted by frame, stable
  std::vector<HostLaunch> hosts;           // `hosts:` in file order
  std::map<std::string, std::string> service_host;  // service name -> a name of `hosts` (absent: this machine)
  bool ros2 = false;                       // `ros2: true` (or LOCKSTEP_ROS2=1): the run has a ros2_bridge service

  std::vector<std::string> RequiredServices() const;
  // The host entry a service runs on; nullptr for this machine.
  const HostLaunch* HostOf(const std::string& service) const;
};

// The build directory: $LOCKSTEP_BUILD_DIR, else the one the running program was built
// into (build/bin/<program>). "${LOCKSTEP_BUILD_DIR}" in `map` and `output_dir` expands to it.
std::string BuildDir();
LaunchConfig LoadLaunchConfig(const std::string& file);
LaunchConfig ParseLaunchConfig(const std::string& yaml_text, const std::string& source_name);
// Checks ranges and cross-field rules; throws InputError naming the field.
void ValidateWorldSettings(const msg::WorldSettings& s, const std::string& where);

}  // namespace lockstep
