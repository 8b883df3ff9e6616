#pragma once
// The baseline the AGEX paper compares against (Plagemann et al., ICRA 2010, Sec. VI):
// the same depth patches and boosted classifier, applied to every window position of the
// frame instead of to AGEX points only. See doc/classifier.md.

#include <agex/classification/patch_classifier.h>
#include <agex/common/point_types.h>

#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace agex
{
/** One window the detector kept. */
struct WindowDetection
{
  int cls = 0;                ///< the window's most confident class
  float confidence = 0.f;     ///< that class's confidence, [0, 1]
  float margin = 0.f;         ///< that class's boosted margin
  int u = 0, v = 0;           ///< centre pixel
  Eigen::Vector3f position = Eigen::Vector3f::Zero ();  ///< the centre pixel's point, metres
  float scale = 1.f;          ///< the scale it was found at (extent = scale * trained extent)
  float extent = 0.f;         ///< the window's side, metres at its centre's depth
};

/** \brief Sliding-window body-part detector over an organized depth frame.
  *
  * Window centres: every pixel on a stride grid (u and v multiples of the stride) with a
  * finite depth, restricted to the indices given with setIndices (e.g. the segmented
  * person) when there are any. The stride is getStride () pixels, or with setStrideMetres
  * the pixels that many metres span at the median depth of those pixels (one stride per
  * frame: the same windows on the person at any resolution). At each centre and each scale s the window is the
  * classifier's patch (agex::DepthPatchEstimation: the trained size, clamp and
  * s * the trained extent in metres), upright (patch axes = image axes): unlike an AGEX
  * point, a window carries no orientation to normalise with. Each window is classified;
  * its most confident class and confidence make a candidate, candidates below
  * getMinConfidence () are dropped (with the classifier's soft cascade, if it has one there),
  * and non-maximum suppression per class within
  * getSuppressionRadius () metres (agex::suppressNonMaxima, across scales) leaves the
  * detections, most confident first.
  *
  * The classifier should be one trained on upright patches centred on the parts (agex_train
  * --sliding-window); any trained PatchClassifier is accepted.
  *
  * Misuse is reported the PCL way (PCL_ERROR and an empty output): no input, an
  * unorganized input, no or an untrained classifier, a classifier without a patch geometry,
  * stride < 1, no scales or a scale that is not finite and positive, a focal length that
  * has to be estimated but cannot be. An all-NaN frame gives no detections, no error.
  *
  * Thread safety: detect () is not reentrant on one object; the classifier may be shared.
  * Explicit instantiations exist for pcl::PointXYZ, pcl::PointXYZI and pcl::PointXYZRGBA.
  */
template <typename PointT>
class SlidingWindowDetector : public pcl::PCLBase<PointT>
{
public:
  using Ptr = std::shared_ptr<SlidingWindowDetector<PointT>>;
  using ConstPtr = std::shared_ptr<const SlidingWindowDetector<PointT>>;

  SlidingWindowDetector () = default;

  void setClassifier (const std::shared_ptr<const PatchClassifier> &classifier) { classifier_ = classifier; }
  std::shared_ptr<const PatchClassifier> getClassifier () const { return classifier_; }

  /** Pixels between window centres, in both directions (default 3). */
  void setStride (int pixels) { stride_ = pixels; }
  int getStride () const { return stride_; }
  /** Metres between window centres at the median depth of the candidate pixels, as pixels
    * round (metres f / z), 1-64; 0 (default): getStride () pixels. */
  void setStrideMetres (float metres) { stride_metres_ = metres; }
  float getStrideMetres () const { return stride_metres_; }
  /** The stride the last detect () used, pixels. */
  int getUsedStride () const { return used_stride_; }

  /** Window extents as multiples of the classifier's trained extent (default {1}). */
  void setScales (const std::vector<float> &scales) { scales_ = scales; }
  const std::vector<float> &getScales () const { return scales_; }

  /** Same-class detections closer than this (metres) to a more confident one are
    * dropped; 0 keeps every window (default 0.15). */
  void setSuppressionRadius (float metres) { suppression_radius_ = metres; }
  float getSuppressionRadius () const { return suppression_radius_; }

  /** Windows less confident than this are not candidates (default 0: all are). A classifier
    * with a soft cascade at this confidence (PatchClassifier::classifyCascade) also drops the
    * windows it rejects early, which may include a few that would have reached it. */
  void setMinConfidence (float confidence) { min_confidence_ = confidence; }
  float getMinConfidence () const { return min_confidence_; }

  /** Focal length in pixels; 0 (default) estimates it from the input each detect (). */
  void setFocalLength (float pixels) { focal_length_ = pixels; }
  float getFocalLength () const { return focal_length_; }

  /** \brief Scans the input; output: the detections, most confident first.
    * \return false (output empty, PCL_ERROR) on misuse */
  bool detect (std::vector<WindowDetection> &output);

  /** Windows classified by the last detect () (centres x scales). */
  std::size_t getWindowCount () const { return window_count_; }

protected:
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::use_indices_;
  using pcl::PCLBase<PointT>::fake_indices_;

private:
  std::shared_ptr<const PatchClassifier> classifier_;
  int stride_ = 3;
  float stride_metres_ = 0.f;
  int used_stride_ = 0;
  std::vector<float> scales_{1.f};
  float suppression_radius_ = 0.15f;
  float min_confidence_ = 0.f;
  float focal_length_ = 0.f;
  std::size_t window_count_ = 0;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/classification/impl/sliding_window_detector.hpp>
#endif
