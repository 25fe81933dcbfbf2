#include "lockstep/runtime/service_main.h"

#include <CLI/CLI.hpp>

#include <csignal>

#include "lockstep/runtime/log.h"

namespace lockstep {
namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }
}  // namespace

int RunServiceMain(int argc, char** argv, const std::string& kind, bool perception,
                   const std::function<std::unique_ptr<ServiceCore>(ServiceContext&)>& make_core,
                   const std::function<void(CLI::App&)>& add_options) {
  CLI::App app{"Lockstep service: " + kind};
  std::string name = kind;
  std::string config_file;
  int domain = -1;
  std::string profile;
  app.add_option("--name", name, "service name, unique in the run");
  app.add_option("--config", config_file, "launch config (YAML)")->check(CLI::ExistingFile);
  app.add_option("--domain", domain, "DDS domain id (overrides the config)");
  app.add_option("--participant-profile", profile, "Fast DDS participant profile (overrides the config)");
  if (add_options) add_options(app);
  CLI11_PARSE(app, argc, argv);
  InitLogging(name);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  try {
    ServiceContext ctx;
    ctx.name = name;
    if (!config_file.empty()) ctx.config = LoadLaunchConfig(config_file);
    if (domain >= 0) ctx.config.domain_id = domain;
    if (!profile.empty()) ctx.config.participant_profile = profile;
    for (const auto& s : ctx.config.services) {
      if (s.name == name) ctx.self = &s;
    }
    // A replacement of a process killed with SIGKILL must not take the dead one's
    // shared-memory ports (CreateDdsBus picks an unused participant id, see
    // FreshParticipantId). Should the port still be deaf (no coordinator heard within
    // 10 s), join again with a new participant while the old one still holds its port.
    std::vector<std::unique_ptr<Bus>> stale;
    constexpr int kAttempts = 3;
    for (int attempt = 1;; ++attempt) {
      auto bus = CreateDdsBus({ctx.config.domain_id, ctx.config.qos_file, ctx.config.participant_profile, name});
      ctx.bus = bus.get();
      std::unique_ptr<ServiceCore> core = make_core(ctx);
      try {
        ServiceOptions options{name, kind, perception};
        options.world_info_timeout_s = 10;
        options.snapshot_period = ctx.config.snapshot_period;
        ServiceRunner runner(*bus, options, *core);
        runner.Run(g_stop);
        spdlog::info("stopping after frame {}", runner.last_frame());
      } catch (const JoinTimeout& e) {
        if (attempt == kAttempts) throw;
        spdlog::warn("{}; joining again with a new participant ({} of {})", e.what(), attempt + 1, kAttempts);
        core.reset();
        stale.push_back(std::move(bus));
        continue;
      }
      core.reset();
      return 0;
    }
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}

}  // namespace lockstep
