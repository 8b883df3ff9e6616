#pragma once

#include <agex/detection/body_part_detection.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/detection/detector_model.h>

#include <pcl/pcl_base.h>

#include <string>
#include <vector>

namespace agex
{
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

  /** \brief A detector with the model in path.
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

  /** \brief Runs the detector on the input cloud; detections sorted by confidence.
    * Without a model, reports an error (PCL_ERROR) and gives none. */
  void compute (std::vector<BodyPartDetection> &detections);

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

  DetectorModel::ConstPtr model_;
  DetectorSettings settings_;
  DepthPipelineResult intermediate_;
  std::size_t patches_classified_ = 0;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/detection/impl/body_part_detector.hpp>
#endif
