#pragma once
// Detections moved to the extremity of their part (doc/classifier.md, "Tip refinement"). The
// fused classifier is trained with every candidate within 10 cm of a tip as a positive, so a
// head found on the forehead or a foot at the ankle can outscore the candidate at the tip;
// the labels, and a robot reaching for a hand, want the tip. The geodesic extremum of the
// same mesh that the classifier also takes for that part is where the tip is.

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
  * confidence, and its geodesic distance from its mesh's centroid (0 when it is no AGEX point). */
struct ScoredCandidate
{
  BodyPartDetection detection;
  std::array<float, kBodyPartCount> confidences{};
  float geodesic_distance = 0.f;
};

/** \brief The detections of the scored candidates, each moved to the AGEX point (rank > 0) of
  * its mesh within params.radius that lies geodesically farthest from the centroid, farther
  * than the candidate itself, and whose confidence for the detection's class reaches
  * params.min_relative_confidence of the detection's. A moved detection keeps its class and
  * confidence and takes the point's position, orientation, pixel and rank. With radius 0 the
  * detections are returned unchanged; candidates of unknown mesh never move. */
std::vector<BodyPartDetection> refineToTips (const std::vector<ScoredCandidate> &scored, const TipRefinementParams &params);
}  // namespace agex
