#pragma once
#include <string>
// Every topic of the system: name, type and QoS family. docs/topics.md mirrors this list.
#include "lockstep/msg/blueprint.h"
#include "lockstep/msg/clock.h"
#include "lockstep/msg/command.h"
#include "lockstep/msg/common.h"
#include "lockstep/msg/map.h"
#include "lockstep/msg/sensor.h"
#include "lockstep/msg/state.h"
#include "lockstep/msg/world.h"
#include "lockstep/runtime/bus.h"

#define LOCKSTEP_MESSAGE_TYPES(X)                                                        \
  X(Tick) X(TickLog) X(Ack) X(ServiceAnnounce) X(ServiceSnapshot) X(RunStatus) X(FrameDone)         \
  X(BlueprintSet) X(SpawnCheck) X(SpawnCheckReply)                                      \
  X(WorldInfo) X(MapData) X(Command) X(CommandReply) X(GroundState) X(AirState)          \
  X(SimEvent) X(Image) X(PointCloud) X(RadarScan) X(Imu) X(Gnss) X(Barometer)            \
  X(Magnetometer) X(CollisionEvent) X(LaneInvasionEvent) X(ObstacleDetection) X(PhysicsEvents) \
  X(DistanceMeasurement) X(LargeImage) X(V2XData)

namespace lockstep {

#define LOCKSTEP_DECLARE_TYPE_OPS(T) \
  template <>                        \
  const TypeOps& TypeOpsOf<msg::T>();
LOCKSTEP_MESSAGE_TYPES(LOCKSTEP_DECLARE_TYPE_OPS)
#undef LOCKSTEP_DECLARE_TYPE_OPS

namespace topics {
// Clock and membership.
inline constexpr Topic<msg::Tick> kTick{"lockstep/tick", QosKind::kClock};
inline constexpr Topic<msg::TickLog> kTickLog{"lockstep/tick_log", QosKind::kClock};
inline constexpr Topic<msg::Ack> kAck{"lockstep/ack", QosKind::kAck};
inline constexpr Topic<msg::ServiceAnnounce> kService{"lockstep/service", QosKind::kMembership};
inline constexpr Topic<msg::ServiceSnapshot> kSnapshot{"lockstep/snapshot", QosKind::kMembership};
// What each service simulates (blueprint.idl); the library is their union.
inline constexpr Topic<msg::BlueprintSet> kBlueprints{"lockstep/blueprints", QosKind::kMembership};
// The owner's check of a spawn before the client's reply (blueprint.idl).
inline constexpr Topic<msg::SpawnCheck> kSpawnCheck{"lockstep/spawn_check", QosKind::kCommand};
inline constexpr Topic<msg::SpawnCheckReply> kSpawnCheckReply{"lockstep/spawn_check_reply", QosKind::kCommand};
inline constexpr Topic<msg::RunStatus> kRunStatus{"lockstep/run_status", QosKind::kClock};
inline constexpr Topic<msg::FrameDone> kFrameDone{"lockstep/frame_done", QosKind::kClock};
inline constexpr Topic<msg::WorldInfo> kWorldInfo{"lockstep/world_info", QosKind::kClock};
inline constexpr Topic<msg::MapData> kMap{"lockstep/map", QosKind::kClock};
// Clients.
inline constexpr Topic<msg::Command> kCommand{"lockstep/command", QosKind::kCommand};
inline constexpr Topic<msg::CommandReply> kCommandReply{"lockstep/command_reply", QosKind::kCommand};
// World state.
inline constexpr Topic<msg::GroundState> kGroundState{"lockstep/ground_state", QosKind::kState};
inline constexpr Topic<msg::AirState> kAirState{"lockstep/air_state", QosKind::kState};
inline constexpr Topic<msg::SimEvent> kEvent{"lockstep/event", QosKind::kEvent};
inline constexpr Topic<msg::PhysicsEvents> kPhysicsEvents{"lockstep/physics_events", QosKind::kState};
// Sensors.
inline constexpr Topic<msg::PointCloud> kPointCloud{"lockstep/sensor/point_cloud", QosKind::kSensor};
inline constexpr Topic<msg::RadarScan> kRadar{"lockstep/sensor/radar", QosKind::kSensor};
inline constexpr Topic<msg::Imu> kImu{"lockstep/sensor/imu", QosKind::kSensor};
inline constexpr Topic<msg::Gnss> kGnss{"lockstep/sensor/gnss", QosKind::kSensor};
inline constexpr Topic<msg::Barometer> kBarometer{"lockstep/sensor/barometer", QosKind::kSensor};
inline constexpr Topic<msg::Magnetometer> kMagnetometer{"lockstep/sensor/magnetometer", QosKind::kSensor};
inline constexpr Topic<msg::CollisionEvent> kCollision{"lockstep/sensor/collision", QosKind::kEvent};
inline constexpr Topic<msg::LaneInvasionEvent> kLaneInvasion{"lockstep/sensor/lane_invasion", QosKind::kEvent};
inline constexpr Topic<msg::ObstacleDetection> kObstacle{"lockstep/sensor/obstacle", QosKind::kSensor};
inline constexpr Topic<msg::DistanceMeasurement> kDistance{"lockstep/sensor/distance", QosKind::kSensor};
// V2X sensors: what each received in a step (only steps in which it received something).
inline constexpr Topic<msg::V2XData> kV2X{"lockstep/sensor/v2x", QosKind::kEvent};
// Camera images: one topic per camera (msg::Image), QosKind::kImage.
inline std::string ImageTopicName(uint32_t sensor) { return "lockstep/sensor/image/" + std::to_string(sensor); }
// A camera whose image exceeds Image's bound publishes msg::LargeImage (unbounded) on its own
// topic instead, QosKind::kLargeImage (no data-sharing: shared memory or UDP fragments).
inline std::string LargeImageTopicName(uint32_t sensor) { return "lockstep/sensor/large_image/" + std::to_string(sensor); }
}  // namespace topics

}  // namespace lockstep
