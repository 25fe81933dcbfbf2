#include "lockstep/map/town_generator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include "lockstep/map/error.h"
#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"

namespace lockstep::map {

TownKind ParseTownKind(const std::string& t) {
  if (t == "town1" || t == "Town1") return TownKind::Town1;
  if (t == "town2" || t == "Town2") return TownKind::Town2;
  throw MapError("unknown town kind '" + t + "' (expected town1 or town2)");
}

namespace {

struct Params {
  const char* name;
  int nx, ny;
  double dx_lo, dx_hi, dy_lo, dy_hi;  // block sizes (m)
  int removals;                       // interior streets removed at most
  double lane_w, walk_w;              // (m)
  double radius;                      // junction half size = turn radius of the reference line (m)
  double min_street_m;
  bool exact_length;
};

// min_street_m: total length of the streets outside junctions is at least this; Town2
// is scaled to exactly this (the paper's ~1.4 km), Town1 only stretched if short.
constexpr Params kTown1{"LockstepTown1", 5, 4, 122, 142, 108, 126, 3, 3.5, 3.0, 12.0, 2950.0, false};
constexpr Params kTown2{"LockstepTown2", 4, 3, 100, 116, 90, 104, 1, 3.25, 2.5, 11.0, 1400.0, true};

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : g_(seed) {}
  double Uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(g_() >> 11) * 0x1.0p-53; }
  std::uint64_t Next() { return g_(); }

 private:
  std::mt19937_64 g_;
};

