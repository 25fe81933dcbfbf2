// The native part of the `lockstep` Python package: the C++ client (lockstep_client)
// with the GIL released while it waits, sensor payloads as numpy views without a copy,
// and map queries. The CARLA- and AirSim-shaped layers are pure Python on top of it.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <map>
#include <memory>

#include "commands.h"
#include "embedded_coordinator.h"
#include "gil.h"
#include "map_queries.h"
#include "ray_queries.h"
#include "recorder.h"
#include "lockstep/client/client.h"
#include "lockstep/client/multirotor.h"
#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"
#include "lockstep/runtime/error.h"

namespace py = pybind11;
using namespace lockstep;
using namespace lockstep::client;
using lockstep::python::PoseToTuple;
using lockstep::python::Vec;

namespace {

PyObject* g_client_error = nullptr;
PyObject* g_command_rejected = nullptr;
PyObject* g_sensor_late = nullptr;

// Deletes the client with the GIL released: its dispatch thread may be waiting for the
// GIL to run a Python callback.
struct ReleaseGilDeleter {
  void operator()(Client* c) const {
    py::gil_scoped_release release;
    delete c;
  }
};

py::dict DeclarationToDict(const msg::BlueprintDeclaration& d) {
  py::dict out;
  out["id"] = d.id().to_string();
  out["tags"] = d.tags().to_string();
  out["kind"] = ActorKindName(d.kind());
  out["half_extents"] = Vec(d.half_extents());
  py::list attrs;
  for (const auto& a : d.attributes()) {
    py::dict ad;
    ad["id"] = a.id().to_string();
    static const char* kTypes[] = {"bool", "int", "float", "string", "rgb"};
    ad["type"] = kTypes[static_cast<int>(a.type())];
    ad["default"] = a.default_value().to_string();
    ad["min"] = a.min();
    ad["max"] = a.max();
    py::list rec;
    for (const auto& r : a.recommended_values()) rec.append(r.to_string());
    ad["recommended_values"] = rec;
    ad["restricted"] = a.restricted();
    ad["modifiable"] = a.modifiable();
    attrs.append(ad);
  }
  out["attributes"] = attrs;
  return out;
}

py::dict ActorToDict(const ActorInfo& a) {
  py::dict d;
  d["id"] = a.id;
  d["blueprint"] = a.blueprint;
  d["kind"] = ActorKindName(a.kind);
  d["parent"] = a.parent;
  d["owner"] = a.owner;
  py::dict attrs;
  for (const auto& [k, v] : a.attributes) attrs[py::str(k)] = v;
  d["attributes"] = attrs;
  d["spawn_transform"] = PoseToTuple(a.spawn_pose);
  d["spawn_frame"] = a.spawn_frame;
  return d;
}

py::dict ControlToDict(const msg::VehicleControl& c) {
  py::dict d;
  d["throttle"] = c.throttle();
  d["steer"] = c.steer();
  d["brake"] = c.brake();
  d["hand_brake"] = c.hand_brake();
  d["reverse"] = c.reverse();
  d["manual_gear_shift"] = c.manual_gear_shift();
  d["gear"] = c.gear();
  return d;
}

const char* LightName(msg::TrafficLightColor c) {
  switch (c) {
    case msg::TrafficLightColor::LIGHT_RED: return "red";
    case msg::TrafficLightColor::LIGHT_YELLOW: return "yellow";
    case msg::TrafficLightColor::LIGHT_GREEN: return "green";
    case msg::TrafficLightColor::LIGHT_OFF: return "off";
    case msg::TrafficLightColor::LIGHT_UNKNOWN: return "unknown";
  }
  return "unknown";
}

py::dict LightToDict(const msg::TrafficLightState& l) {
  py::dict d;
  d["id"] = l.actor();
  d["transform"] = PoseToTuple(l.transform());
  d["state"] = LightName(l.state());
  d["elapsed"] = l.elapsed();
  d["green_time"] = l.green_time();
  d["yellow_time"] = l.yellow_time();
  d["red_time"] = l.red_time();
  d["frozen"] = l.frozen();
  d["group"] = l.group();
  d["opendrive_id"] = l.opendrive_id().to_string();
  return d;
}

// One actor's state in the latest snapshot as a flat dict.
py::object StateOf(const Snapshot& s, uint32_t id) {
  auto a = s.Find(id);
  if (!a) return py::none();
  py::dict d;
  d["id"] = a->id;
  d["kind"] = ActorKindName(a->kind);
  d["blueprint"] = a->blueprint;
  d["transform"] = PoseToTuple(a->transform);
  d["velocity"] = Vec(a->velocity);
  d["angular_velocity"] = Vec(a->angular_velocity);
  d["acceleration"] = Vec(a->acceleration);
  d["half_extents"] = Vec(a->half_extents);
  d["frame"] = s.frame;
  if (const auto* v = s.Vehicle(id)) {
    d["control"] = ControlToDict(v->control());
    d["autopilot"] = v->autopilot();
    d["speed_limit"] = v->speed_limit();
    d["traffic_light"] = v->traffic_light();
    d["light_state"] = v->light_state();
    d["kinematic"] = v->kinematic();
    d["gear"] = v->gear();
    d["role_name"] = v->role_name().to_string();
  } else if (const auto* w = s.Walker(id)) {
    d["ai_controlled"] = w->ai_controlled();
  } else if (const auto* l = s.TrafficLight(id)) {
    d["light"] = LightToDict(*l);
  } else if (const auto* dr = s.Drone(id)) {
    d["armed"] = dr->armed();
    d["landed"] = dr->landed() == msg::LandedState::LANDED_LANDED;
    d["home"] = PoseToTuple(dr->home_pose());
    d["command_status"] = DroneStatusName(dr->command_status());
  }
  return d;
}

// --- sensor samples -----------------------------------------------------------

// A numpy view of `bytes` that keeps the sample alive (no copy).
py::array View(const SensorSample& s, py::dtype dtype, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides,
               const void* ptr) {
  auto* keep = new std::shared_ptr<const void>(s.message);
  py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<const void>*>(p); });
  py::array a(dtype, shape, strides, ptr, base);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

