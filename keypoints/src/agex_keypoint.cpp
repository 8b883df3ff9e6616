#include <agex/keypoints/impl/agex_keypoint.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

PCL_INSTANTIATE_PRODUCT (AGEXKeypoint,
                         ((pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))((agex::InterestPoint)(pcl::PointXYZ)))
