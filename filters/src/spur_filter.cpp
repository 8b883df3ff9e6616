#include <agex/filters/impl/spur_filter.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE (SpurFilter, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))
