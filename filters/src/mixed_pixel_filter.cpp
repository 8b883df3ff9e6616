#include <agex/filters/impl/mixed_pixel_filter.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE (MixedPixelFilter, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))
