#include <agex/classification/impl/sliding_window_detector.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE (SlidingWindowDetector, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))
