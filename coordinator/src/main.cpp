// lockstep_coordinator: owns the clock of one simulation.
#include <CLI/CLI.hpp>

#include <csignal>

#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/log.h"

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Lockstep coordinator: clock, tick barrier, commands"};
  std::string config_file;
  int domain = -1;
  app.add_option("config", config_file, "launch config (YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("--domain", domain, "DDS domain id (overrides the config)");
  CLI11_PARSE(app, argc, argv);
  lockstep::InitLogging("coordinator");
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  try {
    lockstep::LaunchConfig config = lockstep::LoadLaunchConfig(config_file);
    if (domain >= 0) config.domain_id = domain;
    auto bus = lockstep::CreateDdsBus({config.domain_id, config.qos_file, config.participant_profile, "coordinator"});
    lockstep::Coordinator coordinator(*bus, config);
    return coordinator.Run(g_stop);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