const char* ImageEncodingName(uint32_t e) {
  switch (static_cast<msg::ImageEncoding>(e)) {
    case msg::ImageEncoding::IMAGE_BGRA8: return "bgra8";
    case msg::ImageEncoding::IMAGE_DEPTH_F32: return "depth_f32";
    case msg::ImageEncoding::IMAGE_DEPTH_CARLA_BGRA8: return "depth_carla_bgra8";
    case msg::ImageEncoding::IMAGE_SEMANTIC_BGRA8: return "semantic_bgra8";
    case msg::ImageEncoding::IMAGE_INSTANCE_BGRA8: return "instance_bgra8";
    case msg::ImageEncoding::IMAGE_NORMALS_BGRA8: return "normals_bgra8";
    case msg::ImageEncoding::IMAGE_GRAY8: return "gray8";
    case msg::ImageEncoding::IMAGE_FLOW_F32X2: return "flow_f32x2";
    case msg::ImageEncoding::IMAGE_DVS_EVENTS: return "dvs_events";
    case msg::ImageEncoding::IMAGE_DEPTH_PERSPECTIVE_F32: return "depth_perspective_f32";
    case msg::ImageEncoding::IMAGE_DISPARITY_F32: return "disparity_f32";
    case msg::ImageEncoding::IMAGE_SEGMENTATION_BGRA8: return "segmentation_bgra8";
  }
  return "?";
}

py::array SampleArray(const SensorSample& s) {
  if (s.type == SensorType::kImage) {
    const auto& im = s.As<msg::Image>();
    const auto h = static_cast<py::ssize_t>(im.height()), w = static_cast<py::ssize_t>(im.width());
    const auto step = static_cast<py::ssize_t>(im.step());
    using E = msg::ImageEncoding;
    const auto enc = static_cast<E>(im.encoding());
    if (enc == E::IMAGE_DEPTH_F32 || enc == E::IMAGE_DEPTH_PERSPECTIVE_F32 || enc == E::IMAGE_DISPARITY_F32) {
      return View(s, py::dtype::of<float>(), {h, w}, {step, 4}, im.data().data());
    }
    if (enc == E::IMAGE_FLOW_F32X2) {
      return View(s, py::dtype::of<float>(), {h, w, 2}, {step, 8, 4}, im.data().data());
    }
    if (enc == E::IMAGE_DVS_EVENTS) {
      // CARLA's DVSEvent fields: x, y (uint16), t (int64 ns), pol (bool); 16 bytes each.
      py::list names, formats, offsets;
      for (const char* f : {"x", "y", "pol", "t"}) names.append(f);
      for (const char* f : {"<u2", "<u2", "?", "<i8"}) formats.append(f);
      for (int o : {0, 2, 4, 8}) offsets.append(o);
      py::dict spec;
      spec["names"] = names;
      spec["formats"] = formats;
      spec["offsets"] = offsets;
      spec["itemsize"] = 16;
      return View(s, py::dtype::from_args(spec), {w}, {16}, im.data().data());
    }
    if (enc == E::IMAGE_GRAY8) {
      return View(s, py::dtype::of<uint8_t>(), {h, w}, {step, 1}, im.data().data());
    }
    return View(s, py::dtype::of<uint8_t>(), {h, w, 4}, {step, 4, 1}, im.data().data());
  }
  if (s.type == SensorType::kPointCloud) {
    const auto& pc = s.As<msg::PointCloud>();
    const auto n = static_cast<py::ssize_t>(pc.point_count());
    const auto stride = static_cast<py::ssize_t>(pc.point_step());
    if (pc.format() == msg::PointFormat::POINTS_XYZI) {
      return View(s, py::dtype::of<float>(), {n, 4}, {stride, 4}, pc.data().data());
    }
    // Semantic: x, y, z, cos_inc (float32), object_idx, object_tag (uint32), as CARLA's.
    py::list names, formats, offsets;
    for (const char* f : {"x", "y", "z", "CosAngle"}) names.append(f), formats.append("<f4");
    for (const char* f : {"ObjIdx", "ObjTag"}) names.append(f), formats.append("<u4");
    for (int o : {0, 4, 8, 12, 16, 20}) offsets.append(o);
    py::dict spec;
    spec["names"] = names;
    spec["formats"] = formats;
    spec["offsets"] = offsets;
    spec["itemsize"] = stride;
    py::dtype dt = py::dtype::from_args(spec);
    return View(s, dt, {n}, {stride}, pc.data().data());
  }
  throw py::type_error(std::string("a ") + SensorTypeName(s.type) + " sample has no array payload");
}

