#pragma once
// The fused detector's candidates and what it knows about each (doc/classifier.md, "Fused
// detector"): AGEX points (geodesic extrema with their orientation) and the body-part
// forest's part modes (parts that are no extrema: a hand resting on the hip), merged when
// closer than a radius, each with auxiliary features for the classifier: the forest's part
// probabilities at and around it, the modes near it, its AGEX facts and where on its person it
// lies.

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_label_point.h>
#include <agex/classification/part_modes.h>
#include <agex/common/point_types.h>
#include <agex/detection/depth_pipeline.h>

#include <pcl/point_cloud.h>

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace agex
{
/** \brief Labels the pixels of the pipeline's meshes (the person) with a forest
  * (agex::BodyPartLabeling, focal lengths fx, fy, the given pixel stride) and finds the part
  * modes (agex::PartModeEstimation, over the stride's representative pixels): what the forest
  * mode and the fused detector start from. stride 0: forestStrideFor (0, fx).
  * With ms, the milliseconds of the two steps are stored there (labelling, modes).
  * \return false (labels and modes empty) without meshes, a forest or a focal length */
bool labelPersonParts (const DepthPipelineResult &prepared, const BodyPartForest::ConstPtr &forest, float fx, float fy,
                       int stride, pcl::PointCloud<BodyPartLabelPoint> &labels, std::vector<PartMode> &modes,
                       std::pair<double, double> *ms = nullptr);

/** \brief Labels the given pixels of a cloud with a forest (agex::BodyPartLabeling at focal
  * lengths fx, fy and the pixel stride forestStrideFor (stride, fx), which is stored back in
  * stride). \return false if the labelling failed */
bool labelBodyPixels (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud, const std::shared_ptr<pcl::Indices> &body,
                      const BodyPartForest::ConstPtr &forest, float fx, float fy, int &stride,
                      pcl::PointCloud<BodyPartLabelPoint> &labels);

/** \brief The forest's pixel stride for a camera of focal length fx (pixels): stride itself
  * when positive; 0 (auto) gives one evaluated pixel per cell of about 4 mm at 1 m
  * (floor (fx / 250), at least 1, at most 8): 1 at 144x176 (fx 210), 2 at 640x480 (525), 4 at
  * 1280x960, so that the forest's and the part modes' work per person stays about the same
  * whatever the resolution. */
int forestStrideFor (int stride, float fx);

/** Where a candidate came from (bits). */
enum FusedCandidateSource : unsigned
{
  kFromAgex = 1u,          ///< an AGEX point
  kFromModeTip = 2u,       ///< a part mode's tip
  kFromModePosition = 4u,  ///< a part mode's position (its density's peak)
  kFromModeEnd = 8u,       ///< the other end of a part mode from its tip, along its direction
};

struct FusedCandidate
{
  Eigen::Vector3f position = Eigen::Vector3f::Zero ();
  /** Along the limb towards the tip (AGEX's, else the mode's direction); zero if unknown. */
  Eigen::Vector3f orientation = Eigen::Vector3f::Zero ();
  int index = -1;  ///< pixel index in the frame
  unsigned sources = 0;
  int agex_rank = 0;            ///< the AGEX point's rank (0: none)
  float geodesic_distance = 0.f;
  int mesh = -1;
  int mode_part = -1;           ///< the part of the mode it came from (-1: none)
  float mode_confidence = 0.f;
};

struct FusedCandidateParams
{
  /** Candidates closer than this (metres) are one; the AGEX point is kept, with both sources. */
  float merge_radius = 0.03f;
  /** Part modes below this confidence give no candidate. */
  float min_mode_confidence = 0.05f;
  /** \throws std::invalid_argument naming the key (name (key)) out of range */
  void validate (const std::function<std::string (const std::string &key)> &name) const;
};

/** \brief The candidates of a frame: every AGEX point of the pipeline's result, then the tip,
  * the position and the other end (the supporting pixel least far along its direction) of
  * every part mode (of head, hand or foot), each dropped when an earlier candidate lies within
  * merge_radius (whose sources then include it). */
std::vector<FusedCandidate> fusedCandidates (const DepthPipelineResult &prepared, const std::vector<PartMode> &modes,
                                             const FusedCandidateParams &params);

/** The names of the auxiliary features fusedFeatures () computes, in order. */
const std::vector<std::string> &fusedFeatureNames ();

/** \brief Computes what a candidate's patch does not show: the forest's part probabilities at
  * its pixel and averaged over 5 and 10 cm around it (3D), per part the most confident mode
  * within 10 cm and the distance to the nearest mode tip and the agreement of the candidate's
  * orientation with that mode's direction, its sources and AGEX rank and geodesic distance,
  * and its height within its mesh along up (0 at the mesh's top, 1 at its bottom) and the
  * mesh's height in metres. labels is the forest's organized label cloud (empty: every forest
  * feature 0); fx the focal length in pixels (the neighbourhoods' pixel radius); up the
  * world's up axis in camera axes. out holds fusedFeatureNames ().size () values. */
class FusedFeatures
{
public:
  FusedFeatures (const DepthPipelineResult &prepared, const pcl::PointCloud<BodyPartLabelPoint> &labels,
                 const std::vector<PartMode> &modes, float fx, const Eigen::Vector3f &up);
  void compute (const FusedCandidate &candidate, float *out) const;
  /** The candidate's mesh: its own (AGEX points), else the one its pixel lies on; -1: none. */
  int meshOf (const FusedCandidate &candidate) const;

private:
  void meanProbabilities (int index, const Eigen::Vector3f &at, float radius, float *out) const;

  const DepthPipelineResult &prepared_;
  const pcl::PointCloud<BodyPartLabelPoint> &labels_;
  const std::vector<PartMode> &modes_;
  float fx_;
  Eigen::Vector3f up_;
  std::vector<int> mesh_of_;                 ///< per pixel: its mesh, or -1
  std::vector<Eigen::Vector2f> mesh_extent_; ///< per mesh: lowest and highest height along up
};

/** The interest point (position, orientation, pixel) a candidate's patch is cut around. */
agex::InterestPoint candidatePoint (const FusedCandidate &candidate, int width);
}  // namespace agex
