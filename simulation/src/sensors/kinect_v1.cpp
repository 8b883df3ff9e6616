#include <agex/simulation/kinect_v1_sensor.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace agex
{
namespace
{
const float kNaN = std::numeric_limits<float>::quiet_NaN ();

/** Kinect projector shadows: the depth (z) of every measured pixel that the projector
  * (kinect_baseline to the camera's right, +x) lights, NaN for the others. */
std::vector<float>
projectorLitDepth (const IdealRender &ideal, const SensorModel &sensor)
{
  const int w = sensor.width, h = sensor.height;
  const Eigen::Vector3d projector (sensor.kinect_baseline, 0.0, 0.0);
  // The segment from the projector (at +x) to a point seen at pixel u runs along the
  // pixel's row to the right, so an occluder at depth z_o shadows pixels up to
  // f b / z_o to its left: widen the occluders' bins to the left by that.
  const RayCaster shadow_bins (ideal.scene, sensor, 0.0, sensor.intrinsics.fx * sensor.kinect_baseline);
  std::vector<float> z (ideal.range.size (), kNaN);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      if (!std::isfinite (ideal.range[i]))
        continue;
      const Eigen::Vector3d d = ideal.rays (u, v);
      const Eigen::Vector3d p = d * ideal.range[i];
      if (!shadow_bins.anyAt (u, v))
      {
        z[i] = static_cast<float> (p.z ());
        continue;
      }
      Eigen::Vector3d to = p - projector;
      const double length = to.norm ();
      to /= length;
      if (shadow_bins.occluded (u, v, projector, to, length - 0.005))
        continue;
      z[i] = static_cast<float> (p.z ());
    }
  return z;
}

/** Two depths of one surface: within 4 cm + 3% of the depth (as depthEdges). */
bool
sameSurface (float a, float b)
{
  return std::abs (a - b) <= 0.04f + 0.03f * std::min (a, b);
}

/** Depth edges on the noise-free depth: a 4-neighbour more than 4 cm + 3% of the depth
  * away, or nothing (which counts as far). */
std::vector<std::uint8_t>
depthEdges (const std::vector<float> &ideal_z, int w, int h)
{
  std::vector<std::uint8_t> edge (ideal_z.size (), 0);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      const float zi = ideal_z[i];
      if (!std::isfinite (zi))
        continue;
      const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
      for (int q = 0; q < 4; ++q)
      {
        const int uu = u + du[q], vv = v + dv[q];
        if (uu < 0 || vv < 0 || uu >= w || vv >= h)
          continue;
        const float zj = ideal_z[static_cast<std::size_t> (vv) * w + uu];
        if (!std::isfinite (zj) || std::abs (zj - zi) > 0.04 + 0.03 * zi)
        {
          edge[i] = 1;
          break;
        }
      }
    }
  return edge;
}

/** True if a pixel of the 3x3 window around (u, v) is a depth edge. */
bool
besideAnEdge (const std::vector<std::uint8_t> &edge, int u, int v, int w, int h)
{
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
    {
      const int uu = u + du, vv = v + dv;
      if (uu >= 0 && vv >= 0 && uu < w && vv < h && edge[static_cast<std::size_t> (vv) * w + uu])
        return true;
    }
  return false;
}
}  // namespace

bool
KinectV1Sensor::measurePixel (const PixelSamples &samples, const PixelIntegral &, const RayHit &centre,
                              PixelMeasurement &out) const
{
  // The centre ray's range, if the surface is not too oblique and its depth in range.
  const SensorModel &m = model ();
  if (centre.t < 0 || centre.cos < m.kinect_min_cos)
    return false;
  const double z = centre.t * samples.dirs[0].z ();
  if (z < m.min_range || z > m.max_range)
    return false;
  out.range = static_cast<float> (centre.t);
  out.surface = &centre;
  return true;
}

double
KinectV1Sensor::depthStep (double z) const
{
  const SensorModel &m = model ();
  return z * z / (8.0 * m.kinect_f_ir * m.kinect_baseline);
}

