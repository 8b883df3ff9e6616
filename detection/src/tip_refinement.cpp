#include <agex/detection/tip_refinement.h>

#include <sstream>
#include <stdexcept>

namespace agex
{
void
TipRefinementParams::validate (const std::function<std::string (const std::string &key)> &name) const
{
  std::ostringstream v;
  if (!(radius >= 0.f && radius <= 0.5f))
  {
    v << radius;
    throw std::invalid_argument (name ("radius") + " is " + v.str () + ", outside [0, 0.5] metres");
  }
  if (!(min_relative_confidence > 0.f && min_relative_confidence <= 1.f))
  {
    v << min_relative_confidence;
    throw std::invalid_argument (name ("min_relative_confidence") + " is " + v.str () + ", outside (0, 1]");
  }
}

std::vector<BodyPartDetection>
refineToTips (const std::vector<ScoredCandidate> &scored, const TipRefinementParams &params)
{
  std::vector<BodyPartDetection> out;
  out.reserve (scored.size ());
  const float radius_sq = params.radius * params.radius;
  for (const ScoredCandidate &s : scored)
  {
    BodyPartDetection d = s.detection;
    const int part = static_cast<int> (d.part);
    // Heads stay: a head's tip is its top, which its own candidates reach, while a hand held
    // beside it lies farther from the centroid along the body and would take it.
    if (params.radius > 0.f && d.mesh >= 0 && (d.part == BodyPart::Hand || d.part == BodyPart::Foot))
    {
      const float least = params.min_relative_confidence * d.confidence;
      const ScoredCandidate *tip = nullptr;
      float farthest = s.geodesic_distance;
      for (const ScoredCandidate &t : scored)
      {
        const BodyPartDetection &e = t.detection;
        if (e.rank <= 0 || e.mesh != d.mesh || !(t.geodesic_distance > farthest) ||
            !(t.confidences[static_cast<std::size_t> (part)] >= least) ||
            !((e.position - d.position).squaredNorm () <= radius_sq))
          continue;
        tip = &t;
        farthest = t.geodesic_distance;
      }
      if (tip)
      {
        d.position = tip->detection.position;
        d.orientation = tip->detection.orientation;
        d.u = tip->detection.u;
        d.v = tip->detection.v;
        d.rank = tip->detection.rank;
      }
    }
    out.push_back (d);
  }
  return out;
}
}  // namespace agex
