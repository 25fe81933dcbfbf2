#pragma once
// `lockstep up` across hosts: a service whose launch-config entry names a `host` is not
// started here; the launcher prints the exact command that starts it there (an ssh
// command for a machine, a podman/docker run for a container), and the run waits for it
// as for any required member (docs/deployment.md#several-machines).
#include <string>
#include <vector>

#include "lockstep/runtime/launch_config.h"

namespace lockstep::launcher {

// A word for a POSIX shell: as it is when it holds only safe characters, else in single quotes.
std::string ShellQuote(const std::string& word);
// The command that starts `service` on `host`. `config_file` is the launch config as this
// machine reads it; `build_dir` this machine's build (the default of an ssh host's).
std::string RemoteCommand(const LaunchConfig& config, const std::string& config_file, const ServiceLaunch& service,
                          const HostLaunch& host, const std::string& build_dir);
// One line per service that runs elsewhere ("[host] command"), in the config's order.
std::vector<std::string> RemoteCommands(const LaunchConfig& config, const std::string& config_file, const std::string& build_dir);

}  // namespace lockstep::launcher
