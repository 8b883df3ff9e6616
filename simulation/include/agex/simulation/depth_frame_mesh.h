#pragma once
// A real depth frame as a surface the renderer can ray cast (FrameReprojection,
// frame_reprojection.h): each 2x2 block of neighbouring pixels becomes two triangles, and two
// pixels are joined only where their depths are close enough to be one surface, so that
// silhouettes stay open and a person's own surface stays closed.

#include <agex/simulation/scene_primitives.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <opencv2/core/mat.hpp>

#include <cstddef>

namespace agex
{
/** When two neighbouring pixels of a depth frame are one surface. */
struct DepthMeshSettings
{
  /** The source sensor's depth step at depth z is max (depth_quantum, depth_step_growth z^2):
    * a fixed step of its depth encoding (the Bonn frames' 8-bit levels: 0.016 m), metres,
    * 0-0.5 ... */
  double depth_quantum = 0.0;
  /** ... and the structured-light step that grows with depth, metres per squared metre
    * (a Kinect v1's: 0.0029; 0 for exact depth), 0-0.02. */
  double depth_step_growth = 0.0029;
  /** Depth steps two neighbours of one surface may differ by (the sensor's noise and
    * rounding), 0.5-50. */
  double gap_steps = 3.0;
  /** Plus this many times the pixels' lateral spacing at their depth: the tangent of the
    * most oblique surface still joined (4: 76 degrees from facing the camera), 0-50. */
  double gap_slope = 4.0;

  /** \throws std::invalid_argument naming the first setting out of range */
  void validate () const;
  /** The source sensor's depth step at depth z, metres. */
  double depthStep (double z) const;
  /** The largest depth difference of two neighbours of one surface whose nearer depth is z
    * and whose rays are `lateral` metres apart at that depth. */
  double maxGap (double z, double lateral) const;
};

/** What depthFrameScene built. */
struct DepthFrameMeshStats
{
  std::size_t vertices = 0;   ///< valid pixels (finite, in front of the camera)
  std::size_t triangles = 0;
};

/** \brief The frame's surface as a scene in its camera frame: a triangle mesh through the
  * points of its valid pixels (finite, z > 0). In each 2x2 block the diagonal with more
  * triangles whose three sides are all joined (DepthMeshSettings) is taken (ties: the one of
  * the smaller depth difference), and only such triangles are made; isolated pixels and
  * one-pixel lines make none. The lateral spacing of two pixels is measured on the points'
  * own rays (x/z, y/z), so no intrinsics are needed.
  *
  * persons and parts (optional, CV_8UC1 of the cloud's size, empty for none) say what each
  * pixel shows; a triangle takes the value most of its corners have (no majority: the
  * nearest corner's). The triangles of person k become one mesh primitive of object Person
  * with person k, those of no person one of object Wall; with parts but no persons the body
  * is person 1. Parts ride along as the triangles' SynthPart (a 1-255 id as it is).
  * An empty, one-row or all-invalid frame gives an empty scene.
  * \throws std::invalid_argument for bad settings or an image of another size or type */
SynthScene depthFrameScene (const pcl::PointCloud<pcl::PointXYZ> &cloud, const DepthMeshSettings &settings,
                            const cv::Mat &persons = cv::Mat (), const cv::Mat &parts = cv::Mat (),
                            DepthFrameMeshStats *stats = nullptr);
}  // namespace agex
