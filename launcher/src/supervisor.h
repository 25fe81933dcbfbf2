#pragma once
// Starts the processes of one simulation, merges their output with a name prefix, and
// stops them all together.
#include <sys/types.h>

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lockstep {

struct ChildSpec {
  std::string name;               // log prefix and service name
  std::vector<std::string> argv;  // argv[0] is the program path
  bool restart_on_failure = false;
  bool is_coordinator = false;
};

// Why the run reports the service `name` (process `pid`) failed while its process still
// runs (a hang: no heartbeat, or a step that never finishes); nullopt if it does not.
using HangCheck = std::function<std::optional<std::string>(const std::string& name, pid_t pid)>;

class Supervisor {
 public:
  // `hung`: restart-on-failure services it reports are killed (SIGKILL) and replaced
  // like a crashed one.
  explicit Supervisor(std::vector<ChildSpec> children, HangCheck hung = {});
  ~Supervisor();
  // Runs until the coordinator exits, a child fails hard, or `stop` is set. Returns the
  // launcher's exit code: 0 when the coordinator finished normally.
  int Run(const std::atomic<bool>& stop);
  // A status line polled every loop: on a terminal it is redrawn in place below the
  // children's output; otherwise each non-empty line it returns is printed once.
  void SetStatusLine(std::function<std::string()> line, bool terminal);

 private:
  struct Child {
    ChildSpec spec;
    pid_t pid = -1;
    int out_fd = -1;
    std::string pending;  // partial line
    int restarts = 0;
    bool killed = false;  // killed as hung; its exit is then a failure
  };
  void Start(Child& c);
  void Drain(Child& c, bool all);
  void StopAll();                 // the coordinator, then the services
  void Stop(bool coordinator);    // SIGTERM, then SIGKILL after 5 s
  void KillHung();
  void DrawStatus();
  void ClearStatus();
  std::vector<Child> children_;
  HangCheck hung_;
  size_t name_width_ = 0;
  std::function<std::string()> status_;
  bool terminal_ = false;
  bool status_drawn_ = false;
};

}  // namespace lockstep
