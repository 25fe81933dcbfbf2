#pragma once
// Starts the processes of one simulation, merges their output with a name prefix, and
// stops them all together.
#include <sys/types.h>

#include <atomic>
#include <string>
#include <vector>

namespace lockstep {

struct ChildSpec {
  std::string name;               // log prefix and service name
  std::vector<std::string> argv;  // argv[0] is the program path
  bool restart_on_failure = false;
  bool is_coordinator = false;
};

class Supervisor {
 public:
  explicit Supervisor(std::vector<ChildSpec> children);
  ~Supervisor();
  // Runs until the coordinator exits, a child fails hard, or `stop` is set. Returns the
  // launcher's exit code: 0 when the coordinator finished normally.
  int Run(const std::atomic<bool>& stop);

 private:
  struct Child {
    ChildSpec spec;
    pid_t pid = -1;
    int out_fd = -1;
    std::string pending;  // partial line
    int restarts = 0;
  };
  void Start(Child& c);
  void Drain(Child& c, bool all);
  void StopAll();
  std::vector<Child> children_;
  size_t name_width_ = 0;
};

}  // namespace lockstep
