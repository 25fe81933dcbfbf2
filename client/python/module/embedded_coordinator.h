#pragma once
// lockstep.Coordinator: the coordinator of a simulation hosted in the script's own process
// (`lockstep up CONFIG --no-coordinator` starts the services). Its messages to a client
// of the same process never leave it, so a tick costs about the barrier alone.
#include <pybind11/pybind11.h>

namespace lockstep::python {

void AddEmbeddedCoordinator(pybind11::module_& m);

}  // namespace lockstep::python
