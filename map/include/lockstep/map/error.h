#pragma once
#include <stdexcept>
#include <string>

namespace lockstep::map {

// Thrown for malformed or unreadable map input. The message names the file, the
// element and the line ("Town01.xodr:42: <geometry>: missing attribute 'hdg'").
class MapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace lockstep::map
