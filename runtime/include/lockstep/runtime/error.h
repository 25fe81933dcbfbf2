#pragma once
// Errors. Bad user input (config, command, map) throws lockstep::InputError with a
// message that names what was wrong; broken internal invariants use LOCKSTEP_DEMAND,
// which is always on.
#include <stdexcept>
#include <string>

namespace lockstep {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] void DemandFailed(const char* condition, const char* file, int line);

}  // namespace lockstep

#define LOCKSTEP_DEMAND(cond) \
  ((cond) ? static_cast<void>(0) : ::lockstep::DemandFailed(#cond, __FILE__, __LINE__))
