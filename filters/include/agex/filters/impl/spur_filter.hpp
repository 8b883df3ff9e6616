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
  if (min_connected_ < 0 || min_connected_ > 8 || iterations_ < 0 || !(delta_connected_ > 0.f) ||
      !(delta_connected_growth_ >= 0.f) || !std::isfinite (delta_connected_growth_))
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: min connected %d (0-8), iterations %d (>= 0), "
               "delta_connected %g (> 0), its growth %g (finite, >= 0).\n", getClassName ().c_str (), min_connected_,
               iterations_, delta_connected_, delta_connected_growth_);
    return;
  }
  const auto &cloud = *input_;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  if (kept_.size () != cloud.size ())
  {
    kept_.assign (cloud.size (), 0);
    edges_.assign (cloud.size (), 0);
    count_.assign (cloud.size (), 0);
  }
  std::vector<unsigned char> &kept = kept_, &edges = edges_, &count = count_;
  std::vector<int> alive;
  for (const auto i : *indices_)
    if (isFinitePoint (cloud[i]) && !kept[i])
    {
      kept[i] = 1;
      alive.push_back (i);
    }

  // Distances never change between passes, only which neighbours are kept: find each
  // point's connected neighbours once (a bit per direction of kAllNeighbours) and keep a
  // count of the kept ones. A pass then only needs to look at the points whose count
  // dropped in the pass before, the neighbours of what it removed.
  // Each undirected edge is tested once, from its first point (kAllNeighbours[d + 4] is
  // kAllNeighbours[d] reversed).
  for (const int i : alive)
  {
    const int v = i / width, u = i - v * width;
    for (int d = 0; d < 4; ++d)
    {
      const int nu = u + kAllNeighbours[d][0], nv = v + kAllNeighbours[d][1];
      if (nu < 0 || nu >= width || nv >= height)
        continue;
      const int j = nv * width + nu;
      if (kept[j] && connectedNeighbours (cloud[i], cloud[j], delta_connected_, delta_connected_growth_))
      {
        edges[i] |= static_cast<unsigned char> (1u << d);
        edges[j] |= static_cast<unsigned char> (1u << (d + 4));
        ++count[i];
        ++count[j];
      }
    }
  }

  std::vector<int> candidates = alive, dropped;
  for (int pass = 0; pass < iterations_; ++pass)
  {
    // Every decision of a pass uses the counts from before it.
    dropped.clear ();
    for (const int i : candidates)
      if (kept[i] && count[i] < min_connected_)
      {
        kept[i] = 0;  // also keeps a candidate listed twice from being dropped twice
        dropped.push_back (i);
      }
    if (dropped.empty ())
      break;
    candidates.clear ();
    for (const int i : dropped)
    {
      const int u = i % width, v = i / width;
      for (int d = 0; d < 8; ++d)
        if (edges[i] & (1u << d))
        {
          const int j = (v + kAllNeighbours[d][1]) * width + u + kAllNeighbours[d][0];
          if (kept[j])
          {
            --count[j];
            candidates.push_back (j);
          }
        }
    }
  }

  for (const auto i : *indices_)
  {
    const bool is_kept = kept[i] != 0;
    if (isFinitePoint (cloud[i]) && is_kept != negative_)
      indices.push_back (i);
    else if (extract_removed_indices_)
      removed_indices_->push_back (i);
  }
  for (const int i : alive)
    kept[i] = edges[i] = count[i] = 0;
}

#define PCL_INSTANTIATE_SpurFilter(T) template class PCL_EXPORTS agex::SpurFilter<T>;
