#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/common/statistics.h>
#include <agex/filters/spur_filter.h>

#include <algorithm>
#include <cmath>
#include <vector>

template <typename PointT> int
agex::SpurFilter<PointT>::erosionLayers (float z) const
{
  if (!(erosion_depth_ > 0.f))
    return std::min (iterations_, static_cast<int> (kMaxLayers));
  return clampedInt (std::round (erosion_depth_ * focal_length_ / z), 0, kMaxLayers);  // z may be ~0
}

template <typename PointT> float
agex::SpurFilter<PointT>::halfMinWidth (float z) const
{
  const float half = 0.5f * (min_width_ * focal_length_ / z + 0.5f);
  return std::isfinite (half) ? std::clamp (half, 0.f, static_cast<float> (kMaxLayers)) : static_cast<float> (kMaxLayers);
}

/** The width of each point's part, by levels, deepest first: from the points of layer r
  * (and, at the top, every point the erosion left) a search runs down the erosion's layers,
  * one step along connected neighbours for at least one layer down (a point of layer t is
  * entered d steps from its start only when t <= r - d), and a point takes the first level
  * that reaches it. So a part's middle reaches its own sides, not the sides of a narrower
  * part beside it (a wrist beyond a forearm), whose layers do not fall that fast. A point
  * reached before with at least as much left (r - d) is not expanded again: what it reaches
  * was reached then, at a deeper level. */
template <typename PointT> void
agex::SpurFilter<PointT>::localThickness (const std::vector<int> &alive, int top, int width)
{
  // Points the erosion never reached (most of a body) start only where they border a
  // shallower layer: inside, their searches reach nothing new.
  std::vector<std::vector<int>> by_layer (static_cast<std::size_t> (top) + 1);
  for (const int i : alive)
  {
    const int layer = std::min<int> (layer_[i], top);
    if (layer == top)
    {
      thick_[i] = static_cast<unsigned char> (top);
      bool inside = true;
      const int u = i % width, v = i / width;
      for (int d = 0; d < 8 && inside; ++d)
        if (edges_[i] & (1u << d))
          inside = layer_[(v + kAllNeighbours[d][1]) * width + u + kAllNeighbours[d][0]] >= top;
      if (inside)
        continue;
    }
    by_layer[static_cast<std::size_t> (layer)].push_back (i);
  }
  std::vector<int> queue;
  for (int r = top; r >= 1; --r)
  {
    queue.clear ();
    for (const int q : by_layer[static_cast<std::size_t> (r)])
      if (reach_[q] < r)
      {
        reach_[q] = static_cast<unsigned char> (r);  // r - d, d = 0
        queue.push_back (q);
      }
    // First in, first out: a point is queued with the most it gets at this level.
    for (std::size_t head = 0; head < queue.size (); ++head)
    {
      const int p = queue[head];
      if (thick_[p] == 0)
        thick_[p] = static_cast<unsigned char> (r);
      const int left = reach_[p] - 1;
      const int u = p % width, v = p / width;
      for (int d = 0; d < 8; ++d)
        if (edges_[p] & (1u << d))
        {
          const int j = (v + kAllNeighbours[d][1]) * width + u + kAllNeighbours[d][0];
          if (layer_[j] <= left && reach_[j] < left)
          {
            reach_[j] = static_cast<unsigned char> (left);
            queue.push_back (j);
          }
        }
    }
  }
}

/** Joins the kept middles of limbs to the parts they grow out of: where a limb grows out
  * of a wider part, its middle lies within that part's erosion (the layers rise from the
  * limb's to the part's) and would come apart from it. From the middles of limbs long enough
  * to matter (a middle's points, kept by their width and not deeper than their erosion, of
  * at least twice the minimum width squared as the camera sees them: not a bump on an edge)
  * the points up to what the erosion keeps are kept: a neighbour not kept, of a deeper
  * layer, or of the same layer from the top of a ridge (no deeper neighbour), with at most
  * half the minimum width of steps along a layer (reach_ holds 1 + those steps, 0: not
  * reached). */
