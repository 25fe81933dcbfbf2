#pragma once
// Map queries for lockstep.carla beyond waypoints: the geo-reference, junctions,
// landmarks (OpenDRIVE signals), crosswalks and the traffic lights' controlled lanes.
#include <pybind11/pybind11.h>

#include <memory>

#include "lockstep/map/map.h"

namespace lockstep::python {

void AddMapQueries(pybind11::class_<map::Map, std::shared_ptr<map::Map>>& cls);

}  // namespace lockstep::python
