#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/surface_segmentation.h>

#include <algorithm>

template <typename PointT> void
agex::SurfaceSegmentation<PointT>::segment (std::vector<pcl::PointIndices> &meshes)
{
  pcl::PointCloud<pcl::Label> labels;
  segment (labels, meshes);
}

template <typename PointT> void
agex::SurfaceSegmentation<PointT>::segment (pcl::PointCloud<pcl::Label> &labels,
                                           std::vector<pcl::PointIndices> &meshes)
{
  meshes.clear ();
  labels.clear ();
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
  std::vector<unsigned char> selected (n, 0);
  for (const auto i : *indices_)
    if (isFinitePoint (cloud[i]))
      selected[i] = 1;

  // Breadth-first flood fill over the connected 8-neighbours.
  std::vector<int> component (n, -1);
  std::vector<pcl::PointIndices> found;
  std::vector<int> queue;
  for (std::size_t seed = 0; seed < n; ++seed)
  {
    if (!selected[seed] || component[seed] >= 0)
      continue;
    const int id = static_cast<int> (found.size ());
    found.emplace_back ();
    auto &mesh = found.back ().indices;
    queue.assign (1, static_cast<int> (seed));
    component[seed] = id;
    for (std::size_t head = 0; head < queue.size (); ++head)
    {
      const int i = queue[head];
      mesh.push_back (i);
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
    std::sort (mesh.begin (), mesh.end ());
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

  labels.width = cloud.width;
  labels.height = cloud.height;
  labels.is_dense = cloud.is_dense;
  labels.header = cloud.header;
  labels.points.assign (n, pcl::Label ());
  for (auto &l : labels.points)
    l.label = kUnlabelled;
  meshes.reserve (order.size ());
  for (const int id : order)
  {
    const auto label = static_cast<std::uint32_t> (meshes.size ());
    for (const auto i : found[id].indices)
      labels[i].label = label;
    found[id].header = cloud.header;
    meshes.push_back (std::move (found[id]));
  }
  deinitCompute ();
}

#define PCL_INSTANTIATE_SurfaceSegmentation(T) template class PCL_EXPORTS agex::SurfaceSegmentation<T>;
