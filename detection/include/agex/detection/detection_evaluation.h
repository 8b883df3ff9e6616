#pragma once
// The paper's detection evaluation (average precision, precision-recall, confusion,
// orientation error), by distance or by box overlap: library code, so that users can
// score their own data from C++.

#include <agex/common/pixel_box.h>
#include <agex/detection/body_part_detection.h>
#include <agex/detection/fused_candidates.h>
#include <agex/io/dataset.h>

#include <nlohmann/json.hpp>

#include <array>
#include <utility>
#include <vector>

namespace agex
{
/** The physical side (metres) of a body part's box for the overlap criterion: head 0.25,
  * hand 0.15, foot 0.20 (doc/results.md). */
float partBoxSide (BodyPart part);

/** The square of partBoxSide (part) * scale metres at depth z, projected with focal length
  * focal (pixels), centred on pixel (u, v) (the pixel's centre is u + 0.5, v + 0.5). */
PixelBox partBox (BodyPart part, float u, float v, float z, float scale, float focal);

/** \brief The paper's detection evaluation: a detection is correct when it names the class
  * of a labelled tip that matches it and that no more confident detection took. Matching
  * is either distance (the tip within radius of the detection, 3D; the nearest wins) or box
  * overlap (the part's box around the tip and the detection's box, partBox, overlap with
  * intersection over union above min_iou; the largest overlap wins). */
class DetectionEvaluation
{
public:
  /** The distance criterion. */
  explicit DetectionEvaluation (float radius) : radius_ (radius) {}
  /** The box-overlap criterion, boxes projected with focal length focal (pixels). */
  static DetectionEvaluation boxOverlap (float min_iou, float focal);
  void addFrame (const std::vector<BodyPartDetection> &detections, const std::vector<PartLabel> &labels);
  /** Average precision of a class (area under the interpolated precision-recall curve). */
  double averagePrecision (BodyPart part) const;
  /** (recall, precision) points as the threshold falls. */
  std::vector<std::pair<double, double>> precisionRecall (BodyPart part) const;
  /** Rows: truth (head, hand, foot, background); columns: predicted (head, hand, foot,
    * none), counting detections at or above the threshold and tips nothing found. */
  std::array<std::array<int, 4>, 4> confusion (float threshold) const;
  double orientationMedianDeg (BodyPart part) const;
  /** \brief Recall of the top detections: per frame, as many of a class's most confident
    * detections as the frame has visible tips of that class (one head, two hands, ...), the
    * share of those tips they match. What a user who takes "the best head and the two best
    * hands" of every frame gets, without choosing a threshold. */
  double topRecall (BodyPart part) const;
  int frames () const { return frames_; }
  nlohmann::json report (float confusion_threshold) const;

  /** \brief Everything the evaluation holds (its criterion and what each frame added), so
    * that evaluations of disjoint frames, run apart (MPI ranks, --shard runs), can be
    * merged: fromState (state ()) is this evaluation again. */
  nlohmann::json state () const;
  /** \brief The evaluation a state () wrote.
    * \throws std::invalid_argument naming source and what is missing, mistyped or out of range */
  static DetectionEvaluation fromState (const nlohmann::json &state, const std::string &source);
  /** \brief Adds other's frames after this one's: the result is the evaluation of this one's
    * frames followed by other's, added in that order, whatever the split.
    * \throws std::invalid_argument if the two do not use the same criterion */
  void merge (const DetectionEvaluation &other);

private:
  /** How well d fits l under the criterion (larger is better); negative: no match. */
  float matchQuality (const BodyPartDetection &d, const PartLabel &l) const;
  /** The label (any class) that d fits best, or -1. */
  int bestLabel (const BodyPartDetection &d, const std::vector<PartLabel> &labels) const;

  struct Scored
  {
    float confidence;
    bool correct;
  };
  float radius_;
  float min_iou_ = 0.f;  ///< > 0: the box-overlap criterion
  float focal_ = 0.f;
  int frames_ = 0;
  std::array<std::vector<Scored>, kBodyPartCount> scored_;
  std::array<int, kBodyPartCount> positives_{};
  std::array<int, kBodyPartCount> top_hits_{};  ///< tips matched by the frame's top detections
  // For the confusion matrix: every detection's (truth, predicted, confidence) and
  // every tip's best detection confidence of its own class.
  struct Pair
  {
    int truth, predicted;
    float confidence;
  };
  std::vector<Pair> pairs_;
  std::array<std::vector<double>, kBodyPartCount> orientation_errors_;
};

/** \brief How many labelled parts the fused detector's candidates can reach: per class, the
  * fraction of visible tips within radius (3D) of a candidate of each kind: the first five
  * AGEX extrema of their mesh (ranks 2-6, the paper's AGEX_5), every AGEX point computed, the
  * forest's part modes (tips and peaks), and all candidates together. */
class CandidateCoverage
{
public:
  explicit CandidateCoverage (float radius) : radius_ (radius) {}
  void addFrame (const pcl::PointCloud<InterestPoint> &agex_points, const std::vector<FusedCandidate> &candidates,
                 const std::vector<PartLabel> &labels);
  /** {"agex5": {"head": f, ...}, "agex_all": ..., "modes": ..., "union": ..., "labels": {...}} */
  nlohmann::json report () const;
  /** Its counts, for merging (as DetectionEvaluation::state). */
  nlohmann::json state () const;
  /** \throws std::invalid_argument naming source and what is malformed */
  static CandidateCoverage fromState (const nlohmann::json &state, const std::string &source);
  /** \brief Adds other's counts. \throws std::invalid_argument if the radii differ */
  void merge (const CandidateCoverage &other);

private:
  static constexpr int kKinds = 4;
  float radius_;
  std::array<int, kBodyPartCount> labels_{};
  std::array<std::array<int, kBodyPartCount>, kKinds> covered_{};
};
}  // namespace agex

