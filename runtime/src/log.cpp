#include "lockstep/runtime/log.h"

#include <cstdlib>

namespace lockstep {

void InitLogging(const std::string& process_name) {
  // Under `lockstep up` the launcher prefixes each line with the process name.
  const bool launched = std::getenv("LOCKSTEP_LAUNCHED") != nullptr;
  spdlog::set_pattern(launched ? std::string("%^%l%$: %v") : "[" + process_name + "] %^%l%$: %v");
  const char* level = std::getenv("LOCKSTEP_LOG");
  spdlog::set_level(level ? spdlog::level::from_str(level) : spdlog::level::info);
}

}  // namespace lockstep
