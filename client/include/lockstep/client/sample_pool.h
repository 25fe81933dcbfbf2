#pragma once
// Recycled message objects for large sensor payloads (images, point clouds). A reader
// takes a received sample by swapping it with a pooled object: the payload changes
// hands without a copy, and the reader's next sample is read into the pooled object's
// buffer, which already has the right size (no allocation, no zero-fill). A sample's
// last user (a numpy array in Python, say) gives the object back to the pool.
#include <cstddef>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace lockstep::client {

template <class T>
class SamplePool : public std::enable_shared_from_this<SamplePool<T>> {
 public:
  explicit SamplePool(size_t keep) : keep_(keep) {}

  // Takes `received`'s contents into a pooled object (leaving it a recycled one to read
  // into) and shares them; the object returns to the pool when the last owner lets go.
  std::shared_ptr<const T> Take(T& received) {
    std::unique_ptr<T> mine = Get();
    std::swap(*mine, received);
    auto self = this->shared_from_this();
    return std::shared_ptr<const T>(mine.release(), [self](const T* p) { self->Put(const_cast<T*>(p)); });
  }

  size_t idle() const {
    std::lock_guard<std::mutex> lock(mu_);
    return free_.size();
  }

 private:
  std::unique_ptr<T> Get() {
    std::lock_guard<std::mutex> lock(mu_);
    if (free_.empty()) return std::make_unique<T>();
    std::unique_ptr<T> p = std::move(free_.back());
    free_.pop_back();
    return p;
  }
  void Put(T* p) {
    std::unique_ptr<T> owned(p);
    std::lock_guard<std::mutex> lock(mu_);
    if (free_.size() < keep_) free_.push_back(std::move(owned));
  }

  const size_t keep_;
  mutable std::mutex mu_;
  std::vector<std::unique_ptr<T>> free_;
};

}  // namespace lockstep::client
