#pragma once
// Detection among several people: per labelled person (PartLabel::person), whether the
// detector found at least one of its parts, and AP by distance band; and how often it fires on
// surfaces that are nobody's (where a dataset has person images, agex_synth --people).

#include <agex/detection/detection_evaluation.h>

#include <opencv2/core.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <vector>

namespace agex
{
class PersonEvaluation
{
public:
  /** The distance bands of the report, metres (a person's median tip depth). */
  static constexpr std::array<float, 4> kBandEdges{{0.8f, 2.f, 4.f, 6.f}};
  static constexpr int kBands = 3;
  /** Detections at or above this confidence fire: they count for person recall and as
    * firing on a surface. */
  static constexpr float kFiringConfidence = 0.5f;

  explicit PersonEvaluation (float radius);

  /** \brief One frame: a person is found when a firing detection of the right class lies
    * within the radius of one of its visible tips (and found at any confidence when a
    * detection of any confidence does: what a lower threshold could reach). persons (may
    * be null or empty): the frame's person image (0: nobody), for the detections on
    * nobody's surface (a detection fires there when its pixel and the pixels within 2 of
    * it all show nobody). */
  void addFrame (const std::vector<BodyPartDetection> &detections, const std::vector<PartLabel> &labels,
                 const cv::Mat *persons = nullptr);

  /** {"persons", "person_recall", "person_recall_within_4m", "person_recall_any_confidence",
    * "person_recall_any_confidence_within_4m", "firing_confidence", "bands": [{"metres":
    * [lo, hi], "persons", "person_recall", "person_recall_any_confidence", "ap": {...}}],
    * "non_person_detections_per_frame" (null without person images)} */
  nlohmann::json report () const;

  nlohmann::json state () const;
  /** \throws std::invalid_argument naming source on a malformed state */
  static PersonEvaluation fromState (const nlohmann::json &state, const std::string &source);
  void merge (const PersonEvaluation &other);

private:
  float radius_;
  std::array<DetectionEvaluation, kBands> bands_;
  /** Per band, the last slot beyond the bands: persons, found at any confidence, found by
    * a firing detection. */
  std::array<int, kBands + 1> persons_{}, found_{}, found_firing_{};
  int frames_ = 0, frames_with_person_images_ = 0, non_person_detections_ = 0;
};
}  // namespace agex
