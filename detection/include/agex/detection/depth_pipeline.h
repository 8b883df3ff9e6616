#pragma once

#include <agex/common/point_types.h>
#include <agex/filters/depth_median_filter.h>
#include <agex/filters/mixed_pixel_filter.h>
#include <agex/filters/person_segmentation.h>
#include <agex/filters/spur_filter.h>
#include <agex/filters/surface_segmentation.h>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/PointIndices.h>
#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <nlohmann/json_fwd.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
/** \brief Every setting of the depth pipeline, with the documented defaults
  * (doc/pipeline.md). The same ranges hold for flags and model files: validate ()
  * checks them all. */
struct DepthPipelineParams
{
  // Every size the stages measure in pixels follows the focal length, and where it is a
  // length on the person, the depth too (doc/pipeline.md, "Metric settings"), so that frames
  // of one scene at any resolution give the same meshes. The pixel settings stay for models
  // written before (a model file without the metric keys runs as it was trained).

  // Denoising (agex::DepthMedianFilter on depth): a window of median_window pixels (0 or 1:
  // off), or with -1 the odd window nearest to median_extent metres at the depth of the
  // kept points (their median depth, one window per frame; 1: off).
  int median_window = -1;
  float median_extent = 0.025f;
  float median_max_movement = 0.05f;
  // Mixed pixels (agex::MixedPixelFilter): neighbours mixed_window_radius pixels away, or with
  // -1 round (mixed_window_angle * focal length) pixels (at least 1): a sensor's veil spans
  // an angle of its view (radians, metres per metre of depth), whatever the resolution.
  bool remove_mixed_pixels = true;
  int mixed_window_radius = -1;
  float mixed_window_angle = 0.004f;
  float mixed_min_jump = 0.05f;
  float mixed_max_veil_angle_deg = 15.f;
  // People (agex::PersonSegmentation): the person pixels are what the later stages see, and
  // its floor is the floor. Off: the crop box alone isolates the person (models of agex 0.1).
  bool isolate_people = true;
  // With isolate_people: persons seen only in pieces behind a nearer person are persons too
  // (agex::PersonSegmentation::setHiddenPersons). Models trained before this setting: off.
  bool hidden_people = true;
  // Bounding box in the camera frame, metres (pcl::CropBox); off by default (it fits one room).
  bool use_crop_box = false;
  Eigen::Vector3f crop_min = Eigen::Vector3f (-0.75f, -1.5f, 1.3f);
  Eigen::Vector3f crop_max = Eigen::Vector3f (0.75f, 1.5f, 2.6f);
  // Floor (agex::FloorRemoval).
  bool remove_floor = true;
  Eigen::Vector3f up = Eigen::Vector3f (0.f, -1.f, 0.f);
  float floor_max_tilt_deg = 45.f;
  float floor_distance = 0.04f;
  int floor_min_inliers = 200;
  // Spurs and ragged edges (agex::SpurFilter).
  int spur_min_connected = 6;
  /** Erosion passes; 0: no spur filter; -1: spur_depth metres, in passes at each point's
    * depth (with spur_min_width 0: spur_depth over the frame's median point spacing). */
  int spur_iterations = -1;
  float spur_depth = 0.035f;
  /** Strands narrower than this go entirely; parts at least this wide keep at least this
    * width (agex::SpurFilter::setMinWidth), metres at each point's depth. 0: the plain
    * erosion of models written before it, which takes every part narrower than twice the
    * spur depth. */
  float spur_min_width = 0.03f;
  // Surface meshes (agex::SurfaceSegmentation) and AGEX (agex::AGEXKeypoint).
  float delta_connected = 0.03f;
  /** The sensor's depth resolution: one surface's neighbouring depths may differ by steps of
    * depth_step_growth z^2 metres (a structured-light Kinect's: about 0.0029 z^2; 0: exact
    * depth). Neighbours up to 1.5 steps apart stay connected (agex::connectedNeighbours, where
    * that is more than delta_connected) and jumps under 2.5 steps are no silhouette for the
    * mixed-pixel filter (where that is more than mixed_min_jump), so that a person at 3-6 m
    * is not cut into single depth steps and eroded away. Up to 2.6 m the fixed thresholds are
    * the larger. Models trained before this setting: 0. */
  float depth_step_growth = 0.0029f;
  int min_mesh_size = 0;  ///< points; -1: 0.1% of the frame's pixels
  /** Smallest mesh, square metres as the camera sees it (each point counts (z / f)^2, the
    * area its pixel covers at its depth); 0: none (models written before it). */
  float min_mesh_area = 0.003f;
  /** Working density: after person isolation every stage runs on every s-th pixel of the
    * frame in each direction, s = round (working_spacing f / z) at the farthest person's
    * median depth z (1 to kMaxWorkingStride), so that each sample covers about
    * working_spacing metres on the person whatever the sensor's resolution: a person near a
    * 640x480 camera costs what one in a 320x240 frame does. 0: the sensor's density. */
  float working_spacing = 0.f;
  static constexpr int kMaxWorkingStride = 8;
  int k = 5;               ///< AGEX points per mesh, centroid included
  /** AGEX stops adding points to a mesh once the next is closer than this to those found
    * (geodesic metres; AGEXKeypoint::setMinSeparation): up to k, fewer on small meshes.
    * 0: k on every mesh (models written before it). */
  float min_separation = 0.f;
  float delta_orient = 0.10f;
  bool naive = false;  ///< reference AGEX: a full Dijkstra per point (not stored in models)

