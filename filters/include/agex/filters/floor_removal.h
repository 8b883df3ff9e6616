#pragma once

#include <pcl/filters/filter_indices.h>

#include <Eigen/Core>

namespace agex
{
/** \brief Removes the floor of a depth frame: the lowest plane roughly perpendicular to
  * the world's up axis, and everything on or below it (the soles where feet touch it).
  *
  * RANSAC (PCL's perpendicular-plane model) looks for a plane whose normal is within the
  * tilt limit of up, among every sample-stride-th finite point of the indices. The floor
  * is the lowest surface in view: a plane with much of the scene under it (a desk top, or
  * a tilted plane through a patch of wall) is not the floor, and removing everything
  * below it would take the legs. Such a plane is rejected when more than a quarter of its
  * inlier count lies clearly under it (by 0.10 m, or three distance thresholds if more),
  * or when the viewpoint (the cloud's sensor_origin_) is not above it by more than the
  * distance threshold (a camera sees a floor from above; a steep plane through a torso or a
  * wall may pass over it; a cloud moved into another frame, e.g. by pcl::transformPointCloud,
  * must have its sensor_origin_ moved with it, or its floor may pass through the origin), and RANSAC tries again among the points under it, where the
  * floor must be and where it is no longer outnumbered; at most max attempts planes are
  * tried.
  *
  * Output: the finite indices at least the distance threshold above the floor (all finite
  * indices when no floor was found). setNegative gives the floor points instead;
  * setKeepOrganized, the removed indices and setIndices work as for every
  * pcl::FilterIndices. A frame without a floor in view is normal, not an error: nothing
  * is printed, and getFloorFound () says so.
  */
template <typename PointT>
class FloorRemoval : public pcl::FilterIndices<PointT>
{
protected:
  using PointCloud = typename pcl::FilterIndices<PointT>::PointCloud;
  using pcl::FilterIndices<PointT>::filter_name_;
  using pcl::FilterIndices<PointT>::getClassName;
  using pcl::FilterIndices<PointT>::input_;
  using pcl::FilterIndices<PointT>::indices_;
  using pcl::FilterIndices<PointT>::negative_;
  using pcl::FilterIndices<PointT>::extract_removed_indices_;
  using pcl::FilterIndices<PointT>::removed_indices_;

public:
  using Ptr = pcl::shared_ptr<FloorRemoval<PointT>>;
  using ConstPtr = pcl::shared_ptr<const FloorRemoval<PointT>>;

  explicit FloorRemoval (bool extract_removed_indices = false) : pcl::FilterIndices<PointT> (extract_removed_indices)
  {
    filter_name_ = "FloorRemoval";
  }

  /** The world's up direction in the cloud's axes (default (0, -1, 0): camera y points down). */
  void setUpAxis (const Eigen::Vector3f &up) { up_ = up; }
  const Eigen::Vector3f &getUpAxis () const { return up_; }

  /** Largest angle in degrees between the floor's normal and up (default 45: cameras looking
    * down at people are often pitched 30-40 degrees). */
  void setMaxTilt (float degrees) { max_tilt_deg_ = degrees; }
  float getMaxTilt () const { return max_tilt_deg_; }

  /** Points closer than this to the plane (metres) are floor inliers, and points below
    * this height above it are removed (default 0.04). */
  void setDistanceThreshold (float metres) { distance_ = metres; }
  float getDistanceThreshold () const { return distance_; }

  /** Fewest sampled points a search needs; a plane needs a quarter of this many inliers
    * (default 200). */
  void setMinInliers (int points) { min_inliers_ = points; }
  int getMinInliers () const { return min_inliers_; }

  /** RANSAC sees every stride-th finite point (default 4: plenty, and cheap). */
  void setSampleStride (int stride) { sample_stride_ = stride; }
  int getSampleStride () const { return sample_stride_; }

  /** Planes tried before giving up (default 3). */
  void setMaxAttempts (int attempts) { max_attempts_ = attempts; }
  int getMaxAttempts () const { return max_attempts_; }

  /** RANSAC iterations per attempt (default 1000). */
  void setMaxIterations (int iterations) { max_iterations_ = iterations; }
  int getMaxIterations () const { return max_iterations_; }

  /** Whether the last filter () found a floor. */
  bool getFloorFound () const { return floor_found_; }
  /** The last floor found: unit normal pointing up and offset, so n.p + d is the height
    * above the floor (zero when none was found). */
  const Eigen::Vector4f &getFloorPlane () const { return floor_plane_; }

protected:
  void applyFilter (pcl::Indices &indices) override;

private:
  /** The floor plane among the sampled indices, or false. */
  bool findFloor (pcl::IndicesPtr sample);

  Eigen::Vector3f up_ = Eigen::Vector3f (0.f, -1.f, 0.f);
  float max_tilt_deg_ = 45.f;
  float distance_ = 0.04f;
  int min_inliers_ = 200;
  int sample_stride_ = 4;
  int max_attempts_ = 3;
  int max_iterations_ = 1000;
  bool floor_found_ = false;
  Eigen::Vector4f floor_plane_ = Eigen::Vector4f::Zero ();
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/floor_removal.hpp>
#endif
