#include "lockstep/render/dvs.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace lockstep::render {

DvsSensor::DvsSensor(const DvsParams& params, int width, int height, std::uint64_t seed)
    : p_(params), w_(width), h_(height), rng_(seed) {}

double DvsSensor::Threshold(bool positive) {
  const double c = positive ? p_.positive_threshold : p_.negative_threshold;
  const double s = positive ? p_.sigma_positive_threshold : p_.sigma_negative_threshold;
  if (s <= 0) return c;
  std::normal_distribution<double> d(c, s);
  return std::max(0.01, d(rng_));
}

std::vector<DvsEvent> DvsSensor::Update(const std::uint8_t* bgra, std::int64_t t) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  std::vector<double> cur(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Luminance (BT.601) of the BGRA pixel, 0..1.
    const double y = (0.114 * bgra[i * 4] + 0.587 * bgra[i * 4 + 1] + 0.299 * bgra[i * 4 + 2]) / 255.0;
    cur[i] = p_.use_log ? std::log(y + p_.log_eps) : y;
  }
  std::vector<DvsEvent> events;
  if (!primed_) {
    ref_ = cur;
    prev_ = cur;
    last_event_.assign(n, std::numeric_limits<std::int64_t>::min() / 2);
    last_t_ = t;
    primed_ = true;
    return events;
  }
  const double dt = static_cast<double>(t - last_t_);
  for (std::size_t i = 0; i < n; ++i) {
    const double from = prev_[i], to = cur[i];
    if (from == to) continue;
    for (;;) {
      const bool up = to > ref_[i];
      const double c = Threshold(up);
      const double target = up ? ref_[i] + c : ref_[i] - c;
      if (up ? target > to : target < to) break;
      // Time at which the brightness crossed `target`, linear between the frames.
      const double a = std::clamp((target - from) / (to - from), 0.0, 1.0);
      const auto te = last_t_ + static_cast<std::int64_t>(a * dt);
      ref_[i] = target;
      if (te - last_event_[i] < p_.refractory_period_ns) continue;
      last_event_[i] = te;
      events.push_back(DvsEvent{static_cast<std::uint16_t>(i % w_), static_cast<std::uint16_t>(i / w_), up, te});
    }
  }
  std::stable_sort(events.begin(), events.end(), [](const DvsEvent& a, const DvsEvent& b) { return a.t < b.t; });
  prev_ = std::move(cur);
  last_t_ = t;
  return events;
}

std::vector<std::uint8_t> DvsSensor::Pack(const std::vector<DvsEvent>& events) {
  std::vector<std::uint8_t> out(events.size() * 16, 0);
  for (std::size_t i = 0; i < events.size(); ++i) {
    std::uint8_t* p = &out[i * 16];
    std::memcpy(p, &events[i].x, 2);
    std::memcpy(p + 2, &events[i].y, 2);
    p[4] = events[i].pol ? 1 : 0;
    std::memcpy(p + 8, &events[i].t, 8);
  }
  return out;
}

void DvsSensor::Save(StateOut& out) const {
  std::ostringstream rng;
  rng << rng_;
  out.Put<std::uint8_t>(primed_).Put(last_t_).Put(ref_).Put(prev_).Put(last_event_).Put(rng.str());
}

void DvsSensor::Restore(StateIn& in) {
  std::uint8_t primed = 0;
  std::string rng;
  in.Get(primed).Get(last_t_).Get(ref_).Get(prev_).Get(last_event_).Get(rng);
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  if (primed && (ref_.size() != n || prev_.size() != n || last_event_.size() != n)) {
    throw std::invalid_argument("render snapshot: a DVS image of another size than its camera's");
  }
  primed_ = primed != 0;
  std::istringstream text(rng);
  text >> rng_;
  if (!text) throw std::invalid_argument("render snapshot: a DVS noise generator that does not read back");
}

}  // namespace lockstep::render
