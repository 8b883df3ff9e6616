#pragma once

#include <pcl/filters/filter.h>

#include <limits>
#include <utility>
#include <vector>

namespace agex
{
/** \brief Median filter on the depth (z) of an organized cloud: pcl::MedianFilter's
  * result without its per-pixel cost, and optionally keeping each point on its pixel.
  *
  * Why not pcl::MedianFilter: PCL 1.13 builds a std::vector for every pixel (an
  * allocation and a free per point) and runs std::nth_element on it, which made the 3x3
  * median one of the most expensive stages of the detector. This class reads depth from
  * one contiguous array and gathers each window into a fixed scratch buffer; a 3x3 window
  * away from the border, the pipeline's case, goes through a branch-free median-of-9
  * network instead of std::nth_element (doc/benchmarks.md has the timings).
  *
  * Semantics are pcl::MedianFilter's, so that with setKeepOnViewingRay (false) the
  * output is the same cloud bit for bit (test/filters/test_depth_median_filter.cpp checks it):
  *   - the output is a copy of the input (all fields) in which each finite point
  *     (pcl::isFinite: x, y and z finite) gets a new z; invalid points stay as they are;
  *   - the window is the (2 * (size / 2) + 1)^2 pixels around the point (so an even
  *     size behaves as the next odd one, as in PCL), clipped at the image border
  *     (with setSampleSpacing s > 1: as many samples, s pixels apart);
  *     non-finite neighbours are skipped;
  *   - the median is the element at count / 2 after std::nth_element over the window's
  *     depths in row-major order (the upper median for an even count);
  *   - the point moves by at most the max allowed movement: a median farther away
  *     than that moves it exactly that far towards the median.
  * Differences: a max allowed movement of 0 leaves every depth as it is (PCL writes NaN
  * into unchanged points then, dividing 0 by 0); setIndices is honoured (only those
  * points are filtered, their neighbours come from the whole cloud; PCL ignores it); a
  * misuse (unorganized input, window size < 1, negative or NaN max movement) is reported
  * with PCL_ERROR and gives an empty output (PCL leaves the output cloud untouched).
  *
  * setKeepOnViewingRay (true, the default) scales x and y by new z / old z, so that the
  * point stays on the viewing ray of its pixel (x / z and y / z are kept). A depth
  * median is a correction of the range along that ray; moving z alone would shift a
  * point sideways off its pixel (by x * dz / z: 12 mm for a 5 cm correction 0.5 m off
  * axis at 2 m), which the later stages, working on the pixel grid, do not expect.
  * Points at z = 0 have no such ray and keep their x and y.
  */
template <typename PointT>
class DepthMedianFilter : public pcl::Filter<PointT>
{
protected:
  using PointCloud = typename pcl::Filter<PointT>::PointCloud;
  using pcl::Filter<PointT>::filter_name_;
  using pcl::Filter<PointT>::getClassName;
  using pcl::Filter<PointT>::input_;
  using pcl::Filter<PointT>::indices_;

public:
  using Ptr = pcl::shared_ptr<DepthMedianFilter<PointT>>;
  using ConstPtr = pcl::shared_ptr<const DepthMedianFilter<PointT>>;

  DepthMedianFilter () { filter_name_ = "DepthMedianFilter"; }

  /** Window side in pixels (default 5, as pcl::MedianFilter); an even size acts as size + 1. */
  void setWindowSize (int size) { window_size_ = size; }
  int getWindowSize () const { return window_size_; }

  /** Pixels between the window's samples (default 1: every pixel, as pcl::MedianFilter; at
    * most kMaxSpacing). A window of size 3 and spacing s spans 2 s + 1 pixels with 9
    * samples: a median over a given extent in metres costs the same at any resolution. */
  void setSampleSpacing (int pixels) { sample_spacing_ = pixels; }
  int getSampleSpacing () const { return sample_spacing_; }
  static constexpr int kMaxSpacing = 64;

  /** Largest change of a point's depth, metres (default: no limit, as pcl::MedianFilter). */
  void setMaxAllowedMovement (float metres) { max_allowed_movement_ = metres; }
  float getMaxAllowedMovement () const { return max_allowed_movement_; }

  /** Move x and y with z so that each point keeps its pixel (default true; false: z only,
    * as pcl::MedianFilter). */
  void setKeepOnViewingRay (bool keep) { keep_on_viewing_ray_ = keep; }
  bool getKeepOnViewingRay () const { return keep_on_viewing_ray_; }

  /** \brief Filters the points of setIndices in the input cloud itself, leaving every other
    * point as it is: filter ()'s result without its copy of the whole cloud, for a pipeline
    * that filters a person's pixels of a large frame. Every median is taken from the depths
    * before the call. cloud must be the cloud given to setInputCloud (PCL_ERROR otherwise).
    * \return false (cloud unchanged) on a misuse filter () would report */
  bool filterInPlace (PointCloud &cloud);

protected:
  void applyFilter (PointCloud &output) override;

private:
  /** Checks the settings and fills depth_ around the points to filter. */
  bool prepare ();

  /** Filters every point of indices_ with scratch (room for a whole window) as the
    * window buffer. */
  void filterPoints (PointCloud &output, float *scratch) const;

  /** filterPoints with a scratch buffer for the window size. */
  void filterPoints (PointCloud &output);

  int window_size_ = 5;
  int sample_spacing_ = 1;
  float max_allowed_movement_ = std::numeric_limits<float>::max ();
  bool keep_on_viewing_ray_ = true;
  std::vector<float> depth_;    // z of each point, NaN where not finite; current around the points filtered
  std::vector<std::pair<int, int>> spans_;  // per row, the columns read around the points
  std::vector<float> scratch_;  // window buffer for windows larger than kStackWindow
  static constexpr int kStackWindow = 3;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/depth_median_filter.hpp>
#endif
