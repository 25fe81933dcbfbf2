#pragma once
// Shared by the log writer and reader: the file's framing and the value conversions.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "lockstep/msg/common.h"

namespace lockstep::recorder::detail {

inline constexpr char kMagic[8] = {'L', 'S', 'L', 'O', 'G', '\x01', '\r', '\n'};
inline constexpr char kTrailerTag[8] = {'L', 'S', 'L', 'O', 'G', 'E', 'N', 'D'};
inline constexpr uint32_t kFormatVersion = 1;
inline constexpr uint32_t kDefaultKeyframePeriod = 200;
inline constexpr double kPositionQuantum = 0.001;  // m
inline constexpr double kAngleQuantum = 1e-4;      // rad

// Protobuf's base-128 varint.
inline size_t PutVarint(uint64_t v, uint8_t* out) {
  size_t n = 0;
  while (v >= 0x80) {
    out[n++] = static_cast<uint8_t>(v | 0x80);
    v >>= 7;
  }
  out[n++] = static_cast<uint8_t>(v);
  return n;
}

struct Rpy {
  double roll, pitch, yaw;
};

// ENU roll, pitch, yaw (ZYX) of a unit quaternion, and back.
inline Rpy RpyOf(const msg::Quaternion& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  Rpy r;
  r.roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
  const double s = 2 * (w * y - z * x);
  r.pitch = std::asin(s > 1 ? 1 : (s < -1 ? -1 : s));
  r.yaw = std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
  return r;
}

inline msg::Quaternion QuatOf(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2);
  const double cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  msg::Quaternion q;
  q.w(cr * cp * cy + sr * sp * sy);
  q.x(sr * cp * cy - cr * sp * sy);
  q.y(cr * sp * cy + sr * cp * sy);
  q.z(cr * cp * sy - sr * sp * cy);
  return q;
}

inline int64_t Quantise(double v, double quantum) {
  if (!std::isfinite(v)) return 0;
  return std::llround(v / quantum);
}

}  // namespace lockstep::recorder::detail