  /** \brief Checks every setting against its documented range.
    * \param name  how a setting is named in the message, given its key (e.g.
    *              "--mixed-window" for a flag, "model.yml: pipeline.mixed_window_radius")
    * \throws std::invalid_argument naming the first setting out of range and the range */
  void validate (const std::function<std::string (const std::string &key)> &name) const;
  /** validate () naming each setting by its key. */
  void validate () const;

  /** base with the cleaning settings of models written before the metric ones (what the
    * bundled Bonn models run): 3x3 median, mixed-pixel radius 2 pixels, the plain spur
    * erosion, 0.1% of the frame's pixels as the smallest mesh (doc/pipeline.md). */
  static DepthPipelineParams pixelSettings (DepthPipelineParams base);

  /** The settings as stored in a model file ("pipeline" object; naive is not stored). */
  nlohmann::json toJson () const;
  /** \brief Reads what toJson () wrote and validates it.
    * \throws std::invalid_argument naming source and the key on a missing, mistyped or
    *         out-of-range setting */
  static DepthPipelineParams fromJson (const nlohmann::json &doc, const std::string &source);
};

/** What a pipeline run produced: everything a user may want to draw or reuse. */
struct DepthPipelineResult
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr filtered;  ///< organized, NaN where removed
  std::vector<pcl::PointIndices> meshes;         ///< connected surface meshes of filtered
  pcl::PointCloud<agex::InterestPoint> interest_points;
  bool floor_found = false;
  Eigen::Vector4f floor_plane = Eigen::Vector4f::Zero ();  ///< n.p + d = height above the floor
  /** With isolate_people: one index set per person (pixels of the frame, before cleaning),
    * its facts (agex::PersonInfo: distance, height, too_far, ...), and per mesh its person
    * (-1: none). Without: empty, and every mesh's person is -1. */
  std::vector<pcl::PointIndices> persons;
  std::vector<PersonInfo> person_info;
  std::vector<int> mesh_person;
  int mixed_pixels_removed = 0;
  int spur_iterations = 0;  ///< erosion passes actually run
  /** What the metric settings came to on this frame: the focal length used (pixels; 0 when
    * no setting needed one), the median window (pixels, 0: off) and the mixed-pixel radius
    * (pixels, 0: off). */
  float focal_length = 0.f;
  int median_window = 0;
  int mixed_window_radius = 0;
  /** Stage name -> milliseconds, in order (people, crop, working_density, mixed_pixels,
    * denoise, floor, spurs, segmentation, agex, then total). */
  std::vector<std::pair<std::string, double>> ms;
  /** The working density (DepthPipelineParams::working_spacing): every index above (persons,
    * meshes, filtered, interest points' u and v) is a pixel of the working frame, which
    * samples the input's pixel (stride u + offset, stride v + offset); frame is the working
    * frame before cleaning (null with stride 1: the input is not kept alive), input_width and input_height
    * the input's size, and focal_length is the working frame's. */
  int stride = 1;
  int offset = 0;
  std::uint32_t input_width = 0, input_height = 0;
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr frame;

  /** The pixels of all meshes, in mesh order. */
  std::vector<int> meshIndices () const;
  /** The input's pixel (column, row) a pixel of the working frame samples. */
  Eigen::Vector2i inputPixel (int working_index) const;
  /** The working pixel whose stride x stride block holds the input's pixel (u, v) (the block
    * meshesInInput gives it); -1 outside the working frame. */
  int workingIndex (int u, int v) const;
  /** The meshes as pixels of the input: each working pixel stands for the stride x stride
    * block of input pixels around the one it samples (for overlays at the input's size). */
  std::vector<pcl::PointIndices> meshesInInput () const;
};

