#include <agex/filters/impl/depth_median_filter.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE (DepthMedianFilter, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))
