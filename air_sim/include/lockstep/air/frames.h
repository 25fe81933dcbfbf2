// Frame helpers: ENU/FLU (Lockstep) <-> NED/FRD relative to spawn (AirSim client API).
#pragma once

#include "lockstep/air/types.h"

namespace lockstep::air {

// Wraps an angle to (-pi, pi].
double WrapAngle(double a);

Euler ToEuler(const Quat& q);                  // FLU body in ENU world
Quat FromEuler(double roll, double pitch, double yaw);
inline Quat FromEuler(const Euler& e) { return FromEuler(e.roll, e.pitch, e.yaw); }
double YawOf(const Quat& q);                   // rad, ENU heading (0 = east, CCW)

// Vectors: ENU (x east, y north, z up) <-> NED (x north, y east, z down). Its own inverse.
Vec3 EnuToNed(const Vec3& v);
Vec3 NedToEnu(const Vec3& v);
// Vectors in FLU <-> FRD body axes (y and z negated). Its own inverse.
Vec3 FluToFrd(const Vec3& v);
Vec3 FrdToFlu(const Vec3& v);

// Positions: world ENU <-> AirSim NED relative to the drone's spawn point (m).
Vec3 WorldToAirSimPosition(const Vec3& p_world, const Vec3& spawn_world);
Vec3 AirSimToWorldPosition(const Vec3& p_ned, const Vec3& spawn_world);

// Orientations: q (FLU body -> ENU world) <-> q (FRD body -> NED world).
Quat EnuFluToNedFrd(const Quat& q_enu_flu);
Quat NedFrdToEnuFlu(const Quat& q_ned_frd);

// Yaw: ENU heading (0 east, CCW) <-> NED heading (0 north, CW).
double EnuYawToNedYaw(double yaw_enu);
double NedYawToEnuYaw(double yaw_ned);

// AirSim's roll/pitch/yaw (FRD in NED) from/to Lockstep's (FLU in ENU) for the same attitude.
// roll_frd = roll_flu, pitch_frd = -pitch_flu, yaw_ned = pi/2 - yaw_enu.
Euler EnuEulerToNedEuler(const Euler& e);
Euler NedEulerToEnuEuler(const Euler& e);

}  // namespace lockstep::air
