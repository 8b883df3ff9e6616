#pragma once

#include <pcl/filters/filter_indices.h>

#include <vector>

namespace agex
{
/** \brief Removes thin spurs and ragged edges from an organized cloud: a morphological
  * erosion on the pixel grid that only takes weakly connected points.
  *
  * In each of setIterations() passes, a point stays only if at least
  * setMinConnected() of its 8 neighbours are still kept and within delta_connected
  * (3D) of it. Interior points (8 connected neighbours) always stay; a one-pixel
  * strand (2) or a ragged silhouette pixel goes. Geodesic extrema are drawn to
  * exactly such pixels: hair strands, edge noise and flying pixels a sensor leaves
  * on silhouettes, whose depth is the least reliable in the frame.
  *
  * PCL conventions as in pcl::PassThrough: non-finite points are always removed,
  * setNegative, setKeepOrganized, getRemovedIndices and setIndices (only those
  * points take part) are honoured. Needs an organized cloud (else: error, empty).
  */
template <typename PointT>
class SpurFilter : public pcl::FilterIndices<PointT>
{
protected:
  using pcl::FilterIndices<PointT>::filter_name_;
  using pcl::FilterIndices<PointT>::getClassName;
  using pcl::FilterIndices<PointT>::input_;
  using pcl::FilterIndices<PointT>::indices_;
  using pcl::FilterIndices<PointT>::negative_;
  using pcl::FilterIndices<PointT>::extract_removed_indices_;
  using pcl::FilterIndices<PointT>::removed_indices_;

public:
  using Ptr = pcl::shared_ptr<SpurFilter<PointT>>;
  using ConstPtr = pcl::shared_ptr<const SpurFilter<PointT>>;

  explicit SpurFilter (bool extract_removed_indices = false) : pcl::FilterIndices<PointT> (extract_removed_indices)
  {
    filter_name_ = "SpurFilter";
  }

  /** Connected neighbours (of 8) a point needs to stay (default 6). */
  void setMinConnected (int count) { min_connected_ = count; }
  int getMinConnected () const { return min_connected_; }

  /** Erosion passes, i.e. pixels taken from a ragged edge at most (default 3). */
  void setIterations (int passes) { iterations_ = passes; }
  int getIterations () const { return iterations_; }

  /** Largest 3D distance between connected neighbours, metres (default 0.05). */
  void setDeltaConnected (float metres) { delta_connected_ = metres; }
  float getDeltaConnected () const { return delta_connected_; }
  /** The connection limit grows with depth as max (delta, growth z^2) (metres per square
    * metre of depth, default 0: fixed; agex::connectedNeighbours). */
  void setDeltaConnectedGrowth (float per_square_metre) { delta_connected_growth_ = per_square_metre; }
  float getDeltaConnectedGrowth () const { return delta_connected_growth_; }

protected:
  void applyFilter (pcl::Indices &indices) override;

private:
  int min_connected_ = 6;
  int iterations_ = 3;
  float delta_connected_ = 0.05f;
  float delta_connected_growth_ = 0.f;
  // Per point of the frame, all zero between runs (a run clears what it set): a person's
  // pixels of a large frame then cost what they number, not what the frame does.
  std::vector<unsigned char> kept_, edges_, count_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/spur_filter.hpp>
#endif