py::dict SampleFields(const SensorSample& s) {
  py::dict d;
  switch (s.type) {
    case SensorType::kImage: {
      const auto& m = s.As<msg::Image>();
      d["transform"] = PoseToTuple(m.sensor_pose());
      d["width"] = m.width();
      d["height"] = m.height();
      d["fov"] = m.fov();
      d["encoding"] = ImageEncodingName(m.encoding());
      break;
    }
    case SensorType::kPointCloud: {
      const auto& m = s.As<msg::PointCloud>();
      d["transform"] = PoseToTuple(m.sensor_pose());
      d["point_count"] = m.point_count();
      d["semantic"] = m.format() == msg::PointFormat::POINTS_SEMANTIC;
      d["channels"] = std::vector<uint32_t>(m.points_per_channel().begin(), m.points_per_channel().end());
      break;
    }
    case SensorType::kRadar: {
      const auto& m = s.As<msg::RadarScan>();
      d["transform"] = PoseToTuple(m.sensor_pose());
      py::list dets;
      for (const auto& r : m.detections()) dets.append(py::make_tuple(r.velocity(), r.azimuth(), r.altitude(), r.depth()));
      d["detections"] = dets;
      break;
    }
    case SensorType::kImu: {
      const auto& m = s.As<msg::Imu>();
      d["accelerometer"] = Vec(m.accelerometer());
      d["gyroscope"] = Vec(m.gyroscope());
      d["compass"] = m.compass();
      const auto& q = m.orientation();
      d["orientation"] = py::make_tuple(q.w(), q.x(), q.y(), q.z());
      break;
    }
    case SensorType::kGnss: {
      const auto& m = s.As<msg::Gnss>();
      d["latitude"] = m.latitude();
      d["longitude"] = m.longitude();
      d["altitude"] = m.altitude();
      d["eph"] = m.eph();
      d["epv"] = m.epv();
      d["fix"] = m.fix();
      break;
    }
    case SensorType::kBarometer: {
      const auto& m = s.As<msg::Barometer>();
      d["altitude"] = m.altitude();
      d["pressure"] = m.pressure();
      d["qnh"] = m.qnh();
      break;
    }
    case SensorType::kMagnetometer: d["magnetic_field"] = Vec(s.As<msg::Magnetometer>().magnetic_field()); break;
    case SensorType::kCollision: {
      const auto& m = s.As<msg::CollisionEvent>();
      d["actor"] = m.actor();
      d["other_actor"] = m.other_actor();
      d["other_kind"] = static_cast<int>(m.other_kind());
      d["other_semantic_tag"] = static_cast<int>(m.other_semantic_tag());
      d["normal_impulse"] = Vec(m.normal_impulse());
      break;
    }
    case SensorType::kLaneInvasion: {
      const auto& m = s.As<msg::LaneInvasionEvent>();
      d["actor"] = m.actor();
      py::list crossed;
      for (const auto& c : m.crossed()) {
        crossed.append(py::make_tuple(static_cast<int>(c.type()), c.color().to_string(), c.width(), c.lane_change_left(),
                                      c.lane_change_right()));
      }
      d["crossed"] = crossed;
      break;
    }
    case SensorType::kDistance: {
      const auto& m = s.As<msg::DistanceMeasurement>();
      d["transform"] = PoseToTuple(m.sensor_pose());
      d["distance"] = m.distance();
      d["min_distance"] = m.min_distance();
      d["max_distance"] = m.max_distance();
      break;
    }
    case SensorType::kV2X: {
      // [(sending sensor id, received power dBm, payload bytes)]: docs/sensors.md's packed layout.
      py::list got;
      for (const auto& r : s.As<msg::V2XData>().messages()) {
        const auto& p = r.payload();
        got.append(py::make_tuple(r.sender(), r.power_dbm(), py::bytes(reinterpret_cast<const char*>(p.data()), p.size())));
      }
      d["messages"] = got;
      break;
    }
    case SensorType::kObstacle: {
      const auto& m = s.As<msg::ObstacleDetection>();
      d["actor"] = m.actor();
      d["other_actor"] = m.other_actor();
      d["other_kind"] = static_cast<int>(m.other_kind());
      d["other_semantic_tag"] = static_cast<int>(m.other_semantic_tag());
      d["distance"] = m.distance();
      break;
    }
  }
  return d;
}

// --- map ---------------------------------------------------------------------------

py::object Wp(const std::optional<map::Waypoint>& w) {
  if (!w) return py::none();
  return py::cast(*w);
}

}  // namespace

