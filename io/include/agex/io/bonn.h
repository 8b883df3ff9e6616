#pragma once
// Reading the Bonn body-part data (../shared/data/bonn): depth PNGs per sequence
// and labels.csv with head, hand and foot tips and bases in 640x480 pixels.

#include <agex/io/dataset.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace agex
{
/** One row of the Bonn labels.csv (sequence,frame,keyframe,part,instance,tip_u,tip_v,base_u,base_v). */
struct BonnLabel
{
  std::string sequence;
  std::string frame;  ///< as in the file name, e.g. "002"
  bool keyframe = false;
  BodyPart part = BodyPart::Head;
  int instance = 0;
  Eigen::Vector2f tip_px = Eigen::Vector2f::Zero ();
  Eigen::Vector2f base_px = Eigen::Vector2f::Zero ();
};

/** \brief Reads and validates the Bonn labels.csv. \throws DatasetError naming path:line */
std::vector<BonnLabel> readBonnLabels (const std::string &path);

/** \brief The 3D surface point standing for a labelled pixel.
  *
  * Tips are often labelled on a silhouette's edge, where the pixel itself may be
  * background or have no depth. Among the finite points within radius pixels of
  * (u, v) we keep the foreground: those at most depth_band metres behind the
  * nearest of them; the one closest to (u, v) in the image wins (ties: the lower
  * index). Returns false when the window holds no finite point.
  * \param[out] pixel the chosen pixel (u, v), if not null */
bool liftPixelToSurface (const pcl::PointCloud<pcl::PointXYZ> &cloud, float u, float v, int radius,
                         float depth_band, Eigen::Vector3f &point, Eigen::Vector2i *pixel = nullptr);
}  // namespace agex
