#pragma once
// The recorder's logs in the client process: CARLA's show_recorder_* texts, the
// recordings folder, AirSim's airsim_rec.txt from a log (recorder.cpp).
#include <pybind11/pybind11.h>

#include <string>

namespace lockstep::python {

void RegisterRecorder(pybind11::module_& m);
// AirSim's airsim_rec.txt from a log; the number of lines written.
size_t WriteAirSimRecord(const std::string& log_path, const std::string& txt_path, double interval, bool record_on_move);

}  // namespace lockstep::python
