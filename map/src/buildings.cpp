#include "lockstep/map/buildings.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace lockstep::map {
namespace {

struct Rect {
  double u0, v0, u1, v1;  // fractions of width (u) and depth (v), 0..1
};

const std::vector<Rect>& Wings(int footprint) {
  static const std::array<std::vector<Rect>, 4> kWings = {{
      {{0, 0, 1, 1}},                                        // box
      {{0, 0, 1, 0.45}, {0, 0, 0.4, 1}},                     // L
      {{0, 0, 1, 0.4}, {0, 0, 0.3, 1}, {0.7, 0, 1, 1}},      // U
      {{0, 0, 1, 0.45}, {0.33, 0, 0.67, 1}},                 // T
  }};
  return kWings[static_cast<std::size_t>(footprint)];
}

// A box in building-local coordinates (u along width, v along depth, metres, centred).
struct Block {
  double uc, vc, lu, lv;  // centre and full extents
  double z0, h;           // base height above ground and height
};

class Placer {
 public:
  explicit Placer(const BuildingInstance& b) : b_(b), c_(std::cos(b.yaw)), s_(std::sin(b.yaw)) {}
  Eigen::Vector3d P(double u, double v, double z) const {
    return {b_.x + u * c_ - v * s_, b_.y + u * s_ + v * c_, b_.z + z};
  }
  Eigen::Vector3d Dir(double u, double v, double z) const { return {u * c_ - v * s_, u * s_ + v * c_, z}; }

 private:
  const BuildingInstance& b_;
  double c_, s_;
};

void AddBlock(Mesh& m, const Placer& pl, const Block& k, double yaw) {
  AddBox(m, pl.P(k.uc, k.vc, k.z0), k.lu, k.lv, k.h, yaw);
}

void AddRoof(Mesh& m, const Placer& pl, const Block& k, int roof) {
  const double top = k.z0 + k.h;
  if (roof == 0) return;
  if (roof == 1) {  // parapet: a low wall around the flat roof
    const double t = 0.3, h = 0.9;
    const Block walls[4] = {{k.uc, k.vc - 0.5 * k.lv + 0.5 * t, k.lu, t, top, h},
                            {k.uc, k.vc + 0.5 * k.lv - 0.5 * t, k.lu, t, top, h},
                            {k.uc - 0.5 * k.lu + 0.5 * t, k.vc, t, k.lv - 2 * t, top, h},
                            {k.uc + 0.5 * k.lu - 0.5 * t, k.vc, t, k.lv - 2 * t, top, h}};
    for (const Block& w : walls) {
      const Eigen::Vector3d base = pl.P(w.uc, w.vc, w.z0);
      const Eigen::Vector3d axis = pl.Dir(1, 0, 0);
      AddBox(m, base, w.lu, w.lv, w.h, std::atan2(axis.y(), axis.x()));
    }
    return;
  }
  // Gable or hip: the ridge runs along the longer side.
  const bool along_u = k.lu >= k.lv;
  const double L = 0.5 * (along_u ? k.lu : k.lv), W = 0.5 * (along_u ? k.lv : k.lu);
  const double rise = std::min(0.45 * W * 2, 4.0);
  auto Q = [&](double a, double b, double z) {  // a along the ridge, b across
    return along_u ? pl.P(k.uc + a, k.vc + b, z) : pl.P(k.uc + b, k.vc + a, z);
  };
  auto D = [&](double a, double b, double z) { return along_u ? pl.Dir(a, b, z) : pl.Dir(b, a, z); };
  const double ridge = roof == 2 ? L : std::max(0.0, L - W);
  const Eigen::Vector3d r0 = Q(-ridge, 0, top + rise), r1 = Q(ridge, 0, top + rise);
  m.AddQuad(Q(-L, W, top), Q(L, W, top), r1, r0, D(0, 1, 1));
  m.AddQuad(Q(-L, -W, top), Q(L, -W, top), r1, r0, D(0, -1, 1));
  m.AddTriangleFacing(Q(L, -W, top), Q(L, W, top), r1, D(1, 0, roof == 2 ? 0 : 1));
  m.AddTriangleFacing(Q(-L, -W, top), Q(-L, W, top), r0, D(-1, 0, roof == 2 ? 0 : 1));
}

}  // namespace

std::string BuildingDesign::Name() const {
  static const char* kFoot[] = {"box", "L", "U", "T"};
  static const char* kRoof[] = {"flat", "parapet", "gable", "hipped"};
  static const char* kMass[] = {"plain", "setback", "tower"};
  return std::string(kFoot[footprint]) + "-" + kRoof[roof] + "-" + kMass[massing];
}

BuildingDesign DescribeBuildingDesign(int design) {
  design = ((design % kBuildingDesignCount) + kBuildingDesignCount) % kBuildingDesignCount;
  return BuildingDesign{design % 4, (design / 4) % 4, design / 16};
}

void AddBuilding(Mesh& m, const BuildingInstance& b) {
  const BuildingDesign d = DescribeBuildingDesign(b.design);
  const Placer pl(b);
  const double W = std::max(2.0, b.width), Dp = std::max(2.0, b.depth);
  const double sh = std::clamp(b.storey_height, 2.2, 6.0);
  const int storeys = std::clamp(b.storeys, 1, 60);
  const double H = storeys * sh;
  const auto& wings = Wings(d.footprint);
  std::vector<Block> tops;
  for (std::size_t i = 0; i < wings.size(); ++i) {
    const Rect& r = wings[i];
    Block k{(0.5 * (r.u0 + r.u1) - 0.5) * W, (0.5 * (r.v0 + r.v1) - 0.5) * Dp, (r.u1 - r.u0) * W, (r.v1 - r.v0) * Dp, 0, H};
    // Wings after the first are a storey lower, which also breaks up the silhouette.
    if (i > 0 && storeys > 1) k.h = H - sh;
    AddBlock(m, pl, k, b.yaw);
    if (i == 0 && d.massing == 1) {  // setback: narrower upper floors on the main wing
      AddRoof(m, pl, k, 1);
      Block up{k.uc, k.vc, k.lu * 0.7, k.lv * 0.7, H, std::max(1, storeys / 2) * sh};
      AddBlock(m, pl, up, b.yaw);
      tops.push_back(up);
    } else if (i == 0 && d.massing == 2) {  // corner tower rising three storeys above
      tops.push_back(k);
      Block tw{k.uc + 0.35 * k.lu, k.vc, k.lu * 0.3, std::min(k.lv, k.lu * 0.3), 0, H + 3 * sh};
      AddBlock(m, pl, tw, b.yaw);
      AddRoof(m, pl, tw, 3);
    } else {
      tops.push_back(k);
    }
  }
  for (const Block& k : tops) AddRoof(m, pl, k, d.roof);
}

}  // namespace lockstep::map