template <typename PointT> void
agex::SpurFilter<PointT>::joinCores (const std::vector<int> &alive, int width)
{
  const auto &cloud = *input_;
  const auto middle = [&] (int i) {
    const float z = cloud[i].z;
    return kept_[i] && layer_[i] <= erosionLayers (z) && layer_[i] >= halfMinWidth (z);
  };
  // The middles, as connected pieces: thick_ marks them (its widths are used up by now).
  std::vector<int> climb, piece;
  const double per_pixel = 1.0 / (static_cast<double> (focal_length_) * focal_length_);
  const double least = 2.0 * static_cast<double> (min_width_) * min_width_;
  for (const int i : alive)
  {
    reach_[i] = 0;
    thick_[i] = 0;
  }
  for (const int seed : alive)
  {
    if (thick_[seed] || !middle (seed))
      continue;
    piece.assign (1, seed);
    thick_[seed] = 1;
    double area = 0.0;
    for (std::size_t head = 0; head < piece.size (); ++head)
    {
      const int c = piece[head];
      area += static_cast<double> (cloud[c].z) * cloud[c].z * per_pixel;
      const int u = c % width, v = c / width;
      for (int d = 0; d < 8; ++d)
        if (edges_[c] & (1u << d))
        {
          const int j = (v + kAllNeighbours[d][1]) * width + u + kAllNeighbours[d][0];
          if (!thick_[j] && middle (j))
          {
            thick_[j] = 1;
            piece.push_back (j);
          }
        }
    }
    if (area >= least)
      for (const int c : piece)
      {
        reach_[c] = 1;
        climb.push_back (c);
      }
  }
  for (std::size_t head = 0; head < climb.size (); ++head)
  {
    const int c = climb[head];
    const int along = reach_[c] - 1;
    const int most = static_cast<int> (std::ceil (halfMinWidth (cloud[c].z)));
    const int u = c % width, v = c / width;
    bool top = true;
    for (int d = 0; d < 8 && top; ++d)
      if (edges_[c] & (1u << d))
        top = layer_[(v + kAllNeighbours[d][1]) * width + u + kAllNeighbours[d][0]] <= layer_[c];
    for (int d = 0; d < 8; ++d)
      if (edges_[c] & (1u << d))
      {
        const int j = (v + kAllNeighbours[d][1]) * width + u + kAllNeighbours[d][0];
        if (layer_[j] < layer_[c] || (layer_[j] == layer_[c] && !top) || (kept_[j] && reach_[j] == 0))
          continue;  // down, along a side, or kept already (deeper than the erosion, or a middle)
        const int steps = along + (layer_[j] == layer_[c] ? 1 : 0);
        if (steps > most || (reach_[j] != 0 && reach_[j] <= steps + 1))
          continue;
        reach_[j] = static_cast<unsigned char> (steps + 1);
        kept_[j] = 1;
        climb.push_back (j);
      }
  }
}

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
  const auto finite_non_negative = [] (float v) { return std::isfinite (v) && v >= 0.f; };
  if (min_connected_ < 0 || min_connected_ > 8 || iterations_ < 0 || !(delta_connected_ > 0.f) ||
      !finite_non_negative (delta_connected_growth_) || !finite_non_negative (focal_length_) ||
      !finite_non_negative (erosion_depth_) || !finite_non_negative (min_width_) ||
      (min_width_ > 0.f && !(focal_length_ > 0.f)))
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: min connected %d (0-8), iterations %d (>= 0), "
               "delta_connected %g (> 0), its growth %g, focal length %g, erosion depth %g, min width %g (each "
               "finite, >= 0; a min width needs a focal length).\n", getClassName ().c_str (), min_connected_,
               iterations_, delta_connected_, delta_connected_growth_, focal_length_, erosion_depth_, min_width_);
    return;
  }
  const auto &cloud = *input_;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  if (kept_.size () != cloud.size ())
  {
    kept_.assign (cloud.size (), 0);
    edges_.assign (cloud.size (), 0);
    count_.assign (cloud.size (), 0);
    layer_.assign (cloud.size (), 0);
    thick_.assign (cloud.size (), 0);
    reach_.assign (cloud.size (), 0);
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

  // In metres, the passes go as deep as the deepest point needs: its erosion depth, and with
  // a minimum width as far as the widths are compared (a part twice the minimum width plus
  // twice the erosion depth wide is eroded by the erosion depth alone).
  const bool metric = focal_length_ > 0.f, widths = metric && min_width_ > 0.f;
  int passes = iterations_;
  if (metric)
  {
    passes = 0;
    for (const int i : alive)
    {
      const float z = cloud[i].z;
      const int need = erosionLayers (z) + (widths ? static_cast<int> (std::ceil (halfMinWidth (z))) : 0);
      passes = std::max (passes, std::min (need, static_cast<int> (kMaxLayers)));
    }
  }
  passes_run_ = 0;

  std::vector<int> candidates = alive, dropped;
  for (int pass = 0; pass < passes; ++pass)
  {
    // Every decision of a pass uses the counts from before it.
    dropped.clear ();
    for (const int i : candidates)
      if (kept[i] && count[i] < min_connected_)
      {
        kept[i] = 0;  // also keeps a candidate listed twice from being dropped twice
        dropped.push_back (i);
        if (metric)
          layer_[i] = static_cast<unsigned char> (pass + 1);
      }
    if (dropped.empty ())
      break;
    ++passes_run_;
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

  // In metres each point is judged by its erosion layer against its own depth's erosion
  // depth and, with a minimum width, its local thickness against the width's half.
  if (metric)
  {
    for (const int i : alive)
      if (layer_[i] == 0)
        layer_[i] = static_cast<unsigned char> (passes + 1);  // the erosion never reached it
    if (widths)
      localThickness (alive, passes + 1, width);
    for (const int i : alive)
    {
      const float z = cloud[i].z;
      const int t = layer_[i];
      bool remove = t <= erosionLayers (z);
      if (widths)
      {
        const float half = halfMinWidth (z);
        const int thick = thick_[i];
        remove = thick < half || (remove && t + half <= thick);
      }
      kept[i] = remove ? 0 : 1;
    }
    if (widths)
      joinCores (alive, width);
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
    kept[i] = edges[i] = count[i] = layer_[i] = thick_[i] = reach_[i] = 0;
}

#define PCL_INSTANTIATE_SpurFilter(T) template class PCL_EXPORTS agex::SpurFilter<T>;