/** \brief The depth stages composed as the detector runs them: frame -> people
  * (agex::PersonSegmentation; and/or a crop box) -> mixed-pixel removal -> median denoise ->
  * floor removal (the people's floor, or agex::FloorRemoval without them) -> spur removal ->
  * surface meshes -> AGEX. Each stage is a PCL or agex class used as a PCL user would; this
  * class wires them together and times them. Meshes belong to people (mesh_person); a
  * person too far for its hands to have pixels enough is still segmented and flagged.
  *
  * setIndices limits the frame to those pixels (the rest is treated as invalid). Any
  * organized input of an XYZ point type is taken; the stages run on its XYZ copy. Empty,
  * unorganized or all-NaN frames give an empty result, never an exception.
  */
template <typename PointT>
class DepthPipeline : public pcl::PCLBase<PointT>
{
public:
  using Ptr = pcl::shared_ptr<DepthPipeline<PointT>>;
  using ConstPtr = pcl::shared_ptr<const DepthPipeline<PointT>>;

  DepthPipeline () = default;
  explicit DepthPipeline (const DepthPipelineParams &params) : params_ (params) {}

  /** \throws std::invalid_argument on a setting out of range (DepthPipelineParams::validate) */
  void setParams (const DepthPipelineParams &params)
  {
    params.validate ();
    params_ = params;
  }
  const DepthPipelineParams &getParams () const { return params_; }

  /** The camera's focal lengths in pixels, for the metric settings (and the person
    * isolation); 0 (default): estimated from each frame (agex::estimateFocalLengths, or the
    * person isolation's estimate). \throws std::invalid_argument when not 0 and outside
    * agex::kMinFocalLength to agex::kMaxFocalLength */
  void setFocalLength (float fx, float fy);
  float getFocalLengthX () const { return fx_; }
  float getFocalLengthY () const { return fy_; }

  /** Runs every stage on the input cloud; result is replaced. result.filtered is this
    * pipeline's buffer: the next compute () refills it in place when no result holds it any
    * longer (result itself lets go of it first), else it makes a new one. */
  void compute (DepthPipelineResult &result);

protected:
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::use_indices_;

private:
  /** The input as XYZ: the input itself when it is a whole XYZ frame, else a copy with the
    * pixels outside setIndices invalid. */
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr xyzFrame () const;

  /** filtered_ = frame's points_, NaN everywhere else. */
  void startFilteredFrame (const pcl::PointCloud<pcl::PointXYZ> &frame);

  /** The focal length (mean of fx and fy) the metric settings use on frame: the one given,
    * the person isolation's when it ran, else estimated from frame (a 640-pixel-wide Kinect's
    * 525, scaled to the width, when the frame has too few points to tell). */
  float focalLength (const pcl::PointCloud<pcl::PointXYZ> &frame, bool isolated) const;

  DepthPipelineParams params_;
  float fx_ = 0.f, fy_ = 0.f;
  // The stages, and what they keep between frames: a pipeline run on frame after frame
  // does not allocate (and page in) frame-sized buffers anew for each.
  agex::PersonSegmentation<pcl::PointXYZ> people_;
  agex::MixedPixelFilter<pcl::PointXYZ> mixed_;
  agex::DepthMedianFilter<pcl::PointXYZ> median_;
  agex::SpurFilter<pcl::PointXYZ> spurs_;
  agex::SurfaceSegmentation<pcl::PointXYZ> segmentation_;
  agex::AGEXKeypoint<pcl::PointXYZ, agex::InterestPoint> agex_;
  pcl::PointCloud<pcl::Label> person_labels_;
  pcl::PointCloud<pcl::PointXYZ>::Ptr working_frame_;  ///< the sampled frame, reused once no result holds it
  pcl::PointCloud<pcl::Label> working_labels_;         ///< person_labels_ at the working pixels
  pcl::IndicesPtr points_ {new pcl::Indices};  ///< the points kept so far, in increasing order
  pcl::PointCloud<pcl::PointXYZ>::Ptr filtered_;  ///< the result's frame, reused once no result holds it
  pcl::Indices filtered_points_;                   ///< the points of filtered_ that may be finite
};

/** The pipeline run once on cloud with params (DepthPipeline<pcl::PointXYZ> in one call).
  * \throws std::invalid_argument on a setting out of range */
DepthPipelineResult runDepthPipeline (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud,
                                      const DepthPipelineParams &params);
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/detection/impl/depth_pipeline.hpp>
#endif
