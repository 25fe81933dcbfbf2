// Test helper: a tiny driver around Step() that plays the client (sends commands, ticks,
// records reports and events).
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <vector>

#include "lockstep/air/air.h"

namespace lockstep::air::testing {

struct Sim {
  World model;
  WorldState state;
  Environment env;
  double dt = 0.05;
  CommandId next_id = 1;
  Commands pending;
  std::map<CommandId, CommandReport> last_report;
  std::vector<CommandReport> all_reports;
  std::vector<AirEvent> all_events;
  bool allow_resets = false;  // MuJoCo-style: any non-finite reset fails the test unless allowed

  ~Sim() {
    if (allow_resets) return;
    for (const AirEvent& e : all_events) {
      if (e.kind == EventKind::kReset) {
        ADD_FAILURE_AT(__FILE__, __LINE__) << "unexpected reset event of drone " << e.drone << ": " << e.message;
      }
    }
  }

  DroneId Add(DroneId id, const MultirotorParams& p = {}, Vec3 xy = Vec3::Zero(), double yaw = 0) {
    const DerivedParams d = DeriveParams(p);
    Pose spawn;
    spawn.position = Vec3(xy.x(), xy.y(), model.statics.ground_height + RestHeight(d));
    spawn.orientation = FromEuler(0, 0, yaw);
    AddDrone(&model, &state, id, p, spawn);
    return id;
  }
  CommandId Send(DroneId drone, CommandBody body) {
    Command c;
    c.id = next_id++;
    c.drone = drone;
    c.body = std::move(body);
    pending.push_back(std::move(c));
    return pending.back().id;
  }
  void Tick() {
    Step(model, &state, pending, env, dt);
    pending.clear();
    for (const CommandReport& r : state.reports) {
      last_report[r.id] = r;
      all_reports.push_back(r);
    }
    for (const AirEvent& e : state.events) all_events.push_back(e);
  }
  void Run(double seconds) {
    const int n = static_cast<int>(std::llround(seconds / dt));
    for (int i = 0; i < n; ++i) Tick();
  }
  // Ticks until pred() or max_seconds; returns whether pred() became true.
  bool RunUntil(const std::function<bool()>& pred, double max_seconds) {
    const int n = static_cast<int>(std::llround(max_seconds / dt));
    for (int i = 0; i < n; ++i) {
      if (pred()) return true;
      Tick();
    }
    return pred();
  }
  CommandStatus Status(CommandId id) const {
    auto it = last_report.find(id);
    EXPECT_NE(it, last_report.end()) << "no report for command " << id;
    return it == last_report.end() ? CommandStatus::kRejected : it->second.status;
  }
  bool Done(CommandId id) const {
    auto it = last_report.find(id);
    return it != last_report.end() && it->second.status != CommandStatus::kRunning;
  }
  DroneState& D(DroneId id) { return *state.Find(id); }
  // Arms and takes off; returns once the takeoff command completed (fails the test otherwise).
  void TakeOff(DroneId id, double max_seconds = 10) {
    Send(id, cmd::Arm{});
    const CommandId t = Send(id, cmd::Takeoff{});
    ASSERT_TRUE(RunUntil([&] { return Done(t); }, max_seconds));
    ASSERT_EQ(Status(t), CommandStatus::kCompleted);
  }
};

inline MultirotorParams NoDrag(MultirotorParams p = {}) {
  p.linear_drag_coefficient = 0;
  p.angular_drag_coefficient = 0;
  return p;
}

}  // namespace lockstep::air::testing
