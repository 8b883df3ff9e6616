#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/spur_filter.h>

#include <vector>

template <typename PointT> void
agex::SpurFilter<PointT>::applyFilter (pcl::Indices &indices)
{
  indices.clear ();
  removed_indices_->clear ();
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::applyFilter] The input cloud is not organized (height %u); spurs are "
               "found on the pixel grid.\n", getClassName ().c_str (), input_->height);
    return;
  }
  if (min_connected_ < 0 || min_connected_ > 8 || iterations_ < 0 || !(delta_connected_ > 0.f))
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: min connected %d (0-8), iterations %d (>= 0), "
               "delta_connected %g (> 0).\n", getClassName ().c_str (), min_connected_, iterations_, delta_connected_);
    return;
  }
  const auto &cloud = *input_;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  const float max_sq = delta_connected_ * delta_connected_;

  std::vector<unsigned char> kept (cloud.size (), 0);
  std::vector<int> alive;
  for (const auto i : *indices_)
    if (isFinitePoint (cloud[i]) && !kept[i])
    {
      kept[i] = 1;
      alive.push_back (i);
    }

  std::vector<int> survivors, dropped;
  for (int pass = 0; pass < iterations_; ++pass)
  {
    survivors.clear ();
    dropped.clear ();
    for (const int i : alive)
    {
      const int u = i % width, v = i / width;
      int connected = 0;
      for (const auto &d : kAllNeighbours)
      {
        const int nu = u + d[0], nv = v + d[1];
        if (nu < 0 || nu >= width || nv < 0 || nv >= height)
          continue;
        const int j = nv * width + nu;
        if (kept[j] && squaredDistance3D (cloud[i], cloud[j]) < max_sq)
          ++connected;
      }
      (connected >= min_connected_ ? survivors : dropped).push_back (i);
    }
    if (dropped.empty ())
      break;
    for (const int i : dropped)
      kept[i] = 0;  // all of a pass's decisions use the state before it
    alive.swap (survivors);
  }

  for (const auto i : *indices_)
  {
    const bool is_kept = kept[i] != 0;
    if (isFinitePoint (cloud[i]) && is_kept != negative_)
      indices.push_back (i);
    else if (extract_removed_indices_)
      removed_indices_->push_back (i);
  }
}

#define PCL_INSTANTIATE_SpurFilter(T) template class PCL_EXPORTS agex::SpurFilter<T>;
