#include <agex/simulation/time_of_flight_sensor.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace agex
{
int
TimeOfFlightSensor::samplesPerSide () const
{
  return std::max (1, model ().supersample);
}

bool
TimeOfFlightSensor::measurePixel (const PixelSamples &samples, const PixelIntegral &sum, const RayHit &,
                                  PixelMeasurement &out) const
{
  // The pixel integrates the returns of all its samples, each weighted by its amplitude
  // (reflectivity * cos / range^2): mixed pixels.
  const SensorModel &m = model ();
  const double a = sum.amp_sum / static_cast<double> (samples.hits.size ());
  if (sum.amp_sum <= 0 || a < m.tof_min_amplitude)
    return false;
  const double r = sum.amp_range / sum.amp_sum;
  if (r < m.min_range || r > m.max_range)
    return false;
  out.range = static_cast<float> (r);
  out.amplitude = static_cast<float> (a);
  // The surface a blended range shows: the sample whose range is nearest to it, if
  // within 1 cm + 1% of the range; none for a flying pixel between surfaces.
  const RayHit *best = nullptr;
  double best_gap = std::numeric_limits<double>::infinity ();
  for (std::size_t s = 0; s < samples.count; ++s)
  {
    const RayHit &hit = samples.hits[s];
    if (hit.t < 0)
      continue;
    const double gap = std::abs (hit.t - out.range);
    if (gap < best_gap)
    {
      best_gap = gap;
      best = &hit;
    }
  }
  out.surface = best_gap <= 0.01 + 0.01 * out.range ? best : nullptr;
  return true;
}

double
TimeOfFlightSensor::rangeSigma (double amplitude) const
{
  const SensorModel &m = model ();
  return std::min (m.tof_sigma0 + m.tof_sigma_k / amplitude, m.tof_sigma_max);
}

void
TimeOfFlightSensor::measureFrame (const IdealRender &ideal, SynthRng &rng, SynthFrame &frame) const
{
  // Range noise along the ray, growing as the amplitude falls.
  const SensorModel &m = model ();
  const CameraIntrinsics &k = m.intrinsics;
  for (int v = 0; v < m.height; ++v)
    for (int u = 0; u < m.width; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * m.width + u;
      if (!std::isfinite (ideal.range[i]))
        continue;
      const double noise = rng.normal ();
      const double r = ideal.range[i] + rangeSigma (ideal.amplitude[i]) * noise;
      const Eigen::Vector3d d = Eigen::Vector3d ((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized ();
      const double z = r * d.z ();
      // Noise never carries a depth outside the range the sensor reports.
      if (!(z > 0.0) || r < m.min_range || r > m.max_range)
        continue;
      frame.cloud.points[i] = pointOnPixelRay (k, u, v, z);
    }
}
}  // namespace agex
