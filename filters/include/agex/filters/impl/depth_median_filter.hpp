#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/depth_median_filter.h>

#include <pcl/common/point_tests.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace agex
{
namespace detail
{
/** The median as pcl::MedianFilter takes it: the valid depths of the window around
  * (u, v) in row-major order (NaN marks invalid ones), element count / 2 after
  * std::nth_element. The window's samples lie spacing pixels apart, radius of them on each
  * side (spacing 1: pcl::MedianFilter's window). window has room for the whole window;
  * (u, v) itself is valid. */
inline float
windowMedian (const float *depth, int width, int height, int u, int v, int radius, int spacing, float *window)
{
  const int reach = radius * spacing;
  const int u_first = u - std::min (u, reach) / spacing * spacing, u_last = u + std::min (width - 1 - u, reach) / spacing * spacing;
  const int v_first = v - std::min (v, reach) / spacing * spacing, v_last = v + std::min (height - 1 - v, reach) / spacing * spacing;
  int count = 0;
  for (int y = v_first; y <= v_last; y += spacing)
  {
    const float *row = depth + static_cast<std::size_t> (y) * width;
    for (int x = u_first; x <= u_last; x += spacing)
    {
      window[count] = row[x];
      count += std::isnan (row[x]) ? 0 : 1;  // overwritten by the next one if invalid
    }
  }
  float *middle = window + count / 2;
  std::nth_element (window, middle, window + count);
  return *middle;
}

/** The same median for a 3x3 window (samples spacing pixels apart) inside the image,
  * centred at depth[0] (stride width), without branches: a 19-exchange median-of-9 network (Paeth) over the window
  * with its n invalid depths replaced by 4 - n / 2 times -inf and the rest +inf, which
  * leaves element n / 2 of the valid depths in the middle. Any selection yields the same
  * value; only +0 and -0 compare equal with different bits, so a window holding a zero
  * returns false and is left to windowMedian, which picks the zero PCL picks. */
inline bool
median3x3 (const float *depth, int width, int spacing, float &median)
{
  float p[9];
  const std::ptrdiff_t row = static_cast<std::ptrdiff_t> (width) * spacing;
  const float *rows[3] = {depth - row - spacing, depth - spacing, depth + row - spacing};
  int valid = 0;
  bool zero = false;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
    {
      const float z = rows[r][c * spacing];
      p[3 * r + c] = z;
      valid += std::isnan (z) ? 0 : 1;
      zero |= z == 0.f;
    }
  if (zero)
    return false;
  if (valid < 9)
  {
    int low = 4 - valid / 2;
    for (float &z : p)
      if (std::isnan (z))
        z = low-- > 0 ? -std::numeric_limits<float>::infinity () : std::numeric_limits<float>::infinity ();
  }
  const auto sort2 = [&p] (int a, int b) {
    const float lo = std::min (p[a], p[b]), hi = std::max (p[a], p[b]);
    p[a] = lo;
    p[b] = hi;
  };
  sort2 (1, 2); sort2 (4, 5); sort2 (7, 8);
  sort2 (0, 1); sort2 (3, 4); sort2 (6, 7);
  sort2 (1, 2); sort2 (4, 5); sort2 (7, 8);
  sort2 (0, 3); sort2 (5, 8); sort2 (4, 7);
  sort2 (3, 6); sort2 (1, 4); sort2 (2, 5);
  sort2 (4, 7); sort2 (4, 2); sort2 (6, 4);
  sort2 (4, 2);
  median = p[4];
  return true;
}
}  // namespace detail
}  // namespace agex

template <typename PointT> void
agex::DepthMedianFilter<PointT>::filterPoints (PointCloud &output, float *window) const
{
  const int width = static_cast<int> (output.width), height = static_cast<int> (output.height);
  const int radius = window_size_ / 2, spacing = sample_spacing_;
  const float *depth = depth_.data ();
  for (const auto index : *indices_)
  {
    const float z0 = depth[index];
    if (std::isnan (z0))
      continue;  // not a finite point: stays as it is
    const int u = index % width, v = index / width;
    float median;
    const bool inside = u >= spacing && v >= spacing && u < width - spacing && v < height - spacing;
    if (!(radius == 1 && inside && detail::median3x3 (depth + index, width, spacing, median)))
      median = detail::windowMedian (depth, width, height, u, v, radius, spacing, window);

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

template <typename PointT> bool
agex::DepthMedianFilter<PointT>::prepare ()
{
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::applyFilter] The input cloud is not organized (height %u); a median over "
               "neighbouring pixels needs the pixel grid.\n", getClassName ().c_str (), input_->height);
    return false;
  }
  if (window_size_ < 1 || !(max_allowed_movement_ >= 0.f) || sample_spacing_ < 1 || sample_spacing_ > kMaxSpacing)
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: window size %d (>= 1), max allowed movement %g "
               "(>= 0), sample spacing %d (1-%d).\n", getClassName ().c_str (), window_size_, max_allowed_movement_,
               sample_spacing_, kMaxSpacing);
    return false;
  }
  // One contiguous depth array, NaN marking the points PCL skips (pcl::isFinite):
  // the window loop then reads 4 bytes per neighbour instead of a whole point. Only the
  // windows around the filtered points are read, so only they are filled.
  const int width = static_cast<int> (input_->width);
  rowSpans (*indices_, width, static_cast<int> (input_->height), window_size_ / 2 * sample_spacing_, spans_);
  depth_.resize (input_->size ());
  for (int v = 0; v < static_cast<int> (input_->height); ++v)
    for (int u = spans_[static_cast<std::size_t> (v)].first; u <= spans_[static_cast<std::size_t> (v)].second; ++u)
    {
      const std::size_t i = static_cast<std::size_t> (v) * width + u;
      const PointT &p = (*input_)[i];
      depth_[i] = pcl::isFinite (p) ? p.z : std::numeric_limits<float>::quiet_NaN ();
    }
  return true;
}

template <typename PointT> void
agex::DepthMedianFilter<PointT>::filterPoints (PointCloud &output)
{
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

template <typename PointT> void
agex::DepthMedianFilter<PointT>::applyFilter (PointCloud &output)
{
  if (!prepare ())
  {
    output.clear ();
    return;
  }
  output = *input_;
  filterPoints (output);
}

template <typename PointT> bool
agex::DepthMedianFilter<PointT>::filterInPlace (PointCloud &cloud)
{
  if (!input_ || input_.get () != &cloud)
  {
    PCL_ERROR ("[agex::%s::filterInPlace] The cloud to filter in place must be the input cloud.\n",
               getClassName ().c_str ());
    return false;
  }
  if (!this->initCompute ())
    return false;
  const bool ok = prepare ();
  if (ok)
    filterPoints (cloud);
  this->deinitCompute ();
  return ok;
}

#define PCL_INSTANTIATE_DepthMedianFilter(T) template class PCL_EXPORTS agex::DepthMedianFilter<T>;
