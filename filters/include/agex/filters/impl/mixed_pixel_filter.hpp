#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/mixed_pixel_filter.h>

#include <algorithm>
#include <cmath>
#include <limits>

template <typename PointT> bool
agex::MixedPixelFilter<PointT>::isMixed (int index, const float *ranges, float cos_max_veil_angle) const
{
  const PointCloud &cloud = *input_;
  const PointT &p = cloud[index];
  if (!isFinitePoint (p))
    return false;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  const int v = index / width, u = index - v * width;
  auto range = [&] (int i) { return ranges ? ranges[i] : cloud[i].getVector3fMap ().norm (); };
  const float range_p = range (index);
  if (!(range_p > 0.f))
    return false;
  const float min_jump = std::max (min_jump_, min_jump_growth_ * range_p * range_p);

  // Whether the point lies inside a jump between i1 and i2 (ranges r1, r2) and on the line
  // between them as seen from the sensor: a veil pixel.
  auto veiled = [&] (int i1, int i2, float r1, float r2) {
    const float jump = std::abs (r2 - r1);
    if (!(jump >= min_jump))
      return false;
    const float lo = std::min (r1, r2), hi = std::max (r1, r2);
    const float margin = interior_margin_ * jump;
    if (range_p <= lo + margin || range_p >= hi - margin)
      return false;
    // Rarely reached (a jump across the point): the viewing ray only now.
    const Eigen::Vector3f ray = p.getVector3fMap () / range_p;
    const Eigen::Vector3f across = cloud[i2].getVector3fMap () - cloud[i1].getVector3fMap ();
    const float len = across.norm ();
    return len > 0.f && std::abs (across.dot (ray)) >= cos_max_veil_angle * len;
  };

  const int radius = window_radius_;
  if (ranges && u >= radius && u < width - radius && v >= radius && v < height - radius)
  {
    // Every pair inside the image: no bounds to check. NaN ranges fail the jump test.
    for (const auto &d : kForwardNeighbours)
    {
      const int step = d[0] + d[1] * width;
      for (int r = 1; r <= radius; ++r)
      {
        const int i1 = index - r * step, i2 = index + r * step;
        if (std::abs (ranges[i2] - ranges[i1]) >= min_jump && veiled (i1, i2, ranges[i1], ranges[i2]))
          return true;
      }
    }
    return false;
  }

  for (const auto &d : kForwardNeighbours)
    for (int r = 1; r <= radius; ++r)
    {
      const int u1 = u - r * d[0], v1 = v - r * d[1];
      const int u2 = u + r * d[0], v2 = v + r * d[1];
      if (u1 < 0 || u1 >= width || v1 < 0 || v1 >= height || u2 < 0 || u2 >= width || v2 < 0 || v2 >= height)
        continue;
      const int i1 = v1 * width + u1, i2 = v2 * width + u2;
      // Precomputed ranges are NaN for non-finite points: the jump test skips them.
      if (!ranges && (!isFinitePoint (cloud[i1]) || !isFinitePoint (cloud[i2])))
        continue;
      if (veiled (i1, i2, range (i1), range (i2)))
        return true;
    }
  return false;
}

template <typename PointT> void
agex::MixedPixelFilter<PointT>::applyFilter (pcl::Indices &indices)
{
  indices.clear ();
  removed_indices_->clear ();
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::applyFilter] The input cloud is not organized (height %u); "
               "mixed pixels can only be found in an organized depth frame.\n",
               getClassName ().c_str (), input_->height);
    return;
  }
  if (window_radius_ < 1 || !(min_jump_ > 0.f) || !(min_jump_growth_ >= 0.f) || !std::isfinite (min_jump_growth_) ||
      !(max_veil_angle_deg_ > 0.f && max_veil_angle_deg_ < 90.f) || !(interior_margin_ >= 0.f && interior_margin_ < 0.5f))
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: window radius %d (>= 1), min jump %g (> 0), "
               "min jump growth %g (finite, >= 0), max veil angle %g (0-90 degrees), interior margin %g (0-0.5).\n",
               getClassName ().c_str (), window_radius_, min_jump_, min_jump_growth_, max_veil_angle_deg_,
               interior_margin_);
    return;
  }
  const float cos_max_veil_angle = cosMaxVeilAngle ();
  // Each point's range is needed by up to 16 tests of its neighbours: compute it once,
  // NaN for a non-finite point (what isMixed relies on to skip it).
  // Only the window around the tested points is read: the ranges of a person's pixels and
  // their neighbours, not of the whole frame (the rest of ranges_ may hold another frame's).
  const int width = static_cast<int> (input_->width);
  rowSpans (*indices_, width, static_cast<int> (input_->height), window_radius_, spans_);
  ranges_.resize (input_->size ());
  for (int v = 0; v < static_cast<int> (input_->height); ++v)
    for (int u = spans_[static_cast<std::size_t> (v)].first; u <= spans_[static_cast<std::size_t> (v)].second; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * width + u;
      const PointT &p = (*input_)[i];
      ranges_[i] = isFinitePoint (p) ? p.getVector3fMap ().norm () : std::numeric_limits<float>::quiet_NaN ();
    }

  indices.reserve (indices_->size ());
  for (const auto index : *indices_)
  {
    const bool finite = isFinitePoint ((*input_)[index]);
    const bool keep = finite && (isMixed (index, ranges_.data (), cos_max_veil_angle) == negative_);
    if (keep)
      indices.push_back (index);
    else if (extract_removed_indices_)
      removed_indices_->push_back (index);
  }
}

#define PCL_INSTANTIATE_MixedPixelFilter(T) template class PCL_EXPORTS agex::MixedPixelFilter<T>;
