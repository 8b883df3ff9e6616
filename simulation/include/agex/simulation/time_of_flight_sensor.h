#pragma once
// Time-of-flight sensors: the SR4000 and a Kinect v2-like one (doc/synthetic.md, "Sensor
// models"; fitted in doc/sensors.md).

#include <agex/simulation/depth_sensor.h>

namespace agex
{
/** A time-of-flight sensor: each pixel integrates the returns of its supersample x
  * supersample samples weighted by their amplitude (reflectivity * cos / range^2), so
  * pixels on a silhouette measure a range between foreground and background (flying
  * pixels); range noise sigma = tof_sigma0 + tof_sigma_k / amplitude (capped at
  * tof_sigma_max), growing about as range^2; no measurement below tof_min_amplitude or
  * outside [min_range, max_range]. */
class TimeOfFlightSensor : public DepthSensor
{
public:
  using DepthSensor::DepthSensor;

  int samplesPerSide () const override;
  bool needsAmplitude () const override { return true; }
  bool measurePixel (const PixelSamples &samples, const PixelIntegral &sum, const RayHit &centre,
                     PixelMeasurement &out) const override;
  void measureFrame (const IdealRender &ideal, SynthRng &rng, SynthFrame &frame) const override;

  /** Range noise (metres, one sigma) at a returned amplitude. */
  double rangeSigma (double amplitude) const;
};
}  // namespace agex
