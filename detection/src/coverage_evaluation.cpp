#include <agex/detection/coverage_evaluation.h>

#include <agex/common/statistics.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace agex
{

void
CoverageEvaluation::addFrame (const pcl::PointCloud<agex::InterestPoint> &points, const std::vector<PartLabel> &labels)
{
  ++frames_;
  for (const auto &label : labels)
  {
    if (!label.visible || !label.tip.allFinite ())
      continue;
    const int cls = static_cast<int> (label.part);
    int first = 0, first_with_centroid = 0;
    const agex::InterestPoint *covering = nullptr;
    double nearest = std::numeric_limits<double>::infinity ();
    for (const auto &p : points)
    {
      if (p.rank >= 2 && p.rank - 1 <= detail_k_)
        nearest = std::min (nearest, static_cast<double> ((p.getVector3fMap () - label.tip).norm ()));
      if ((p.getVector3fMap () - label.tip).norm () > radius_)
        continue;
      if (p.rank <= max_k_ && (first_with_centroid == 0 || p.rank < first_with_centroid))
        first_with_centroid = p.rank;
      const int extremum = p.rank - 1;  // rank 1 is the centroid
      if (extremum >= 1 && extremum <= max_k_ && (first == 0 || extremum < first))
      {
        first = extremum;
        covering = &p;
      }
    }
    first_found_[cls].push_back (first);
    details_.push_back ({{"frame", label.frame},
                         {"part", bodyPartName (label.part)},
                         {"instance", label.instance},
                         {"first_extremum", first},
                         {"nearest_within_k_m", std::isfinite (nearest) ? nlohmann::json (nearest) : nlohmann::json (nullptr)}});
    first_found_counting_centroid_[cls].push_back (first_with_centroid);
    if (covering && label.base.allFinite ())
    {
      const double error = angleBetweenDeg (label.tip - label.base, covering->getOrientationVector3fMap ());
      if (std::isfinite (error))
        orientation_errors_deg_[cls].push_back (error);
    }
  }
}

double
CoverageEvaluation::coverage (BodyPart part, int k) const
{
  const auto &found = first_found_[static_cast<int> (part)];
  if (found.empty ())
    return std::nan ("");
  return static_cast<double> (std::count_if (found.begin (), found.end (), [k] (int f) { return f >= 1 && f <= k; })) /
         found.size ();
}

std::size_t
CoverageEvaluation::coveredCount (BodyPart part, int k) const
{
  const auto &found = first_found_[static_cast<int> (part)];
  return static_cast<std::size_t> (std::count_if (found.begin (), found.end (), [k] (int f) { return f >= 1 && f <= k; }));
}

double
CoverageEvaluation::coverageCountingCentroid (BodyPart part, int k) const
{
  const auto &found = first_found_counting_centroid_[static_cast<int> (part)];
  if (found.empty ())
    return std::nan ("");
  return static_cast<double> (std::count_if (found.begin (), found.end (), [k] (int f) { return f >= 1 && f <= k; })) /
         found.size ();
}

double
CoverageEvaluation::orientationMedianDeg (BodyPart part) const
{
  return median (orientation_errors_deg_[static_cast<int> (part)]);
}

nlohmann::json
CoverageEvaluation::report (int k) const
{
  auto number = [] (double v) { return std::isfinite (v) ? nlohmann::json (v) : nlohmann::json (nullptr); };
  nlohmann::json doc;
  doc["frames"] = frames_;
  doc["k"] = k;
  doc["radius_m"] = radius_;
  doc["k_counts"] = "geodesic extrema after the mesh centroid (AGEX ranks 2..k+1)";
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    const auto part = static_cast<BodyPart> (c);
    const std::string name = bodyPartName (part);
    doc["labels"][name] = labelCount (part);
    doc["coverage"][name] = number (coverage (part, k));
    doc["coverage_counting_centroid"][name] = number (coverageCountingCentroid (part, k));
    doc["orientation_median_deg"][name] = number (orientationMedianDeg (part));
    nlohmann::json curve = nlohmann::json::array ();
    for (int kk = 1; kk <= max_k_; ++kk)
      curve.push_back (number (coverage (part, kk)));
    doc["coverage_curve"][name] = curve;
    std::vector<double> ranks;
    for (const int f : first_found_[c])
      if (f > 0)
        ranks.push_back (f);
    doc["first_rank_median"][name] = number (median (ranks));
    doc["never_found_within_k"][name] =
        std::count (first_found_[c].begin (), first_found_[c].end (), 0);
  }
  return doc;
}
}  // namespace agex
