#pragma once
// The depth pipeline as the apps run it: library stages composed in the order
// frame -> crop box -> mixed-pixel removal -> median denoise -> floor removal ->
// spur removal -> surface meshes -> AGEX. Each stage is a PCL or agex class used as a PCL user
// would; this file only wires them together and times them.

#include <agex/common/frame_io.h>
#include <agex/common/point_types.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <boost/program_options/options_description.hpp>
#include <boost/program_options/variables_map.hpp>

#include <map>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** Every tunable of the pipeline, with the documented defaults (doc/pipeline.md). */
struct PipelineParams
{
  // Denoising (agex::DepthMedianFilter on depth); window 0 or 1 disables it.
  int median_window = 3;
  float median_max_movement = 0.05f;
  // Mixed pixels (agex::MixedPixelFilter).
  bool remove_mixed_pixels = true;
  int mixed_window_radius = 2;
  float mixed_min_jump = 0.05f;
  float mixed_max_veil_angle_deg = 15.f;
  // Bounding box in the camera frame, metres (pcl::CropBox).
  Eigen::Vector3f crop_min = Eigen::Vector3f (-0.75f, -1.5f, 1.3f);
  Eigen::Vector3f crop_max = Eigen::Vector3f (0.75f, 1.5f, 2.6f);
  // Floor (pcl::SACSegmentation, plane perpendicular to the camera's up axis).
  bool remove_floor = true;
  Eigen::Vector3f up = Eigen::Vector3f (0.f, -1.f, 0.f);
  float floor_max_tilt_deg = 25.f;
  float floor_distance = 0.04f;
  int floor_min_inliers = 200;
  // Spurs and ragged edges (agex::SpurFilter).
  int spur_min_connected = 6;
  int spur_iterations = -1;  ///< negative: auto, spur_depth over the median point spacing
  float spur_depth = 0.035f;
  // Surface meshes (agex::SurfaceSegmentation) and AGEX (agex::AGEXKeypoint).
  float delta_connected = 0.03f;
  int min_mesh_size = -1;  ///< points; negative: 0.1% of the frame's pixels
  int k = 5;
  float delta_orient = 0.10f;
  bool naive = false;
};

struct PipelineResult
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr filtered;  ///< organized, NaN where removed
  std::vector<pcl::PointIndices> meshes;
  pcl::PointCloud<agex::InterestPoint> interest_points;
  std::vector<std::pair<std::string, double>> ms;  ///< stage name -> milliseconds, in order
  bool floor_found = false;
  Eigen::Vector4f floor_plane = Eigen::Vector4f::Zero ();
  int mixed_pixels_removed = 0;
  int spur_iterations = 0;  ///< erosion passes actually run
};

/** Runs the pipeline on an organized cloud. Never throws on empty or all-NaN input. */
PipelineResult runDepthPipeline (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud,
                                 const PipelineParams &params);

/** Flags for the frame input (--fx --fy --cx --cy --depth-scale --width --height). */
boost::program_options::options_description frameOptionsDescription (FrameOptions &options);

/** Flags for the pipeline stages; values land in params after notify(). */
boost::program_options::options_description pipelineOptionsDescription (PipelineParams &params,
                                                                        std::vector<std::string> &storage);

/** Parses the "x,y,z" strings collected by pipelineOptionsDescription into params.
  * \throws std::runtime_error with the flag name on a malformed value */
void finishPipelineOptions (const std::vector<std::string> &storage, PipelineParams &params);
}  // namespace apps
}  // namespace agex
