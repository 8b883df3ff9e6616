#pragma once

#include <pcl/PointIndices.h>
#include <pcl/pcl_base.h>
#include <pcl/point_types.h>

#include <limits>
#include <vector>

namespace agex
{
/** \brief Splits an organized cloud into connected surface meshes.
  *
  * Two 8-neighbour pixels belong to the same mesh when both are finite and their
  * 3D distance is below delta_connected (the paper's delta_connected). Unlike
  * pcl::OrganizedConnectedComponentSegmentation this is 8-connected and needs no
  * comparator. Only the points selected by setIndices take part. Meshes smaller
  * than the minimum (or larger than the maximum) size are dropped. Meshes come out
  * sorted by size, largest first (ties: lowest first index), each with its point
  * indices in increasing order, so results are deterministic.
  */
template <typename PointT>
class SurfaceSegmentation : public pcl::PCLBase<PointT>
{
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

public:
  using PointCloud = pcl::PointCloud<PointT>;
  /** Label of points in no (kept) mesh. */
  static constexpr std::uint32_t kUnlabelled = std::numeric_limits<std::uint32_t>::max ();

  /** Largest 3D distance in metres between connected neighbours (default 0.05). */
  void setDeltaConnected (float metres) { delta_connected_ = metres; }
  float getDeltaConnected () const { return delta_connected_; }
  /** The connection limit grows with depth as max (delta, growth z^2) (metres per square
    * metre of depth, default 0: fixed; agex::connectedNeighbours). */
  void setDeltaConnectedGrowth (float per_square_metre) { delta_connected_growth_ = per_square_metre; }
  float getDeltaConnectedGrowth () const { return delta_connected_growth_; }

  /** Meshes with fewer points are dropped (default 1: keep all). */
  void setMinMeshSize (std::size_t points) { min_mesh_size_ = points; }
  std::size_t getMinMeshSize () const { return min_mesh_size_; }

  /** Meshes with more points are dropped (default: no limit). */
  void setMaxMeshSize (std::size_t points) { max_mesh_size_ = points; }
  std::size_t getMaxMeshSize () const { return max_mesh_size_; }

  /** \brief Finds the meshes. Empty on error (unorganized input, bad parameters). */
  void segment (std::vector<pcl::PointIndices> &meshes);

  /** \brief Finds the meshes and labels every input point with its mesh index
    * (kUnlabelled for points in no kept mesh). */
  void segment (pcl::PointCloud<pcl::Label> &labels, std::vector<pcl::PointIndices> &meshes);

protected:
  std::string getClassName () const { return "SurfaceSegmentation"; }

private:
  /** segment () with labels only where asked (nullptr: none). */
  void segmentInto (pcl::PointCloud<pcl::Label> *labels, std::vector<pcl::PointIndices> &meshes);

  float delta_connected_ = 0.05f;
  float delta_connected_growth_ = 0.f;
  std::size_t min_mesh_size_ = 1;
  std::size_t max_mesh_size_ = std::numeric_limits<std::size_t>::max ();
  // Per point of the frame, between runs 0 and -1 (a run resets what it set): a person's
  // pixels of a large frame then cost what they number, not what the frame does.
  std::vector<unsigned char> selected_;
  std::vector<int> component_;
  std::vector<int> seeds_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/surface_segmentation.hpp>
#endif
