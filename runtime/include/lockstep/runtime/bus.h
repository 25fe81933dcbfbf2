#pragma once
// The middleware boundary. Services talk through a Bus: DdsBus (Fast DDS, for real
// processes) or InProcessBus (in memory, for tests with no network). Fast DDS headers
// stay behind this interface.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace lockstep {

// QoS families; each is a pair of writer/reader profiles in deploy/qos/fastdds.xml
// named "lockstep.<family>.writer" / ".reader" (docs/topics.md lists them).
enum class QosKind {
  kClock,       // RELIABLE, KEEP_LAST 1, TRANSIENT_LOCAL: tick, world info, run status, map
  kAck,         // RELIABLE, KEEP_LAST 1 per service, VOLATILE
  kMembership,  // RELIABLE, KEEP_LAST 1, TRANSIENT_LOCAL: service announcements, snapshots
  kCommand,     // RELIABLE, KEEP_LAST 256, VOLATILE: commands and replies
  kState,       // RELIABLE, KEEP_LAST 256, TRANSIENT_LOCAL: ground / air state, physics events (kept
                //   for a replacement's replay: MaxSnapshotPeriod in service.h)
  kEvent,       // RELIABLE, KEEP_LAST 64, VOLATILE
  kSensor,      // RELIABLE, KEEP_LAST 2, VOLATILE: point clouds, IMU, ...
  kImage,       // RELIABLE, KEEP_LAST 2, TRANSIENT_LOCAL, preallocated, data-sharing: camera images
  kLargeImage,  // RELIABLE, KEEP_LAST 2, TRANSIENT_LOCAL, no data-sharing: images over Image's bound
};
const char* QosFamilyName(QosKind kind);
int QosHistoryDepth(QosKind kind);
bool QosTransientLocal(QosKind kind);

struct SampleInfo {
  uint64_t writer_id = 0;  // identifies the DataWriter that wrote the sample
};

struct LivelinessChange {
  uint64_t writer_id = 0;  // the writer whose liveliness changed
  bool alive = false;      // false: lease expired or writer gone
};

// Type-erased operations on one message type; TypeOpsOf<T>() gives them (messages.h).
struct TypeOps {
  const char* type_name;
  void* (*new_dds_type)();  // a new eprosima::fastdds::dds::TopicDataType
  void* (*new_sample)();
  void (*delete_sample)(void*);
  void (*copy)(void* dst, const void* src);
  // The sample's instance key (16 bytes, as DDS computes it); false for a keyless type.
  bool (*key)(const void* sample, std::array<uint8_t, 16>* out);
};

class RawWriter {
 public:
  virtual ~RawWriter() = default;
  virtual void Write(const void* sample) = 0;
  virtual void AssertLiveliness() = 0;
  virtual int MatchedReaders() const = 0;
  virtual uint64_t id() const = 0;
  // Blocks until every matched reliable reader acknowledged what was written, or the
  // timeout passes; false on timeout. Call before exiting so last samples are not lost.
  virtual bool WaitForAcknowledgments(double timeout_s) = 0;
};

class RawReader {
 public:
  virtual ~RawReader() = default;
  virtual int MatchedWriters() const = 0;
};

using RawCallback = std::function<void(const void* sample, const SampleInfo& info)>;
using LivelinessCallback = std::function<void(const LivelinessChange& change)>;
// Like RawCallback, but the sample is the reader's own: the callback may take its
// contents by swapping them with an object of its own (the next sample is read into it).
using RawTakeCallback = std::function<void(void* sample, const SampleInfo& info)>;

