#include <agex/detection/impl/body_part_detector.hpp>

#include <pcl/impl/instantiate.hpp>

namespace agex
{
const char *
detectorModeName (DetectorMode mode)
{
  return mode == DetectorMode::Forest ? "forest" : "model";
}

bool
parseDetectorMode (const std::string &name, DetectorMode &mode)
{
  for (const DetectorMode m : {DetectorMode::Model, DetectorMode::Forest})
    if (name == detectorModeName (m))
    {
      mode = m;
      return true;
    }
  return false;
}
}  // namespace agex

#include <pcl/point_types.h>

PCL_INSTANTIATE (BodyPartDetector, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGB)(pcl::PointXYZRGBA))
