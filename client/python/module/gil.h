// The GIL around native waits, and signals while they wait.
//
// Two things a Python user takes for granted that a native extension must do itself:
// - Ctrl-C reaches a script blocked in world.tick(), wait_for_tick() or join(): the
//   client polls SignalRaised() while it waits (ClientOptions::interrupted), which runs
//   Python's signal handlers in the main thread; a handler that raises (KeyboardInterrupt)
//   ends the wait with that exception, one that does not lets the wait go on.
// - The process exits cleanly with client threads alive. At interpreter exit Python ends a
//   daemon thread that re-takes the GIL with pthread_exit (a forced unwind). Unwinding out
//   of pybind11's gil_scoped_release, whose destructor is noexcept, aborts the process
//   ("FATAL: exception not rethrown"). ReleaseGil parks such a thread instead (it never
//   returns into a finalizing interpreter) and lets a forced unwind pass if it races.
#pragma once

#include <Python.h>

namespace lockstep::python {

// Call once, at import, from the thread that imports the module.
void RecordMainThread();
bool IsMainThread();
// True when the interpreter is shutting down (no Python code may run in other threads).
bool Finalizing();
// In the main thread: runs pending signal handlers (the GIL is taken); true when one raised,
// its exception left set for the caller's exception translator. False in other threads.
bool SignalRaised();

// lockstep's atexit hook calls this before it closes the clients: from then on a thread
// other than the main one whose native call ends (woken by close()) parks instead of
// returning into Python, so daemon threads end silently as the process exits.
void PrepareExit();

// Marks the running thread as inside a client callback while it lives (such a thread never parks).
class CallbackScope {
 public:
  CallbackScope();
  ~CallbackScope();
  CallbackScope(const CallbackScope&) = delete;
  CallbackScope& operator=(const CallbackScope&) = delete;
};

class ReleaseGil {
 public:
  ReleaseGil() : state_(PyEval_SaveThread()) {}
  ~ReleaseGil() noexcept(false);
  ReleaseGil(const ReleaseGil&) = delete;
  ReleaseGil& operator=(const ReleaseGil&) = delete;

 private:
  PyThreadState* state_;
};

}  // namespace lockstep::python
