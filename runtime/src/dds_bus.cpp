// Bus over eProsima Fast DDS. Participants and endpoint QoS come from the XML
// profiles in deploy/qos/; nothing here relies on a vendor default.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/log.h"
#include "lockstep/runtime/shm_sweep.h"

namespace lockstep {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

uint64_t HandleId(const dds::InstanceHandle_t& h) {
  return Fnv1a64().Bytes(h.value, sizeof h.value).value();
}

std::string ProfileName(QosKind kind, const char* role) {
  return std::string("lockstep.") + QosFamilyName(kind) + "." + role;
}

// DDS Security (deploy/security, docs/deployment.md): the dds.sec.* properties of a
// participant profile may name their files with ${QOS_DIR}, the QoS file's folder, and
// ${IDENTITY}: LOCKSTEP_SECURITY_IDENTITY, else the participant's name when a certificate
// of that name exists, else "client". So one QoS file serves every process of a run, each
// under its own certificate, wherever the file and its pki/ folder are copied.
void ExpandSecurityProperties(dds::DomainParticipantQos& pqos, const std::string& qos_file, const std::string& name) {
  auto& props = pqos.properties().properties();
  auto has_sec = [&] {
    for (const auto& p : props)
      if (p.name().rfind("dds.sec.", 0) == 0) return true;
    return false;
  };
  if (!has_sec()) return;
  const std::string dir = std::filesystem::absolute(qos_file).parent_path().string();
  auto expand = [&](std::string v, const std::string& identity) {
    for (const auto& [token, value] : {std::pair<std::string, std::string>{"${QOS_DIR}", dir}, {"${IDENTITY}", identity}}) {
      for (size_t at = v.find(token); at != std::string::npos; at = v.find(token, at + value.size()))
        v.replace(at, token.size(), value);
    }
    return v;
  };
  std::string cert_template;
  for (const auto& p : props)
    if (p.name() == "dds.sec.auth.builtin.PKI-DH.identity_certificate") cert_template = p.value();
  auto cert_file = [&](const std::string& identity) {
    std::string f = expand(cert_template, identity);
    return f.rfind("file://", 0) == 0 ? f.substr(7) : f;  // Fast DDS takes file://PATH
  };
  std::string identity;
  if (const char* env = std::getenv("LOCKSTEP_SECURITY_IDENTITY"); env && *env) {
    identity = env;
  } else {
    identity = !cert_template.empty() && std::filesystem::exists(cert_file(name)) ? name : "client";
  }
  if (!cert_template.empty() && !std::filesystem::exists(cert_file(identity))) {
    throw InputError("DDS Security (" + qos_file + "): no certificate " + cert_file(identity) + " for identity '" + identity +
                     "' (make one with deploy/security/make_pki.sh)");
  }
  for (auto& p : props) {
    if (p.name().rfind("dds.sec.", 0) == 0) p.value() = expand(p.value(), identity);
  }
  spdlog::info("DDS Security on: participant '{}' authenticates as '{}'", name, identity);
}

class DdsWriter final : public RawWriter {
 public:
  DdsWriter(dds::Publisher* pub, dds::DataWriter* writer) : pub_(pub), writer_(writer) {}
  ~DdsWriter() override { pub_->delete_datawriter(writer_); }
  void Write(const void* sample) override {
    if (!writer_->write(const_cast<void*>(sample))) {
      spdlog::error("DDS write on topic '{}' failed (sample too large for the type's bound or history full)",
                    writer_->get_topic()->get_name());
    }
  }
  void AssertLiveliness() override { writer_->assert_liveliness(); }
  int MatchedReaders() const override {
    dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    return status.current_count;
  }
  uint64_t id() const override { return HandleId(writer_->get_instance_handle()); }
  bool WaitForAcknowledgments(double timeout_s) override {
    return writer_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(timeout_s)) == ReturnCode_t::RETCODE_OK;
  }

 private:
  dds::Publisher* pub_;
  dds::DataWriter* writer_;
};