std::string F(double v, int digits = 6) {
  if (std::fabs(v) < 0.5 * std::pow(10.0, -digits)) v = 0;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

struct Street {
  int a, b;  // node indices, a before b
};

struct Arm {
  int road;          // index into streets
  Eigen::Vector2d d; // unit vector from the node along the street
  bool at_start;     // the street starts at this node
};

class Writer {
 public:
  Writer(const Params& p, std::uint64_t seed) : p_(p), rng_(seed) {}

  GeneratedTown Run() {
    Layout();
    GeneratedTown town;
    town.name = p_.name;
    std::ostringstream& os = os_;
    const double pad = p_.radius + 10;
    os << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<OpenDRIVE>\n";
    os << "  <header revMajor=\"1\" revMinor=\"4\" name=\"" << p_.name << "\" version=\"1\" date=\"\" north=\""
       << F(ys_.back() + pad) << "\" south=\"" << F(-pad) << "\" east=\"" << F(xs_.back() + pad) << "\" west=\""
       << F(-pad) << "\" vendor=\"Lockstep\">\n";
    os << "    <geoReference><![CDATA[+proj=tmerc +lat_0=0 +lon_0=0 +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m "
          "+no_defs]]></geoReference>\n  </header>\n";
    WriteStreets(&town);
    WriteJunctions(&town);
    os << "</OpenDRIVE>\n";
    town.xodr = os.str();
    town.junctions = static_cast<int>(nodes_.size());
    return town;
  }

 private:
  int Node(int i, int j) const { return j * p_.nx + i; }
  Eigen::Vector2d Pos(int n) const { return {xs_[static_cast<std::size_t>(n % p_.nx)], ys_[static_cast<std::size_t>(n / p_.nx)]}; }

  void Layout() {
    xs_.assign(1, 0.0);
    ys_.assign(1, 0.0);
    for (int i = 1; i < p_.nx; ++i) xs_.push_back(xs_.back() + std::round(rng_.Uniform(p_.dx_lo, p_.dx_hi)));
    for (int j = 1; j < p_.ny; ++j) ys_.push_back(ys_.back() + std::round(rng_.Uniform(p_.dy_lo, p_.dy_hi)));
    for (int j = 0; j < p_.ny; ++j)
      for (int i = 0; i < p_.nx; ++i) {
        if (i + 1 < p_.nx) streets_.push_back({Node(i, j), Node(i + 1, j)});
        if (j + 1 < p_.ny) streets_.push_back({Node(i, j), Node(i, j + 1)});
      }
    // Remove a few interior streets (T junctions, like the CARLA towns), keeping every
    // node at degree >= 2 and the network connected.
    for (int k = 0; k < p_.removals; ++k) {
      const std::size_t pick = static_cast<std::size_t>(rng_.Next() % streets_.size());
      const Street st = streets_[pick];
      const Eigen::Vector2d a = Pos(st.a), b = Pos(st.b);
      const bool border = (a.x() == b.x() && (a.x() == xs_.front() || a.x() == xs_.back())) ||
                          (a.y() == b.y() && (a.y() == ys_.front() || a.y() == ys_.back()));
      if (border || Degree(st.a) <= 3 || Degree(st.b) <= 3) continue;
      std::vector<Street> trial = streets_;
      trial.erase(trial.begin() + static_cast<std::ptrdiff_t>(pick));
      if (Connected(trial)) streets_ = trial;
    }
    // Scale the grid so the street length meets the target (whole metres, so the file
    // stays tidy; rounding up keeps the minimum).
    double span = 0;
    for (const Street& st : streets_) span += (Pos(st.b) - Pos(st.a)).norm();
    const double fixed = 2 * p_.radius * static_cast<double>(streets_.size());
    if (p_.exact_length || span - fixed < p_.min_street_m) {
      const double k = (p_.min_street_m + fixed) / span;
      for (double& x : xs_) x = std::ceil(x * k);
      for (double& y : ys_) y = std::ceil(y * k);
    }
    nodes_.assign(static_cast<std::size_t>(p_.nx * p_.ny), {});
    for (std::size_t r = 0; r < streets_.size(); ++r) {
      const Street& st = streets_[r];
      const Eigen::Vector2d d = (Pos(st.b) - Pos(st.a)).normalized();
      nodes_[static_cast<std::size_t>(st.a)].push_back(Arm{static_cast<int>(r), d, true});
      nodes_[static_cast<std::size_t>(st.b)].push_back(Arm{static_cast<int>(r), -d, false});
    }
    centre_mark_.clear();
    for (std::size_t r = 0; r < streets_.size(); ++r) centre_mark_.push_back(rng_.Uniform(0, 1) < 0.6);
  }

  int Degree(int n) const {
    return static_cast<int>(std::count_if(streets_.begin(), streets_.end(), [&](const Street& s) { return s.a == n || s.b == n; }));
  }

  bool Connected(const std::vector<Street>& streets) const {
    const int n = p_.nx * p_.ny;
    std::vector<int> seen(static_cast<std::size_t>(n), 0), stack{0};
    seen[0] = 1;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (const Street& s : streets) {
        const int w = s.a == v ? s.b : s.b == v ? s.a : -1;
        if (w >= 0 && !seen[static_cast<std::size_t>(w)]) {
          seen[static_cast<std::size_t>(w)] = 1;
          stack.push_back(w);
        }
      }
    }
    return std::all_of(seen.begin(), seen.end(), [](int v) { return v; });
  }

  static std::string JunctionId(int node) { return std::to_string(1000 + node); }
  static std::string StreetId(int r) { return std::to_string(r + 1); }

  void Lane(int id, const char* type, double width, const std::string& mark, const std::string& links = "") {
    os_ << "          <lane id=\"" << id << "\" type=\"" << type << "\" level=\"false\">\n";
    if (!links.empty()) os_ << "            <link>" << links << "</link>\n";
    os_ << "            <width sOffset=\"0.000000\" a=\"" << F(width) << "\" b=\"0\" c=\"0\" d=\"0\"/>\n";
    os_ << "            " << mark << "\n          </lane>\n";
  }

  void Geometry(double x, double y, double hdg, double length, double curvature) {
    os_ << "      <geometry s=\"0.000000\" x=\"" << F(x) << "\" y=\"" << F(y) << "\" hdg=\"" << F(hdg, 12)
        << "\" length=\"" << F(length) << "\">";
    if (curvature == 0) os_ << "<line/>";
    else os_ << "<arc curvature=\"" << F(curvature, 12) << "\"/>";
    os_ << "</geometry>\n";
  }

  void Profiles() {
    os_ << "    <elevationProfile><elevation s=\"0.000000\" a=\"0\" b=\"0\" c=\"0\" d=\"0\"/></elevationProfile>\n";
    os_ << "    <lateralProfile/>\n";
  }

  void WriteStreets(GeneratedTown* town) {
    const std::string curb = "<roadMark sOffset=\"0.000000\" type=\"curb\" color=\"standard\" width=\"0.150000\" laneChange=\"none\"/>";
    const std::string none = "<roadMark sOffset=\"0.000000\" type=\"none\" color=\"standard\" width=\"0.000000\" laneChange=\"none\"/>";
    for (std::size_t r = 0; r < streets_.size(); ++r) {
      const Street& st = streets_[r];
      const Eigen::Vector2d a = Pos(st.a), b = Pos(st.b);
      const Eigen::Vector2d d = (b - a).normalized();
      const double len = (b - a).norm() - 2 * p_.radius;
      const Eigen::Vector2d start = a + p_.radius * d;
      const double hdg = std::atan2(d.y(), d.x());
      const std::string id = StreetId(static_cast<int>(r));
      os_ << "  <road name=\"Street " << id << "\" length=\"" << F(len) << "\" id=\"" << id << "\" junction=\"-1\">\n";
      os_ << "    <link><predecessor elementType=\"junction\" elementId=\"" << JunctionId(st.a)
          << "\"/><successor elementType=\"junction\" elementId=\"" << JunctionId(st.b) << "\"/></link>\n";
      os_ << "    <type s=\"0.000000\" type=\"town\"><speed max=\"30\" unit=\"km/h\"/></type>\n";
      os_ << "    <planView>\n";
      Geometry(start.x(), start.y(), hdg, len, 0);
      os_ << "    </planView>\n";
      Profiles();
      os_ << "    <lanes>\n      <laneOffset s=\"0.000000\" a=\"0\" b=\"0\" c=\"0\" d=\"0\"/>\n";
      os_ << "      <laneSection s=\"0.000000\">\n        <left>\n";
      Lane(2, "sidewalk", p_.walk_w, none);
      Lane(1, "driving", p_.lane_w, curb);
      os_ << "        </left>\n        <center>\n          <lane id=\"0\" type=\"none\" level=\"false\">\n";
      if (centre_mark_[r])
        os_ << "            <roadMark sOffset=\"0.000000\" type=\"solid\" color=\"yellow\" width=\"0.150000\" laneChange=\"none\"/>\n";
      else
        os_ << "            <roadMark sOffset=\"0.000000\" type=\"broken\" color=\"white\" width=\"0.120000\" laneChange=\"both\"/>\n";
      os_ << "          </lane>\n        </center>\n        <right>\n";
      Lane(-1, "driving", p_.lane_w, curb);
      Lane(-2, "sidewalk", p_.walk_w, none);
      os_ << "        </right>\n      </laneSection>\n    </lanes>\n";
      WriteStreetFurniture(r, len, town);
      os_ << "  </road>\n";
      town->roads += 1;
      town->road_length_m += len;
      town->driving_lane_length_m += 2 * len;
    }
  }

  bool Signalised(int node) const { return nodes_[static_cast<std::size_t>(node)].size() >= 3; }

  // Traffic lights and crosswalks at signalised ends, a speed sign near each start.
  void WriteStreetFurniture(std::size_t r, double len, GeneratedTown* town) {
    const Street& st = streets_[r];
    const double side_t = p_.lane_w + p_.walk_w - 0.6;
    std::ostringstream sig, obj;
    for (int end = 0; end < 2; ++end) {
      const int node = end == 0 ? st.a : st.b;
      if (!Signalised(node)) continue;
      // Traffic entering the junction at this end: lane 1 at the start (against s), -1 at the end.
      const double s = end == 0 ? 1.5 : len - 1.5;
      const double t = end == 0 ? side_t : -side_t;
      const int sid = next_signal_++;
      signals_of_[node].push_back(sid);
      sig << "      <signal name=\"TrafficLight\" id=\"" << sid << "\" s=\"" << F(s) << "\" t=\"" << F(t)
          << "\" zOffset=\"0.000000\" hOffset=\"0.000000\" roll=\"0\" pitch=\"0\" orientation=\"" << (end == 0 ? "-" : "+")
          << "\" dynamic=\"yes\" country=\"OpenDRIVE\" type=\"1000001\" subtype=\"-1\" value=\"-1\" text=\"\" height=\"4.200000\" width=\"0.350000\">\n"
          << "        <validity fromLane=\"" << (end == 0 ? 1 : -1) << "\" toLane=\"" << (end == 0 ? 1 : -1) << "\"/>\n      </signal>\n";
      ++town->traffic_lights;
      const double cs = end == 0 ? 3.5 : len - 3.5;
      obj << "      <object id=\"" << next_object_++ << "\" name=\"Crosswalk\" type=\"crosswalk\" s=\"" << F(cs)
          << "\" t=\"0.000000\" zOffset=\"0.000000\" hdg=\"0.000000\" roll=\"0\" pitch=\"0\" orientation=\"none\" length=\"3.000000\" width=\""
          << F(2 * p_.lane_w) << "\" height=\"0.000000\">\n        <outline>\n";
      for (auto [u, v] : std::array<std::pair<double, double>, 4>{{{-1.5, -p_.lane_w}, {1.5, -p_.lane_w}, {1.5, p_.lane_w}, {-1.5, p_.lane_w}}})
        obj << "          <cornerLocal u=\"" << F(u) << "\" v=\"" << F(v) << "\" z=\"0\" height=\"0\"/>\n";
      obj << "        </outline>\n      </object>\n";
    }
    if (r % 3 == 0 && len > 30) {
      sig << "      <signal name=\"SpeedLimit30\" id=\"" << next_signal_++ << "\" s=\"10.000000\" t=\"" << F(-side_t)
          << "\" zOffset=\"2.000000\" hOffset=\"0.000000\" roll=\"0\" pitch=\"0\" orientation=\"+\" dynamic=\"no\" country=\"DE\" type=\"274\" subtype=\"-1\" value=\"30\" unit=\"km/h\" text=\"\" height=\"0.600000\" width=\"0.600000\"/>\n";
    }
    if (!obj.str().empty()) os_ << "    <objects>\n" << obj.str() << "    </objects>\n";
    if (!sig.str().empty()) os_ << "    <signals>\n" << sig.str() << "    </signals>\n";
  }

  void WriteJunctions(GeneratedTown* town) {
    std::ostringstream junctions;
    int next_road = static_cast<int>(streets_.size()) + 1;
    for (std::size_t n = 0; n < nodes_.size(); ++n) {
      const auto& arms = nodes_[n];
      const Eigen::Vector2d c = Pos(static_cast<int>(n));
      const std::string jid = JunctionId(static_cast<int>(n));
      junctions << "  <junction id=\"" << jid << "\" name=\"Junction " << jid << "\">\n";
      int connection = 0;
      for (const Arm& in : arms) {
        for (const Arm& out : arms) {
          if (&in == &out) continue;
          const Eigen::Vector2d fwd = -in.d;
          const Eigen::Vector2d p = c + p_.radius * in.d;
          const double hdg = std::atan2(fwd.y(), fwd.x());
          const double cross = fwd.x() * out.d.y() - fwd.y() * out.d.x();
          const bool straight = std::fabs(cross) < 1e-9;
          const double len = straight ? 2 * p_.radius : p_.radius * std::numbers::pi / 2;
          const double curvature = straight ? 0.0 : (cross > 0 ? 1.0 : -1.0) / p_.radius;
          const int in_lane = in.at_start ? 1 : -1, out_lane = out.at_start ? -1 : 1;
          const std::string id = std::to_string(next_road++);
          os_ << "  <road name=\"Connector " << id << "\" length=\"" << F(len) << "\" id=\"" << id << "\" junction=\"" << jid << "\">\n";
          os_ << "    <link><predecessor elementType=\"road\" elementId=\"" << StreetId(in.road) << "\" contactPoint=\""
              << (in.at_start ? "start" : "end") << "\"/><successor elementType=\"road\" elementId=\"" << StreetId(out.road)
              << "\" contactPoint=\"" << (out.at_start ? "start" : "end") << "\"/></link>\n";
          os_ << "    <type s=\"0.000000\" type=\"town\"><speed max=\"30\" unit=\"km/h\"/></type>\n";
          os_ << "    <planView>\n";
          Geometry(p.x(), p.y(), hdg, len, curvature);
          os_ << "    </planView>\n";
          Profiles();
          os_ << "    <lanes>\n      <laneOffset s=\"0.000000\" a=\"0\" b=\"0\" c=\"0\" d=\"0\"/>\n";
          os_ << "      <laneSection s=\"0.000000\">\n        <center>\n          <lane id=\"0\" type=\"none\" level=\"false\">\n"
                 "            <roadMark sOffset=\"0.000000\" type=\"none\" color=\"standard\" width=\"0.000000\" laneChange=\"none\"/>\n"
                 "          </lane>\n        </center>\n        <right>\n";
          // Turns on the outside of the block get the corner sidewalk on their right: every
          // right turn, and at two-arm corners the left turn too (nothing else is there).
          const bool corner_walk = !straight && (cross < 0 || arms.size() == 2);
          const int in_walk = in.at_start ? 2 : -2, out_walk = out.at_start ? -2 : 2;
          Lane(-1, "driving", p_.lane_w,
               corner_walk ? "<roadMark sOffset=\"0.000000\" type=\"curb\" color=\"standard\" width=\"0.150000\" laneChange=\"none\"/>"
                           : "<roadMark sOffset=\"0.000000\" type=\"none\" color=\"standard\" width=\"0.000000\" laneChange=\"none\"/>",
               "<predecessor id=\"" + std::to_string(in_lane) + "\"/><successor id=\"" + std::to_string(out_lane) + "\"/>");
          if (corner_walk)
            Lane(-2, "sidewalk", p_.walk_w,
                 "<roadMark sOffset=\"0.000000\" type=\"none\" color=\"standard\" width=\"0.000000\" laneChange=\"none\"/>",
                 "<predecessor id=\"" + std::to_string(in_walk) + "\"/><successor id=\"" + std::to_string(out_walk) + "\"/>");
          os_ << "        </right>\n      </laneSection>\n    </lanes>\n  </road>\n";
          junctions << "    <connection id=\"" << connection++ << "\" incomingRoad=\"" << StreetId(in.road)
                    << "\" connectingRoad=\"" << id << "\" contactPoint=\"start\">\n      <laneLink from=\"" << in_lane
                    << "\" to=\"-1\"/>\n";
          if (corner_walk) junctions << "      <laneLink from=\"" << in_walk << "\" to=\"-2\"/>\n";
          junctions << "    </connection>\n";
          town->roads += 1;
          town->road_length_m += len;
          town->junction_road_length_m += len;
          town->driving_lane_length_m += len;
        }
      }
      if (!signals_of_[static_cast<int>(n)].empty()) junctions << "    <controller id=\"" << jid << "\" type=\"0\"/>\n";
      junctions << "  </junction>\n";
    }
    for (const auto& [node, ids] : signals_of_) {
      os_ << "  <controller id=\"" << JunctionId(node) << "\" name=\"Controller " << JunctionId(node) << "\">\n";
      for (int id : ids) os_ << "    <control signalId=\"" << id << "\" type=\"0\"/>\n";
      os_ << "  </controller>\n";
    }
    os_ << junctions.str();
  }

  const Params& p_;
  Rng rng_;
  std::vector<double> xs_, ys_;
  std::vector<Street> streets_;
  std::vector<std::vector<Arm>> nodes_;
  std::vector<bool> centre_mark_;  // true: solid yellow centre line, false: broken white
  std::map<int, std::vector<int>> signals_of_;
  int next_signal_ = 1, next_object_ = 1;
  std::ostringstream os_;
};

}  // namespace

GeneratedTown GenerateTown(TownKind kind, std::uint64_t seed) {
  const Params& p = kind == TownKind::Town1 ? kTown1 : kTown2;
  GeneratedTown town = Writer(p, seed).Run();
  const Map map = Map::FromString(town.xodr, town.name);
  // A different stream for the scene so road and scene choices stay independent.
  const Scene scene = GenerateScene(map, seed ^ 0x5CE4E5CE4E5CE4E5ull);
  town.scene_yaml = SceneToYaml(scene);
  return town;
}

void WriteTownFiles(const GeneratedTown& town, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw MapError(dir + ": cannot create directory: " + ec.message());
  for (const auto& [path, text] : {std::pair{dir + "/" + town.name + ".xodr", &town.xodr},
                                   std::pair{dir + "/" + town.name + ".scene.yaml", &town.scene_yaml}}) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << *text;
    if (!out) throw MapError(path + ": cannot write file");
  }
}

}  // namespace lockstep::map
