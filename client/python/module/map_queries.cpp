#include "map_queries.h"

#include <pybind11/stl.h>

#include <string>
#include <unordered_map>
#include <vector>

namespace lockstep::python {

namespace py = pybind11;

namespace {

// (x, y, z, yaw, pitch, roll): ENU metres and radians, as Map.spawn_points gives them.
py::tuple Pose6(const map::Transform& t) {
  return py::make_tuple(t.location.x(), t.location.y(), t.location.z(), t.yaw, t.pitch, t.roll);
}

py::tuple Box(const map::BoundingBox& b) {
  return py::make_tuple(py::make_tuple(b.location.x(), b.location.y(), b.location.z()),
                        py::make_tuple(b.extent.x(), b.extent.y(), b.extent.z()), b.yaw);
}

py::dict JunctionDict(const map::JunctionInfo& j) {
  py::dict d;
  d["index"] = j.index;
  d["id"] = j.id;
  d["bounding_box"] = Box(j.bounding_box);
  return d;
}

py::list Validity(const std::vector<std::pair<int, int>>& v) {
  py::list out;
  for (const auto& [from, to] : v) out.append(py::make_tuple(from, to));
  return out;
}

// A signal met on `road` at (s, t) with that orientation and validity (a <signal> on its
// own road, or a <signalReference>): CARLA's carla.Landmark fields.
py::dict LandmarkDict(const map::Map& mp, const map::Signal& sig, int road, double s, double t,
                      const std::string& orientation, const std::vector<std::pair<int, int>>& validity) {
  py::dict d;
  d["id"] = sig.id;
  d["name"] = sig.name;
  d["road"] = road;
  d["road_id"] = mp.Data().roads[static_cast<size_t>(road)].id;
  d["s"] = s;
  d["t"] = t;
  d["orientation"] = orientation;
  d["z_offset"] = sig.z_offset;
  d["h_offset"] = sig.h_offset;
  d["height"] = sig.height;
  d["width"] = sig.width;
  d["dynamic"] = sig.dynamic;
  d["country"] = sig.country;
  d["type"] = sig.type;
  d["subtype"] = sig.subtype;
  d["unit"] = sig.unit;
  d["text"] = sig.text;
  d["value"] = sig.value;
  d["validity"] = Validity(validity);
  d["pose"] = py::make_tuple(sig.x, sig.y, sig.z - sig.z_offset, sig.yaw, 0.0, 0.0);
  return d;
}

const map::Signal* FindSignal(const map::Map& mp, const std::string& id) {
  for (const auto& r : mp.Data().roads)
    for (const auto& s : r.signals)
      if (s.id == id) return &s;
  return nullptr;
}

}  // namespace

void AddMapQueries(py::class_<map::Map, std::shared_ptr<map::Map>>& cls) {
  cls.def_static("load", [](const std::string& path) { return std::make_shared<map::Map>(map::Map::Load(path)); },
                 "An OpenDRIVE file as a map (tests, tools); a running simulation's is Client.map()")
      .def_property_readonly("geo_reference", [](const map::Map& mp) { return mp.Data().header.geo_reference; })
      .def("junction",
           [](const map::Map& mp, const map::Waypoint& w) -> py::object {
             auto j = mp.JunctionOf(w);
             if (!j) return py::none();
             return JunctionDict(*j);
           })
      .def("junction_by_index",
           [](const map::Map& mp, int index) -> py::object {
             if (index < 0 || index >= static_cast<int>(mp.Junctions().size())) return py::none();
             return JunctionDict(mp.Junctions()[static_cast<size_t>(index)]);
           })
      .def("junction_waypoints",
           [](const map::Map& mp, int index, int types) {
             return mp.JunctionWaypoints(index, static_cast<map::LaneTypeMask>(types));
           })
      .def("road_index", &map::Map::RoadIndex)
      .def("waypoint_xodr",
           [](const map::Map& mp, const std::string& road, int lane, double s) -> py::object {
             auto w = mp.WaypointXodr(road, lane, s);
             if (!w) return py::none();
             return py::cast(*w);
           })
      .def("landmarks_ahead",
           [](const map::Map& mp, const map::Waypoint& w, double distance, bool stop_at_junction) {
             py::list out;
             for (const auto& l : mp.LandmarksAhead(w, distance, stop_at_junction)) {
               const map::Signal* sig = FindSignal(mp, l.id);
               if (!sig) continue;
               // The orientation and validity of the record met (the signal, or a reference to it).
               std::string orientation = sig->orientation;
               std::vector<std::pair<int, int>> validity = sig->validity;
               const auto& road = mp.Data().roads[static_cast<size_t>(l.road)];
               for (const auto& ref : road.signal_refs) {
                 if (ref.id == l.id && ref.s == l.s && ref.t == l.t) {
                   orientation = ref.orientation;
                   validity = ref.validity;
                 }
               }
               py::dict d = LandmarkDict(mp, *sig, l.road, l.s, l.t, orientation, validity);
               d["distance"] = l.distance;
               d["waypoint"] = l.waypoint;
               out.append(d);
             }
             return out;
           })
      .def("all_landmarks",
           [](const map::Map& mp) {
             // Every <signal> on its road and every <signalReference>, in file order (CARLA:
             // one landmark per signal reference, a signal being a reference on its own road).
             std::unordered_map<std::string, const map::Signal*> by_id;
             for (const auto& r : mp.Data().roads)
               for (const auto& s : r.signals) by_id.emplace(s.id, &s);
             py::list out;
             const auto& roads = mp.Data().roads;
             for (size_t i = 0; i < roads.size(); ++i) {
               for (const auto& s : roads[i].signals)
                 out.append(LandmarkDict(mp, s, static_cast<int>(i), s.s, s.t, s.orientation, s.validity));
               for (const auto& ref : roads[i].signal_refs) {
                 auto it = by_id.find(ref.id);
                 if (it != by_id.end())
                   out.append(LandmarkDict(mp, *it->second, static_cast<int>(i), ref.s, ref.t, ref.orientation, ref.validity));
               }
             }
             return out;
           })
      .def("landmark_groups",
           [](const map::Map& mp) {
             // controller id -> its signal ids (carla.Map.get_landmark_group)
             py::dict out;
             for (const auto& c : mp.Data().controllers) out[py::str(c.id)] = c.signal_ids;
             return out;
           })
      .def("crosswalks",
           [](const map::Map& mp) {
             py::list out;
             for (const auto& poly : mp.Crosswalks())
               for (const auto& p : poly) out.append(py::make_tuple(p.x(), p.y(), p.z()));
             return out;
           })
      .def("traffic_light_infos", [](const map::Map& mp) {
        py::list out;
        for (const auto& tl : mp.TrafficLights()) {
          py::dict d;
          d["signal_id"] = tl.signal_id;
          d["junction"] = tl.junction;
          d["controller_id"] = tl.controller_id;
          d["pose"] = Pose6(tl.pose);
          d["stop_waypoints"] = tl.stop_waypoints;
          d["trigger_volume"] = Box(tl.trigger_volume);
          out.append(d);
        }
        return out;
      });
}

}  // namespace lockstep::python
