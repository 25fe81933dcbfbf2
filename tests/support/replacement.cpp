#include "replacement.h"

#include <signal.h>

#include <chrono>
#include <memory>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {

using namespace std::chrono_literals;

ReplacementRun RunWithReplacement(const std::string& config, const std::string& program, const std::string& name,
                                  uint64_t kill_at, uint64_t last_frame) {
  return RunWithReplacement(config, {Bin(program), "--name", name, "--config", config}, {}, kill_at, last_frame);
}

ReplacementRun RunWithReplacement(const std::string& config, const std::vector<std::string>& argv,
                                  const std::vector<std::string>& replacement_argv, uint64_t kill_at, uint64_t last_frame) {
  ReplacementRun r;
  Process coordinator({Bin("lockstep_coordinator"), config});
  auto service = std::make_unique<Process>(argv);
  auto bus = CreateDdsBus({TestDomain(), "", "lockstep.participant.loopback", "replacement-test"});
  Observer obs(*bus);
  auto fail = [&](const std::string& what) {
    if (r.error.empty()) r.error = what + "\ncoordinator:\n" + coordinator.Output();
  };
  std::unique_ptr<Process> replacement;
  if (kill_at > 0) {
    if (!obs.WaitUntil([&] { return obs.last_frame() >= kill_at; }, 60s)) fail("frame " + std::to_string(kill_at) + " never done");
    service->Signal(SIGKILL);
    if (!obs.WaitUntil([&] { return obs.status() && obs.status()->state() == msg::RunState::RUN_FAULTED; }, 10s))
      fail("the run did not fault after the kill");
    replacement = std::make_unique<Process>(replacement_argv.empty() ? argv : replacement_argv);
  }
  if (!obs.WaitUntil([&] { return obs.frames().count(last_frame) > 0; }, 90s)) fail("frame " + std::to_string(last_frame) + " never done");
  if (!coordinator.Wait(10s)) fail("the coordinator did not finish");
  if (replacement) r.replacement_log = replacement->Output();
  auto frames = obs.frames();
  if (frames.count(last_frame)) {
    r.world_hash = frames.at(last_frame).world_hash();
    r.diverged = frames.at(last_frame).diverged();
  }
  return r;
}

}  // namespace lockstep::testing
