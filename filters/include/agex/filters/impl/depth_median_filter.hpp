#pragma once

#include <agex/filters/depth_median_filter.h>

#include <pcl/common/point_tests.h>

#include <algorithm>
#include <cmath>
#include <limits>

template <typename PointT> void
agex::DepthMedianFilter<PointT>::filterPoints (PointCloud &output, float *window) const
{
  const int width = static_cast<int> (output.width), height = static_cast<int> (output.height);
  const int radius = window_size_ / 2;
  const float *depth = depth_.data ();
  for (const auto index : *indices_)
  {
    const float z0 = depth[index];
    if (std::isnan (z0))
      continue;  // not a finite point: stays as it is
    const int u = index % width, v = index / width;
    const int u_first = std::max (u - radius, 0), u_last = std::min (u + radius, width - 1);
    const int v_first = std::max (v - radius, 0), v_last = std::min (v + radius, height - 1);
    // Row-major, skipping invalid neighbours without a branch: the order PCL gathers
    // them in, so that nth_element picks the very same element.
    int count = 0;
    for (int y = v_first; y <= v_last; ++y)
    {
      const float *row = depth + static_cast<std::size_t> (y) * width;
      for (int x = u_first; x <= u_last; ++x)
      {
        window[count] = row[x];
        count += std::isnan (row[x]) ? 0 : 1;
      }
    }
    float *middle = window + count / 2;  // count >= 1: the point itself is in the window
    std::nth_element (window, middle, window + count);
    const float median = *middle;

    // pcl::MedianFilter's clamp, in its arithmetic (bit-identical results).
    const float step = median - z0;
    float z1;
    if (std::abs (step) < max_allowed_movement_)
      z1 = median;
    else if (step == 0.f)
      z1 = z0;  // max movement 0: PCL would compute 0 / 0 here
    else
      z1 = z0 + max_allowed_movement_ * step / std::abs (step);

    PointT &p = output[index];
    p.z = z1;
    if (keep_on_viewing_ray_ && z1 != z0 && z0 != 0.f)
    {
      const float scale = z1 / z0;
      p.x *= scale;
      p.y *= scale;
    }
  }
}

template <typename PointT> void
agex::DepthMedianFilter<PointT>::applyFilter (PointCloud &output)
{
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::applyFilter] The input cloud is not organized (height %u); a median over "
               "neighbouring pixels needs the pixel grid.\n", getClassName ().c_str (), input_->height);
    output.clear ();
    return;
  }
  if (window_size_ < 1 || !(max_allowed_movement_ >= 0.f))
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: window size %d (>= 1), max allowed movement %g "
               "(>= 0).\n", getClassName ().c_str (), window_size_, max_allowed_movement_);
    output.clear ();
    return;
  }

  output = *input_;
  // One contiguous depth array, NaN marking the points PCL skips (pcl::isFinite):
  // the window loop then reads 4 bytes per neighbour instead of a whole point.
  depth_.resize (input_->size ());
  for (std::size_t i = 0; i < input_->size (); ++i)
  {
    const PointT &p = (*input_)[i];
    depth_[i] = pcl::isFinite (p) ? p.z : std::numeric_limits<float>::quiet_NaN ();
  }

  const int side = 2 * (window_size_ / 2) + 1;
  if (side <= kStackWindow)
  {
    float window[kStackWindow * kStackWindow];
    filterPoints (output, window);
  }
  else
  {
    scratch_.resize (static_cast<std::size_t> (side) * side);
    filterPoints (output, scratch_.data ());
  }
}

#define PCL_INSTANTIATE_DepthMedianFilter(T) template class PCL_EXPORTS agex::DepthMedianFilter<T>;