class DdsReader final : public RawReader, public dds::DataReaderListener {
 public:
  DdsReader(const TypeOps& ops, RawTakeCallback on_sample, LivelinessCallback on_liveliness)
      : ops_(ops), on_sample_(std::move(on_sample)), on_liveliness_(std::move(on_liveliness)),
        sample_(ops.new_sample()) {}
  ~DdsReader() override {
    {
      // Wait for a callback in flight, then refuse new ones.
      std::lock_guard<std::mutex> lock(mu_);
      alive_ = false;
    }
    if (reader_) {
      reader_->set_listener(nullptr);
      sub_->delete_datareader(reader_);
    }
    ops_.delete_sample(sample_);
  }
  void Attach(dds::Subscriber* sub, dds::DataReader* reader) {
    sub_ = sub;
    reader_ = reader;
  }
  int MatchedWriters() const override {
    dds::SubscriptionMatchedStatus status;
    reader_->get_subscription_matched_status(status);
    return status.current_count;
  }

  void on_data_available(dds::DataReader* reader) override {
    std::lock_guard<std::mutex> lock(mu_);
    if (!alive_) return;
    dds::SampleInfo info;
    while (reader->take_next_sample(sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      on_sample_(sample_, SampleInfo{HandleId(info.publication_handle)});
    }
  }

  void on_liveliness_changed(dds::DataReader*, const dds::LivelinessChangedStatus& status) override {
    std::lock_guard<std::mutex> lock(mu_);
    if (!alive_ || !on_liveliness_) return;
    on_liveliness_(LivelinessChange{HandleId(status.last_publication_handle), status.alive_count_change > 0});
  }

 private:
  const TypeOps& ops_;
  RawTakeCallback on_sample_;  // sample_ is ours alone: the callback may take it
  LivelinessCallback on_liveliness_;
  void* sample_;
  std::mutex mu_;
  bool alive_ = true;
  dds::Subscriber* sub_ = nullptr;
  dds::DataReader* reader_ = nullptr;
};

class DdsBus final : public Bus {
 public:
  explicit DdsBus(const DdsOptions& options) : options_(options) {
    auto* factory = dds::DomainParticipantFactory::get_instance();
    std::string file = options.profiles_file;
    if (file.empty()) {
      const char* env = std::getenv("LOCKSTEP_QOS_FILE");
      file = env ? env : DefaultQosFile();
    }
    if (factory->load_XML_profiles_file(file) != ReturnCode_t::RETCODE_OK) {
      throw InputError("cannot load Fast DDS QoS profiles from '" + file + "'");
    }
    file_ = file;
    dds::DomainParticipantQos pqos;
    if (factory->get_participant_qos_from_profile(options.participant_profile, pqos) != ReturnCode_t::RETCODE_OK) {
      throw InputError("QoS file '" + file + "' has no participant profile '" + options.participant_profile + "'");
    }
    pqos.name(options.participant_name);
    ExpandSecurityProperties(pqos, file, options.participant_name);
    {
      // Choosing and taking the id under a lock: processes starting at once pick different ones.
      std::optional<runtime::ParticipantIdLock> lock;
      int id = options.participant_id;
      if (id < 0) {
        lock.emplace(options.domain_id);
        id = runtime::FreshParticipantId(options.domain_id);
        if (id < 0) {
          spdlog::warn("every DDS participant id of domain {} was used since the last sweep: run `lockstep clean-shm`",
                       options.domain_id);
        }
      }
      if (id >= 0) pqos.wire_protocol().participant_id = id;
      participant_ = factory->create_participant(options.domain_id, pqos);
    }
    if (!participant_) {
      throw InputError("cannot create a DDS participant on domain " + std::to_string(options.domain_id) +
                       " (with DDS Security: are the certificates, governance and permissions valid and signed by the CA?)");
    }
    publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  }

