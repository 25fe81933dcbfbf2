#pragma once
// Small synthetic OpenDRIVE files, written by the tests themselves to a temp folder.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "lockstep/map/map.h"
#include "lockstep/map/opendrive_reader.h"

namespace lockstep::map::testing {

inline std::string Xodr(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<OpenDRIVE>\n<header revMajor=\"1\" revMinor=\"6\" name=\"synthetic\"/>\n" + body +
         "</OpenDRIVE>\n";
}

// Writes `text` to a file named after the running test and loads it with Map::Load.
inline Map WriteAndLoad(const std::string& text) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("lockstep_map_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / (std::string(info ? info->name() : "t") + ".xodr");
  {
    std::ofstream out(file);
    out << text;
  }
  Map m = Map::Load(file.string());
  std::filesystem::remove(file);
  std::filesystem::remove(dir);
  return m;
}

// The MapError text of parsing `text`, "" if it parses.
inline std::string ParseErrorOf(const std::string& text) {
  try {
    ParseOpenDrive(text, "t.xodr");
  } catch (const MapError& e) {
    return e.what();
  }
  return "";
}

inline std::string Width(double a, double b = 0, double c = 0, double d = 0, double s_offset = 0) {
  return "<width sOffset=\"" + std::to_string(s_offset) + "\" a=\"" + std::to_string(a) + "\" b=\"" +
         std::to_string(b) + "\" c=\"" + std::to_string(c) + "\" d=\"" + std::to_string(d) + "\"/>";
}

// A straight road along +x from (x0, 0) with the given lane sections (inner XML).
inline std::string StraightRoad(const std::string& id, double x0, double length, const std::string& link,
                                const std::string& sections, const std::string& extra_lanes = "") {
  return "<road id=\"" + id + "\" length=\"" + std::to_string(length) + "\" junction=\"-1\">\n" + link +
         "<planView><geometry s=\"0\" x=\"" + std::to_string(x0) + "\" y=\"0\" hdg=\"0\" length=\"" +
         std::to_string(length) + "\"><line/></geometry></planView>\n<lanes>" + extra_lanes + sections +
         "</lanes>\n</road>\n";
}

}  // namespace lockstep::map::testing
