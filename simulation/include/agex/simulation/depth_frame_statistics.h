#pragma once
// Statistics that tell depth sensors apart, computed alike on real and synthetic frames
// so that sensor models can be fitted to real ones (doc/sensors.md).

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace agex
{
/** Accumulates, over organized depth frames (NaN = no measurement) and an optional
  * person mask per frame:
  *  - depth steps between 4-neighbours: per depth bin, the smallest step the sensor makes
  *    (the 10th percentile of non-zero steps below 10% of the depth: disparity quantisation
  *    shows as steps growing with depth^2);
  *  - noise on flat surfaces: per depth bin, the median RMS residual of a plane fitted to
  *    square patches of valid pixels without depth edges, off the person;
  *  - silhouettes (with a mask): the histogram of depth steps from a person pixel to its
  *    4-neighbours off the person, the hole (NaN) rate of the mask's pixels within
  *    band pixels of its edge, and the rate of "flying" pixels near the edge (valid, with
  *    valid 8-neighbours both nearer and farther by more than 3 cm + 2% of the depth). */
class DepthFrameStatistics
{
public:
  /** Upper edges of the silhouette step histogram's bins, metres (the last bin is open). */
  static constexpr std::array<double, 7> kStepEdges = {0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 1e9};

  /** Depth bins of bin_width metres from 0 to max_depth (defaults 0.5, 10). */
  void setDepthBins (double bin_width, double max_depth);
  /** Side of the flat-surface patches, pixels (odd, 3-31; default 7). */
  void setPatchSize (int pixels);
  /** Pixels of the mask within this many pixels (4-neighbour steps) of its edge form the
    * silhouette band (1-10; default 2). */
  void setBandWidth (int pixels);

  /** \brief Adds a frame. mask: row-major, width x height, non-zero = person (the person
    * as the sensor should have seen it, holes included); empty: no silhouette statistics.
    * \throws std::invalid_argument if the cloud is not organized or the mask's size differs */
  void add (const pcl::PointCloud<pcl::PointXYZ> &cloud, const std::vector<std::uint8_t> &mask = {});

  int depthBins () const { return static_cast<int> (noise_.size ()); }
  double binCentre (int bin) const { return (bin + 0.5) * bin_width_; }
  /** Smallest depth step at a depth bin's centre, metres (the 10th percentile of step / z^2
    * within the bin, times the centre's z^2); NaN with fewer than 50 steps. */
  double depthStep (int bin) const;
  /** Median plane-fit RMS of flat patches in a depth bin, metres; NaN with fewer than 10. */
  double flatNoise (int bin) const;
  std::size_t flatPatches (int bin) const { return noise_[static_cast<std::size_t> (bin)].size (); }
  /** Fraction of silhouette steps in each kStepEdges bin. */
  std::array<double, kStepEdges.size ()> silhouetteStepHistogram () const;
  std::size_t silhouetteSteps () const { return step_count_; }
  /** NaN rate of the silhouette band (NaN if no band pixels). */
  double silhouetteHoleRate () const;
  /** Flying-pixel rate among valid pixels within the band width of the silhouette. */
  double silhouetteFlyingRate () const;
  /** Fit of step = z^2 / k over the depth bins with a step (the mean of step / z^2): k
    * (metres), the 8 f b of a structured-light sensor; NaN without two bins. */
  double fittedDisparityConstant () const;
  /** A text table of everything, one line per depth bin and one per silhouette value. */
  std::string report (const std::string &name) const;

private:
  int binOf (double z) const;
  void ensureBins ();

  double bin_width_ = 0.5, max_depth_ = 10.0;
  int patch_ = 7, band_ = 2;
  std::vector<std::vector<float>> steps_, noise_;
  std::array<std::size_t, kStepEdges.size ()> step_hist_{};
  std::size_t step_count_ = 0, band_pixels_ = 0, band_holes_ = 0, near_valid_ = 0, near_flying_ = 0;
};
}  // namespace agex
