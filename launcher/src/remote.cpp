#include "remote.h"

#include <filesystem>

namespace lockstep::launcher {

namespace fs = std::filesystem;

std::string ShellQuote(const std::string& word) {
  const bool safe = !word.empty() && word.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_./:=@,+-%") == std::string::npos;
  if (safe) return word;
  std::string out(1, '\'');
  for (char c : word) {
    if (c == '\'') {
      out.append("'\\''");
    } else {
      out.push_back(c);
    }
  }
  out.push_back('\'');
  return out;
}

namespace {

std::string Join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) {
    if (!out.empty()) out.push_back(' ');
    out.append(ShellQuote(w));
  }
  return out;
}

std::string Absolute(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  return ec ? path : p.lexically_normal().string();
}

}  // namespace

std::string RemoteCommand(const LaunchConfig& config, const std::string& config_file, const ServiceLaunch& service,
                          const HostLaunch& host, const std::string& build_dir) {
  const std::string domain = std::to_string(config.domain_id);
  if (!host.container.empty()) {
    // The service's image runs its program (deploy/containers): the config's folder is
    // mounted at /etc/lockstep, so paths relative to the config (map, qos_file) resolve.
    const fs::path cfg = Absolute(config_file);
    std::vector<std::string> argv{host.container, "run", "-d", "--name", service.name};
    if (!host.network.empty()) argv.insert(argv.end(), {"--network", host.network});
    argv.insert(argv.end(), {"-v", cfg.parent_path().string() + ":/etc/lockstep:ro", "-e", "LOCKSTEP_DOMAIN=" + domain,
                             host.image_prefix + service.kind, "--name", service.name, "--config",
                             "/etc/lockstep/" + cfg.filename().string(), "--domain", domain});
    argv.insert(argv.end(), service.args.begin(), service.args.end());
    return Join(argv);
  }
  const std::string bin = (host.build_dir.empty() ? build_dir : host.build_dir) + "/bin/";
  std::string program = service.executable.empty() ? "lockstep_" + service.kind : service.executable;
  if (program.find('/') == std::string::npos) program = bin + program;
  std::vector<std::string> argv{program, "--name", service.name, "--config", host.config.empty() ? Absolute(config_file) : host.config,
                                "--domain", domain};
  argv.insert(argv.end(), service.args.begin(), service.args.end());
  std::string line = "ssh ";
  line.append(ShellQuote(host.address));
  line.push_back(' ');
  line.append(ShellQuote(Join(argv)));
  return line;
}

std::vector<std::string> RemoteCommands(const LaunchConfig& config, const std::string& config_file, const std::string& build_dir) {
  std::vector<std::string> out;
  for (const auto& s : config.services) {
    const HostLaunch* h = config.HostOf(s.name);
    if (h == nullptr) continue;
    std::string line(1, '[');
    line.append(h->name);
    line.append("] ");
    line.append(RemoteCommand(config, config_file, s, *h, build_dir));
    out.push_back(std::move(line));
  }
  return out;
}

}  // namespace lockstep::launcher
