#pragma once
// CARLA 0.9.16's V2X sensors (Unreal Carla/Sensor/V2XSensor, CustomV2XSensor, V2X/CaService,
// V2X/PathLossModel): cooperative awareness messages (CAM) generated from the parent
// vehicle's state by ETSI EN 302 637-2's triggering rules, and custom text messages, each
// received by the other V2X sensors of its family through CARLA's path-loss model (WINNER+
// or geometric two-ray / log-distance, vehicle knife-edge diffraction, ETSI shadow fading).
// The state of the path between two vehicles (line of sight, blocked by vehicles, blocked by
// buildings) comes from a trace through the same ray scene the LiDAR sees.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/sensors/blueprints.h"
#include "lockstep/sensors/geo.h"
#include "lockstep/sensors/ray_scene.h"
#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

// One message a V2X sensor received in a step.
struct V2XMessage {
  uint32_t sender = 0;           // actor id of the sending V2X sensor
  float power_dbm = 0;           // received power
  std::vector<uint8_t> payload;  // the packed layout below
};

// ---- the packed payload (docs/sensors.md): little-endian int32 fields ----
// Both kinds start with CARLA's ItsPduHeader: protocol version, message id, station id.
// CAM (message id 2): kCamFields int32 in the order of CamField. Custom (message id 0):
// the header, then the text's bytes.
enum CamField : int {
  kProtocolVersion, kMessageId, kStationId,
  kGenerationDeltaTime, kStationType,
  kLatitude, kLongitude, kSemiMajorConfidence, kSemiMinorConfidence, kSemiMajorOrientation, kAltitudeValue, kAltitudeConfidence,
  kHighFrequencyPresent,  // 0 nothing, 1 basic vehicle container, 2 RSU container
  kHeadingValue, kHeadingConfidence, kSpeedValue, kSpeedConfidence, kDriveDirection,
  kVehicleLengthValue, kVehicleLengthConfidence, kVehicleWidth,
  kLongitudinalAccelerationValue, kLongitudinalAccelerationConfidence,
  kCurvatureValue, kCurvatureConfidence, kCurvatureCalculationMode,
  kYawRateValue, kYawRateConfidence,
  kOptionalPresent,  // bits: 0 acceleration control, 1 lane position, 2 steering wheel angle, 3 lateral
                     // acceleration, 4 vertical acceleration, 5 performance class, 6 CEN DSRC tolling zone
  kLateralAccelerationValue, kLateralAccelerationConfidence,
  kVerticalAccelerationValue, kVerticalAccelerationConfidence,
  kLowFrequencyPresent,  // 0 nothing, 1 basic vehicle container low frequency
  kVehicleRole, kExteriorLights, kPathHistoryPoints,
  kCamFields
};
using CamMessage = std::array<int32_t, kCamFields>;

constexpr int32_t kV2XProtocolVersion = 2;
constexpr int32_t kMessageIdCustom = 0;
constexpr int32_t kMessageIdCam = 2;
constexpr size_t kV2XHeaderBytes = 12;
constexpr size_t kCustomV2XMaxText = 1024;  // V2XSend.data's bound

std::vector<uint8_t> PackCam(const CamMessage& cam);
CamMessage UnpackCam(const std::vector<uint8_t>& payload);  // zeros past the end
std::vector<uint8_t> PackCustom(int32_t station_id, const std::string& text);
std::string CustomText(const std::vector<uint8_t>& payload);
int32_t PayloadField(const std::vector<uint8_t>& payload, int index);  // the index-th int32 (0 past the end)

// ---- the path-loss model (PathLossModel.cpp) ----

enum class PathState { kLos, kNlosBuilding, kNlosVehicle };

class PathLoss {
 public:
  explicit PathLoss(const Attributes& a);
  double transmit_power() const { return transmit_power_; }
  // Received power (dBm) at `receiver` of a message `sender` sent with `tx_power`, or
  // nullopt when it is farther than filter_distance or below receiver_sensitivity. The
  // shadow fading draw (one per sender within filter_distance) comes from `rng`.
  std::optional<float> Receive(const RayScene& scene, const Actor& receiver, const Actor& sender, double tx_power, const WorldFrame& frame,
                               Rng& rng, PathState* state = nullptr) const;
  // The loss itself for a path state, without fading (tests).
  double PathLossDb(PathState state, double distance3d, double ht, double hr, double knife_edge) const;
  // CARLA's single knife-edge loss of an obstacle of height h (m above the reference)
  // d1 / d2 m from the two ends.
  double KnifeEdge(double d1, double d2, double h) const;
  double FadingStddev(PathState state) const;

 private:
  double transmit_power_, sensitivity_, gain_, path_loss_exponent_, d_ref_, filter_distance_, custom_fading_;
  double frequency_ghz_, frequency_, lambda_, fspl_d0_;
  bool etsi_fading_, winner_;
  int scenario_;  // 0 highway, 1 rural, 2 urban
};

// ---- the cooperative awareness service (CaService.cpp) ----

class CaService {
 public:
  explicit CaService(const Attributes& a);
  // CheckTriggeringConditions at `t` (s of simulation time) for the parent vehicle `owner`:
  // a CAM when one is due (ETSI rules: heading > 4 deg, position > 4 m or speed > 0.5 m/s
  // changed since the last CAM, and at least gen_cam_min since it; else every T_GenCam),
  // with noise from `rng` in CARLA's order.
  std::optional<CamMessage> Trigger(const Actor& owner, double t, double dt, const GeoReference& geo, Rng& rng);
  // What changes from step to step (a snapshot for a replacement process).
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  CamMessage Create(const Actor& owner, double dt, const GeoReference& geo, Rng& rng);
  double gen_cam_min_, gen_cam_max_, gen_cam_;
  bool fixed_rate_;
  double lat_sd_, lat_bias_, lon_sd_, lon_bias_, alt_sd_, alt_bias_, head_sd_, head_bias_;
  Vec3 accel_sd_;
  double yaw_sd_, yaw_bias_, vel_sd_;
  bool started_ = false;
  double elapsed_ = 0, last_cam_ = 0, last_low_cam_ = 0;
  unsigned low_dynamics_counter_ = 0;
  Vec3 position_ = Vec3::Zero(), heading_ = Vec3::Zero();
  double speed_ = 0;
  Vec3 last_position_ = Vec3::Zero(), last_heading_ = Vec3::Zero();
  double last_speed_ = 0;
  bool accel_started_ = false;
  Vec3 prev_location_[2] = {Vec3::Zero(), Vec3::Zero()};
  double prev_dt_ = 0;
};

// ETSI station type of a vehicle (CaService::GetStationType): from its semantic tag, and
// special vehicles (special_type "emergency").
int32_t StationType(const Actor& a);

}  // namespace lockstep::sensors
