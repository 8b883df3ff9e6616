#pragma once

#include <agex/common/point_types.h>

#include <pcl/features/feature.h>
#include <pcl/point_cloud.h>

#include <vector>

namespace agex
{
/** \brief Oriented depth patches around interest points of an organized depth frame
  * (the local descriptor of Plagemann et al., ICRA 2010, for classifying AGEX points).
  *
  * For each interest point the patch is a square of getPatchSize () x getPatchSize ()
  * cells, getPatchExtent () metres across at the point's depth, i.e. a fixed physical
  * size, so that patches of the same body part at different distances are comparable.
  * Cell (row, col) samples the pixel (nearest, never blended) that sees the
  * fronto-parallel offset
  *     ((col - c) e + (row - c) d) * metres_per_cell,   c = (size - 1) / 2,
  * from the point, where d is the unit image direction of the point's orientation and
  * e = (d.y, -d.x) (a rotation, no mirroring): the orientation points DOWN the patch
  * (+row), so on an AGEX limb tip the limb itself lies above the centre. Without an
  * orientation, or with one along the viewing ray, d = (0, 1): patch axes = image axes.
  *
  * A cell holds z(pixel) - z(point) in metres (positive = farther away), clamped to
  * [-clamp, +clamp]. Pixels that are NaN or outside the frame get the background value
  * +clamp ("far behind"), the same as a surface more than clamp behind the point. An
  * interest point whose own pixel is NaN gets an all-background patch and a zero
  * orientation. The centre cell of an odd-sized patch is the point itself, 0.
  *
  * Which points: either
  *  - setIndices (the keypoint indices into the organized input), optionally with
  *    setInterestPoints (the interest points, matched with the indices by order; their
  *    orientations are used, their x, y, z, u, v are not), or
  *  - setInterestPoints alone: each point's pixel is (u, v).
  * With neither, every pixel gets a patch (pcl::Feature's convention; the output is then
  * organized like the input). Output point i is the patch of index / interest point i.
  *
  * Image direction of an orientation o at point p: the derivative of the pinhole
  * projection along o, (o.x - o.z p.x / p.z, o.y - o.z p.y / p.z) (camera x right,
  * y down), which is (o.x, o.y) on the optical axis or for o in the image plane. If its
  * length is below 1e-3 |o| (or o is zero or not finite, e.g. the AGEX centroid), the
  * patch is not rotated.
  *
  * Focal length: offsets become pixels through f / z(point). setFocalLength (f) in
  * pixels (square pixels assumed); left at 0 (default), f is estimated from the input
  * itself once per compute(), see estimateFocalLength ().
  *
  * Misuse is reported the PCL way (PCL_ERROR and an empty output): no input, an
  * unorganized input, a patch size outside 1..41, a non-positive extent or clamp, a
  * negative focal length, indices or (u, v) outside the cloud, as many interest points
  * as indices, or a focal length that has to be estimated but cannot be.
  *
  * PointOutT needs the fields of agex::DepthPatch (patch, orientation, size,
  * metres_per_cell). Explicit instantiations exist for pcl::PointXYZ, pcl::PointXYZI and
  * pcl::PointXYZRGBA inputs with agex::DepthPatch output.
  */
template <typename PointInT, typename PointOutT = agex::DepthPatch>
class DepthPatchEstimation : public pcl::Feature<PointInT, PointOutT>
{
public:
  using Ptr = pcl::shared_ptr<DepthPatchEstimation<PointInT, PointOutT>>;
  using ConstPtr = pcl::shared_ptr<const DepthPatchEstimation<PointInT, PointOutT>>;
  using PointCloudIn = typename pcl::Feature<PointInT, PointOutT>::PointCloudIn;
  using PointCloudOut = typename pcl::Feature<PointInT, PointOutT>::PointCloudOut;
  using InterestPointCloud = pcl::PointCloud<agex::InterestPoint>;

  /** The largest patch size (the registered agex::DepthPatch holds 41 x 41 cells). */
  static constexpr int kMaxPatchSize = agex::DepthPatch::kMaxSize;

  DepthPatchEstimation () { feature_name_ = "DepthPatchEstimation"; }

  /** Interest points whose orientations align the patches: matched by order with
    * setIndices, or, without indices, located by their (u, v). nullptr: none. */
  void setInterestPoints (const typename InterestPointCloud::ConstPtr &points) { interest_points_ = points; }
  typename InterestPointCloud::ConstPtr getInterestPoints () const { return interest_points_; }

  /** Cells per side, 1..41 (default 41). */
  void setPatchSize (int cells) { patch_size_ = cells; }
  int getPatchSize () const { return patch_size_; }

  /** Side of the patch in metres at the point's depth (default 0.6). */
  void setPatchExtent (float metres) { patch_extent_ = metres; }
  float getPatchExtent () const { return patch_extent_; }

  /** Relative depths are clamped to +-clamp metres (default 0.3); +clamp is also the
    * background value. */
  void setClampDepth (float metres) { clamp_depth_ = metres; }
  float getClampDepth () const { return clamp_depth_; }
  /** The value of NaN and out-of-frame cells: +clamp. */
  float getBackgroundValue () const { return clamp_depth_; }

  /** Focal length in pixels; 0 (default) estimates it from the input each compute(). */
  void setFocalLength (float pixels) { focal_length_ = pixels; }
  float getFocalLength () const { return focal_length_; }
  /** The focal length the last compute() used: the one set, or its estimate (0 when it
    * needed none: no finite interest point). */
  float getUsedFocalLength () const { return used_focal_length_; }

  /** \brief Least-squares focal length of an organized cloud from a pinhole camera with
    * square pixels: fits u = f x/z + cx and v = f y/z + cy (one f, two centres) over the
    * finite points with z > 0 of a grid of about 4096 pixels (all pixels if that grid
    * holds fewer than 64 finite points).
    * \return f in pixels, or 0 if the cloud is not organized, has fewer than 3 usable
    *         points, or the fit is degenerate or not positive */
  static float estimateFocalLength (const PointCloudIn &cloud);

protected:
  using pcl::Feature<PointInT, PointOutT>::feature_name_;
  using pcl::Feature<PointInT, PointOutT>::input_;
  using pcl::Feature<PointInT, PointOutT>::indices_;
  using pcl::Feature<PointInT, PointOutT>::fake_indices_;
  using pcl::Feature<PointInT, PointOutT>::getClassName;

  /** Checks input and parameters, resolves the points and the focal length; no search
    * tree or radius is needed (the patch is read from the pixel grid). */
  bool initCompute () override;
  void computeFeature (PointCloudOut &output) override;

private:
  /** Fills out with the patch around cloud point index; orientation may be null. */
  void computePatch (int index, const agex::InterestPoint *orientation, PointOutT &out) const;

  typename InterestPointCloud::ConstPtr interest_points_;
  int patch_size_ = kMaxPatchSize;
  float patch_extent_ = 0.6f;
  float clamp_depth_ = 0.3f;
  float focal_length_ = 0.f;
  float used_focal_length_ = 0.f;
  /** indices_ was built from the interest points' (u, v) by the last initCompute. */
  bool uv_indices_ = false;
  /** (k - c) for k = 0..size-1: cell offsets from the centre, in cells. */
  std::vector<float> cell_offsets_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/features/impl/depth_patch_estimation.hpp>
#endif
