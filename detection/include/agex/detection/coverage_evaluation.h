#pragma once
// The paper's first evaluation: how often is a labelled body part among the first
// k AGEX interest points? Accumulated frame by frame, reported per class.

#include <agex/io/dataset.h>
#include <agex/common/point_types.h>

#include <pcl/point_cloud.h>

#include <nlohmann/json.hpp>

#include <array>
#include <vector>

namespace agex
{
/** \brief Coverage of labelled tips by AGEX points, for k = 1..max_k.
  *
  * "k" counts geodesic extrema: the first k points of a mesh after its centroid
  * (ranks 2..k+1). The centroid sits on the torso and is never a body-part tip;
  * counting it would leave AGEX_5 four extrema for five extremities (head, two
  * hands, two feet). Coverage with the centroid counted is reported as well.
  * A tip is covered at k when a point among those is within the radius (3D); its
  * first rank is the smallest such k. */
class CoverageEvaluation
{
public:
  CoverageEvaluation (int max_k, float radius) : max_k_ (max_k), radius_ (radius)
  {
    for (auto &c : first_found_)
      c.clear ();
    for (auto &c : first_found_counting_centroid_)
      c.clear ();
  }

  /** Adds one frame: its interest points (all meshes, ranks up to at least max_k + 1)
    * and its labels (only visible labels with a finite tip are scored). */
  void addFrame (const pcl::PointCloud<agex::InterestPoint> &points, const std::vector<PartLabel> &labels);

  /** Fraction of the class's labels covered at k (extrema); NaN for a class without labels. */
  double coverage (BodyPart part, int k) const;
  /** How many of the class's labels are covered at k (extrema). */
  std::size_t coveredCount (BodyPart part, int k) const;
  double coverageCountingCentroid (BodyPart part, int k) const;
  /** Median angle in degrees between the covering point's orientation and tip - base. */
  double orientationMedianDeg (BodyPart part) const;
  std::size_t labelCount (BodyPart part) const { return first_found_[static_cast<int> (part)].size (); }
  int frames () const { return frames_; }

  /** The report: coverage at k, the curve up to max_k, first ranks, orientations. */
  nlohmann::json report (int k) const;

  /** Per scored label: frame, part, instance, first extremum index (0: none within
    * max_k) and the distance to the nearest of the first k extrema. */
  const nlohmann::json &details () const { return details_; }
  void setDetailK (int k) { detail_k_ = k; }

private:
  int max_k_;
  float radius_;
  int frames_ = 0;
  // Per class: per label, the first extremum index covering it (0 = never).
  std::array<std::vector<int>, kBodyPartCount> first_found_, first_found_counting_centroid_;
  std::array<std::vector<double>, kBodyPartCount> orientation_errors_deg_;
  nlohmann::json details_ = nlohmann::json::array ();
  int detail_k_ = 5;
};
}  // namespace agex
