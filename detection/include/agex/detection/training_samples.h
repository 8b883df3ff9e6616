#pragma once
// Depth patches of a pipeline result, and the training examples agex_train mines from
// labelled frames: library code, so that a model can be trained from any data in C++.

#include <agex/classification/patch_classifier.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/detection/fused_candidates.h>
#include <agex/io/dataset.h>

#include <random>
#include <vector>

namespace agex
{
/** Depth patches (agex::DepthPatchEstimation) of points, in order, cut from the pipeline's
  * filtered frame with the given geometry; none when the frame is missing or unorganized. */
void computePatches (const DepthPipelineResult &prepared, const pcl::PointCloud<agex::InterestPoint> &points,
                     const PatchGeometry &geometry, std::vector<agex::DepthPatch> &patches);

/** \brief AGEX training examples from one labelled frame, appended to patches and
  * classes: every interest point (positive for class c when within radius of a visible
  * tip of class c, the nearest such tip's class; else background, label -1) and
  * random_negatives random mesh points with random in-plane orientations, farther than
  * 1.5 radius from every tip (label -1). */
void collectTrainingSamples (const DepthPipelineResult &prepared, const std::vector<PartLabel> &labels, float radius,
                             int random_negatives, const PatchGeometry &geometry, std::mt19937_64 &rng,
                             std::vector<agex::DepthPatch> &patches, std::vector<int> &classes);

/** \brief Sliding-window training examples from one labelled frame, all upright: per
  * visible tip, the mesh pixel nearest to it in 3D (within radius) and up to jitter more
  * random mesh pixels within jitter_radius of the tip (positives of the tip's class; a
  * window a stride apart from the tip must still fire), and random_negatives random mesh
  * pixels farther than 1.5 radius from every tip (background, label -1). */
void collectWindowTrainingSamples (const DepthPipelineResult &prepared, const std::vector<PartLabel> &labels,
                                   float radius, int jitter, float jitter_radius, int random_negatives,
                                   const PatchGeometry &geometry, std::mt19937_64 &rng,
                                   std::vector<agex::DepthPatch> &patches, std::vector<int> &classes);

/** \brief Fused training examples from one labelled frame, appended: every fused candidate
  * (agex::fusedCandidates of the frame's AGEX points and part modes; positive for class c when
  * within radius of a visible tip of class c, the nearest such tip's class, else background)
  * with its patch (oriented along the candidate) and its auxiliary features
  * (agex::FusedFeatures over the forest's labels). */
void collectFusedTrainingSamples (const DepthPipelineResult &prepared, const pcl::PointCloud<BodyPartLabelPoint> &labels,
                                  const std::vector<PartMode> &modes, float fx, const Eigen::Vector3f &up,
                                  const FusedCandidateParams &params, const std::vector<PartLabel> &truth, float radius,
                                  const PatchGeometry &geometry, std::vector<agex::DepthPatch> &patches,
                                  std::vector<std::vector<float>> &auxiliary, std::vector<int> &classes);

/** \brief Keeps at most max_ratio background examples (label -1) per positive, chosen
  * uniformly at random, and every positive, in their order. On whole scenes the background
  * candidates far from any part outnumber the parts many times over; boosting learns little
  * from most of them but pays for all of them. max_ratio 0 keeps everything; auxiliary may be empty or
  * hold a row per example.
  * \return the background examples dropped */
std::size_t keepBackgroundAtMost (float max_ratio, std::mt19937_64 &rng, std::vector<agex::DepthPatch> &patches,
                                  std::vector<std::vector<float>> &auxiliary, std::vector<int> &classes);
}  // namespace agex
