// libFuzzer target: any bytes into the scene reader (the <town>.scene.yaml beside a map, and
// LoadMap's inline scene), and the meshes built from what it accepts. Malformed input must
// end in MapError naming the key and line; anything else (crash, sanitizer report, other
// exception, a mesh of unbounded size) is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lockstep/map/error.h"
#include "lockstep/map/scene.h"
#include "lockstep/map/scene_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const lockstep::map::Scene scene = lockstep::map::SceneFromYaml(text, "fuzz.scene.yaml");
    // What it accepted writes back and reads again as the same scene.
    const std::string yaml = lockstep::map::SceneToYaml(scene);
    const lockstep::map::Scene again = lockstep::map::SceneFromYaml(yaml, "fuzz-again.scene.yaml");
    if (again.buildings.size() != scene.buildings.size() || again.props.size() != scene.props.size()) __builtin_trap();
    lockstep::map::BuildSceneMeshes(scene);
  } catch (const lockstep::map::MapError&) {
    // Expected for malformed input.
  }
  return 0;
}
