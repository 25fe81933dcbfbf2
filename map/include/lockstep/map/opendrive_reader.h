#pragma once
#include <string>
#include <string_view>

#include "lockstep/map/error.h"
#include "lockstep/map/opendrive.h"

namespace lockstep::map {

// Parses OpenDRIVE 1.4-1.6 text. `source` names the input in error messages.
// Throws MapError naming the element and line on malformed input.
OpenDrive ParseOpenDrive(std::string_view xml, const std::string& source = "<memory>");
// Reads and parses a .xodr file.
OpenDrive LoadOpenDriveFile(const std::string& path);

}  // namespace lockstep::map
