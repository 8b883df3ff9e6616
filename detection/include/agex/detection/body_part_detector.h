#pragma once

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_label_point.h>
#include <agex/classification/part_modes.h>
#include <agex/detection/body_part_detection.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/detection/detector_model.h>
#include <agex/detection/forest_parts.h>
#include <agex/detection/fused_candidates.h>
#include <agex/detection/tip_refinement.h>

#include <pcl/pcl_base.h>

#include <string>
#include <vector>

namespace agex
{
/** What a detector names parts with. */
enum class DetectorMode
{
  Model,   ///< the model's classifier: on AGEX points, sliding windows or fused candidates (its kind)
  Forest,  ///< the per-pixel body-part forest alone: one detection per part mode
};
/** "model", "forest". */
const char *detectorModeName (DetectorMode mode);
/** Inverse of detectorModeName; false for an unknown name. */
bool parseDetectorMode (const std::string &name, DetectorMode &mode);

/** \brief Heads, hands and feet in one organized depth frame: the whole agex detector as
  * the apps run it, in the spirit of pcl::people::GroundBasedPeopleDetectionApp.
  *
  * The model (agex::DetectorModel) decides how: an AGEX model runs the depth pipeline
  * (agex::DepthPipeline with the model's settings), cuts an oriented depth patch
  * (agex::DepthPatchEstimation, the model's patch geometry) around every AGEX point and
  * names it with the boosted classifier: each point becomes a detection of its most
  * confident class. A sliding-window model classifies upright windows over the pipeline's
  * meshes instead (agex::SlidingWindowDetector), the paper's baseline. Either way several
  * detections of one class closer than the model's suppression radius keep only the most
  * confident, and compute () returns them sorted by confidence, highest first.
  *
  * One detector serves one thread; several may share one model (loaded once, const).
  * setIndices limits the frame to those pixels. Empty, unorganized or all-NaN frames give
  * no detections.
  *
  * \code
  * auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel ("agex_bonn.yml");
  * detector->setInputCloud (cloud);
  * std::vector<agex::BodyPartDetection> parts;
  * detector->compute (parts);
  * \endcode
  */
template <typename PointT>
class BodyPartDetector : public pcl::PCLBase<PointT>
{
public:
  using Ptr = pcl::shared_ptr<BodyPartDetector<PointT>>;
  using ConstPtr = pcl::shared_ptr<const BodyPartDetector<PointT>>;

  BodyPartDetector () = default;

  /** \brief A detector with the model in path (and, for a fused model, its forest and the
    * sliding-window model it names, if any, with its weight).
    * \throws agex::ModelError naming the file and the problem */
  static Ptr fromModel (const std::string &path);

  /** The model to apply; its settings become the detector's (setSettings overrides them). */
  void setModel (const DetectorModel::ConstPtr &model);
  const DetectorModel::ConstPtr &getModel () const { return model_; }

  /** \brief Overrides the model's pipeline and detector settings (e.g. another crop box).
    * \throws std::invalid_argument on a setting out of range; std::logic_error if the
    *         detector kind differs from the model's */
  void setSettings (const DetectorSettings &settings);
  const DetectorSettings &getSettings () const { return settings_; }

  /** The per-pixel body-part forest (our model file or PCL's trees, BodyPartForest::load).
    * With a forest, the meshes' pixels are labelled in every mode (getPartLabels). */
  void setForest (const BodyPartForest::ConstPtr &forest) { forest_ = forest; }
  const BodyPartForest::ConstPtr &getForest () const { return forest_; }

  /** How parts are named (default Model). Forest, and a fused model, need setForest. */
  void setMode (DetectorMode mode) { mode_ = mode; }
  DetectorMode getMode () const { return mode_; }

  /** \brief Focal lengths of the camera in pixels, for the forest's depth-scaled offsets
    * and the part modes' areas; 0 (the default): estimated from the cloud (a pinhole fit,
    * agex::DepthPatchEstimation::estimateFocalLength). */
  void setFocalLength (float fx, float fy)
  {
    fx_ = fx;
    fy_ = fy;
  }

  /** Pixel stride of the forest pass in Forest mode (1: every person pixel; 2: one per 2x2
    * cell, the rest copy it; 0: by the focal length, agex::forestStrideFor). A fused model
    * uses the stride it was trained with (DetectorSettings::forest_stride). */
  void setForestStride (int stride) { forest_stride_ = stride; }
  int getForestStride () const { return forest_stride_; }

  /** \brief The classifier's soft cascade (agex::SoftCascade): candidates it rejects at this
    * confidence are dropped without computing all their features; the others keep exactly
    * their confidences. The cascade used is the one fitted for the largest level at most
    * this; 0 (or a model without a cascade): every candidate is classified in full. Default
    * kDefaultCascadeMinConfidence.
    * \throws std::invalid_argument outside [0, 1) */
  void setCascadeMinConfidence (float confidence);
  float getCascadeMinConfidence () const { return cascade_min_confidence_; }
  /** \brief The fraction of the training positives (reaching the minimum confidence) the
    * cascade may reject (agex::SoftCascade's miss rates; the largest fitted at most this).
    * Default kDefaultCascadeMissRate. \throws std::invalid_argument outside [0, 0.5] */
  void setCascadeMissRate (float rate);
  float getCascadeMissRate () const { return cascade_miss_rate_; }
  /** A confidence far below the detections that decide AP (doc/classifier.md). */
  static constexpr float kDefaultCascadeMinConfidence = 0.05f;
  static constexpr float kDefaultCascadeMissRate = 0.f;  // 0.02 costs held-out hands (doc/benchmarks.md)

