#pragma once
// CARLA's dynamic vision sensor: events where the (log) brightness of a pixel changed by
// more than a threshold since its last event, time-stamped by linear interpolation
// between two rendered frames, sorted by time.
#include <cstdint>
#include <random>
#include <vector>

#include "lockstep/render/state_io.h"

namespace lockstep::render {

struct DvsParams {  // CARLA's attribute names and defaults
  double positive_threshold = 0.3;
  double negative_threshold = 0.3;
  double sigma_positive_threshold = 0.0;
  double sigma_negative_threshold = 0.0;
  std::int64_t refractory_period_ns = 0;
  bool use_log = true;
  double log_eps = 0.001;
};

struct DvsEvent {  // 16 bytes on the wire, little-endian: x u16, y u16, pol u8 (1 = brighter), 3 pad, t i64 ns
  std::uint16_t x = 0, y = 0;
  bool pol = false;
  std::int64_t t = 0;  // ns, simulation time
};

class DvsSensor {
 public:
  // seed: run seed ^ sensor id (threshold noise only).
  DvsSensor(const DvsParams& params, int width, int height, std::uint64_t seed);
  // Events between the previous frame and this one (BGRA8 image at time t_ns). The first
  // frame only sets the reference and gives none.
  std::vector<DvsEvent> Update(const std::uint8_t* bgra, std::int64_t t_ns);
  static std::vector<std::uint8_t> Pack(const std::vector<DvsEvent>& events);
  // What the next Update depends on besides its image: the reference and previous
  // log-intensity images, each pixel's last event time, the previous frame's time and the
  // threshold noise generator (the parameters and size come from the spawn).
  void Save(StateOut& out) const;
  void Restore(StateIn& in);

 private:
  double Threshold(bool positive);
  DvsParams p_;
  int w_, h_;
  std::mt19937_64 rng_;
  bool primed_ = false;
  std::int64_t last_t_ = 0;
  std::vector<double> ref_, prev_;
  std::vector<std::int64_t> last_event_;
};

}  // namespace lockstep::render
