#include "lockstep/map/map_info.h"

#include <cstdio>
#include <sstream>

namespace lockstep::map {

MapStats ComputeStats(const Map& map) {
  MapStats st;
  st.name = map.Name();
  const OpenDrive& od = map.Data();
  st.roads = static_cast<int>(od.roads.size());
  st.junctions = static_cast<int>(od.junctions.size());
  for (const Road& r : od.roads) {
    st.road_length_m += r.length;
    if (r.junction_index >= 0) {
      ++st.junction_roads;
      st.junction_road_length_m += r.length;
    }
    st.lane_sections += static_cast<int>(r.sections.size());
    for (const Signal& s : r.signals) {
      if (s.dynamic || s.type == "1000001") ++st.traffic_lights;
      else if (s.type == "206") ++st.stop_signs;
      else if (s.type == "274") ++st.speed_limit_signs;
    }
    for (const RoadObject& o : r.objects) {
      if (o.type == "crosswalk") ++st.crosswalks;
      if (o.name.rfind("Speed_", 0) == 0) ++st.speed_limit_signs;
    }
  }
  for (const LaneNode& n : map.Nodes()) {
    if (n.type == LaneType::Driving) {
      ++st.driving_lanes;
      st.driving_lane_length_m += n.Length();
    } else if (n.type == LaneType::Sidewalk) {
      st.sidewalk_length_m += n.Length();
    }
  }
  st.spawn_points = static_cast<int>(map.SpawnPoints().size());
  st.pedestrian_spawn_points = static_cast<int>(map.PedestrianSpawnPoints().size());
  st.min_x = map.BoundsMin().x();
  st.min_y = map.BoundsMin().y();
  st.max_x = map.BoundsMax().x();
  st.max_y = map.BoundsMax().y();
  return st;
}

namespace {
std::string F(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}
std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out;
}
}  // namespace

std::string StatsToJson(const MapStats& s) {
  std::ostringstream os;
  os << "{\"name\":\"" << Escape(s.name) << "\",\"roads\":" << s.roads << ",\"junction_roads\":" << s.junction_roads
     << ",\"junctions\":" << s.junctions << ",\"lane_sections\":" << s.lane_sections
     << ",\"driving_lanes\":" << s.driving_lanes << ",\"road_length_m\":" << F(s.road_length_m)
     << ",\"junction_road_length_m\":" << F(s.junction_road_length_m)
     << ",\"driving_lane_length_m\":" << F(s.driving_lane_length_m) << ",\"sidewalk_length_m\":" << F(s.sidewalk_length_m)
     << ",\"traffic_lights\":" << s.traffic_lights << ",\"stop_signs\":" << s.stop_signs
     << ",\"speed_limit_signs\":" << s.speed_limit_signs << ",\"crosswalks\":" << s.crosswalks
     << ",\"spawn_points\":" << s.spawn_points << ",\"pedestrian_spawn_points\":" << s.pedestrian_spawn_points
     << ",\"bounds\":{\"min_x\":" << F(s.min_x) << ",\"min_y\":" << F(s.min_y) << ",\"max_x\":" << F(s.max_x)
     << ",\"max_y\":" << F(s.max_y) << "}}";
  return os.str();
}

std::string StatsToText(const MapStats& s) {
  std::ostringstream os;
  auto line = [&](const char* k, const std::string& v) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%-26s %s\n", k, v.c_str());
    os << buf;
  };
  line("name:", s.name);
  line("roads:", std::to_string(s.roads) + " (" + std::to_string(s.junction_roads) + " inside junctions)");
  line("junctions:", std::to_string(s.junctions));
  line("lane sections:", std::to_string(s.lane_sections));
  line("driving lanes:", std::to_string(s.driving_lanes));
  line("road length:", F(s.road_length_m) + " m (junctions " + F(s.junction_road_length_m) + " m)");
  line("driving lane length:", F(s.driving_lane_length_m) + " m");
  line("sidewalk length:", F(s.sidewalk_length_m) + " m");
  line("traffic lights:", std::to_string(s.traffic_lights));
  line("stop signs:", std::to_string(s.stop_signs));
  line("speed limit signs:", std::to_string(s.speed_limit_signs));
  line("crosswalks:", std::to_string(s.crosswalks));
  line("vehicle spawn points:", std::to_string(s.spawn_points));
  line("pedestrian spawn points:", std::to_string(s.pedestrian_spawn_points));
  line("bounds:", "x [" + F(s.min_x) + ", " + F(s.max_x) + "] y [" + F(s.min_y) + ", " + F(s.max_y) + "] m");
  return os.str();
}

}  // namespace lockstep::map
