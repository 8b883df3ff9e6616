#include <agex/features/impl/depth_patch_estimation.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE_PRODUCT (DepthPatchEstimation,
                         ((pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))((agex::DepthPatch)))
