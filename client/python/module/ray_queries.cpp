#include "ray_queries.h"

#include <pybind11/stl.h>

#include "gil.h"
#include "lockstep/client/client.h"
#include "lockstep/client/ray_caster.h"

namespace py = pybind11;

namespace lockstep::python {

namespace {

msg::Vector3 Vec3Of(const py::sequence& t, const char* what) {
  if (t.size() != 3) throw py::value_error(std::string(what) + " needs 3 values (x, y, z)");
  msg::Vector3 v;
  v.x(t[0].cast<double>());
  v.y(t[1].cast<double>());
  v.z(t[2].cast<double>());
  return v;
}

py::tuple PointTuple(const client::LabelledPoint& p) {
  return py::make_tuple(py::make_tuple(p.location.x(), p.location.y(), p.location.z()), static_cast<int>(p.label));
}

}  // namespace

void AddRayQueries(py::module_& m) {
  py::class_<client::RayCaster>(m, "RayCaster",
                                "Ray queries against the town's meshes and the latest frame's actor boxes (world ENU, m)")
      .def(py::init<client::Client&>(), py::keep_alive<1, 2>())
      .def(
          "cast_ray",
          [](client::RayCaster& r, const py::sequence& from, const py::sequence& to) {
            const msg::Vector3 a = Vec3Of(from, "cast_ray: initial_location"), b = Vec3Of(to, "cast_ray: final_location");
            std::vector<client::LabelledPoint> hits;
            {
              ReleaseGil release;
              hits = r.CastRay(a, b);
            }
            py::list out;
            for (const auto& h : hits) out.append(PointTuple(h));
            return out;
          },
          "[((x, y, z), label), ...]: every object the segment crosses, nearest first")
      .def(
          "project_point",
          [](client::RayCaster& r, const py::sequence& location, const py::sequence& direction, double distance) -> py::object {
            const msg::Vector3 p = Vec3Of(location, "project_point: location"), d = Vec3Of(direction, "project_point: direction");
            std::optional<client::LabelledPoint> hit;
            {
              ReleaseGil release;
              hit = r.ProjectPoint(p, d, distance);
            }
            if (!hit) return py::none();
            return PointTuple(*hit);
          },
          "((x, y, z), label) of the first surface along direction within distance, or None");
}

}  // namespace lockstep::python
