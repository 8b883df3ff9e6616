#pragma once

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/impl/surface_segmentation.hpp>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/common/copy_point.h>

#include <algorithm>
#include <limits>

template <typename PointInT, typename PointOutT> bool
agex::AGEXKeypoint<PointInT, PointOutT>::initCompute ()
{
  keypoints_indices_.reset (new pcl::PointIndices);
  if (!pcl::PCLBase<PointInT>::initCompute ())
  {
    PCL_ERROR ("[agex::%s::initCompute] No input cloud was given.\n", getClassName ().c_str ());
    return false;
  }
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::%s::initCompute] The input cloud is not organized (height %u); "
               "AGEX needs the pixel grid of a depth frame.\n", getClassName ().c_str (), input_->height);
    return false;
  }
  if (k_per_mesh_ < 1 || !(delta_connected_ > 0.f) || !(delta_orient_ >= 0.f) || !(delta_connected_growth_ >= 0.f) ||
      !std::isfinite (delta_connected_growth_) || !(min_separation_ >= 0.f) || !std::isfinite (min_separation_))
  {
    PCL_ERROR ("[agex::%s::initCompute] Invalid parameters: k %d (>= 1), delta_connected %g (> 0), "
               "its growth %g (finite, >= 0), delta_orient %g (>= 0), min_separation %g (finite, >= 0).\n",
               getClassName ().c_str (), k_per_mesh_, delta_connected_, delta_connected_growth_, delta_orient_,
               min_separation_);
    return false;
  }
  if (user_meshes_)
    for (const auto &mesh : meshes_)
      for (const auto i : mesh.indices)
        if (i < 0 || static_cast<std::size_t> (i) >= input_->size ())
        {
          PCL_ERROR ("[agex::%s::initCompute] A mesh holds index %d, outside the %zu-point cloud.\n",
                     getClassName ().c_str (), i, input_->size ());
          return false;
        }
  return true;
}

template <typename PointInT, typename PointOutT> void
agex::AGEXKeypoint<PointInT, PointOutT>::buildGraph (const pcl::Indices &mesh, MeshGraph &graph)
{
  const PointCloudIn &cloud = *input_;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  graph.points.clear ();
  for (const auto i : mesh)
    if (isFinitePoint (cloud[i]) && point_to_vertex_[i] < 0)
    {
      point_to_vertex_[i] = 0;  // mark; numbered below in index order
      graph.points.push_back (i);
    }
  // Vertex ids follow point indices, which makes every tie-break index-based.
  if (!std::is_sorted (graph.points.begin (), graph.points.end ()))
    std::sort (graph.points.begin (), graph.points.end ());
  const int n = static_cast<int> (graph.points.size ());
  for (int vtx = 0; vtx < n; ++vtx)
    point_to_vertex_[graph.points[vtx]] = vtx;

  graph.degree.assign (n, 0);
  graph.edges.resize (static_cast<std::size_t> (n) * 8);
  max_edge_ = delta_connected_;
  // Each undirected edge is measured once, from its first pixel in scan order.
  for (int vtx = 0; vtx < n; ++vtx)
  {
    const int i = graph.points[vtx];
    const int u = i % width, v = i / width;
    for (const auto &d : kForwardNeighbours)
    {
      const int nu = u + d[0], nv = v + d[1];
      if (nu < 0 || nu >= width || nv >= height)
        continue;
      const int j = nv * width + nu;
      const int other = point_to_vertex_[j];
      if (other < 0)
        continue;
      if (!connectedNeighbours (cloud[i], cloud[j], delta_connected_, delta_connected_growth_))
        continue;
      const float length = std::sqrt (squaredDistance3D (cloud[i], cloud[j]));
      max_edge_ = std::max (max_edge_, length);
      const std::size_t a = static_cast<std::size_t> (vtx) * 8 + graph.degree[vtx]++;
      const std::size_t b = static_cast<std::size_t> (other) * 8 + graph.degree[other]++;
      graph.edges[a] = {other, length};
      graph.edges[b] = {vtx, length};
    }
  }
}

// Shortest paths from whatever is queued, relaxing only vertices whose distance
// drops. Parents are chosen deterministically: the lowest-index neighbour among
// those that are strictly closer and give exactly the final distance. That makes
// the shortest-path tree a function of the distances alone, so the incremental
// and naive modes agree on orientations too.
template <typename PointInT, typename PointOutT> void
agex::AGEXKeypoint<PointInT, PointOutT>::relax (const MeshGraph &graph)
{
  float *distance = distance_.data ();
  int *parent = parent_.data ();
  const auto *edges = graph.edges.data ();
  const int *degree = graph.degree.data ();
  while (!queue_.empty ())
  {
    const auto [d, u] = queue_.pop ();
    if (d > distance[u])
      continue;  // stale entry
    const auto *edge = edges + static_cast<std::size_t> (u) * 8;
    for (int e = 0, end = degree[u]; e < end; ++e)
    {
      const int v = edge[e].target;
      const float nd = d + edge[e].length;
      if (nd < distance[v])
      {
        distance[v] = nd;
        parent[v] = u;
        queue_.push (nd, v);
      }
      else if (nd == distance[v] && d < nd && u < parent[v])
        parent[v] = u;
    }
  }
}

