#pragma once
// Kinect v1 structured light (doc/synthetic.md, "Sensor models"; fitted in doc/sensors.md).

#include <agex/simulation/depth_sensor.h>

#include <cstdint>
#include <vector>

namespace agex
{
/** Kinect v1: the pixel-centre ray's surface (no mixed pixels), then
  *  - projector shadows: pixels the projector (kinect_baseline to the right) cannot light;
  *  - the correlation window (kinect_window): a pixel takes the disparity of the surface
  *    that dominates its block-matching window, so thin limbs thin out or vanish far away
  *    and silhouettes round off;
  *  - holes at grazing incidence and along depth edges;
  *  - disparity noise and quantisation in 1/8 pixel: depth steps z^2 / (8 f_ir b). */
class KinectV1Sensor : public DepthSensor
{
public:
  using DepthSensor::DepthSensor;

  bool measurePixel (const PixelSamples &samples, const PixelIntegral &sum, const RayHit &centre,
                     PixelMeasurement &out) const override;
  void measureFrame (const IdealRender &ideal, SynthRng &rng, SynthFrame &frame) const override;

  /** The depth step between neighbouring disparity levels at depth z, metres:
    * z^2 / (8 f_ir b) to first order. */
  double depthStep (double z) const;

  /** \brief The correlation window's effect on a depth image (NaN: none), row-major
    * w x h: each pixel's depth becomes that of the surface dominating its window. Sets
    * source[i] to the pixel whose surface pixel i now shows (-1: none). */
  std::vector<float> correlate (const std::vector<float> &z, int w, int h, std::vector<int> &source) const;
};
}  // namespace agex
