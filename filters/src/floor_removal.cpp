#include <agex/filters/impl/floor_removal.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE (FloorRemoval, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))
