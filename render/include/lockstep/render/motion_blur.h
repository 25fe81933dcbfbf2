#pragma once
// Motion blur of a colour image from its per-pixel motion (the optical flow output):
// CARLA's motion_blur_intensity and motion_blur_max_distortion (see Camera).
#include <cstdint>
#include <vector>

#include "lockstep/render/camera.h"

namespace lockstep::render {

// out = bgra blurred: each pixel the mean of the image along intensity x its motion
// (centred on it; flow in CARLA's units, 2 = the image size, x right, y down), the blur at
// most max_distortion % of the width long; pixels that moved less than half a pixel's blur
// are copied. Nearest-pixel taps, one per pixel of blur length (at most 64).
void ApplyMotionBlur(const Camera& cam, const std::uint8_t* bgra, const float* flow, int width, int height,
                     std::vector<std::uint8_t>* out);

}  // namespace lockstep::render
