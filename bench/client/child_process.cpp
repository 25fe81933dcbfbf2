#include "child_process.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace lockstep::bench {

ChildProcess::ChildProcess(const std::vector<std::string>& argv) : name_(argv.at(0)) {
  int to[2], from[2];
  // Close-on-exec: a child started later must not hold our ends open (EOF would never come).
  if (pipe2(to, O_CLOEXEC) != 0 || pipe2(from, O_CLOEXEC) != 0) throw std::runtime_error("pipe2() failed");
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork() failed");
  if (pid_ == 0) {
    dup2(to[0], 0);
    dup2(from[1], 1);
    close(to[0]);
    close(to[1]);
    close(from[0]);
    close(from[1]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(to[0]);
  close(from[1]);
  to_ = fdopen(to[1], "w");
  from_ = fdopen(from[0], "r");
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0) Wait();
}

std::string ChildProcess::ReadLine() {
  char* buf = nullptr;
  size_t cap = 0;
  const ssize_t n = getline(&buf, &cap, from_);
  std::string line = n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string();
  std::free(buf);
  if (n <= 0) throw std::runtime_error(name_ + " exited before answering");
  if (!line.empty() && line.back() == '\n') line.pop_back();
  return line;
}

void ChildProcess::Send(const std::string& command) {
  std::fputs(command.c_str(), to_);
  std::fputc('\n', to_);
  std::fflush(to_);
}

std::string ChildProcess::Ask(const std::string& command) {
  Send(command);
  return ReadLine();
}

int ChildProcess::Wait() {
  if (pid_ <= 0) return -1;
  if (to_) std::fclose(to_);
  to_ = nullptr;
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
  if (from_) std::fclose(from_);
  from_ = nullptr;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int ChildProcess::Terminate() {
  if (pid_ > 0) kill(pid_, SIGTERM);
  return Wait();
}

std::vector<double> ParseNumbers(const std::string& line) {
  std::vector<double> out;
  std::istringstream in(line);
  for (double v; in >> v;) out.push_back(v);
  return out;
}

}  // namespace lockstep::bench
