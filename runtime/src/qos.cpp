#include "lockstep/runtime/bus.h"

namespace lockstep {

const char* QosFamilyName(QosKind kind) {
  switch (kind) {
    case QosKind::kClock: return "clock";
    case QosKind::kAck: return "ack";
    case QosKind::kMembership: return "membership";
    case QosKind::kCommand: return "command";
    case QosKind::kState: return "state";
    case QosKind::kEvent: return "event";
    case QosKind::kSensor: return "sensor";
    case QosKind::kImage: return "image";
    case QosKind::kLargeImage: return "large_image";
  }
  return "unknown";
}

// Mirrors deploy/qos/fastdds.xml for the in-process bus.
int QosHistoryDepth(QosKind kind) {
  switch (kind) {
    case QosKind::kClock:
    case QosKind::kAck:
    case QosKind::kMembership: return 1;
    case QosKind::kCommand: return 256;
    case QosKind::kState: return 256;  // the inputs of a replay, back to the last snapshot
    case QosKind::kEvent: return 64;
    case QosKind::kSensor:
    case QosKind::kImage:
    case QosKind::kLargeImage: return 2;
  }
  return 1;
}

bool QosTransientLocal(QosKind kind) {
  return kind == QosKind::kClock || kind == QosKind::kMembership || kind == QosKind::kState || kind == QosKind::kImage ||
         kind == QosKind::kLargeImage;
}

std::string DefaultQosFile() { return LOCKSTEP_DEFAULT_QOS_FILE; }

}  // namespace lockstep
