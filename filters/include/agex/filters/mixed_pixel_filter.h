#pragma once

#include <pcl/filters/filter_indices.h>

#include <cmath>
#include <utility>
#include <vector>

namespace agex
{
/** \brief Removes mixed ("flying") pixels at depth discontinuities of an organized cloud.
  *
  * Range sensors average foreground and background across a silhouette, which
  * leaves a veil of points floating between the two surfaces. A finite point p is
  * a mixed pixel when, for some direction (horizontal, vertical or either diagonal)
  * and some radius r <= window radius, its two opposite neighbours q1 = p - r*d and
  * q2 = p + r*d
  *   1. straddle a jump: | |q2| - |q1| | >= min jump (ranges from the sensor),
  *   2. p lies strictly inside that jump: its range is more than
  *      interior margin * jump away from both neighbours' ranges, and
  *   3. the segment q1->q2 is nearly parallel to the viewing ray through p
  *      (angle below the max veil angle), which is what separates a veil from a
  *      real surface seen at a grazing angle, such as the floor.
  *
  * Non-finite points are always removed (as PCL's filters do). The filter honours
  * setIndices (only those points are tested and output; neighbours are read from
  * the whole cloud), setNegative (output only the mixed pixels), setKeepOrganized
  * (removed points become the user filter value, NaN by default) and
  * getRemovedIndices. It needs an organized cloud; on an unorganized one it reports
  * an error and outputs nothing.
  */
template <typename PointT>
class MixedPixelFilter : public pcl::FilterIndices<PointT>
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
  using Ptr = pcl::shared_ptr<MixedPixelFilter<PointT>>;
  using ConstPtr = pcl::shared_ptr<const MixedPixelFilter<PointT>>;

  explicit MixedPixelFilter (bool extract_removed_indices = false)
    : pcl::FilterIndices<PointT> (extract_removed_indices)
  {
    filter_name_ = "MixedPixelFilter";
  }

  /** Largest neighbour distance r in pixels (default 2, so bands up to 3 pixels wide go). */
  void setWindowRadius (int radius) { window_radius_ = radius; }
  int getWindowRadius () const { return window_radius_; }

  /** Smallest range jump in metres that counts as a discontinuity (default 0.05). */
  void setMinJump (float metres) { min_jump_ = metres; }
  float getMinJump () const { return min_jump_; }

  /** The smallest jump grows with the range r of the tested point as max (min jump,
    * growth r^2) (metres per square metre; default 0: fixed): a structured-light camera's
    * depth steps grow so, and a slanted surface shows a few of them within the window. */
  void setMinJumpGrowth (float per_square_metre) { min_jump_growth_ = per_square_metre; }
  float getMinJumpGrowth () const { return min_jump_growth_; }

  /** Largest angle in degrees between the jump and the viewing ray (default 15). */
  void setMaxVeilAngle (float degrees) { max_veil_angle_deg_ = degrees; }
  float getMaxVeilAngle () const { return max_veil_angle_deg_; }

  /** Fraction of the jump a mixed pixel must keep from both sides (default 0.1). */
  void setInteriorMargin (float fraction) { interior_margin_ = fraction; }
  float getInteriorMargin () const { return interior_margin_; }

  /** True if the point at index of the input cloud is a mixed pixel by the criterion
    * above (setInputCloud first). */
  bool isMixedPixel (int index) const { return isMixed (index, nullptr, cosMaxVeilAngle ()); }

protected:
  void applyFilter (pcl::Indices &indices) override;

private:
  /** The test, with the points' ranges precomputed (or nullptr to compute them). */
  bool isMixed (int index, const float *ranges, float cos_max_veil_angle) const;
  float cosMaxVeilAngle () const { return std::cos (max_veil_angle_deg_ * static_cast<float> (M_PI) / 180.f); }

  int window_radius_ = 2;
  float min_jump_ = 0.05f;
  float min_jump_growth_ = 0.f;
  float max_veil_angle_deg_ = 15.f;
  float interior_margin_ = 0.1f;
  std::vector<float> ranges_;  // distance of each point from the sensor, current around the tested points
  std::vector<std::pair<int, int>> spans_;  // per row, the columns read around the points
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/mixed_pixel_filter.hpp>
#endif
