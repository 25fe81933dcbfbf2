// lockstep-map: map utilities usable before the main CLI exists.
//   lockstep-map info <file.xodr> [--json]
//   lockstep-map generate --kind town1|town2 --seed N --out DIR
//   lockstep-map scene <file.xodr> --seed N --out FILE     (scene for any OpenDRIVE map)
//   lockstep-map meshes <file.xodr> [scene.yaml]            (triangle counts per semantic class)
//   lockstep-map topview <file.xodr> [scene.yaml] --out FILE.ppm [--px-per-m K]
//                                                            (top-down semantic image, CARLA palette)
#include <algorithm>
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
               "  lockstep-map meshes <file.xodr> [scene.yaml]\n"
               "  lockstep-map topview <file.xodr> [scene.yaml] --out FILE.ppm [--px-per-m K]\n";
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

// CARLA semantic palette (ids 0..28), for the top view.
const unsigned char kPalette[29][3] = {
    {0, 0, 0},       {128, 64, 128},  {244, 35, 232}, {70, 70, 70},    {102, 102, 156}, {190, 153, 153},
    {153, 153, 153}, {250, 170, 30},  {220, 220, 0},  {107, 142, 35},  {152, 251, 152}, {70, 130, 180},
    {220, 20, 60},   {255, 0, 0},     {0, 0, 142},    {0, 0, 70},      {0, 60, 100},    {0, 80, 100},
    {0, 0, 230},     {119, 11, 32},   {110, 190, 160}, {170, 120, 50}, {55, 90, 80},    {45, 60, 150},
    {157, 234, 50},  {81, 0, 81},     {150, 100, 100}, {230, 150, 140}, {180, 165, 180}};

// Orthographic top-down rasteriser: triangles drawn lowest first, so roofs cover walls.
void TopView(const std::vector<lm::Mesh>& meshes, double ppm, const std::string& out) {
  struct Tri { float z; int tag; float x[3], y[3]; };
  std::vector<Tri> tris;
  float minx = 1e30f, miny = 1e30f, maxx = -1e30f, maxy = -1e30f;
  for (const lm::Mesh& m : meshes)
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
      Tri tr{-1e30f, m.semantic_tag, {}, {}};
      for (int k = 0; k < 3; ++k) {
        const std::size_t v = 3 * m.indices[t + static_cast<std::size_t>(k)];
        tr.x[k] = m.vertices[v];
        tr.y[k] = m.vertices[v + 1];
        tr.z = std::max(tr.z, m.vertices[v + 2]);
        minx = std::min(minx, tr.x[k]); maxx = std::max(maxx, tr.x[k]);
        miny = std::min(miny, tr.y[k]); maxy = std::max(maxy, tr.y[k]);
      }
      tris.push_back(tr);
    }
  std::stable_sort(tris.begin(), tris.end(), [](const Tri& a, const Tri& b) { return a.z < b.z; });
  const int w = static_cast<int>((maxx - minx) * ppm) + 1, h = static_cast<int>((maxy - miny) * ppm) + 1;
  std::vector<unsigned char> img(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3, 0);
  for (const Tri& t : tris) {
    float px[3], py[3];
    for (int k = 0; k < 3; ++k) {
      px[k] = static_cast<float>((t.x[k] - minx) * ppm);
      py[k] = static_cast<float>((maxy - t.y[k]) * ppm);  // north up
    }
    const int x0 = std::max(0, static_cast<int>(std::min({px[0], px[1], px[2]})));
    const int x1 = std::min(w - 1, static_cast<int>(std::max({px[0], px[1], px[2]})));
    const int y0 = std::max(0, static_cast<int>(std::min({py[0], py[1], py[2]})));
    const int y1 = std::min(h - 1, static_cast<int>(std::max({py[0], py[1], py[2]})));
    const float area = (px[1] - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (py[1] - py[0]);
    if (area == 0) continue;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float cx = static_cast<float>(x) + 0.5f, cy = static_cast<float>(y) + 0.5f;
        const float w0 = ((px[1] - cx) * (py[2] - cy) - (px[2] - cx) * (py[1] - cy)) / area;
        const float w1 = ((px[2] - cx) * (py[0] - cy) - (px[0] - cx) * (py[2] - cy)) / area;
        if (w0 < 0 || w1 < 0 || w0 + w1 > 1) continue;
        unsigned char* p = &img[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 3];
        const unsigned char* c = kPalette[t.tag < 29 ? t.tag : 0];
        p[0] = c[0]; p[1] = c[1]; p[2] = c[2];
      }
  }
  std::ofstream f(out, std::ios::binary);
  f << "P6\n" << w << " " << h << "\n255\n";
  f.write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
  if (!f) throw lm::MapError(out + ": cannot write");
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
    if (args[0] == "topview" && args.size() >= 2) {
      const std::string out = Flag(args, "--out");
      if (out.empty()) return Usage();
      const lm::Map map = lm::Map::Load(args[1]);
      const bool has_scene = args.size() >= 3 && args[2].rfind("--", 0) != 0;
      const lm::Scene scene = has_scene ? lm::LoadSceneFile(args[2]) : lm::GenerateScene(map, 0);
      TopView(lm::BuildWorldMeshes(map, scene), std::atof(Flag(args, "--px-per-m", "2").c_str()), out);
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "lockstep-map: " << e.what() << "\n";
    return 1;
  }
  return Usage();
}
