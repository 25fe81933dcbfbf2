// Type operations for every message: the only place that sees the generated
// PubSubTypes (and through them Fast DDS headers).
#include "lockstep/runtime/messages.h"

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <memory>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/NotEnoughMemoryException.h>

#include "lockstep/runtime/actor_list.h"

#include "lockstep/msg/actorsPubSubTypes.h"
#include "lockstep/msg/blueprintPubSubTypes.h"
#include "lockstep/msg/clockPubSubTypes.h"
#include "lockstep/msg/commandPubSubTypes.h"
#include "lockstep/msg/mapPubSubTypes.h"
#include "lockstep/msg/sensorPubSubTypes.h"
#include "lockstep/msg/statePubSubTypes.h"
#include "lockstep/msg/worldPubSubTypes.h"

namespace lockstep {
namespace {

// The generated PubSubType of a type that nests unbounded sequences of large unions
// computes its maximum serialised size in its constructor by walking every bound: 4-5 s
// of CPU for TickLog (sequence<Tick>, each a sequence<Command>), paid by every process
// that makes a TickLog reader or writer (every service, a replacement included, and the
// coordinator). This type does what the generated one does, without that walk: the size
// is that of an unbounded type (each payload sized by getSerializedSizeProvider).
template <class T>
class UnboundedPubSubType : public eprosima::fastdds::dds::TopicDataType {
 public:
  using SerializedPayload_t = eprosima::fastrtps::rtps::SerializedPayload_t;
  using InstanceHandle_t = eprosima::fastrtps::rtps::InstanceHandle_t;
  explicit UnboundedPubSubType(const char* name) {
    setName(name);
    m_typeSize = 0xF0000000u;  // unbounded, as the generated type's (4.1e9) says
    m_isGetKeyDefined = T::isKeyDefined();
    key_size_ = std::max<size_t>(T::getKeyMaxCdrSerializedSize(), 16);
    key_buffer_ = static_cast<unsigned char*>(calloc(key_size_, 1));
  }
  ~UnboundedPubSubType() override { free(key_buffer_); }
  bool serialize(void* data, SerializedPayload_t* payload) override {
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    eprosima::fastcdr::Cdr ser(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    payload->encapsulation = ser.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    ser.serialize_encapsulation();
    try {
      static_cast<T*>(data)->serialize(ser);
    } catch (eprosima::fastcdr::exception::NotEnoughMemoryException&) {
      return false;
    }
    payload->length = static_cast<uint32_t>(ser.getSerializedDataLength());
    return true;
  }
  bool deserialize(SerializedPayload_t* payload, void* data) override {
    try {
      eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
      eprosima::fastcdr::Cdr deser(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
      deser.read_encapsulation();
      payload->encapsulation = deser.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
      static_cast<T*>(data)->deserialize(deser);
    } catch (eprosima::fastcdr::exception::NotEnoughMemoryException&) {
      return false;
    }
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data]() -> uint32_t { return static_cast<uint32_t>(T::getCdrSerializedSize(*static_cast<T*>(data))) + 4u; };
  }
  void* createData() override { return new T(); }
  void deleteData(void* data) override { delete static_cast<T*>(data); }
  bool getKey(void* data, InstanceHandle_t* handle, bool force_md5) override {
    if (!m_isGetKeyDefined) return false;
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(key_buffer_), T::getKeyMaxCdrSerializedSize());
    eprosima::fastcdr::Cdr ser(buffer, eprosima::fastcdr::Cdr::BIG_ENDIANNESS);
    static_cast<T*>(data)->serializeKey(ser);
    if (force_md5 || T::getKeyMaxCdrSerializedSize() > 16) {
      md5_.init();
      md5_.update(key_buffer_, static_cast<unsigned int>(ser.getSerializedDataLength()));
      md5_.finalize();
      for (uint8_t i = 0; i < 16; ++i) handle->value[i] = md5_.digest[i];
    } else {
      for (uint8_t i = 0; i < 16; ++i) handle->value[i] = key_buffer_[i];
    }
    return true;
  }

 private:
  size_t key_size_ = 16;
  unsigned char* key_buffer_ = nullptr;
  MD5 md5_;
};

// The DDS type of T: the generated one, or UnboundedPubSubType where that one's
// constructor is too slow.
template <class T, class Generated>
struct DdsTypeOf {
  using type = Generated;
  static type* New() { return new type(); }
};
template <class Generated>
struct DdsTypeOf<msg::TickLog, Generated> {
  using type = UnboundedPubSubType<msg::TickLog>;
  static type* New() { return new type("lockstep::msg::TickLog"); }
};

}  // namespace

#define LOCKSTEP_DEFINE_TYPE_OPS(T)                                                           \
  template <>                                                                                 \
  const TypeOps& TypeOpsOf<msg::T>() {                                                        \
    static const TypeOps ops{                                                                 \
        "lockstep::msg::" #T,                                                                 \
        []() -> void* {                                                                       \
          return static_cast<eprosima::fastdds::dds::TopicDataType*>(DdsTypeOf<msg::T, msg::T##PubSubType>::New()); \
        },                                                                                    \
        []() -> void* { return new msg::T(); },                                               \
        [](void* p) { delete static_cast<msg::T*>(p); },                                      \
        [](void* dst, const void* src) {                                                      \
          *static_cast<msg::T*>(dst) = *static_cast<const msg::T*>(src);                      \
        },                                                                                    \
        [](const void* sample, std::array<uint8_t, 16>* out) -> bool {                        \
          thread_local std::unique_ptr<DdsTypeOf<msg::T, msg::T##PubSubType>::type> type(     \
              DdsTypeOf<msg::T, msg::T##PubSubType>::New());                                  \
          eprosima::fastrtps::rtps::InstanceHandle_t h;                                       \
          if (!type->getKey(const_cast<void*>(sample), &h, false)) return false;              \
          for (size_t i = 0; i < out->size(); ++i) (*out)[i] = h.value[i];                   \
          return true;                                                                        \
        }};                                                                                   \
    return ops;                                                                               \
  }
LOCKSTEP_MESSAGE_TYPES(LOCKSTEP_DEFINE_TYPE_OPS)
LOCKSTEP_DEFINE_TYPE_OPS(ActorList)
#undef LOCKSTEP_DEFINE_TYPE_OPS

}  // namespace lockstep
