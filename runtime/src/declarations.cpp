#include "lockstep/runtime/declarations.h"

#include <algorithm>

namespace lockstep {

Declarations::Declarations(Bus& bus)
    : sets_reader_(bus, topics::kBlueprints,
                   [this](const msg::BlueprintSet& s, const SampleInfo&) {
                     {
                       std::lock_guard<std::mutex> lock(mu_);
                       sets_[s.service().to_string()] = s;
                       ++version_;
                     }
                     cv_.notify_all();
                   }),
      announce_reader_(bus, topics::kService, [this](const msg::ServiceAnnounce& a, const SampleInfo&) {
        {
          std::lock_guard<std::mutex> lock(mu_);
          const bool stopping = a.state() == msg::ServiceState::SERVICE_STOPPING;
          auto [it, added] = stopping_.emplace(a.service().to_string(), stopping);
          if (!added && it->second == stopping) return;  // a heartbeat: nothing changed
          it->second = stopping;
          ++version_;
        }
        cv_.notify_all();
      }) {}

bool Declarations::WaitUntil(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    uint64_t seen;
    {
      std::lock_guard<std::mutex> lock(mu_);
      seen = version_;
    }
    if (pred()) return true;
    std::unique_lock<std::mutex> lock(mu_);
    if (!cv_.wait_until(lock, deadline, [&] { return version_ != seen; })) return false;
  }
}

bool Declarations::WaitFor(const std::vector<std::string>& services, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  return cv_.wait_for(lock, timeout, [&] {
    return std::all_of(services.begin(), services.end(), [&](const std::string& s) { return sets_.count(s) > 0; });
  });
}

std::map<std::string, msg::BlueprintSet> Declarations::Live() {
  std::lock_guard<std::mutex> lock(mu_);
  std::map<std::string, msg::BlueprintSet> out;
  for (const auto& [name, set] : sets_) {
    auto it = stopping_.find(name);
    if (it == stopping_.end() || !it->second) out[name] = set;
  }
  return out;
}

std::vector<std::string> Declarations::Declaring(msg::ActorKind kind, const std::vector<std::string>& among) {
  std::vector<std::string> out;
  for (const auto& [name, set] : Live()) {
    if (!among.empty() && std::find(among.begin(), among.end(), name) == among.end()) continue;
    const auto& bps = set.blueprints();
    if (std::any_of(bps.begin(), bps.end(), [&](const msg::BlueprintDeclaration& b) { return b.kind() == kind; })) {
      out.push_back(name);
    }
  }
  return out;
}

std::vector<std::string> RequiredServices(const msg::WorldInfo& world) {
  std::vector<std::string> out;
  for (const auto& s : world.required_services()) out.push_back(s.to_string());
  return out;
}

}  // namespace lockstep
