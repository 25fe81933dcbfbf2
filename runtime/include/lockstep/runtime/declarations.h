#pragma once
// What the services of a run declare on lockstep/blueprints, for a service that must find
// another's data by what it simulates, never by its name: "does a required service
// simulate vehicles? then wait for its GroundState". Thread safe.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

class Declarations {
 public:
  explicit Declarations(Bus& bus);

  // Waits until each of `services` has published its BlueprintSet (give it
  // WorldInfo.required_services at BeginRun); false on timeout.
  bool WaitFor(const std::vector<std::string>& services, std::chrono::milliseconds timeout);
  // Services that declare a blueprint of `kind`, in name order: all that declared and have
  // not announced that they stop, or only those in `among` if it is not empty.
  std::vector<std::string> Declaring(msg::ActorKind kind, const std::vector<std::string>& among = {});
  bool AnyDeclares(msg::ActorKind kind, const std::vector<std::string>& among = {}) {
    return !Declaring(kind, among).empty();
  }
  // The latest set of every service that has not announced that it stops.
  std::map<std::string, msg::BlueprintSet> Live();
  // Waits until `pred` (which may call the methods above) holds, re-checking it whenever a
  // set or an announcement arrives; false on timeout.
  bool WaitUntil(const std::function<bool()>& pred, std::chrono::milliseconds timeout);

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<std::string, msg::BlueprintSet> sets_;
  std::map<std::string, bool> stopping_;
  uint64_t version_ = 0;  // counts arrivals
  Reader<msg::BlueprintSet> sets_reader_;
  Reader<msg::ServiceAnnounce> announce_reader_;
};

// WorldInfo.required_services as names.
std::vector<std::string> RequiredServices(const msg::WorldInfo& world);

}  // namespace lockstep
