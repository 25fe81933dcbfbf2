#include "lockstep/coordinator/outbox.h"

namespace lockstep {

void OrderedOutbox::Flush(std::unique_lock<std::mutex>& lock) {
  if (pending_.empty()) return;
  std::vector<std::function<void()>> work;
  work.swap(pending_);
  const uint64_t ticket = next_ticket_++;
  lock.unlock();
  {
    std::unique_lock<std::mutex> turn(turn_mu_);
    turn_cv_.wait(turn, [&] { return serving_ == ticket; });
  }
  struct NextTurn {
    OrderedOutbox* box;
    ~NextTurn() {
      {
        std::lock_guard<std::mutex> turn(box->turn_mu_);
        ++box->serving_;
      }
      box->turn_cv_.notify_all();
    }
  } next{this};
  for (auto& f : work) f();
  lock.lock();
}

}  // namespace lockstep