PYBIND11_MODULE(_lockstep, m) {
  python::RecordMainThread();
  python::AddEmbeddedCoordinator(m);
  m.doc() = "Lockstep's native client (C++ over DDS). Use lockstep.carla or lockstep.airsim.";

  static py::exception<ClientError> client_error(m, "ClientError", PyExc_RuntimeError);
  static py::exception<CommandRejected> command_rejected(m, "CommandRejected", client_error.ptr());
  static py::exception<SensorLate> sensor_late(m, "SensorLate", client_error.ptr());
  g_client_error = client_error.ptr();
  g_command_rejected = command_rejected.ptr();
  g_sensor_late = sensor_late.ptr();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted&) {
      // A signal handler raised while the call waited (SignalRaised): its exception is set.
      if (!PyErr_Occurred()) PyErr_SetNone(PyExc_KeyboardInterrupt);
    } catch (const CommandRejected& e) {
      py::object exc = py::reinterpret_borrow<py::object>(g_command_rejected)(e.what());
      exc.attr("reason") = e.reason();
      PyErr_SetObject(g_command_rejected, exc.ptr());
    } catch (const SensorLate& e) {
      py::object exc = py::reinterpret_borrow<py::object>(g_sensor_late)(e.what());
      exc.attr("sensors") = e.sensors();
      exc.attr("frame") = e.frame();
      PyErr_SetObject(g_sensor_late, exc.ptr());
    } catch (const ClientError& e) {
      PyErr_SetString(g_client_error, e.what());
    } catch (const lockstep::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  py::class_<SensorSample>(m, "SensorSample")
      .def_property_readonly("type", [](const SensorSample& s) { return SensorTypeName(s.type); })
      .def_property_readonly("sensor", [](const SensorSample& s) { return s.sensor; })
      .def_property_readonly("run", [](const SensorSample& s) { return s.stamp.run(); })
      .def_property_readonly("frame", [](const SensorSample& s) { return s.stamp.frame(); })
      .def_property_readonly("sim_time", [](const SensorSample& s) { return s.stamp.sim_time(); })
      .def("fields", &SampleFields, "The sample's small fields as a dict")
      .def("array", &SampleArray, "The image or point cloud payload as a read-only numpy view (no copy)")
      .def("raw", [](const SensorSample& s) {
        return View(s, py::dtype::of<uint8_t>(), {static_cast<py::ssize_t>(s.ByteCount())}, {1}, s.Bytes());
      });

  py::class_<map::Waypoint>(m, "Waypoint")
      .def_readonly("road", &map::Waypoint::road)
      .def_readonly("section", &map::Waypoint::section)
      .def_readonly("lane", &map::Waypoint::lane)
      .def_readonly("s", &map::Waypoint::s)
      .def_readonly("id", &map::Waypoint::id)
      .def_readonly("lane_width", &map::Waypoint::lane_width)
      .def_readonly("junction", &map::Waypoint::junction)
      .def_readonly("road_xodr", &map::Waypoint::road_id)
      .def_readonly("junction_xodr", &map::Waypoint::junction_id)
      .def_property_readonly("lane_type", [](const map::Waypoint& w) { return static_cast<int>(w.lane_type); })
      .def_property_readonly("pose", [](const map::Waypoint& w) {
        const auto& t = w.transform;
        return py::make_tuple(t.location.x(), t.location.y(), t.location.z(), t.yaw, t.pitch, t.roll);
      });

  py::class_<map::Map, std::shared_ptr<map::Map>> map_class(m, "Map");
  python::AddMapQueries(map_class);
  python::AddRayQueries(m);
  python::RegisterRecorder(m);
  map_class.def_property_readonly("name", &map::Map::Name)
      .def(
          "waypoint",
          [](const map::Map& mp, double x, double y, double z, bool project, int types) {
            return Wp(mp.NearestWaypoint(Eigen::Vector3d(x, y, z), project, static_cast<map::LaneTypeMask>(types)));
          },
          py::arg("x"), py::arg("y"), py::arg("z"), py::arg("project_to_road") = true, py::arg("lane_types") = 2)
      .def("make_waypoint", &map::Map::MakeWaypoint)
      .def("next", &map::Map::Next)
      .def("previous", &map::Map::Previous)
      .def("next_until_lane_end", &map::Map::NextUntilLaneEnd)
      .def("left_lane", [](const map::Map& mp, const map::Waypoint& w) { return Wp(mp.LeftLane(w)); })
      .def("right_lane", [](const map::Map& mp, const map::Waypoint& w) { return Wp(mp.RightLane(w)); })
      .def("lane_change", [](const map::Map& mp, const map::Waypoint& w) { return static_cast<int>(mp.AllowedLaneChange(w)); })
      .def("marking",
           [](const map::Map& mp, const map::Waypoint& w, bool left) -> py::object {
             auto mk = left ? mp.LeftMarking(w) : mp.RightMarking(w);
             if (!mk) return py::none();
             return py::make_tuple(static_cast<int>(mk->type), static_cast<int>(mk->color), static_cast<int>(mk->lane_change),
                                   mk->width);
           })
      .def("generate_waypoints",
           [](const map::Map& mp, double d) { return mp.GenerateWaypoints(d, map::LaneType::Driving); })
      .def("topology", &map::Map::Topology)
      .def("speed_limit", [](const map::Map& mp, const map::Waypoint& w) { return mp.SpeedLimit(w); })
      .def("spawn_points",
           [](const map::Map& mp, double spacing) {
             py::list out;
             for (const auto& t : mp.SpawnPoints(spacing)) {
               out.append(py::make_tuple(t.location.x(), t.location.y(), t.location.z(), t.yaw, t.pitch, t.roll));
             }
             return out;
           },
           py::arg("spacing") = 25.0)
      .def("pedestrian_spawn_points",
           [](const map::Map& mp, double spacing) {
             py::list out;
             for (const auto& t : mp.PedestrianSpawnPoints(spacing)) {
               out.append(py::make_tuple(t.location.x(), t.location.y(), t.location.z(), t.yaw, t.pitch, t.roll));
             }
             return out;
           },
           py::arg("spacing") = 20.0)
      .def("bounds", [](const map::Map& mp) {
        return py::make_tuple(mp.BoundsMin().x(), mp.BoundsMin().y(), mp.BoundsMax().x(), mp.BoundsMax().y());
      });

  py::class_<Client, std::unique_ptr<Client, ReleaseGilDeleter>>(m, "Client")
      .def(py::init([](int domain, double timeout, const std::string& name, double sensor_timeout) {
             ClientOptions o;
             o.domain = domain;
             o.timeout_s = timeout;
             o.name = name;
             o.sensor_timeout_s = sensor_timeout;
             o.interrupted = &python::SignalRaised;
             python::ReleaseGil release;
             return std::unique_ptr<Client, ReleaseGilDeleter>(new Client(o));
           }),
           py::arg("domain") = -1, py::arg("timeout") = 10.0, py::arg("name") = "", py::arg("sensor_timeout") = 10.0)
      .def_property_readonly("domain", &Client::domain)
      .def_property_readonly("name", &Client::name)
      .def("world_info",
           [](const Client& c) {
             const msg::WorldInfo w = c.world_info();
             py::dict d;
             d["run"] = w.run();
             d["map_name"] = w.map_name().to_string();
             d["seed"] = w.seed();
             d["settings"] = python::SettingsToDict(w.settings());
             d["weather"] = python::WeatherToDict(w.weather());
             return d;
           })
      .def("run_status",
           [](const Client& c) -> py::object {
             auto s = c.run_status();
             if (!s) return py::none();
             py::dict d;
             d["run"] = s->run();
             d["state"] = RunStateName(s->state());
             d["frame"] = s->frame();
             d["tick_rate_hz"] = s->tick_rate_hz();
             d["reason"] = s->reason().to_string();
             py::list members;
             for (const auto& mm : s->members()) {
               members.append(py::make_tuple(mm.service().to_string(), mm.kind().to_string(), mm.alive(), mm.required()));
             }
             d["members"] = members;
             return d;
           })
      .def("close", &Client::close, py::call_guard<python::ReleaseGil>(),
           "Stops the client: no more callbacks; waiting calls end with ClientError. lockstep closes every client at exit")
      .def_property_readonly("closed", &Client::closed)
      .def("wait_ready", &Client::wait_ready, py::arg("timeout") = 10.0, py::call_guard<python::ReleaseGil>())
      .def("run", &Client::run)
      .def("frame", &Client::frame)
      .def("apply_settings",
           [](Client& c, const py::dict& d) {
             const msg::WorldSettings s = python::SettingsFromDict(d, c.settings());
             python::ReleaseGil release;
             return c.apply_settings(s);
           })
      .def("set_weather",
           [](Client& c, const py::dict& d) {
             const msg::WeatherParameters w = python::WeatherFromDict(d, c.world_info().weather());
             python::ReleaseGil release;
             c.set_weather(w);
           })
      .def("tick", &Client::tick, py::arg("timeout_s") = -1.0, py::call_guard<python::ReleaseGil>())
      .def("wait_for_tick", &Client::wait_for_tick, py::arg("timeout") = -1.0, py::call_guard<python::ReleaseGil>())
      .def("reset", &Client::reset, py::arg("seed") = 0, py::call_guard<python::ReleaseGil>())
      .def("load_map", &Client::load_map, py::arg("name"), py::arg("opendrive") = "", py::arg("scene") = "",
           py::call_guard<python::ReleaseGil>())
      .def(
          "submit",
          [](Client& c, const py::dict& d, bool throw_if_rejected, const std::string& watch) {
            msg::CommandBody b = python::CommandFromDict(d);
            msg::CommandReply r;
            {
              python::ReleaseGil release;
              r = watch.empty() ? c.Submit(std::move(b), throw_if_rejected) : c.SubmitWatched(std::move(b), watch);
            }
            return py::make_tuple(r.accepted(), r.reason().to_string(), r.actor(), r.frame());
          },
          py::arg("command"), py::arg("throw_if_rejected") = true, py::arg("watch") = "",
          "Sends a command dict and waits for the coordinator's reply. With `watch` (the call's name), a failure "
          "where the owning service applies it is raised by a later tick() / wait_for_tick() / check_failures()")
      .def("watch",
           [](Client& c, uint32_t actor, uint64_t frame, const std::string& call) { c.watch(actor, c.run(), frame, call); })
      .def("check_failures", &Client::check_failures)
      .def("vehicle_physics",
           [](const Client& c, uint32_t id) -> py::object {
             auto p = c.physics_control(id);
             if (!p) return py::none();
             return python::PhysicsToDict(*p);
           })
      .def("submit_batch",
           [](Client& c, const py::list& list) {
             std::vector<msg::CommandBody> bodies;
             for (const auto& item : list) bodies.push_back(python::CommandFromDict(item.cast<py::dict>()));
             std::vector<msg::CommandReply> replies;
             {
               python::ReleaseGil release;
               replies = c.SubmitBatch(bodies);
             }
             py::list out;
             for (const auto& r : replies) out.append(py::make_tuple(r.accepted(), r.reason().to_string(), r.actor(), r.frame()));
             return out;
           })
      .def(
          "spawn",
          [](Client& c, const std::string& bp, const py::object& pose, const std::map<std::string, std::string>& attrs,
             uint32_t parent) {
            const msg::Pose p = python::PoseFromTuple(pose);
            AttributeList list(attrs.begin(), attrs.end());
            python::ReleaseGil release;
            return c.spawn(bp, p, list, parent);
          },
          py::arg("blueprint"), py::arg("transform"), py::arg("attributes") = std::map<std::string, std::string>{},
          py::arg("parent") = 0)
      .def("destroy", &Client::destroy, py::call_guard<python::ReleaseGil>())
      // CARLA's recorder calls (lockstep/client/client.h)
      .def("start_recorder", &Client::start_recorder, py::arg("name"), py::arg("additional_data") = false,
           py::call_guard<python::ReleaseGil>())
      .def("stop_recorder", &Client::stop_recorder, py::call_guard<python::ReleaseGil>())
      .def("replay_file", &Client::replay_file, py::arg("name"), py::arg("start") = 0.0, py::arg("duration") = 0.0,
           py::arg("follow_id") = 0, py::arg("replay_sensors") = false, py::call_guard<python::ReleaseGil>())
      .def("stop_replayer", &Client::stop_replayer, py::arg("keep_actors"), py::call_guard<python::ReleaseGil>())
      .def("set_replayer_time_factor", &Client::set_replayer_time_factor, py::call_guard<python::ReleaseGil>())
      .def("set_replayer_ignore_hero", &Client::set_replayer_ignore_hero, py::call_guard<python::ReleaseGil>())
      .def("set_replayer_ignore_spectator", &Client::set_replayer_ignore_spectator, py::call_guard<python::ReleaseGil>())
      .def("blueprints",
           [](const Client& c, double wait) {
             BlueprintLibrary lib;
             {
               python::ReleaseGil release;
               lib = c.blueprints(wait);
             }
             py::list out;
             for (const auto& d : lib.all()) out.append(DeclarationToDict(d));
             return out;
           },
           py::arg("wait") = 2.0)
      .def("actors",
           [](const Client& c) {
             py::list out;
             for (const auto& a : c.actors()) out.append(ActorToDict(a));
             return out;
           })
      .def("actor",
           [](const Client& c, uint32_t id) -> py::object {
             auto a = c.actor(id);
             if (!a) return py::none();
             return ActorToDict(*a);
           })
      .def("state", [](const Client& c, uint32_t id) { return StateOf(c.snapshot(), id); })
      .def("states",
           [](const Client& c) {
             const Snapshot s = c.snapshot();
             py::dict out;
             for (const auto& a : s.Actors()) out[py::int_(a.id)] = StateOf(s, a.id);
             return out;
           })
      .def("snapshot_frame",
           [](const Client& c) {
             const Snapshot s = c.snapshot();
             return py::make_tuple(s.run, s.frame, s.sim_time, s.ground ? static_cast<int64_t>(s.ground->stamp().frame()) : -1,
                                   s.air ? static_cast<int64_t>(s.air->stamp().frame()) : -1);
           })
      .def("traffic_lights",
           [](const Client& c) {
             const Snapshot s = c.snapshot();
             py::list out;
             if (s.ground) {
               for (const auto& l : s.ground->traffic_lights()) out.append(LightToDict(l));
             }
             return out;
           })
      // The town's static objects as the services build them (the map's scene, else the one
      // generated from the run seed): (name, mesh instance id, semantic tag, (min xyz), (max xyz)).
      .def("scene_objects",
           [](Client& c) {
             std::vector<map::Mesh> meshes;
             {
               python::ReleaseGil release;
               const std::optional<msg::MapData> data = c.map_data();
               if (!data || data->opendrive().empty()) throw ClientError("scene_objects(): the simulation has no map loaded");
               const map::Map town = map::Map::FromString(data->opendrive(), data->name().to_string());
               const map::Scene sc = data->scene().empty()
                                         ? map::GenerateScene(town, c.world_info().seed())
                                         : map::SceneFromYaml(data->scene(), data->name().to_string() + ".scene.yaml");
               meshes = map::BuildWorldMeshes(town, sc);
             }
             py::list out;
             for (const map::Mesh& m : meshes) {
               double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
               for (std::size_t i = 0; i + 2 < m.vertices.size(); i += 3) {
                 for (int k = 0; k < 3; ++k) {
                   lo[k] = std::min(lo[k], static_cast<double>(m.vertices[i + k]));
                   hi[k] = std::max(hi[k], static_cast<double>(m.vertices[i + k]));
                 }
               }
               if (m.vertices.empty()) continue;
               out.append(py::make_tuple(m.name, m.instance_id, m.semantic_tag, py::make_tuple(lo[0], lo[1], lo[2]),
                                         py::make_tuple(hi[0], hi[1], hi[2])));
             }
             return out;
           })
      .def("map",
           [](Client& c) {
             std::shared_ptr<const map::Map> mp;
             {
               python::ReleaseGil release;
               mp = c.map();
             }
             return std::const_pointer_cast<map::Map>(mp);
           })
      .def("listen",
           [](Client& c, uint32_t sensor, py::function cb) {
             // The callback runs on the client's dispatch thread: take the GIL only to call it.
             auto fn = std::shared_ptr<py::function>(new py::function(std::move(cb)), [](py::function* f) {
               if (python::Finalizing() && !python::IsMainThread()) return;  // leaked: Python is going away
               py::gil_scoped_acquire gil;
               delete f;
             });
             c.listen(sensor, [fn](const SensorSample& s) {
               if (python::Finalizing()) return;  // no Python code runs in other threads any more
               python::CallbackScope in_callback;
               py::gil_scoped_acquire gil;
               try {
                 (*fn)(s);
               } catch (py::error_already_set& e) {
                 e.discard_as_unraisable("lockstep sensor callback");
               }
             });
           })
      .def("stop", &Client::stop, py::call_guard<python::ReleaseGil>())
      .def("is_listening", &Client::is_listening)
      .def("delivered", &Client::delivered)
      .def("drone_state",
           [](const Client& c, uint32_t id) -> py::object {
             auto d = c.drone_state(id);
             if (!d) return py::none();
             py::dict out;
             out["transform"] = PoseToTuple(d->transform());
             out["home"] = PoseToTuple(d->home_pose());
             out["velocity"] = Vec(d->linear_velocity());
             out["armed"] = d->armed();
             out["landed"] = d->landed() == msg::LandedState::LANDED_LANDED;
             out["command_id"] = d->command_id();
             out["command_status"] = DroneStatusName(d->command_status());
             return out;
           })
      .def("send_drone",
           [](Client& c, const py::dict& d) {
             msg::CommandBody b = python::CommandFromDict(d);
             if (b._d() != msg::CommandKind::CMD_DRONE) throw py::value_error("send_drone needs a command of type 'drone'");
             python::ReleaseGil release;
             return c.send_drone(b.drone());
           })
      .def("wait_drone",
           [](Client& c, uint32_t actor, uint64_t id, double timeout) {
             msg::DroneCommandStatus s;
             {
               python::ReleaseGil release;
               s = c.wait_drone(actor, id, timeout);
             }
             return DroneStatusName(s);
           },
           py::arg("actor"), py::arg("command_id"), py::arg("timeout") = -1.0);

  // --- AirSim-shaped drones (NED from the spawn point) ---------------------------------
  using MC = MultirotorClient;
  auto ned = [](const Ned& n) { return py::make_tuple(n.x, n.y, n.z); };
  auto nedq = [](const NedQuaternion& q) { return py::make_tuple(q.w, q.x, q.y, q.z); };
  auto yawmode = [](bool is_rate, double v) {
    NedYawMode y;
    y.is_rate = is_rate;
    y.yaw_or_rate = v;
    return y;
  };
  auto drive = [](int d) { return d == 1 ? NedDrivetrain::kForwardOnly : NedDrivetrain::kMaxDegreeOfFreedom; };

  py::class_<CommandFuture>(m, "CommandFuture")
      .def("join", &CommandFuture::join, py::arg("timeout") = -1.0, py::call_guard<python::ReleaseGil>())
      .def("status", [](CommandFuture& f, double t) {
        msg::DroneCommandStatus s;
        {
          python::ReleaseGil release;
          s = f.status(t);
        }
        return DroneStatusName(s);
      }, py::arg("timeout") = -1.0)
      .def_property_readonly("actor", &CommandFuture::actor)
      .def_property_readonly("command_id", &CommandFuture::command_id);

  py::class_<MC>(m, "Multirotor")
      .def(py::init<Client&>(), py::keep_alive<1, 2>())
      .def("resolve", &MC::Resolve)
      .def("list_vehicles", &MC::listVehicles)
      .def("add_vehicle",
           [](MC& mc, const std::string& name, const std::string& bp, const py::object& pose) {
             const msg::Pose p = python::PoseFromTuple(pose);
             python::ReleaseGil release;
             return mc.addVehicle(name, bp, p);
           })
      .def("home", [](const MC& mc, const std::string& v) { return Vec(mc.homeEnu(v)); })
      .def("enable_api_control", &MC::enableApiControl, py::call_guard<python::ReleaseGil>())
      .def("is_api_control_enabled", &MC::isApiControlEnabled, py::call_guard<python::ReleaseGil>())
      .def("arm_disarm", &MC::armDisarm, py::call_guard<python::ReleaseGil>())
      .def("takeoff", &MC::takeoffAsync, py::call_guard<python::ReleaseGil>())
      .def("land", &MC::landAsync, py::call_guard<python::ReleaseGil>())
      .def("go_home", &MC::goHomeAsync, py::call_guard<python::ReleaseGil>())
      .def("hover", &MC::hoverAsync, py::call_guard<python::ReleaseGil>())
      .def("cancel", &MC::cancelLastTask, py::call_guard<python::ReleaseGil>())
      .def("move_to_position",
           [=](MC& mc, double x, double y, double z, double v, double t, int d, bool is_rate, double yaw, double la,
               const std::string& name) {
             python::ReleaseGil release;
             return mc.moveToPositionAsync(x, y, z, v, t, drive(d), yawmode(is_rate, yaw), la, name);
           })
      .def("move_to_z",
           [=](MC& mc, double z, double v, double t, bool is_rate, double yaw, double la, const std::string& name) {
             python::ReleaseGil release;
             return mc.moveToZAsync(z, v, t, yawmode(is_rate, yaw), la, name);
           })
      .def("move_on_path",
           [=](MC& mc, const std::vector<std::tuple<double, double, double>>& path, double v, double t, int d, bool is_rate,
               double yaw, double la, const std::string& name) {
             std::vector<Ned> p;
             for (const auto& [x, y, z] : path) p.push_back({x, y, z});
             python::ReleaseGil release;
             return mc.moveOnPathAsync(p, v, t, drive(d), yawmode(is_rate, yaw), la, name);
           })
      .def("move_by_velocity",
           [=](MC& mc, double vx, double vy, double vz, double dur, int d, bool is_rate, double yaw, bool body,
               const std::string& name) {
             python::ReleaseGil release;
             return body ? mc.moveByVelocityBodyFrameAsync(vx, vy, vz, dur, drive(d), yawmode(is_rate, yaw), name)
                         : mc.moveByVelocityAsync(vx, vy, vz, dur, drive(d), yawmode(is_rate, yaw), name);
           })
      .def("move_by_velocity_z",
           [=](MC& mc, double vx, double vy, double z, double dur, int d, bool is_rate, double yaw, const std::string& name) {
             python::ReleaseGil release;
             return mc.moveByVelocityZAsync(vx, vy, z, dur, drive(d), yawmode(is_rate, yaw), name);
           })
      .def("rotate_to_yaw", &MC::rotateToYawAsync, py::call_guard<python::ReleaseGil>())
      .def("rotate_by_yaw_rate", &MC::rotateByYawRateAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_rpy_throttle", &MC::moveByRollPitchYawThrottleAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_rpy_z", &MC::moveByRollPitchYawZAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_angle_rates_throttle", &MC::moveByAngleRatesThrottleAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_motor_pwms", &MC::moveByMotorPWMsAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_rp_yawrate_throttle", &MC::moveByRollPitchYawrateThrottleAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_rp_yawrate_z", &MC::moveByRollPitchYawrateZAsync, py::call_guard<python::ReleaseGil>())
      .def("move_by_angle_rates_z", &MC::moveByAngleRatesZAsync, py::call_guard<python::ReleaseGil>())
      .def("move_to_gps",
           [=](MC& mc, double lat, double lon, double alt, double v, double t, int d, bool is_rate, double yaw, double la,
               double adaptive, const std::string& name) {
             python::ReleaseGil release;
             return mc.moveToGPSAsync(lat, lon, alt, v, t, drive(d), yawmode(is_rate, yaw), la, adaptive, name);
           })
      .def("set_gains",
           [](MC& mc, const std::string& loop, const std::vector<std::tuple<double, double, double>>& pids,
              const std::string& name) {
             static const std::map<std::string, msg::GainsLoop> loops = {{"angle_rate", msg::GainsLoop::GAINS_ANGLE_RATE},
                                                                         {"angle_level", msg::GainsLoop::GAINS_ANGLE_LEVEL},
                                                                         {"velocity", msg::GainsLoop::GAINS_VELOCITY},
                                                                         {"position", msg::GainsLoop::GAINS_POSITION}};
             auto it = loops.find(loop);
             if (it == loops.end()) throw py::value_error("set_gains: unknown loop '" + loop + "'");
             if (pids.size() != 3) throw py::value_error("set_gains: three PIDs (one per axis), got " + std::to_string(pids.size()));
             std::vector<MC::Pid> p;
             for (const auto& [kp, ki, kd] : pids) p.push_back({kp, ki, kd});
             python::ReleaseGil release;
             mc.setControllerGains(it->second, p[0], p[1], p[2], name);
           })
      .def("set_wind",
           [](MC& mc, std::tuple<double, double, double> w) {
             python::ReleaseGil release;
             mc.simSetWind({std::get<0>(w), std::get<1>(w), std::get<2>(w)});
           })
      .def("set_kinematics",
           [](MC& mc, std::tuple<double, double, double> p, std::tuple<double, double, double, double> q,
              std::tuple<double, double, double> v, std::tuple<double, double, double> w, const std::string& name) {
             NedKinematics k;
             k.position = {std::get<0>(p), std::get<1>(p), std::get<2>(p)};
             k.orientation = {std::get<0>(q), std::get<1>(q), std::get<2>(q), std::get<3>(q)};
             k.linear_velocity = {std::get<0>(v), std::get<1>(v), std::get<2>(v)};
             k.angular_velocity = {std::get<0>(w), std::get<1>(w), std::get<2>(w)};
             python::ReleaseGil release;
             mc.simSetKinematics(k, name);
           })
      .def("track_target",
           [](MC& mc, std::tuple<double, double, double> p, std::tuple<double, double, double> v, double max_speed,
              double dur, const std::string& name) {
             python::ReleaseGil release;
             return mc.trackTargetAsync({std::get<0>(p), std::get<1>(p), std::get<2>(p)},
                                        {std::get<0>(v), std::get<1>(v), std::get<2>(v)}, max_speed, dur, name);
           })
      .def("state",
           [=](const MC& mc, const std::string& name) {
             const MultirotorStateNed s = mc.getMultirotorState(name);
             py::dict d;
             d["position"] = ned(s.kinematics.position);
             d["orientation"] = nedq(s.kinematics.orientation);
             d["linear_velocity"] = ned(s.kinematics.linear_velocity);
             d["linear_acceleration"] = ned(s.kinematics.linear_acceleration);
             d["angular_velocity"] = ned(s.kinematics.angular_velocity);
             d["angular_acceleration"] = ned(s.kinematics.angular_acceleration);
             d["landed"] = s.landed;
             d["armed"] = s.armed;
             d["timestamp"] = static_cast<uint64_t>(s.timestamp_ns);
             d["frame"] = s.frame;
             d["rotor_speeds"] = s.rotor_speeds;
             d["rotor_thrusts"] = s.rotor_thrusts;
             d["rotor_controls"] = s.rotor_controls;
             const auto& c = s.collision;
             d["collision"] = py::make_tuple(c.has_collided, ned(c.normal), ned(c.impact_point), ned(c.position),
                                             c.penetration_depth, c.object_id, c.object_name, c.frame);
             return d;
           })
      .def("pose",
           [=](const MC& mc, const std::string& name) {
             const auto p = mc.simGetVehiclePose(name);
             return py::make_tuple(ned(p.first), nedq(p.second));
           })
      .def("set_pose", [](MC& mc, std::tuple<double, double, double> p, std::tuple<double, double, double, double> q,
                          const std::string& name) {
        python::ReleaseGil release;
        mc.simSetVehiclePose({std::get<0>(p), std::get<1>(p), std::get<2>(p)},
                             {std::get<0>(q), std::get<1>(q), std::get<2>(q), std::get<3>(q)}, name);
      });

  m.def("default_domain", &DefaultDomain);
  m.def("_prepare_exit", &python::PrepareExit, "lockstep's atexit hook: see gil.h");
  m.def("enu_yaw_from_ned_deg", &NedYawDegToEnu);
}
