// In-memory Bus for tests: no network, samples copied between threads of one process.
// Like DDS, delivery is asynchronous: each reader has its own dispatch thread, so a
// callback may write (even to a topic it reads) without re-entering itself, and
// samples from one writer arrive in order. Transient-local topics replay the
// last `depth` samples of each live writer to a reader that joins late (per writer,
// not per key: each service writes its own instance, so this matches DDS there).
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <thread>
#include <variant>
#include <map>
#include <mutex>
#include <vector>

#include "lockstep/runtime/bus.h"

namespace lockstep {
namespace {

struct Sample {
  const TypeOps* ops;
  void* data;
  Sample(const TypeOps* o, const void* src) : ops(o), data(o->new_sample()) { o->copy(data, src); }
  ~Sample() { ops->delete_sample(data); }
  Sample(const Sample&) = delete;
  Sample& operator=(const Sample&) = delete;
};

// One reader: a queue of deliveries and the thread that runs its callbacks.
class ReaderSlot {
 public:
  ReaderSlot(RawCallback on_sample, LivelinessCallback on_liveliness)
      : on_sample_(std::move(on_sample)), on_liveliness_(std::move(on_liveliness)), thread_([this] { Loop(); }) {}
  ~ReaderSlot() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }
  void Deliver(std::shared_ptr<Sample> s, uint64_t writer) { Push(Item{std::move(s), LivelinessChange{writer, true}}); }
  void WriterGone(uint64_t writer) {
    if (on_liveliness_) Push(Item{nullptr, LivelinessChange{writer, false}});
  }

 private:
  struct Item {
    std::shared_ptr<Sample> sample;  // null: a liveliness change
    LivelinessChange change;
  };
  void Push(Item item) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      queue_.push_back(std::move(item));
    }
    cv_.notify_one();
  }
  void Loop() {
    std::unique_lock<std::mutex> lock(mu_);
    while (true) {
      cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      Item item = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      if (item.sample) {
        on_sample_(item.sample->data, SampleInfo{item.change.writer_id});
      } else {
        on_liveliness_(item.change);
      }
      lock.lock();
    }
  }

  RawCallback on_sample_;
  LivelinessCallback on_liveliness_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  bool stop_ = false;
  std::thread thread_;  // last: starts once the members above exist
};

struct TopicState {
  std::mutex mu;
  std::string type_name;
  std::vector<std::shared_ptr<ReaderSlot>> readers;
  // Per writer id and instance key (all zero for keyless types), as DDS keeps it.
  std::map<std::pair<uint64_t, std::array<uint8_t, 16>>, std::deque<std::shared_ptr<Sample>>> history;
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
      std::erase_if(topic_->history, [&](const auto& e) { return e.first.first == id_; });
    }
    for (auto& r : Snapshot(*topic_)) r->WriterGone(id_);
  }
  void Write(const void* sample) override {
    auto copy = std::make_shared<Sample>(&ops_, sample);
    // Under the topic lock, so a reader joining now gets it either as history or live.
    std::lock_guard<std::mutex> lock(topic_->mu);
    if (QosTransientLocal(qos_)) {
      std::array<uint8_t, 16> key{};
      if (ops_.key) ops_.key(sample, &key);
      auto& h = topic_->history[{id_, key}];
      h.push_back(copy);
      while (static_cast<int>(h.size()) > QosHistoryDepth(qos_)) h.pop_front();
    }
    for (auto& r : topic_->readers) r->Deliver(copy, id_);
  }
  void AssertLiveliness() override {}
  int MatchedReaders() const override {
    std::lock_guard<std::mutex> lock(topic_->mu);
    return static_cast<int>(topic_->readers.size());
  }
  uint64_t id() const override { return id_; }
  bool WaitForAcknowledgments(double) override { return true; }  // queued deliveries are never lost

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
      std::lock_guard<std::mutex> lock(topic_->mu);
      auto& v = topic_->readers;
      v.erase(std::remove(v.begin(), v.end(), slot_), v.end());
    }
    slot_.reset();  // joins its thread: no callback runs after this
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
    auto slot = std::make_shared<ReaderSlot>(std::move(on_sample), std::move(on_liveliness));
    {
      std::lock_guard<std::mutex> lock(t->mu);
      if (QosTransientLocal(qos)) {
        for (auto& [instance, samples] : t->history) {
          for (auto& s : samples) slot->Deliver(s, instance.first);
        }
      }
      t->readers.push_back(slot);
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
