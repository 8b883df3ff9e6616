#pragma once
// Hand and foot detections moved to the extremity of their part (doc/classifier.md, "Tip
// refinement"). The fused classifier is trained with every candidate within 10 cm of a tip as
// a positive, so a foot found at the ankle or a hand at the wrist can outscore the candidate
// at the tip; the labels, and a robot reaching for a hand, want the tip. The most salient
// geodesic extremum of the same mesh nearby that the classifier also takes for that part is
// where the tip is.

#include <agex/common/body_part.h>
#include <agex/detection/body_part_detection.h>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace agex
{
struct TipRefinementParams
{
  /** How far (metres) a detection may move to its part's extremity; 0: not at all. */
  float radius = 0.f;
  /** The extremity's own confidence for the detection's class must reach this fraction of
    * the detection's confidence, (0, 1]: the classifier must agree it is the same part. */
  float min_relative_confidence = 0.5f;
  /** \throws std::invalid_argument naming the key (name (key)) out of range */
  void validate (const std::function<std::string (const std::string &key)> &name) const;
};

/** A classified candidate: its detection (the most confident class), every class's
  * confidence, and, for an AGEX point, its geodesic distance when AGEX found it (from the
  * centroid and every point found before it; 0 when it is no AGEX point). */
struct ScoredCandidate
{
  BodyPartDetection detection;
  std::array<float, kBodyPartCount> confidences{};
  float geodesic_distance = 0.f;
};

/** \brief The detections of the scored candidates, each hand and foot moved to the AGEX point
  * (rank > 0) of its mesh within params.radius with the largest geodesic distance (the
  * extremum AGEX found farthest from everything found before it: a limb's tip before a heel or
  * a thumb beside it), larger than the candidate's own, whose confidence for the detection's
  * class reaches params.min_relative_confidence of the detection's. A moved detection keeps
  * its class and confidence and takes the point's position, orientation, pixel and rank.
  * Heads, candidates of unknown mesh and everything with radius 0 stay as they are. */
std::vector<BodyPartDetection> refineToTips (const std::vector<ScoredCandidate> &scored, const TipRefinementParams &params);
}  // namespace agex
