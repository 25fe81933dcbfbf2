#pragma once
// `lockstep serve`: what a CARLA user starts as "the simulator". Every service that is built
// (air_sim, ground_sim, sensors, render) on one map, free-running at real time
// (asynchronous, 0.05 s steps, as CARLA's server starts), waiting for clients until Ctrl-C.
// The config it runs is the one ../shared/tools/compat writes for CARLA's own scripts.
#include <string>
#include <vector>

namespace lockstep::launcher {

struct ServeOptions {
  std::string map = "Town01";      // a name (<name>.xodr on the map path) or a path to an .xodr
  int domain = 0;
  unsigned long long seed = 1;
  double fixed_delta_seconds = 0.05;
};

// Where a map name is looked up, in order: $LOCKSTEP_MAPS_PATH (':'-separated), the build's
// generated towns (<build>/maps/generated) and CARLA's towns beside the checkout
// (<checkout>/../shared/maps/carla) — the folders carla.Client.load_world searches.
std::vector<std::string> MapSearchPath(const std::string& build_dir);
// The .xodr file of `map` (a path as it is, or <name>.xodr on the search path); throws
// lockstep::InputError naming the folders searched.
std::string FindMap(const std::string& map, const std::vector<std::string>& search);
// The services that are built: the lockstep_<kind> programs in <build>/bin.
std::vector<std::string> BuiltServices(const std::string& build_dir);
// The launch config (YAML) of the server.
std::string ServeConfig(const ServeOptions& options, const std::string& map_file, const std::vector<std::string>& services);

}  // namespace lockstep::launcher
