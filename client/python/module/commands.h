#pragma once
// Python dicts <-> wire types for the `lockstep` module. One converter for every command,
// so the Python layers (lockstep.carla, lockstep.airsim) build commands as plain dicts:
//   {"type": "vehicle_control", "actor": 5, "throttle": 0.5, ...}
// Unknown keys and types raise ValueError naming them.
#include <pybind11/pybind11.h>

#include "lockstep/runtime/messages.h"

namespace lockstep::python {

namespace py = pybind11;

msg::CommandBody CommandFromDict(const py::dict& d);
msg::WorldSettings SettingsFromDict(const py::dict& d, msg::WorldSettings base);
py::dict SettingsToDict(const msg::WorldSettings& s);
msg::WeatherParameters WeatherFromDict(const py::dict& d, msg::WeatherParameters base);
py::dict WeatherToDict(const msg::WeatherParameters& w);
msg::Pose PoseFromTuple(const py::handle& t);  // (x, y, z, qw, qx, qy, qz), world ENU
py::tuple PoseToTuple(const msg::Pose& p);
py::tuple Vec(const msg::Vector3& v);

}  // namespace lockstep::python

namespace lockstep::python {

// VehiclePhysicsControl <-> {"torque_curve": [(rpm, Nm)...], "forward_gears": [(ratio, down, up)...],
// "center_of_mass": (x, y, z), every other field by its wire name}; SI units, world ENU body frame.
msg::VehiclePhysicsControl PhysicsFromDict(const py::dict& d);
py::dict PhysicsToDict(const msg::VehiclePhysicsControl& p);

}  // namespace lockstep::python
