// In-memory Bus for tests: no network, samples copied between threads of one process.
// Delivery is synchronous on the writer's thread. Transient-local topics replay the
// last `depth` samples of each live writer to a reader that joins late (per writer,
// not per key: each service writes its own instance, so this matches DDS there).
#include <algorithm>
#include <atomic>
#include <deque>
#include <map>
#include <mutex>
#include <vector>

#include "lockstep/runtime/bus.h"

namespace lockstep {
namespace {

struct ReaderSlot {
  std::mutex mu;
  bool alive = true;
  RawCallback on_sample;
  LivelinessCallback on_liveliness;
};

struct Sample {
  const TypeOps* ops;
  void* data;
  Sample(const TypeOps* o, const void* src) : ops(o), data(o->new_sample()) { o->copy(data, src); }
  ~Sample() { ops->delete_sample(data); }
  Sample(const Sample&) = delete;
  Sample& operator=(const Sample&) = delete;
};

struct TopicState {
  std::mutex mu;
  std::string type_name;
  std::vector<std::shared_ptr<ReaderSlot>> readers;
  std::map<uint64_t, std::deque<std::shared_ptr<Sample>>> history;  // per writer id
  int writers = 0;
};

class Registry {
 public:
  std::shared_ptr<TopicState> Get(const std::string& name, const TypeOps& ops) {
    std::lock_guard<std::mutex> lock(mu_);
    auto& t = topics_[name];
    if (!t) {
      t = std::make_shared<TopicState>();
      t->type_name = ops.type_name;
    }
    if (t->type_name != ops.type_name) {
      throw std::runtime_error("topic '" + name + "' used with two types: " + t->type_name + " and " + ops.type_name);
    }
    return t;
  }

 private:
  std::mutex mu_;
  std::map<std::string, std::shared_ptr<TopicState>> topics_;
};

std::vector<std::shared_ptr<ReaderSlot>> Snapshot(TopicState& t) {
  std::lock_guard<std::mutex> lock(t.mu);
  return t.readers;
}

class InProcWriter final : public RawWriter {
 public:
  InProcWriter(std::shared_ptr<TopicState> topic, const TypeOps& ops, QosKind qos, uint64_t id)
      : topic_(std::move(topic)), ops_(ops), qos_(qos), id_(id) {
    std::lock_guard<std::mutex> lock(topic_->mu);
    ++topic_->writers;
  }
  ~InProcWriter() override {
    {
      std::lock_guard<std::mutex> lock(topic_->mu);
      --topic_->writers;
      topic_->history.erase(id_);
    }
    for (auto& r : Snapshot(*topic_)) {
      std::lock_guard<std::mutex> lock(r->mu);
      if (r->alive && r->on_liveliness) r->on_liveliness(LivelinessChange{id_, false});
    }
  }
  void Write(const void* sample) override {
    if (QosTransientLocal(qos_)) {
      auto kept = std::make_shared<Sample>(&ops_, sample);
      std::lock_guard<std::mutex> lock(topic_->mu);
      auto& h = topic_->history[id_];
      h.push_back(std::move(kept));
      while (static_cast<int>(h.size()) > QosHistoryDepth(qos_)) h.pop_front();
    }
    for (auto& r : Snapshot(*topic_)) {
      std::lock_guard<std::mutex> lock(r->mu);
      if (r->alive) r->on_sample(sample, SampleInfo{id_});
    }
  }
  void AssertLiveliness() override {}
  int MatchedReaders() const override {
    std::lock_guard<std::mutex> lock(topic_->mu);
    return static_cast<int>(topic_->readers.size());
  }
  uint64_t id() const override { return id_; }

 private:
  std::shared_ptr<TopicState> topic_;
  const TypeOps& ops_;
  QosKind qos_;
  uint64_t id_;
};

class InProcReader final : public RawReader {
 public:
  InProcReader(std::shared_ptr<TopicState> topic, std::shared_ptr<ReaderSlot> slot)
      : topic_(std::move(topic)), slot_(std::move(slot)) {}
  ~InProcReader() override {
    {
      std::lock_guard<std::mutex> lock(slot_->mu);
      slot_->alive = false;
    }
    std::lock_guard<std::mutex> lock(topic_->mu);
    auto& v = topic_->readers;
    v.erase(std::remove(v.begin(), v.end(), slot_), v.end());
  }
  int MatchedWriters() const override {
    std::lock_guard<std::mutex> lock(topic_->mu);
    return topic_->writers;
  }

 private:
  std::shared_ptr<TopicState> topic_;
  std::shared_ptr<ReaderSlot> slot_;
};

class InProcessBus final : public Bus {
 public:
  std::unique_ptr<RawWriter> CreateRawWriter(const std::string& topic, const TypeOps& ops, QosKind qos) override {
    return std::make_unique<InProcWriter>(registry_.Get(topic, ops), ops, qos, ++next_writer_id_);
  }
  std::unique_ptr<RawReader> CreateRawReader(const std::string& topic, const TypeOps& ops, QosKind qos,
                                             RawCallback on_sample, LivelinessCallback on_liveliness) override {
    auto t = registry_.Get(topic, ops);
    auto slot = std::make_shared<ReaderSlot>();
    slot->on_sample = std::move(on_sample);
    slot->on_liveliness = std::move(on_liveliness);
    std::vector<std::pair<uint64_t, std::shared_ptr<Sample>>> replay;
    {
      std::lock_guard<std::mutex> lock(t->mu);
      t->readers.push_back(slot);
      if (QosTransientLocal(qos)) {
        for (auto& [writer, samples] : t->history) {
          for (auto& s : samples) replay.emplace_back(writer, s);
        }
      }
    }
    for (auto& [writer, s] : replay) {
      std::lock_guard<std::mutex> lock(slot->mu);
      slot->on_sample(s->data, SampleInfo{writer});
    }
    return std::make_unique<InProcReader>(std::move(t), std::move(slot));
  }
  std::string Describe() const override { return "in-process bus"; }

 private:
  Registry registry_;
  std::atomic<uint64_t> next_writer_id_{0};
};

}  // namespace

std::unique_ptr<Bus> CreateInProcessBus() { return std::make_unique<InProcessBus>(); }

}  // namespace lockstep
