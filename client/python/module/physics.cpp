// carla.VehiclePhysicsControl's wire form (msg::VehiclePhysicsControl) as a Python dict.
#include <pybind11/stl.h>

#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "commands.h"

namespace lockstep::python {

#define LOCKSTEP_PHYSICS_SCALARS(X)                                                                          \
  X(max_rpm) X(moi) X(damping_rate_full_throttle) X(gear_switch_time) X(clutch_strength) X(final_ratio)     \
  X(mass) X(drag_coefficient) X(tire_friction) X(wheel_radius) X(max_steer_angle) X(max_brake_torque)       \
  X(max_handbrake_torque) X(suspension_stiffness) X(suspension_damping) X(wheelbase) X(track)

msg::VehiclePhysicsControl PhysicsFromDict(const py::dict& d) {
  msg::VehiclePhysicsControl p;
  std::set<std::string> used;
  auto get = [&](const char* key) -> py::object {
    used.insert(key);
    if (!d.contains(key)) throw py::value_error(std::string("vehicle physics: missing '") + key + "'");
    return d[key];
  };
#define X(name) p.name(get(#name).cast<double>());
  LOCKSTEP_PHYSICS_SCALARS(X)
#undef X
  p.use_gear_autobox(get("use_gear_autobox").cast<bool>());
  const auto com = get("center_of_mass").cast<std::tuple<double, double, double>>();
  p.center_of_mass().x(std::get<0>(com));
  p.center_of_mass().y(std::get<1>(com));
  p.center_of_mass().z(std::get<2>(com));
  const auto curve = get("torque_curve").cast<std::vector<std::tuple<double, double>>>();
  if (curve.size() > 32) throw py::value_error("vehicle physics: a torque curve has at most 32 points");
  for (const auto& [x, y] : curve) {
    msg::CurvePoint c;
    c.x(x);
    c.y(y);
    p.torque_curve().push_back(c);
  }
  const auto gears = get("forward_gears").cast<std::vector<std::tuple<double, double, double>>>();
  if (gears.size() > 16) throw py::value_error("vehicle physics: at most 16 forward gears");
  for (const auto& [ratio, down, up] : gears) {
    msg::GearPhysicsControl g;
    g.ratio(ratio);
    g.down_ratio(down);
    g.up_ratio(up);
    p.forward_gears().push_back(g);
  }
  for (const auto& item : d) {
    const std::string k = py::str(item.first);
    if (!used.count(k)) throw py::value_error("vehicle physics: unknown key '" + k + "'");
  }
  return p;
}

py::dict PhysicsToDict(const msg::VehiclePhysicsControl& p) {
  py::dict d;
#define X(name) d[#name] = p.name();
  LOCKSTEP_PHYSICS_SCALARS(X)
#undef X
  d["use_gear_autobox"] = p.use_gear_autobox();
  d["center_of_mass"] = Vec(p.center_of_mass());
  py::list curve, gears;
  for (const auto& c : p.torque_curve()) curve.append(py::make_tuple(c.x(), c.y()));
  for (const auto& g : p.forward_gears()) gears.append(py::make_tuple(g.ratio(), g.down_ratio(), g.up_ratio()));
  d["torque_curve"] = curve;
  d["forward_gears"] = gears;
  return d;
}

}  // namespace lockstep::python
