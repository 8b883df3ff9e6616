#pragma once
// The per-pixel body-part labelling stage, PCL-style: an organized cloud and the person's
// pixels in, an organized cloud of agex::BodyPartLabelPoint out (doc/forest.md).

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_label_point.h>

#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>

#include <memory>

namespace agex
{
/** \brief Labels the pixels of an organized cloud given with setIndices (the person, e.g. the
  * depth pipeline's meshes; without indices every pixel) with a BodyPartForest.
  *
  * The forest sees the depth image of PCL's people detector after its foreground step: the
  * given pixels in millimetres, every other pixel background (ForestDepthImage), optionally
  * with PCL's dilated ring of real depth around them (setForegroundDilation). Output: an
  * organized cloud of the input's size; a labelled pixel keeps its point and gets its
  * part probabilities (the forest's class probabilities summed per part) and its winning
  * part (the part of the forest's winning class: -1 when that class is no body part);
  * every other pixel is unlabelled (NaN point and probabilities, label -1). With a stride
  * > 1 only one pixel per stride x stride cell runs the trees and the others copy it, or stay
  * unlabelled (setStrideFill).
  *
  * Misuse is reported the PCL way (PCL_ERROR and an empty output): no input, an
  * unorganized input, no or an empty forest, a stride < 1, focal lengths that are not finite
  * and positive. NaN, empty or all-invalid input gives an all-unlabelled output, no error.
  *
  * Thread safety: compute () is not reentrant on one object; the forest may be shared.
  * Explicit instantiations exist for pcl::PointXYZ, pcl::PointXYZI and pcl::PointXYZRGBA. */
template <typename PointT>
class BodyPartLabeling : public pcl::PCLBase<PointT>
{
public:
  using Ptr = std::shared_ptr<BodyPartLabeling<PointT>>;
  using ConstPtr = std::shared_ptr<const BodyPartLabeling<PointT>>;
  using PointCloudOut = pcl::PointCloud<BodyPartLabelPoint>;

  BodyPartLabeling () = default;

  void setForest (const BodyPartForest::ConstPtr &forest) { forest_ = forest; }
  BodyPartForest::ConstPtr getForest () const { return forest_; }

  /** Focal lengths of the camera in pixels; the forest's offsets are scaled by them over its
    * reference focal length. 0 (the default) means the forest's own (525 for PCL's). */
  void setFocalLength (float fx, float fy) { fx_ = fx, fy_ = fy; }
  void setFocalLength (float f) { setFocalLength (f, f); }
  /** The same from full intrinsics (the principal point does not enter the features). */
  void setIntrinsics (float fx, float fy, float /*cx*/, float /*cy*/) { setFocalLength (fx, fy); }
  float getFocalLengthX () const { return fx_; }
  float getFocalLengthY () const { return fy_; }

  /** One evaluated pixel per stride x stride cell (default 1: every pixel). */
  void setStride (int stride) { options_.stride = stride; }
  int getStride () const { return options_.stride; }
  void setStrideFill (BodyPartForest::StrideFill fill) { options_.fill = fill; }
  BodyPartForest::StrideFill getStrideFill () const { return options_.fill; }

  /** PCL's 5x5 label smoothing after the vote (default off; see EvaluationOptions). */
  void setPclSmoothing (bool on) { options_.pcl_smoothing = on; }
  bool getPclSmoothing () const { return options_.pcl_smoothing; }

  /** Pixels around the given ones (a square of this radius) that keep their own depth
    * instead of background, as PCL's people detector dilates its person mask (2: its 5x5
    * dilation). Default 0: only the given pixels are foreground. */
  void setForegroundDilation (int pixels) { dilation_ = pixels; }
  int getForegroundDilation () const { return dilation_; }

  void setNumberOfThreads (int threads) { options_.threads = threads; }
  int getNumberOfThreads () const { return options_.threads; }

  /** \brief Labels the pixels. \return false (with PCL_ERROR, output empty) on misuse */
  bool compute (PointCloudOut &output);

  /** The forest's raw output of the last compute (), one row per index, in index order:
    * the part distributions (per_part) and the winning classes (BodyPartForest::Evaluation). */
  const BodyPartForest::Evaluation &getEvaluation () const { return evaluation_; }
  /** The depth image of the last compute (). */
  const ForestDepthImage &getDepthImage () const { return depth_; }

protected:
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

private:
  BodyPartForest::ConstPtr forest_;
  float fx_ = 0.f, fy_ = 0.f;
  int dilation_ = 0;
  BodyPartForest::EvaluationOptions options_;
  ForestDepthImage depth_;
  BodyPartForest::Evaluation evaluation_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/classification/impl/body_part_labeling.hpp>
#endif
