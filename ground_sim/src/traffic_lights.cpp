// Traffic light groups: one per signalled junction. The group's lights take turns:
// green, yellow, then all red for red_time, then the next light (CARLA's cycle).
#include <algorithm>
#include <limits>

#include "internal.h"

namespace lockstep::ground {

void World::Impl::InitLights() {
  const auto& tl = town->Lights();
  lights.assign(tl.size(), LightState{});
  group_lights.assign(static_cast<size_t>(town->GroupCount()), {});
  for (size_t i = 0; i < tl.size(); ++i) {
    lights[i].group = tl[i].group;
    group_lights[static_cast<size_t>(tl[i].group)].push_back(static_cast<int>(i));
  }
  group_current.assign(group_lights.size(), 0);
  group_all_red.assign(group_lights.size(), false);
  for (size_t g = 0; g < group_lights.size(); ++g) ResetLightGroup(g);
}

// CARLA's ATrafficLightGroup::ResetGroup: every controller back to its last stage (red),
// then the first controller starts its cycle (green).
void World::Impl::ResetLightGroup(size_t g) {
  const auto& members = group_lights[g];
  for (int i : members) {
    lights[static_cast<size_t>(i)].color = LightColor::kRed;
    lights[static_cast<size_t>(i)].elapsed = 0;
  }
  group_current[g] = 0;
  group_all_red[g] = false;
  if (!members.empty()) lights[static_cast<size_t>(members.front())].color = LightColor::kGreen;
}

void World::Impl::StepLights(double dt) {
  for (size_t g = 0; g < group_lights.size(); ++g) {
    const auto& members = group_lights[g];
    if (members.empty()) continue;
    for (int i : members) lights[static_cast<size_t>(i)].elapsed += dt;
    LightState& cur = lights[static_cast<size_t>(members[static_cast<size_t>(group_current[g])])];
    if (cur.frozen) continue;
    if (cur.color == LightColor::kGreen && cur.elapsed >= cur.green_time) {
      cur.color = LightColor::kYellow;
      cur.elapsed = 0;
    } else if (cur.color == LightColor::kYellow && cur.elapsed >= cur.yellow_time) {
      cur.color = LightColor::kRed;
      cur.elapsed = 0;
      group_all_red[g] = true;
    } else if (cur.color == LightColor::kRed && group_all_red[g] && cur.elapsed >= cur.red_time) {
      group_all_red[g] = false;
      group_current[g] = (group_current[g] + 1) % static_cast<int>(members.size());
      LightState& next = lights[static_cast<size_t>(members[static_cast<size_t>(group_current[g])])];
      next.color = LightColor::kGreen;
      next.elapsed = 0;
    }
  }
}

// Seconds until a red light turns green (0 when it is not red), from its group's cycle: what
// is left of the active light's green, yellow and all-red, then a full turn of each light
// between. Infinite where the cycle stands still (a frozen group).
double World::Impl::RedTimeLeft(int light) const {
  const LightState& l = lights[static_cast<size_t>(light)];
  if (l.color != LightColor::kRed) return 0;
  constexpr double kNever = std::numeric_limits<double>::infinity();
  const size_t g = static_cast<size_t>(l.group);
  const auto& members = group_lights[g];
  const size_t n = members.size();
  const size_t at = static_cast<size_t>(group_current[g]);
  const LightState& cur = lights[static_cast<size_t>(members[at])];
  if (cur.frozen || l.frozen) return kNever;
  double t = 0;
  if (cur.color == LightColor::kGreen) {
    t = std::max(0.0, cur.green_time - cur.elapsed) + cur.yellow_time + cur.red_time;
  } else if (cur.color == LightColor::kYellow) {
    t = std::max(0.0, cur.yellow_time - cur.elapsed) + cur.red_time;
  } else if (cur.color == LightColor::kRed && group_all_red[g]) {
    t = std::max(0.0, cur.red_time - cur.elapsed);
  } else {
    return kNever;  // off, or red outside the cycle: it does not advance
  }
  for (size_t k = 1; k <= n; ++k) {
    const int m = members[(at + k) % n];
    if (m == light) return t;
    const LightState& o = lights[static_cast<size_t>(m)];
    t += o.green_time + o.yellow_time + o.red_time;
  }
  return t;
}

std::string World::SetTrafficLight(uint32_t id, std::optional<LightColor> color, double green, double yellow, double red,
                                   std::optional<bool> freeze) {
  auto& I = *impl_;
  if (id == 0 || id > I.lights.size()) return "actor " + std::to_string(id) + " is not a traffic light of this map";
  const size_t index = id - 1;
  LightState& l = I.lights[index];
  for (double t : {green, yellow, red}) {
    if (std::isnan(t) || t > 3600) return "traffic light times must be <= 3600 s (< 0 = unchanged)";
  }
  if (green >= 0) l.green_time = green;
  if (yellow >= 0) l.yellow_time = yellow;
  if (red >= 0) l.red_time = red;
  const size_t g = static_cast<size_t>(l.group);
  if (color && *color != l.color) {
    const auto& members = I.group_lights[g];
    if (*color == LightColor::kGreen || *color == LightColor::kYellow) {
      // This light becomes the group's active one; the others turn red.
      for (size_t k = 0; k < members.size(); ++k) {
        LightState& o = I.lights[static_cast<size_t>(members[k])];
        if (members[k] == static_cast<int>(index)) {
          I.group_current[g] = static_cast<int>(k);
        } else if (o.color != LightColor::kRed) {
          o.color = LightColor::kRed;
          o.elapsed = 0;
        }
      }
      I.group_all_red[g] = false;
    } else if (*color == LightColor::kRed && members[static_cast<size_t>(I.group_current[g])] == static_cast<int>(index)) {
      I.group_all_red[g] = true;
    }
    l.color = *color;
    l.elapsed = 0;
  }
  if (freeze) {
    for (int k : I.group_lights[g]) I.lights[static_cast<size_t>(k)].frozen = *freeze;
  }
  return {};
}

void World::FreezeAllLights(bool freeze) {
  for (auto& l : impl_->lights) l.frozen = freeze;
}

std::string World::ResetLightGroup(uint32_t id) {
  auto& I = *impl_;
  if (id == 0 || id > I.lights.size()) return "actor " + std::to_string(id) + " is not a traffic light of this map";
  I.ResetLightGroup(static_cast<size_t>(I.lights[id - 1].group));
  return {};
}

void World::ResetAllLights() {
  for (size_t g = 0; g < impl_->group_lights.size(); ++g) impl_->ResetLightGroup(g);
}

}  // namespace lockstep::ground
