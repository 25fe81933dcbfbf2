#include "embedded_coordinator.h"

#include "gil.h"

#include <pybind11/stl.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/bus.h"

namespace py = pybind11;

namespace lockstep::python {
namespace {

// Runs Coordinator::Run on a thread of its own, which never takes the GIL.
class EmbeddedCoordinator {
 public:
  EmbeddedCoordinator(const std::string& config_file, int domain) {
    LaunchConfig config = LoadLaunchConfig(config_file);
    if (domain >= 0) config.domain_id = domain;
    domain_ = config.domain_id;
    bus_ = CreateDdsBus({config.domain_id, config.qos_file, config.participant_profile, "coordinator"});
    coordinator_ = std::make_unique<Coordinator>(*bus_, config);
    thread_ = std::thread([this] { exit_code_ = coordinator_->Run(stop_); });
  }
  ~EmbeddedCoordinator() { Close(); }
  EmbeddedCoordinator(const EmbeddedCoordinator&) = delete;
  EmbeddedCoordinator& operator=(const EmbeddedCoordinator&) = delete;

  // Stops the clock and leaves the DDS domain; the exit code of the run (0: normal).
  int Close() {
    if (!thread_.joinable()) return exit_code_;
    stop_ = true;
    thread_.join();
    coordinator_.reset();
    bus_.reset();
    return exit_code_;
  }
  bool running() const { return thread_.joinable(); }
  int domain() const { return domain_; }
  CoordinatorStats stats() const {
    if (!coordinator_) throw std::runtime_error("lockstep.Coordinator.stats(): the coordinator is closed");
    return coordinator_->stats();
  }

 private:
  int domain_ = 0;
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<Coordinator> coordinator_;
  std::atomic<bool> stop_{false};
  int exit_code_ = 0;
  std::thread thread_;
};

}  // namespace

void AddEmbeddedCoordinator(py::module_& m) {
  py::class_<EmbeddedCoordinator>(m, "Coordinator",
                                  "The coordinator of a simulation, in this process: Coordinator(config, domain=-1) "
                                  "loads the launch config (YAML) and starts the clock on a thread of its own. Start "
                                  "the services with `lockstep up CONFIG --no-coordinator`.")
      .def(py::init([](const std::string& config, int domain) {
             python::ReleaseGil release;
             return std::make_unique<EmbeddedCoordinator>(config, domain);
           }),
           py::arg("config"), py::arg("domain") = -1)
      .def("close", &EmbeddedCoordinator::Close, py::call_guard<python::ReleaseGil>(),
           "stops the clock and leaves the domain; returns the run's exit code (0: normal)")
      .def_property_readonly("running", &EmbeddedCoordinator::running)
      .def_property_readonly("domain", &EmbeddedCoordinator::domain)
      .def("stats",
           [](const EmbeddedCoordinator& c) {
             const CoordinatorStats s = c.stats();
             py::dict d;
             d["frames"] = s.frames;
             d["tick_rate_hz"] = s.tick_rate_hz;
             d["mean_barrier_us"] = s.mean_barrier_us;
             d["barrier_us"] = s.barrier_us;
             return d;
           })
      .def("__enter__", [](EmbeddedCoordinator& c) -> EmbeddedCoordinator& { return c; }, py::return_value_policy::reference)
      .def("__exit__", [](EmbeddedCoordinator& c, py::args) {
        python::ReleaseGil release;
        c.Close();
      });
}

}  // namespace lockstep::python