  ~DdsBus() override {
    // Endpoints must be gone before this; delete_contained_entities catches stragglers.
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  std::unique_ptr<RawWriter> CreateRawWriter(const std::string& topic, const TypeOps& ops, QosKind qos) override {
    dds::Topic* t = GetTopic(topic, ops);
    dds::DataWriterQos wqos;
    LoadWriterQos(qos, &wqos);
    dds::DataWriter* writer = publisher_->create_datawriter(t, wqos);
    if (!writer) throw InputError("cannot create a writer for topic '" + topic + "'");
    return std::make_unique<DdsWriter>(publisher_, writer);
  }

  std::unique_ptr<RawReader> CreateRawReader(const std::string& topic, const TypeOps& ops, QosKind qos,
                                             RawCallback on_sample, LivelinessCallback on_liveliness) override {
    return MakeReader(topic, ops, qos, [cb = std::move(on_sample)](void* s, const SampleInfo& info) { cb(s, info); },
                      std::move(on_liveliness));
  }
  std::unique_ptr<RawReader> CreateRawTakingReader(const std::string& topic, const TypeOps& ops, QosKind qos,
                                                   RawTakeCallback on_sample) override {
    return MakeReader(topic, ops, qos, std::move(on_sample), {});
  }

  std::string Describe() const override {
    return "Fast DDS domain " + std::to_string(options_.domain_id) + " (" + options_.participant_profile + ", " + file_ + ")";
  }

 private:
  std::unique_ptr<RawReader> MakeReader(const std::string& topic, const TypeOps& ops, QosKind qos, RawTakeCallback on_sample,
                                        LivelinessCallback on_liveliness) {
    dds::Topic* t = GetTopic(topic, ops);
    dds::DataReaderQos rqos;
    LoadReaderQos(qos, &rqos);
    auto reader = std::make_unique<DdsReader>(ops, std::move(on_sample), std::move(on_liveliness));
    dds::StatusMask mask = dds::StatusMask::data_available() << dds::StatusMask::liveliness_changed();
    dds::DataReader* r = subscriber_->create_datareader(t, rqos, reader.get(), mask);
    if (!r) throw InputError("cannot create a reader for topic '" + topic + "'");
    reader->Attach(subscriber_, r);
    return reader;
  }

  dds::Topic* GetTopic(const std::string& name, const TypeOps& ops) {
    std::lock_guard<std::mutex> lock(mu_);
    if (auto it = topics_.find(name); it != topics_.end()) return it->second;
    if (!participant_->find_type(ops.type_name).get()) {
      dds::TypeSupport type(static_cast<dds::TopicDataType*>(ops.new_dds_type()));
      type.register_type(participant_);
    }
    dds::Topic* t = participant_->create_topic(name, ops.type_name, dds::TOPIC_QOS_DEFAULT);
    if (!t) throw InputError("cannot create topic '" + name + "' of type " + ops.type_name);
    topics_[name] = t;
    return t;
  }

  void LoadWriterQos(QosKind kind, dds::DataWriterQos* qos) {
    const std::string name = ProfileName(kind, "writer");
    if (publisher_->get_datawriter_qos_from_profile(name, *qos) != ReturnCode_t::RETCODE_OK) {
      throw InputError("QoS file '" + file_ + "' has no data writer profile '" + name + "'");
    }
  }
  void LoadReaderQos(QosKind kind, dds::DataReaderQos* qos) {
    const std::string name = ProfileName(kind, "reader");
    if (subscriber_->get_datareader_qos_from_profile(name, *qos) != ReturnCode_t::RETCODE_OK) {
      throw InputError("QoS file '" + file_ + "' has no data reader profile '" + name + "'");
    }
  }

  DdsOptions options_;
  std::string file_;
  dds::DomainParticipant* participant_ = nullptr;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  std::mutex mu_;
  std::map<std::string, dds::Topic*> topics_;
};

}  // namespace

std::unique_ptr<Bus> CreateDdsBus(const DdsOptions& options) { return std::make_unique<DdsBus>(options); }

}  // namespace lockstep
