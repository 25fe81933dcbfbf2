#pragma once
// Logging through spdlog. Each process names itself once; every line carries that name
// so the launcher's merged output stays readable.
#include <spdlog/spdlog.h>

#include <string>

namespace lockstep {

// Sets the default logger's pattern to "[name] level: message" and the level from
// LOCKSTEP_LOG (trace, debug, info, warn, error; default info).
void InitLogging(const std::string& process_name);

}  // namespace lockstep
