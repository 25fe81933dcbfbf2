// The recorder's logs read in the client process (lockstep/recorder/log_reader.h): CARLA's
// show_recorder_* texts and AirSim's airsim_rec.txt written from a log.
#include "recorder.h"

#include <pybind11/stl.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "gil.h"
#include "lockstep/client/client.h"
#include "lockstep/client/multirotor.h"
#include "lockstep/recorder/carla_text.h"
#include "lockstep/recorder/log_reader.h"

namespace lockstep::python {

namespace {

struct DroneTrack {
  std::string name;        // AirSim's vehicle name (role_name)
  msg::Vector3 home;       // spawn position: AirSim's NED origin of the vehicle
  bool have_last = false;  // RecordOnMove: the pose of the line written last
  msg::Pose last;
  double last_time = -1e300;
};

bool Moved(const msg::Pose& a, const msg::Pose& b) {
  const auto& p = a.position();
  const auto& q = b.position();
  const auto& r = a.orientation();
  const auto& s = b.orientation();
  // As Eigen's isApprox at the log's resolution (1 mm, 1e-4 rad).
  return std::abs(p.x() - q.x()) > 5e-4 || std::abs(p.y() - q.y()) > 5e-4 || std::abs(p.z() - q.z()) > 5e-4 ||
         std::abs(std::abs(r.w() * s.w() + r.x() * s.x() + r.y() * s.y() + r.z() * s.z()) - 1.0) > 1e-9;
}

}  // namespace

size_t WriteAirSimRecord(const std::string& log_path, const std::string& txt_path, double interval, bool record_on_move) {
  recorder::LogReader log(log_path);
  std::map<uint32_t, DroneTrack> drones;
  for (const auto& [id, a] : log.actors()) {
    if (a.kind != msg::ActorKind::ACTOR_DRONE) continue;
    DroneTrack t;
    t.name = a.Attribute("role_name");
    if (t.name.empty()) t.name = "Drone" + std::to_string(id);
    t.home = a.spawn_pose.position();
    drones[id] = t;
  }
  std::ofstream out(txt_path);
  if (!out) throw client::ClientError("cannot write '" + txt_path + "'");
  // AirSim's multirotor header (PawnSimApi::getRecordFileLine), then the image files column.
  out << "VehicleName\tTimeStamp\tPOS_X\tPOS_Y\tPOS_Z\tQ_W\tQ_X\tQ_Y\tQ_Z\tImageFile\n";
  size_t lines = 0;
  if (drones.empty() || log.empty()) return 0;
  log.ForEach([&](const recorder::LogFrame& f) {
    for (const auto& s : f.actors) {
      auto it = drones.find(s.id);
      if (it == drones.end()) continue;
      DroneTrack& t = it->second;
      if (f.sim_time - t.last_time < interval - 1e-9) continue;  // AirSim's RecordInterval
      const msg::Pose pose = s.pose();
      if (record_on_move && t.have_last && !Moved(pose, t.last)) continue;
      const client::Ned p = client::EnuToNed(pose.position(), t.home);
      const client::NedQuaternion q = client::EnuToNedQuaternion(pose.orientation());
      // AirSim's clock in ms: Lockstep's AirSim timestamps are the simulation time.
      out << t.name << "\t" << static_cast<uint64_t>(std::llround(f.sim_time * 1e3)) << "\t" << p.x << "\t" << p.y << "\t"
          << p.z << "\t" << q.w << "\t" << q.x << "\t" << q.y << "\t" << q.z << "\t"
          << "\n";
      t.last_time = f.sim_time;
      t.last = pose;
      t.have_last = true;
      ++lines;
    }
    return true;
  });
  return lines;
}

void RegisterRecorder(pybind11::module_& m) {
  namespace py = pybind11;
  m.def(
      "recorder_file_info",
      [](const std::string& name, bool show_all) { return recorder::ShowRecorderFileInfo(name, show_all); },
      py::arg("name"), py::arg("show_all") = false, py::call_guard<ReleaseGil>(),
      "CARLA's show_recorder_file_info text of a log (a relative name: the recordings folder)");
  m.def(
      "recorder_collisions",
      [](const std::string& name, char type1, char type2) { return recorder::ShowRecorderCollisions(name, type1, type2); },
      py::call_guard<ReleaseGil>(), "CARLA's show_recorder_collisions text of a log");
  m.def(
      "recorder_actors_blocked",
      [](const std::string& name, double min_time, double min_distance) {
        return recorder::ShowRecorderActorsBlocked(name, min_time, min_distance);
      },
      py::call_guard<ReleaseGil>(), "CARLA's show_recorder_actors_blocked text of a log");
  m.def("recording_path", &recorder::ResolveLogPath,
        "The file a recorder name stands for (a relative name: $LOCKSTEP_RECORDINGS_DIR, else "
        "~/.local/share/lockstep/recordings)");
  m.def("write_airsim_record", &WriteAirSimRecord, py::arg("log"), py::arg("txt"), py::arg("interval") = 0.05,
        py::arg("record_on_move") = false, py::call_guard<ReleaseGil>(),
        "AirSim's airsim_rec.txt from a log: one line per drone every `interval` s of simulation time "
        "(NED from the drone's spawn point); returns the number of lines");
}

}  // namespace lockstep::python
