#pragma once
// CARLA's recorder queries on a Lockstep log, in CARLA's text formats (scripts parse
// them): Client.show_recorder_file_info, show_recorder_collisions,
// show_recorder_actors_blocked. `name` resolves as start_recorder's does (ResolveLogPath);
// a missing file gives CARLA's "File <path> not found on server" text, not an exception.
// Units as CARLA prints them: locations in cm, y = -ENU y (left-handed), angles in degrees
// (roll, pitch, yaw with CARLA's signs), vehicles at the base of their box.
#include <string>

namespace lockstep::recorder {

// "Version", "Map", "Date", then the frames with their events (all frames, positions,
// traffic lights and animations when show_all), then "Frames: N" and "Duration: T seconds".
std::string ShowRecorderFileInfo(const std::string& name, bool show_all);
// Collisions whose actors match the categories: 'h' hero, 'v' vehicle, 'w' walker,
// 't' traffic light, 'o' other, 'a' any. A collision shows once, at its first frame.
std::string ShowRecorderCollisions(const std::string& name, char type1, char type2);
// Actors that moved less than min_distance (cm) for at least min_time (s), longest first.
std::string ShowRecorderActorsBlocked(const std::string& name, double min_time, double min_distance);

}  // namespace lockstep::recorder
