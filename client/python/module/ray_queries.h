#pragma once
// lockstep.RayCaster: CARLA's World.cast_ray / project_point in the client's process
// (lockstep/client/ray_caster.h).
#include <pybind11/pybind11.h>

namespace lockstep::python {

void AddRayQueries(pybind11::module_& m);

}  // namespace lockstep::python