  /** \brief Fused models: each hand and foot detection moved to its part's extremity, an AGEX
    * point of its mesh the classifier also takes for that part (agex::refineToTips). Default:
    * TipRefinementParams (). \throws std::invalid_argument on a setting out of range */
  void setTipRefinement (const TipRefinementParams &params)
  {
    params.validate ([] (const std::string &key) { return "TipRefinementParams::" + key; });
    tip_refinement_ = params;
  }
  const TipRefinementParams &getTipRefinement () const { return tip_refinement_; }

  /** \brief Fused models: each candidate's confidences blended with a sliding-window model's
    * at the candidate's pixel (its upright patch, that model's geometry and classifier):
    * (1 - weight) fused + weight window, per class, before the candidate takes its most
    * confident class. The sliding window ranks heads of unseen people better than the fused
    * classifier (doc/results.md). nullptr or weight 0 (the default): off.
    * \throws std::invalid_argument for a weight outside [0, 1] or a model that is no
    *         sliding-window model */
  void setWindowRescoring (const DetectorModel::ConstPtr &window_model, float weight);
  /** The weight for a window model given without one (apps, Python): the best of those
    * measured on held-out folds (doc/results.md). */
  static constexpr float kDefaultWindowWeight = 0.3f;
  const DetectorModel::ConstPtr &getWindowModel () const { return window_model_; }
  float getWindowWeight () const { return window_weight_; }

  /** \brief How Forest mode labels and names parts (agex::ForestPartSettings; default: the
    * persons as segmented, PCL-style blobs at their extremities). A fused model keeps its
    * training's meshes and modes.
    * \throws std::invalid_argument on a setting out of range */
  void setForestParts (const ForestPartSettings &settings)
  {
    settings.validate ([] (const std::string &key) { return "ForestPartSettings::" + key; });
    forest_parts_ = settings;
  }
  const ForestPartSettings &getForestParts () const { return forest_parts_; }

  /** \brief Runs the detector on the input cloud; detections sorted by confidence.
    * Without a model (or, in Forest mode, a forest), reports an error (PCL_ERROR) and gives
    * none. */
  void compute (std::vector<BodyPartDetection> &detections);

  /** The last compute ()'s part labels (organized like the input; empty unless the forest
    * ran) and part modes. */
  const pcl::PointCloud<BodyPartLabelPoint> &getPartLabels () const { return part_labels_; }
  const std::vector<PartMode> &getPartModes () const { return part_modes_; }
  /** A fused model's candidates of the last compute (), in the order they were made. */
  const std::vector<FusedCandidate> &getCandidates () const { return candidates_; }

  /** What the last compute () saw on the way: the filtered cloud, meshes, AGEX points,
    * floor plane, and per-stage milliseconds (the pipeline's stages, then patches and
    * classify, then total). */
  const DepthPipelineResult &getIntermediate () const { return intermediate_; }
  /** Patches classified by the last compute () (AGEX points, or windows x scales). */
  std::size_t getPatchesClassified () const { return patches_classified_; }

protected:
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::use_indices_;

private:
  /** Names the AGEX points (or, windows, classifies the sliding windows) of the
    * intermediate result, appending the "patches" and "classify" timings. */
  void classify (std::vector<BodyPartDetection> &detections, bool windows);
  /** Labels the person's pixels with the forest and finds the parts: Forest mode as
    * forest_parts_ says, a fused model on its meshes with modes ("forest" timing). */
  bool labelParts ();
  /** One detection per part mode, suppressed and sorted ("modes" timing). */
  void detectFromModes (std::vector<BodyPartDetection> &detections);
  /** A fused model's candidates named by its classifier ("patches", "classify" timings). */
  void classifyFused (std::vector<BodyPartDetection> &detections);
  /** Each detection's person (from its pixel's mesh, else its pixel's person); drops those
    * of persons too far away. */
  void assignPersons (std::vector<BodyPartDetection> &detections) const;
  /** Keeps the most confident detection of a class within the suppression radius, sorted. */
  void suppress (std::vector<BodyPartDetection> &candidates, std::vector<BodyPartDetection> &detections) const;

  DetectorModel::ConstPtr model_;
  DetectorSettings settings_;
  DepthPipelineResult intermediate_;
  DepthPipeline<PointT> pipeline_;  ///< kept across frames with its buffers
  std::size_t patches_classified_ = 0;
  BodyPartForest::ConstPtr forest_;
  DetectorMode mode_ = DetectorMode::Model;
  float fx_ = 0.f, fy_ = 0.f;
  float used_fx_ = 0.f;  ///< the focal length the last forest pass used
  int forest_stride_ = 1;
  float cascade_min_confidence_ = kDefaultCascadeMinConfidence;
  float cascade_miss_rate_ = kDefaultCascadeMissRate;
  TipRefinementParams tip_refinement_;
  DetectorModel::ConstPtr window_model_;
  float window_weight_ = 0.f;
  ForestPartSettings forest_parts_;
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz_frame_;  ///< the input as XYZ, for other point types
  pcl::PointCloud<BodyPartLabelPoint> part_labels_;
  std::vector<PartMode> part_modes_;
  std::vector<FusedCandidate> candidates_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/detection/impl/body_part_detector.hpp>
#endif