std::vector<float>
KinectV1Sensor::correlate (const std::vector<float> &z, int w, int h, std::vector<int> &source) const
{
  const SensorModel &m = model ();
  const int r = m.kinect_window / 2;
  source.assign (z.size (), -1);
  std::vector<float> out (z.size (), kNaN);
  for (std::size_t i = 0; i < z.size (); ++i)
    if (std::isfinite (z[i]))
      source[i] = static_cast<int> (i);
  if (r < 1)
    return z;
  const double fg = m.kinect_foreground_weight;
  std::vector<int> others;
  others.reserve (static_cast<std::size_t> (m.kinect_window) * m.kinect_window);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      const float zi = z[i];
      const bool valid = std::isfinite (zi);
      // Shares of the window: the pixel's own surface, and every other pixel (nearer
      // ones weigh kinect_foreground_weight, a pixel without a return 1).
      double own = 0.0, total = 0.0;
      others.clear ();
      for (int vv = std::max (0, v - r); vv <= std::min (h - 1, v + r); ++vv)
        for (int uu = std::max (0, u - r); uu <= std::min (w - 1, u + r); ++uu)
        {
          const std::size_t j = static_cast<std::size_t> (vv) * w + uu;
          const float zj = z[j];
          if (!std::isfinite (zj))
          {
            total += 1.0;
            continue;
          }
          if (valid && sameSurface (zi, zj))
          {
            own += 1.0;
            total += 1.0;
            continue;
          }
          const double weight = (!valid || zj < zi) ? fg : 1.0;
          total += weight;
          others.push_back (static_cast<int> (j));
        }
      if (valid && own >= m.kinect_min_support * total)
      {
        out[i] = zi;
        continue;
      }
      source[i] = -1;
      if (others.empty ())
        continue;
      // The dominant other surface: the one around the median depth of the others.
      std::nth_element (others.begin (), others.begin () + others.size () / 2, others.end (),
                        [&] (int a, int b) { return z[a] < z[b]; });
      const int median = others[others.size () / 2];
      double share = 0.0;
      int nearest_to_centre = -1, best_d2 = 1 << 30;
      for (const int j : others)
        if (sameSurface (z[j], z[median]))
        {
          share += (!valid || z[j] < zi) ? fg : 1.0;
          const int du = j % w - u, dv = j / w - v, d2 = du * du + dv * dv;
          if (d2 < best_d2)
          {
            best_d2 = d2;
            nearest_to_centre = j;
          }
        }
      // It takes over if it dominates the window; else no surface does: no match.
      if (share >= m.kinect_min_support * total && share > own)
      {
        out[i] = z[nearest_to_centre];
        source[i] = nearest_to_centre;
      }
    }
  return out;
}

void
KinectV1Sensor::measureFrame (const IdealRender &ideal, SynthRng &rng, SynthFrame &frame) const
{
  const SensorModel &m = model ();
  const CameraIntrinsics &k = m.intrinsics;
  const int w = m.width, h = m.height;
  std::vector<float> z = projectorLitDepth (ideal, m);
  if (m.kinect_window > 1)
  {
    // The pixels that now show another surface take its labels and clean depth.
    std::vector<int> source;
    z = correlate (z, w, h, source);
    const std::vector<std::uint8_t> part = frame.part_label, person = frame.person_label;
    for (std::size_t i = 0; i < z.size (); ++i)
    {
      if (!std::isfinite (z[i]) || source[i] == static_cast<int> (i))
        continue;
      const std::size_t s = static_cast<std::size_t> (source[i]);
      frame.part_label[i] = part[s];
      frame.person_label[i] = person[s];
      frame.clean_z[i] = z[i];
    }
  }
  // Holes at depth edges, then disparity noise and quantisation in 1/8 pixel.
  const std::vector<std::uint8_t> edge = depthEdges (frame.ideal_z, w, h);
  const double fb8 = 8.0 * m.kinect_f_ir * m.kinect_baseline;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * w + u;
      if (!std::isfinite (z[i]))
        continue;
      const bool near_edge = !edge[i] && besideAnEdge (edge, u, v, w, h);
      if ((edge[i] && rng.uniform () < m.kinect_edge_drop) || (near_edge && rng.uniform () < m.kinect_edge_drop_near))
        continue;
      const double q = std::round (fb8 / z[i] + m.kinect_sigma_q * rng.normal ());
      if (q < 1.0)
        continue;
      const double zq = fb8 / q;
      if (zq < m.min_range || zq > m.max_range)
        continue;
      frame.cloud.points[i] = pointOnPixelRay (k, u, v, zq);
    }
}
}  // namespace agex
