#pragma once

#include <pcl/filters/filter_indices.h>

#include <vector>

namespace agex
{
/** \brief Removes thin spurs and ragged edges from an organized cloud: a morphological
  * erosion on the pixel grid that only takes weakly connected points.
  *
  * The erosion: in each pass a point stays only if at least setMinConnected() of its 8
  * neighbours are still kept and within delta_connected (3D) of it. Interior points (8
  * connected neighbours) always stay; a one-pixel strand (2) or a ragged silhouette pixel
  * goes, and a straight edge loses one pixel per pass. Geodesic extrema are drawn to exactly
  * such pixels: hair strands, edge noise and flying pixels a sensor leaves on silhouettes,
  * whose depth is the least reliable in the frame.
  *
  * Two ways to say how far it goes:
  * - **In pixels** (focal length 0, the default): setIterations() passes; every part
  *   narrower than twice that many pixels goes entirely.
  * - **In metres** (setFocalLength > 0): each point is judged at its own depth z, where a
  *   pixel spans z / f. The erosion takes setErosionDepth() metres off the edges
  *   (round (depth f / z) passes; 0: setIterations() passes), and with setMinWidth() > 0 a
  *   part's width decides, not the erosion alone: a strand narrower than the minimum width
  *   goes entirely, and a part at least that wide keeps at least that width around its
  *   middle (the erosion stops there), so a forearm stays a forearm at any resolution and
  *   distance while hair strands and one-pixel spurs go. A point's width is the deepest
  *   erosion layer r whose point reaches it going down the layers, at least one layer per
  *   step (about 2 r - 0.5 pixels wide): a part's middle reaches its own sides, not those of
  *   a narrower part beyond it. A point goes when that width is below the minimum, or when
  *   it lies within the erosion depth and outside the middle minimum width of its part. The
  *   middle of a limb (at least twice the minimum width squared in area, as the camera sees
  *   it), where the limb grows out of a wider part, lies within that part's erosion: the
  *   points from it up the layers to what the erosion keeps stay, so the limb stays joined.
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

  /** Erosion passes, i.e. pixels taken from a ragged edge at most (default 3); in metres
    * (focal length > 0) only with an erosion depth of 0. */
  void setIterations (int passes) { iterations_ = passes; }
  int getIterations () const { return iterations_; }

  /** The camera's focal length in pixels: > 0 judges every point in metres at its depth
    * (setErosionDepth, setMinWidth); 0 (default): in pixels (setIterations). */
  void setFocalLength (float pixels) { focal_length_ = pixels; }
  float getFocalLength () const { return focal_length_; }
  /** With a focal length: metres the erosion takes off an edge (default 0.035; 0: the
    * setIterations () passes). */
  void setErosionDepth (float metres) { erosion_depth_ = metres; }
  float getErosionDepth () const { return erosion_depth_; }
  /** With a focal length: parts narrower than this go entirely, wider ones keep at least
    * this much of their width, metres (default 0: the plain erosion). */
  void setMinWidth (float metres) { min_width_ = metres; }
  float getMinWidth () const { return min_width_; }
  /** Most passes (and layers of width) a point is judged by in metres: a bound on the work
    * for points very near the camera (0.035 m at 0.3 m with f = 525 px is 61 passes). */
  static constexpr int kMaxLayers = 64;
  /** Erosion passes the last filter () ran (in metres: what the nearest point needed, at
    * most kMaxLayers). */
  int getPassesRun () const { return passes_run_; }

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
  /** Passes and half of the minimum width, in pixels at depth z (metric judging). */
  int erosionLayers (float z) const;
  float halfMinWidth (float z) const;
  /** layer_ -> thick_ for the points of alive: the local thickness (see the class comment). */
  void localThickness (const std::vector<int> &alive, int top, int width);
  /** Keeps the points between a limb's kept middle and the eroded part it grows from. */
  void joinCores (const std::vector<int> &alive, int width);

  int min_connected_ = 6;
  int iterations_ = 3;
  float delta_connected_ = 0.05f;
  float delta_connected_growth_ = 0.f;
  float focal_length_ = 0.f;
  float erosion_depth_ = 0.035f;
  float min_width_ = 0.f;
  int passes_run_ = 0;
  // Per point of the frame, all zero between runs (a run clears what it set): a person's
  // pixels of a large frame then cost what they number, not what the frame does.
  // layer_: the pass that removed the point (0: none so far); thick_: its local thickness;
  // reach_: 1 + the most steps a thickness search still had left when it got there.
  std::vector<unsigned char> kept_, edges_, count_, layer_, thick_, reach_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/spur_filter.hpp>
#endif
