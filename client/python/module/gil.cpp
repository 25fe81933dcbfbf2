#include "gil.h"

#include <pythread.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace lockstep::python {
namespace {
std::atomic<unsigned long> g_main_thread{0};
std::atomic<bool> g_exiting{false};
thread_local int t_callbacks = 0;  // > 0: this thread runs a client callback (the dispatch thread)

[[noreturn]] void Park() {
  for (;;) std::this_thread::sleep_for(std::chrono::hours(24));
}
}  // namespace

void RecordMainThread() { g_main_thread = PyThread_get_thread_ident(); }

bool IsMainThread() { return PyThread_get_thread_ident() == g_main_thread.load(); }

bool Finalizing() { return _Py_IsFinalizing() != 0; }

bool SignalRaised() {
  if (!IsMainThread() || Finalizing()) return false;
  PyGILState_STATE gil = PyGILState_Ensure();
  const bool raised = PyErr_CheckSignals() != 0;
  PyGILState_Release(gil);
  return raised;
}

void PrepareExit() { g_exiting = true; }

CallbackScope::CallbackScope() { ++t_callbacks; }
CallbackScope::~CallbackScope() { --t_callbacks; }

ReleaseGil::~ReleaseGil() noexcept(false) {
  // The main thread is the one that exits and finalizes: it always gets the GIL back. A
  // client callback must return, or close() could not join its thread.
  if (!IsMainThread() && (Finalizing() || (g_exiting && t_callbacks == 0))) Park();
  PyEval_RestoreThread(state_);
}

}  // namespace lockstep::python
