#include <agex/classification/body_part_labeling.h>
#include <agex/classification/impl/body_part_labeling.hpp>

#include <pcl/point_types.h>

template class agex::BodyPartLabeling<pcl::PointXYZ>;
template class agex::BodyPartLabeling<pcl::PointXYZI>;
template class agex::BodyPartLabeling<pcl::PointXYZRGBA>;
