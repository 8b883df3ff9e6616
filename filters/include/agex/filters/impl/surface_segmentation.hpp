#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/surface_segmentation.h>

#include <algorithm>

template <typename PointT> void
agex::SurfaceSegmentation<PointT>::segment (std::vector<pcl::PointIndices> &meshes)
{
  segmentInto (nullptr, meshes);
}

template <typename PointT> void
agex::SurfaceSegmentation<PointT>::segment (pcl::PointCloud<pcl::Label> &labels,
                                           std::vector<pcl::PointIndices> &meshes)
{
  segmentInto (&labels, meshes);
}

template <typename PointT> void
agex::SurfaceSegmentation<PointT>::segmentInto (pcl::PointCloud<pcl::Label> *labels,
                                               std::vector<pcl::PointIndices> &meshes)
{
  meshes.clear ();
  if (labels)
    labels->clear ();
  if (!initCompute ())
    return;
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::segment] The input cloud is not organized (height %u); "
               "surface meshes are defined on the pixel grid.\n", getClassName ().c_str (), input_->height);
    deinitCompute ();
    return;
  }
  if (!(delta_connected_ > 0.f) || !(delta_connected_growth_ >= 0.f) || !std::isfinite (delta_connected_growth_) ||
      min_mesh_size_ > max_mesh_size_)
  {
    PCL_ERROR ("[agex::%s::segment] Invalid parameters: delta_connected %g must be > 0, its growth %g finite "
               "and >= 0, and the minimum mesh size (%zu) at most the maximum (%zu).\n",
               getClassName ().c_str (), delta_connected_, delta_connected_growth_, min_mesh_size_, max_mesh_size_);
    deinitCompute ();
    return;
  }

  const PointCloud &cloud = *input_;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  const std::size_t n = cloud.size ();
  if (selected_.size () != n)
  {
    selected_.assign (n, 0);
    component_.assign (n, -1);
  }
  std::vector<unsigned char> &selected = selected_;
  std::vector<int> &component = component_;
  // Seeds in increasing index order, as a scan of the whole frame would meet them.
  seeds_.clear ();
  for (const auto i : *indices_)
    if (isFinitePoint (cloud[i]) && !selected[i])
    {
      selected[i] = 1;
      seeds_.push_back (i);
    }
  if (!std::is_sorted (seeds_.begin (), seeds_.end ()))
    std::sort (seeds_.begin (), seeds_.end ());

  // Breadth-first flood fill over the connected 8-neighbours.
  std::vector<pcl::PointIndices> found;
  std::vector<int> queue;
  for (const int seed : seeds_)
  {
    if (component[seed] >= 0)
      continue;
    const int id = static_cast<int> (found.size ());
    found.emplace_back ();
    queue.assign (1, seed);
    component[seed] = id;
    for (std::size_t head = 0; head < queue.size (); ++head)
    {
      const int i = queue[head];
      const int u = i % width, v = i / width;
      for (const auto &d : kAllNeighbours)
      {
        const int nu = u + d[0], nv = v + d[1];
        if (nu < 0 || nu >= width || nv < 0 || nv >= height)
          continue;
        const int j = nv * width + nu;
        if (!selected[j] || component[j] >= 0 ||
            !connectedNeighbours (cloud[i], cloud[j], delta_connected_, delta_connected_growth_))
          continue;
        component[j] = id;
        queue.push_back (j);
      }
    }
    found.back ().indices.reserve (queue.size ());
  }
  // Each mesh's points in increasing order, as the seeds are: no sort needed.
  for (const int i : seeds_)
  {
    found[static_cast<std::size_t> (component[i])].indices.push_back (i);
    selected[i] = 0;
    component[i] = -1;
  }

  // Keep meshes within the size limits, largest first; ties keep scan order.
  std::vector<int> order;
  for (int id = 0; id < static_cast<int> (found.size ()); ++id)
  {
    const std::size_t size = found[id].indices.size ();
    if (size >= min_mesh_size_ && size <= max_mesh_size_)
      order.push_back (id);
  }
  std::stable_sort (order.begin (), order.end (), [&] (int a, int b) {
    return found[a].indices.size () > found[b].indices.size ();
  });

  if (labels)
  {
    labels->width = cloud.width;
    labels->height = cloud.height;
    labels->is_dense = cloud.is_dense;
    labels->header = cloud.header;
    labels->points.assign (n, pcl::Label ());
    for (auto &l : labels->points)
      l.label = kUnlabelled;
  }
  meshes.reserve (order.size ());
  for (const int id : order)
  {
    const auto label = static_cast<std::uint32_t> (meshes.size ());
    if (labels)
      for (const auto i : found[id].indices)
        (*labels)[i].label = label;
    found[id].header = cloud.header;
    meshes.push_back (std::move (found[id]));
  }
  deinitCompute ();
}

#define PCL_INSTANTIATE_SurfaceSegmentation(T) template class PCL_EXPORTS agex::SurfaceSegmentation<T>;
