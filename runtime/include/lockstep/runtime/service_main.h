#pragma once
// The common main() of a service process: parses --name, --domain, --config, sets up
// logging, signals and the DDS bus, then runs the core until SIGINT/SIGTERM.
#include <functional>
#include <memory>
#include <string>

#include "lockstep/runtime/launch_config.h"
#include "lockstep/runtime/service.h"

namespace CLI {
class App;
}

namespace lockstep {

struct ServiceContext {
  std::string name;          // this service's name
  LaunchConfig config;       // the whole launch config (built-in default if none given)
  const ServiceLaunch* self = nullptr;  // this service's entry, if the config lists it
  Bus* bus = nullptr;
};

// make_core builds the core once the bus exists (cores may open readers/writers).
// add_options adds a service's own options to the command line (CLI11) beside the common
// ones; they are parsed and checked with them, and --help lists them all.
int RunServiceMain(int argc, char** argv, const std::string& kind, bool perception,
                   const std::function<std::unique_ptr<ServiceCore>(ServiceContext&)>& make_core,
                   const std::function<void(CLI::App&)>& add_options = {});

}  // namespace lockstep
