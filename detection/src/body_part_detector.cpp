#include <agex/detection/impl/body_part_detector.hpp>

#include <pcl/impl/instantiate.hpp>

namespace agex
{
const char *
detectorModeName (DetectorMode mode)
{
  return mode == DetectorMode::Forest ? "forest" : "agex";
}

bool
parseDetectorMode (const std::string &name, DetectorMode &mode)
{
  for (const DetectorMode m : {DetectorMode::Agex, DetectorMode::Forest})
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
