#pragma once
// A child process of bench_client driven line by line: the parent writes a command on
// its stdin and reads one answer line from its stdout.
#include <sys/types.h>

#include <cstdio>
#include <string>
#include <vector>

namespace lockstep::bench {

class ChildProcess {
 public:
  // Starts argv[0] (a path) with argv; throws std::runtime_error if it cannot.
  explicit ChildProcess(const std::vector<std::string>& argv);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // The next line the child writes (without the newline); throws if it exited first.
  std::string ReadLine();
  // Writes `command` and a newline, then returns the child's answer line.
  std::string Ask(const std::string& command);
  void Send(const std::string& command);
  // Closes its stdin and waits for it; returns its exit status (-1: killed).
  int Wait();
  // SIGTERM, then Wait().
  int Terminate();

 private:
  pid_t pid_ = -1;
  FILE* to_ = nullptr;
  FILE* from_ = nullptr;
  std::string name_;
};

// The numbers of a line of space-separated values.
std::vector<double> ParseNumbers(const std::string& line);

}  // namespace lockstep::bench
