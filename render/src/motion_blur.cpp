#include "lockstep/render/motion_blur.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lockstep::render {

void ApplyMotionBlur(const Camera& cam, const std::uint8_t* bgra, const float* flow, int width, int height,
                     std::vector<std::uint8_t>* out) {
  const std::size_t n = static_cast<std::size_t>(width) * height;
  out->resize(n * 4);
  std::memcpy(out->data(), bgra, n * 4);
  const float k = static_cast<float>(cam.motion_blur_intensity);
  const float max_len = static_cast<float>(cam.motion_blur_max_distortion / 100.0 * width);
  if (k <= 0 || max_len <= 0) return;
  const float sx = 0.5f * width * k, sy = 0.5f * height * k;
  const float max_u = static_cast<float>(width) - 1e-3f, max_v = static_cast<float>(height) - 1e-3f;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      float bx = flow[i * 2] * sx, by = flow[i * 2 + 1] * sy;
      const float len2 = bx * bx + by * by;
      if (!(len2 >= 0.25f)) continue;  // under half a pixel (also NaN): unchanged
      float len = std::sqrt(len2);
      if (len > max_len) {
        bx *= max_len / len;
        by *= max_len / len;
        len = max_len;
      }
      const int taps = std::min(64, static_cast<int>(std::ceil(len)) + 1);
      const float step_x = bx / static_cast<float>(taps - 1), step_y = by / static_cast<float>(taps - 1);
      float x = u + 0.5f - 0.5f * bx, y = v + 0.5f - 0.5f * by;
      // B, G, R summed in 16-bit lanes of one 64-bit word (64 taps of 255 fit in 14 bits).
      std::uint64_t sum = 0;
      for (int t = 0; t < taps; ++t, x += step_x, y += step_y) {
        const int su = static_cast<int>(std::clamp(x, 0.0f, max_u)), sv = static_cast<int>(std::clamp(y, 0.0f, max_v));
        std::uint32_t p;
        std::memcpy(&p, bgra + (static_cast<std::size_t>(sv) * width + su) * 4, 4);
        sum += (p & 0xffu) | (static_cast<std::uint64_t>((p >> 8) & 0xffu) << 16) | (static_cast<std::uint64_t>((p >> 16) & 0xffu) << 32);
      }
      const unsigned count = static_cast<unsigned>(taps), half = count / 2;
      std::uint8_t* o = out->data() + i * 4;
      o[0] = static_cast<std::uint8_t>(((sum & 0xffffu) + half) / count);
      o[1] = static_cast<std::uint8_t>((((sum >> 16) & 0xffffu) + half) / count);
      o[2] = static_cast<std::uint8_t>((((sum >> 32) & 0xffffu) + half) / count);
    }
  }
}

}  // namespace lockstep::render
