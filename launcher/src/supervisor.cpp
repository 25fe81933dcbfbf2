#include "supervisor.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace lockstep {

Supervisor::Supervisor(std::vector<ChildSpec> children, HangCheck hung) : hung_(std::move(hung)) {
  for (auto& spec : children) {
    name_width_ = std::max(name_width_, spec.name.size());
    Child c;
    c.spec = std::move(spec);
    children_.push_back(std::move(c));
  }
}

Supervisor::~Supervisor() { StopAll(); }

void Supervisor::Start(Child& c) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    setenv("LOCKSTEP_LAUNCHED", "1", 1);  // children leave the name prefix to us
    std::vector<char*> args;
    for (auto& a : c.spec.argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "cannot start %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  close(fds[1]);
  fcntl(fds[0], F_SETFL, O_NONBLOCK);
  c.pid = pid;
  c.out_fd = fds[0];
  c.killed = false;
}

void Supervisor::KillHung() {
  if (!hung_) return;
  for (auto& c : children_) {
    if (c.pid <= 0 || c.killed || c.spec.is_coordinator || !c.spec.restart_on_failure) continue;
    if (auto why = hung_(c.spec.name, c.pid)) {
      ClearStatus();
      std::printf("%-*s | hung (%s): killing pid %d to replace it\n", static_cast<int>(name_width_), c.spec.name.c_str(),
                  why->c_str(), static_cast<int>(c.pid));
      std::fflush(stdout);
      kill(c.pid, SIGKILL);
      c.killed = true;
    }
  }
}

void Supervisor::Drain(Child& c, bool all) {
  char buf[4096];
  while (c.out_fd >= 0) {
    ssize_t n = read(c.out_fd, buf, sizeof buf);
    if (n <= 0) {
      if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
        close(c.out_fd);
        c.out_fd = -1;
      }
      break;
    }
    c.pending.append(buf, static_cast<size_t>(n));
    if (!all) break;
  }
  size_t pos;
  if (c.pending.find('\n') != std::string::npos || (c.out_fd < 0 && !c.pending.empty())) ClearStatus();
  while ((pos = c.pending.find('\n')) != std::string::npos) {
    std::printf("%-*s | %s\n", static_cast<int>(name_width_), c.spec.name.c_str(), c.pending.substr(0, pos).c_str());
    c.pending.erase(0, pos + 1);
  }
  if (c.out_fd < 0 && !c.pending.empty()) {
    std::printf("%-*s | %s\n", static_cast<int>(name_width_), c.spec.name.c_str(), c.pending.c_str());
    c.pending.clear();
  }
  std::fflush(stdout);
}

void Supervisor::StopAll() {
  // The clock first: once the coordinator is gone no tick starts, and the services finish
  // the one in flight together. Stopped at once with the rest, a service could stop
  // before the last tick reached it while a perception service waits for that service's
  // output of it (until its input timeout, past the grace period: then it gets SIGKILL).
  Stop(true);
  Stop(false);
}

void Supervisor::Stop(bool coordinator) {
  for (auto& c : children_) {
    if (c.pid > 0 && c.spec.is_coordinator == coordinator) kill(c.pid, SIGTERM);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  for (auto& c : children_) {
    if (c.spec.is_coordinator != coordinator) continue;
    while (c.pid > 0) {
      int st;
      pid_t r = waitpid(c.pid, &st, WNOHANG);
      if (r == c.pid || r < 0) {
        c.pid = -1;
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        kill(c.pid, SIGKILL);
        waitpid(c.pid, &st, 0);
        c.pid = -1;
        break;
      }
      for (auto& other : children_) Drain(other, false);  // no child blocks on a full pipe meanwhile
      poll(nullptr, 0, 10);
    }
    Drain(c, true);
  }
}

void Supervisor::SetStatusLine(std::function<std::string()> line, bool terminal) {
  status_ = std::move(line);
  terminal_ = terminal;
}

void Supervisor::ClearStatus() {
  if (!status_drawn_) return;
  std::fputs("\r\033[K", stdout);
  status_drawn_ = false;
}

void Supervisor::DrawStatus() {
  if (!status_) return;
  const std::string line = status_();
  if (line.empty()) return;
  if (terminal_) {
    std::printf("\r\033[K%s", line.c_str());
    status_drawn_ = true;
  } else {
    std::printf("%-*s | %s\n", static_cast<int>(name_width_), "progress", line.c_str());
  }
  std::fflush(stdout);
}

int Supervisor::Run(const std::atomic<bool>& stop) {
  for (auto& c : children_) Start(c);
  int exit_code = 0;
  while (!stop) {
    std::vector<pollfd> fds;
    for (auto& c : children_) {
      if (c.out_fd >= 0) fds.push_back(pollfd{c.out_fd, POLLIN, 0});
    }
    poll(fds.data(), fds.size(), 100);
    for (auto& c : children_) Drain(c, false);
    DrawStatus();
    KillHung();
    // Reap children that ended.
    bool done = false;
    for (auto& c : children_) {
      if (c.pid <= 0) continue;
      int st;
      if (waitpid(c.pid, &st, WNOHANG) != c.pid) continue;
      Drain(c, true);
      const int code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      c.pid = -1;
      if (c.spec.is_coordinator) {
        ClearStatus();
        std::printf("%-*s | exited with %d\n", static_cast<int>(name_width_), c.spec.name.c_str(), code);
        exit_code = code;
        done = true;
      } else if ((code != 0 || c.killed) && c.spec.restart_on_failure && c.restarts < 5) {
        ++c.restarts;
        ClearStatus();
        std::printf("%-*s | failed (%d): starting a replacement (%d of 5)\n", static_cast<int>(name_width_),
                    c.spec.name.c_str(), code, c.restarts);
        Start(c);
      } else {
        ClearStatus();
        std::printf("%-*s | exited with %d: stopping the simulation\n", static_cast<int>(name_width_), c.spec.name.c_str(), code);
        exit_code = code == 0 ? 1 : code;
        done = true;
      }
    }
    if (done) break;
  }
  ClearStatus();
  StopAll();
  return exit_code;
}

}  // namespace lockstep
