#include <agex/simulation/bonn_sensor.h>

#include <agex/simulation/renderer.h>

#include <cmath>
#include <limits>

namespace agex
{
int
BonnSensor::depthLevel (double z)
{
  if (!std::isfinite (z))
    return 0;
  const long level = std::lround (z / kBonnDepthStep);
  return level < 1 || level > 255 ? 0 : static_cast<int> (level);
}

void
BonnSensor::apply (SynthFrame &frame) const
{
  const float nan = std::numeric_limits<float>::quiet_NaN ();
  const CameraIntrinsics &k = kinect_.intrinsics;
  for (int v = 0; depth_levels_ && v < kinect_.height; ++v)
    for (int u = 0; u < kinect_.width; ++u)
    {
      pcl::PointXYZ &p = frame.cloud (u, v);
      if (!std::isfinite (p.z))
        continue;
      const int level = depthLevel (p.z);
      if (level == 0)
      {
        p.x = p.y = p.z = nan;
        continue;
      }
      const double z = static_cast<double> (level) * kBonnDepthStep;
      p.x = static_cast<float> ((u - k.cx) * z / k.fx);
      p.y = static_cast<float> ((v - k.cy) * z / k.fy);
      p.z = static_cast<float> (z);
    }
  const FrameView view = bonnPortraitView ();
  pcl::PointCloud<pcl::PointXYZ> portrait;
  applyView (frame.cloud, view, portrait);
  frame.cloud = std::move (portrait);
  auto resample = [&] (auto &values) {
    auto source = values;
    values.resize (static_cast<std::size_t> (bonn_.width) * bonn_.height);
    for (int v = 0; v < bonn_.height; ++v)
      for (int u = 0; u < bonn_.width; ++u)
      {
        const cv::Point s = view.sourcePixel (u, v);
        values[static_cast<std::size_t> (v) * bonn_.width + u] =
            source[static_cast<std::size_t> (s.y) * kinect_.width + s.x];
      }
  };
  resample (frame.object);
  resample (frame.primitive);
  resample (frame.ideal_z);
  resample (frame.sample_min_z);
  resample (frame.sample_max_z);
  resample (frame.clean_z);
  resample (frame.part_label);
  resample (frame.person_label);
  clearLabelsWithoutDepth (frame);  // the 8-bit depth steps drop some
}

void
toBonnView (const SensorModel &kinect, const SensorModel &bonn, SynthFrame &frame)
{
  BonnSensor (kinect, bonn).apply (frame);
}
}  // namespace agex
