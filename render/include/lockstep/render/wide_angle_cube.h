#pragma once
// How the renderer draws a wide-angle lens camera (Camera::wide_angle): six 90 degree
// square pinhole faces at the camera's position (a cube map, as CARLA's
// SceneCaptureSensor_WideAngleLens captures), then each output pixel takes the face pixel
// its lens ray (WideAngleRay) passes through, weighted by the fov fade (colour). Colour, labels, and
// depth and normals as the face drew them (planar to the face, in its camera frame).
#include <array>

#include "lockstep/render/camera.h"
#include "lockstep/render/renderer.h"

namespace lockstep::render {

// Face f of the cube (0 +x forward, 1 -x, 2 +y left, 3 -y, 4 +z up, 5 -z, body axes):
// a pinhole of 90 degrees, square, sized so its centre resolves the lens's centre.
Camera WideAngleFace(const Camera& cam, int face);
// The lens image from the six faces' frames (faces[f] drawn by WideAngleFace(cam, f)).
CameraFrame ComposeWideAngle(const Camera& cam, const std::array<CameraFrame, 6>& faces);

}  // namespace lockstep::render
