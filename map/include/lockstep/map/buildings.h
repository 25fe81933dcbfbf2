#pragma once
#include <string>

#include "lockstep/map/mesh.h"
#include "lockstep/map/scene.h"

namespace lockstep::map {

// Parametric building designs: footprint (box, L, U, T) x roof (flat, parapet, gable,
// hipped) x massing (plain, setback upper floors, corner tower) = 48 designs. Instance
// parameters (size, storeys, storey height) scale each design.
inline constexpr int kBuildingDesignCount = 48;

struct BuildingDesign {
  int footprint = 0;  // 0 box, 1 L, 2 U, 3 T
  int roof = 0;       // 0 flat, 1 parapet, 2 gable, 3 hipped
  int massing = 0;    // 0 plain, 1 setback, 2 tower
  std::string Name() const;
};

BuildingDesign DescribeBuildingDesign(int design);
// Appends the building's triangles (walls, roof) to `mesh`.
void AddBuilding(Mesh& mesh, const BuildingInstance& b);

}  // namespace lockstep::map
