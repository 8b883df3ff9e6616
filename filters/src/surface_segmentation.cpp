#include <agex/filters/impl/surface_segmentation.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE (SurfaceSegmentation, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))
