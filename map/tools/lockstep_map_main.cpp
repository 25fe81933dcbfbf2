// lockstep-map: map utilities usable before the main CLI exists.
//   lockstep-map info <file.xodr> [--json]
//   lockstep-map generate --kind town1|town2 --seed N --out DIR
//   lockstep-map scene <file.xodr> --seed N --out FILE     (scene for any OpenDRIVE map)
//   lockstep-map meshes <file.xodr> [scene.yaml]            (triangle counts per semantic class)
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "lockstep/map/error.h"
#include "lockstep/map/map.h"
#include "lockstep/map/map_info.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/map/town_generator.h"

namespace lm = lockstep::map;

namespace {

int Usage() {
  std::cerr << "usage:\n"
               "  lockstep-map info <file.xodr> [--json]\n"
               "  lockstep-map generate --kind town1|town2 --seed N --out DIR\n"
               "  lockstep-map scene <file.xodr> --seed N --out FILE\n"
               "  lockstep-map meshes <file.xodr> [scene.yaml]\n";
  return 2;
}

std::string Flag(const std::vector<std::string>& args, const std::string& name, const std::string& fallback = "") {
  for (std::size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == name) return args[i + 1];
  return fallback;
}

std::uint64_t ParseSeed(const std::string& s) {
  char* end = nullptr;
  const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0') throw lm::MapError("--seed must be a non-negative integer, got '" + s + "'");
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return Usage();
  try {
    if (args[0] == "info" && args.size() >= 2) {
      const lm::Map map = lm::Map::Load(args[1]);
      const lm::MapStats st = lm::ComputeStats(map);
      const bool json = args.size() >= 3 && args[2] == "--json";
      std::cout << (json ? lm::StatsToJson(st) + "\n" : lm::StatsToText(st));
      return 0;
    }
    if (args[0] == "generate") {
      const std::string out = Flag(args, "--out");
      if (out.empty()) return Usage();
      const lm::GeneratedTown town = lm::GenerateTown(lm::ParseTownKind(Flag(args, "--kind", "town1")), ParseSeed(Flag(args, "--seed", "0")));
      lm::WriteTownFiles(town, out);
      std::cout << out << "/" << town.name << ".xodr\n" << out << "/" << town.name << ".scene.yaml\n";
      return 0;
    }
    if (args[0] == "scene" && args.size() >= 2) {
      const std::string out = Flag(args, "--out");
      if (out.empty()) return Usage();
      const lm::Map map = lm::Map::Load(args[1]);
      std::ofstream f(out, std::ios::binary);
      f << lm::SceneToYaml(lm::GenerateScene(map, ParseSeed(Flag(args, "--seed", "0"))));
      if (!f) throw lm::MapError(out + ": cannot write");
      return 0;
    }
    if (args[0] == "meshes" && args.size() >= 2) {
      const lm::Map map = lm::Map::Load(args[1]);
      const lm::Scene scene = args.size() >= 3 ? lm::LoadSceneFile(args[2]) : lm::GenerateScene(map, 0);
      std::map<int, std::pair<std::size_t, std::size_t>> per_tag;  // tag -> (meshes, triangles)
      std::size_t total = 0;
      for (const lm::Mesh& m : lm::BuildWorldMeshes(map, scene)) {
        per_tag[m.semantic_tag].first += 1;
        per_tag[m.semantic_tag].second += m.TriangleCount();
        total += m.TriangleCount();
      }
      for (const auto& [tag, c] : per_tag) std::printf("tag %2d: %5zu meshes %8zu triangles\n", tag, c.first, c.second);
      std::printf("total: %zu triangles, %zu buildings\n", total, scene.buildings.size());
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "lockstep-map: " << e.what() << "\n";
    return 1;
  }
  return Usage();
}