template <typename PointInT, typename PointOutT> void
agex::AGEXKeypoint<PointInT, PointOutT>::runMesh (const MeshGraph &graph, int mesh_id, PointCloudOut &output)
{
  const PointCloudIn &cloud = *input_;
  const int n = static_cast<int> (graph.points.size ());
  const float inf = std::numeric_limits<float>::infinity ();

  // AGEX_1: the vertex nearest to the 3D centroid (ties: lowest index).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero ();
  for (const int i : graph.points)
    centroid += cloud[i].getVector3fMap ().template cast<double> ();
  centroid /= n;
  int first = 0;
  double best = std::numeric_limits<double>::infinity ();
  for (int vtx = 0; vtx < n; ++vtx)
  {
    const double sq = (cloud[graph.points[vtx]].getVector3fMap ().template cast<double> () - centroid).squaredNorm ();
    if (sq < best)
    {
      best = sq;
      first = vtx;
    }
  }

  distance_.assign (n, inf);
  parent_.assign (n, -1);
  std::vector<int> sources;
  auto add_point = [&] (int vtx, float geodesic, const Eigen::Vector3f &orientation) {
    const int index = graph.points[vtx];
    agex::InterestPoint ip;
    ip.getVector3fMap () = cloud[index].getVector3fMap ();
    ip.getOrientationVector3fMap () = orientation;
    ip.geodesic_distance = geodesic;
    ip.rank = static_cast<std::int32_t> (sources.size () + 1);
    ip.mesh = mesh_id;
    ip.u = static_cast<std::int32_t> (index % cloud.width);
    ip.v = static_cast<std::int32_t> (index / cloud.width);
    PointOutT out;
    pcl::copyPoint (ip, out);
    output.push_back (out);
    keypoints_indices_->indices.push_back (index);
    sources.push_back (vtx);

    // Buckets 1/32 of the longest edge wide: nearly Dijkstra's order, few revisits.
    queue_.reset (max_edge_ / 32.f, max_edge_);
    if (mode_ == Mode::Naive)
    {
      // Reference: forget everything and run a full multi-source Dijkstra.
      distance_.assign (n, inf);
      parent_.assign (n, -1);
      for (const int s : sources)
      {
        distance_[s] = 0.f;
        queue_.push (0.f, s);
      }
    }
    else
    {
      // The zero-cost edge to the new source: only what gets closer is touched.
      distance_[vtx] = 0.f;
      parent_[vtx] = -1;
      queue_.push (0.f, vtx);
    }
    relax (graph);
  };

  add_point (first, 0.f, Eigen::Vector3f::Zero ());
  for (int rank = 2; rank <= k_per_mesh_; ++rank)
  {
    int farthest = -1;
    float far_distance = 0.f;
    for (int vtx = 0; vtx < n; ++vtx)
      if (distance_[vtx] > far_distance && distance_[vtx] < inf)
      {
        far_distance = distance_[vtx];
        farthest = vtx;
      }
    if (farthest < 0)
      break;  // every reachable vertex is already a point: k exceeds the mesh
    if (far_distance < min_separation_)
      break;  // what is left are bumps beside the points found, no extremities

    int reached = farthest;
    while (parent_[reached] >= 0 && far_distance - distance_[reached] < delta_orient_)
      reached = parent_[reached];
    Eigen::Vector3f orientation =
        cloud[graph.points[farthest]].getVector3fMap () - cloud[graph.points[reached]].getVector3fMap ();
    const float length = orientation.norm ();
    orientation = length > 0.f ? Eigen::Vector3f (orientation / length) : Eigen::Vector3f::Zero ();
    add_point (farthest, far_distance, orientation);
  }
}

template <typename PointInT, typename PointOutT> void
agex::AGEXKeypoint<PointInT, PointOutT>::detectKeypoints (PointCloudOut &output)
{
  output.clear ();
  keypoints_indices_->indices.clear ();

  if (!user_meshes_)
  {
    agex::SurfaceSegmentation<PointInT> segmentation;
    segmentation.setInputCloud (input_);
    segmentation.setIndices (indices_);
    segmentation.setDeltaConnected (delta_connected_);
    segmentation.setDeltaConnectedGrowth (delta_connected_growth_);
    segmentation.setMinMeshSize (std::max<std::size_t> (1, min_mesh_size_));
    segmentation.segment (meshes_);
  }

  point_to_vertex_.assign (input_->size (), -1);
  MeshGraph graph;
  for (std::size_t m = 0; m < meshes_.size (); ++m)
  {
    buildGraph (meshes_[m].indices, graph);
    if (!graph.points.empty () && graph.points.size () >= min_mesh_size_)
      runMesh (graph, static_cast<int> (m), output);
    for (const int i : graph.points)
      point_to_vertex_[i] = -1;
  }
  output.width = static_cast<std::uint32_t> (output.size ());
  output.height = 1;
  output.is_dense = true;
  output.header = input_->header;
}

#define PCL_INSTANTIATE_AGEXKeypoint(IN, OUT) template class PCL_EXPORTS agex::AGEXKeypoint<IN, OUT>;
