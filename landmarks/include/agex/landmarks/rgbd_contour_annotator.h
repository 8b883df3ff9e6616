#pragma once
// Contour annotations of the people in an RGB-D frame: which surface meshes of the depth
// stages are people (by metric size, silhouette fill and position), and their 180-landmark
// outlines on the colour image, anchored by the AGEX extrema of each mesh; and such a frame
// read from a PCD file.

#include <agex/common/point_types.h>
#include <agex/landmarks/contour_annotation.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <string>
#include <vector>

namespace agex
{
/** \brief The colour image of an organized XYZRGBA PCD file (read with agex::readPcd) and its
  * XYZ cloud, on the same pixel grid. Clouds without colour (agex_synth frames made without
  * --colour) give shaded depth instead: near bright, no measurement black.
  * \throws std::runtime_error (FrameError) naming the file when it cannot be read or is not
  *         organized */
cv::Mat readRgbdFrame (const std::string &path, pcl::PointCloud<pcl::PointXYZ>::Ptr &xyz);

/** Which meshes are people. Lengths in metres (camera y is taken as roughly vertical). */
struct RgbdPersonSelectionParams
{
  float min_person_height = 1.0f;  ///< shorter meshes are not people
  float max_person_height = 2.3f;  ///< taller meshes are not people
  float max_person_width = 2.0f;   ///< wider meshes are not people (walls)
  float max_person_depth = 1.2f;   ///< deeper meshes are not people (floors, tables)
  /** Silhouettes filling more of their box are not people (wall strips, boxes). */
  double max_fill = 0.8;
  /** Keep the N people nearest the image centre (a camera looks at its subject; side walls
    * and furniture sit at the edges); 0: all. People too short to annotate do not count. */
  int max_people = 0;
  /** People whose outline is shorter than this (pixels) are listed as too small. */
  int min_height_px = 48;
  ContourAnnotationParams contour;
};

/** A person found in the frame. */
struct RgbdPerson
{
  int mesh = -1;                  ///< index into the meshes given
  ContourAnnotation annotation;   ///< ok for every person returned
  bool too_small = false;         ///< shorter than min_height_px: an ignore box, no landmarks
  float centre_distance_px = 0;   ///< of the outline's box centre from the image centre
};

/** Why a mesh is not a person, for reports. */
struct RgbdRejection
{
  int mesh = -1;
  std::string reason;
};

/** \brief Annotates the people of an organized frame from its depth meshes.
  *
  * Input: the organized cloud the meshes index (the depth pipeline's filtered frame, whose
  * pixel grid is the colour image's), the meshes and the interest points (AGEX extrema; those
  * of rank > 1 anchor the landmarks, as the head / hands / feet candidates of their mesh).
  * compute () lists the people most central first.
  */
class RgbdContourAnnotator
{
public:
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;

  void setInputCloud (const Cloud::ConstPtr &cloud) { cloud_ = cloud; }
  void setMeshes (const std::vector<pcl::PointIndices> &meshes) { meshes_ = meshes; }
  void setInterestPoints (const pcl::PointCloud<InterestPoint> &points) { points_ = points; }
  void setParams (const RgbdPersonSelectionParams &params) { params_ = params; }
  const RgbdPersonSelectionParams &getParams () const { return params_; }

  /** People, most central first. An unorganized or missing cloud gives none (PCL_ERROR). */
  void compute (std::vector<RgbdPerson> &people);
  /** The meshes the last compute () did not take, and why. */
  const std::vector<RgbdRejection> &rejections () const { return rejections_; }

private:
  /** Metric size check; empty when the mesh could be a person, else the reason. */
  std::string sizeProblem (const pcl::PointIndices &mesh) const;
  cv::Mat meshMask (const pcl::PointIndices &mesh) const;
  ContourAnchors meshAnchors (int mesh) const;
  static double silhouetteFill (const cv::Mat &mask, const cv::Rect &box);

  Cloud::ConstPtr cloud_;
  std::vector<pcl::PointIndices> meshes_;
  pcl::PointCloud<InterestPoint> points_;
  RgbdPersonSelectionParams params_;
  std::vector<RgbdRejection> rejections_;
};
}  // namespace agex
