#pragma once
// Writes a Lockstep log (idl/proto/lockstep_log.proto, docs/recorder.md). The recorder
// service feeds it one frame at a time; every frame is flushed to the file, so a crash
// loses at most the frame being written. Plain C++ (no DDS).
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/msg/sensor.h"
#include "lockstep/msg/state.h"
#include "lockstep/recorder/log_reader.h"

namespace lockstep::recorder {

// A message as CDR bytes (little endian, no encapsulation), bit for bit, and back.
template <class T>
std::vector<uint8_t> ToCdr(const T& value) {
  std::vector<uint8_t> buf(T::getCdrSerializedSize(value) + 8);
  eprosima::fastcdr::FastBuffer fb(reinterpret_cast<char*>(buf.data()), buf.size());
  eprosima::fastcdr::Cdr cdr(fb, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR);
  value.serialize(cdr);
  buf.resize(cdr.getSerializedDataLength());
  return buf;
}
template <class T>
T FromCdr(const void* data, size_t size) {
  T value;
  eprosima::fastcdr::FastBuffer fb(const_cast<char*>(static_cast<const char*>(data)), size);
  eprosima::fastcdr::Cdr cdr(fb, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR);
  value.deserialize(cdr);  // throws eprosima::fastcdr::exception::NotEnoughMemoryException when cut short
  return value;
}
template <class T>
T FromCdr(const std::vector<uint8_t>& bytes) {
  return FromCdr<T>(bytes.data(), bytes.size());
}

// What one frame of the log is made of; pointers stay the caller's.
struct FrameInputs {
  const msg::Tick* tick = nullptr;                  // required
  uint64_t state_frame = 0;                         // frame the states show
  std::vector<const msg::GroundState*> ground;      // one per ground service
  std::vector<const msg::AirState*> air;            // one per air service
  std::vector<const msg::PhysicsEvents*> events;    // one per physics service
  // Hashes that arrived since the frame before (FrameDone comes after the recorder's ack).
  std::vector<std::pair<uint64_t, FrameHashes>> hashes;
  // Actors with no state in the state messages (sensors, controllers, props) alive now.
  std::vector<uint32_t> stateless_actors;
  // The description of an actor new in this frame (blueprint, attributes, owner...): from
  // the tick's spawn or the coordinator's actor list. nullopt: the writer makes one from the state.
  std::function<std::optional<ActorInfo>(uint32_t)> describe;
  std::vector<SensorRecord> sensors;
};

class LogWriter {
 public:
  // Creates `path` (and its folder), writes the magic and the header. Throws LogError.
  LogWriter(const std::string& path, const LogHeader& header);
  ~LogWriter();  // closes with reason "closed" if Close was not called
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  void WriteFrame(const FrameInputs& in);
  // Writes the footer (index, late hashes) and the trailer; the file is then complete.
  void Close(const std::string& reason, const std::vector<std::pair<uint64_t, FrameHashes>>& late_hashes = {});

  const std::string& path() const;
  uint64_t bytes() const;   // written so far
  uint64_t frames() const;  // frames written
  uint64_t last_frame() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lockstep::recorder