class Bus {
 public:
  virtual ~Bus() = default;
  virtual std::unique_ptr<RawWriter> CreateRawWriter(const std::string& topic, const TypeOps& ops,
                                                     QosKind qos) = 0;
  // Callbacks run on a middleware thread: keep them short and never block in them.
  virtual std::unique_ptr<RawReader> CreateRawReader(const std::string& topic, const TypeOps& ops,
                                                     QosKind qos, RawCallback on_sample,
                                                     LivelinessCallback on_liveliness) = 0;
  // A reader whose callback may take each sample (large payloads reach their user
  // without a copy). Buses that share a sample between readers hand each a copy.
  virtual std::unique_ptr<RawReader> CreateRawTakingReader(const std::string& topic, const TypeOps& ops, QosKind qos,
                                                           RawTakeCallback on_sample) {
    std::shared_ptr<void> own(ops.new_sample(), ops.delete_sample);
    return CreateRawReader(
        topic, ops, qos,
        [ops = &ops, own, cb = std::move(on_sample)](const void* s, const SampleInfo& info) {
          ops->copy(own.get(), s);
          cb(own.get(), info);
        },
        {});
  }
  virtual std::string Describe() const = 0;
};

template <class T>
const TypeOps& TypeOpsOf();

template <class T>
struct Topic {
  const char* name;
  QosKind qos;
};

template <class T>
class Writer {
 public:
  Writer() = default;
  Writer(Bus& bus, const Topic<T>& topic)
      : raw_(bus.CreateRawWriter(topic.name, TypeOpsOf<T>(), topic.qos)) {}
  void Write(const T& sample) { raw_->Write(&sample); }
  void AssertLiveliness() { raw_->AssertLiveliness(); }
  int MatchedReaders() const { return raw_->MatchedReaders(); }
  uint64_t id() const { return raw_->id(); }
  bool WaitForAcknowledgments(double timeout_s) { return raw_->WaitForAcknowledgments(timeout_s); }
  explicit operator bool() const { return raw_ != nullptr; }

 private:
  std::unique_ptr<RawWriter> raw_;
};

template <class T>
class Reader {
 public:
  using Callback = std::function<void(const T&, const SampleInfo&)>;
  Reader() = default;
  Reader(Bus& bus, const Topic<T>& topic, Callback on_sample, LivelinessCallback on_liveliness = {})
      : raw_(bus.CreateRawReader(
            topic.name, TypeOpsOf<T>(), topic.qos,
            [cb = std::move(on_sample)](const void* s, const SampleInfo& info) {
              cb(*static_cast<const T*>(s), info);
            },
            std::move(on_liveliness))) {}
  int MatchedWriters() const { return raw_->MatchedWriters(); }
  explicit operator bool() const { return raw_ != nullptr; }

 private:
  std::unique_ptr<RawReader> raw_;
};

// A reader whose callback gets a sample it may take: std::swap it with a T of its own
// (say, a recycled one) and the bus reads the next sample into that T.
template <class T>
class TakingReader {
 public:
  using Callback = std::function<void(T&, const SampleInfo&)>;
  TakingReader() = default;
  TakingReader(Bus& bus, const Topic<T>& topic, Callback on_sample)
      : raw_(bus.CreateRawTakingReader(topic.name, TypeOpsOf<T>(), topic.qos,
                                       [cb = std::move(on_sample)](void* s, const SampleInfo& info) {
                                         cb(*static_cast<T*>(s), info);
                                       })) {}
  int MatchedWriters() const { return raw_->MatchedWriters(); }
  explicit operator bool() const { return raw_ != nullptr; }

 private:
  std::unique_ptr<RawReader> raw_;
};

struct DdsOptions {
  int domain_id = 0;
  std::string profiles_file;                         // Fast DDS XML; empty = LOCKSTEP_QOS_FILE or the installed default
  std::string participant_profile = "lockstep.participant";
  std::string participant_name = "lockstep";
  // Fixes the participant's ports. -1: an id whose shared-memory ports no process used since
  // the last sweep (runtime::FreshParticipantId), so a participant never inherits the
  // ports of one killed with SIGKILL; Fast DDS picks when none is left.
  int participant_id = -1;
};

std::unique_ptr<Bus> CreateDdsBus(const DdsOptions& options);
std::unique_ptr<Bus> CreateInProcessBus();

// The QoS profile file compiled in for this build (deploy/qos/fastdds.xml).
std::string DefaultQosFile();

}  // namespace lockstep
