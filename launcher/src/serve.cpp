#include "serve.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "lockstep/runtime/error.h"

namespace lockstep::launcher {

namespace fs = std::filesystem;

std::vector<std::string> MapSearchPath(const std::string& build_dir) {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("LOCKSTEP_MAPS_PATH"); env && *env) {
    std::stringstream ss(env);
    for (std::string d; std::getline(ss, d, ':');) {
      if (!d.empty()) dirs.push_back(d);
    }
  }
  const fs::path build = fs::path(build_dir);
  dirs.push_back((build / "maps" / "generated").string());
  dirs.push_back((build.parent_path().parent_path() / "shared" / "maps" / "carla").lexically_normal().string());
  return dirs;
}

std::string FindMap(const std::string& map, const std::vector<std::string>& search) {
  if (map.empty()) throw InputError("lockstep serve: --map needs a map name or an .xodr file");
  if (map.find('/') != std::string::npos || fs::path(map).extension() == ".xodr") {
    if (!fs::is_regular_file(map)) throw InputError("lockstep serve: no map file " + map);
    return fs::absolute(map).lexically_normal().string();
  }
  std::string looked;
  for (const auto& dir : search) {
    const fs::path p = fs::path(dir) / (map + ".xodr");
    if (fs::is_regular_file(p)) return fs::absolute(p).lexically_normal().string();
    looked += (looked.empty() ? "" : ", ") + dir;
  }
  throw InputError("lockstep serve: no map '" + map + "' (" + map + ".xodr) in " + looked +
                   " (set LOCKSTEP_MAPS_PATH, or give a path to an .xodr file)");
}

std::vector<std::string> BuiltServices(const std::string& build_dir) {
  std::vector<std::string> out;
  for (const char* kind : {"air_sim", "ground_sim", "sensors", "render"}) {
    if (fs::exists(fs::path(build_dir) / "bin" / (std::string("lockstep_") + kind))) out.push_back(kind);
  }
  return out;
}

std::string ServeConfig(const ServeOptions& o, const std::string& map_file, const std::vector<std::string>& services) {
  std::ostringstream y;
  y << "# lockstep serve: every built service on one map, free-running at real time\n";
  y << "name: serve\n";
  y << "domain_id: " << o.domain << "\n";
  y << "seed: " << o.seed << "\n";
  y << "map: \"" << map_file << "\"\n";
  y << "world:\n";
  y << "  synchronous_mode: false\n";
  y << "  fixed_delta_seconds: " << o.fixed_delta_seconds << "\n";
  y << "  real_time_factor: 1\n";
  y << "  service_timeout: 30\n";
  y << "services:\n";
  for (const auto& s : services) {
    const bool perception = s == "sensors" || s == "render";
    y << "  - {name: " << s << ", kind: " << s << ", perception: " << (perception ? "true" : "false") << "}\n";
  }
  return y.str();
}

}  // namespace lockstep::launcher
