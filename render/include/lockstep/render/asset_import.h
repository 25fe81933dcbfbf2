#pragma once
// Custom assets: OBJ, glTF and FBX files imported at run time with Assimp. Each becomes
// a model labelled with one semantic class, centred on its bounding box.
#include <cstdint>
#include <string>

#include "lockstep/render/models.h"

namespace lockstep::render {

struct AssetSpec {
  std::string name;        // blueprint id is custom.<name>
  std::string path;        // .obj, .gltf/.glb, .fbx
  std::uint8_t tag = 20;   // CARLA semantic class (default Static)
  double scale = 1.0;      // file units to metres
  bool y_up = true;        // the file's up axis is +y (OBJ and glTF convention); else +z
};

// Throws std::runtime_error naming the file and Assimp's reason.
Model ImportAsset(const AssetSpec& spec);

}  // namespace lockstep::render
