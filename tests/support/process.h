#pragma once
// Test helpers: child processes (spawn, signal, wait with timeout) and the paths of the
// built programs. Output of each child goes to a log file the test can print on failure.
#include <sys/types.h>

#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lockstep::testing {

std::string BinDir();                    // build/bin
std::string Bin(const std::string& name);
std::string SourceDir();
// A DDS domain id of this test process's own (tests run in parallel under ctest).
int TestDomain();
// Writes `text` to a fresh file in a per-test temporary folder and returns its path.
std::string WriteTempFile(const std::string& name, const std::string& text);

class Process {
 public:
  Process(std::vector<std::string> argv, const std::map<std::string, std::string>& env = {});
  ~Process();  // kills with SIGKILL if still running
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  void Signal(int sig);
  // Exit status (or 128+signal) if it ended within `timeout`.
  std::optional<int> Wait(std::chrono::milliseconds timeout);
  bool Running();
  std::string Output() const;  // everything it printed so far
  const std::string& log_path() const { return log_; }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string log_;
};

}  // namespace lockstep::testing
