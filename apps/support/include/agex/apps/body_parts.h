#pragma once
// Body-part identification as the apps run it: AGEX points from the depth
// pipeline -> orientation-normalised depth patches (agex::DepthPatchEstimation)
// -> the boosted patch classifier (agex::PatchClassifier) -> detections sorted by
// confidence. Also what training and evaluation need around it.

#include <agex/apps/depth_pipeline.h>
#include <agex/common/dataset.h>
#include <agex/common/point_types.h>

#include <nlohmann/json.hpp>

#include <array>
#include <random>
#include <string>
#include <vector>

namespace agex
{
class PatchClassifier;

namespace apps
{
/** Patch parameters (agex::DepthPatchEstimation); stored in every model. */
struct PatchParams
{
  int size = 41;
  float extent = 0.6f;  ///< metres across
  float clamp = 0.3f;   ///< metres
  /** Detections of a class closer than this to a more confident one are dropped. */
  float suppression_radius = 0.15f;
};

struct Detection
{
  BodyPart part = BodyPart::Head;
  float confidence = 0.f;  ///< in [0, 1]
  float margin = 0.f;      ///< boosted margin of that class
  agex::InterestPoint point;
};

/** Everything a model needs to be applied as it was trained. */
struct DetectorSettings
{
  PipelineParams pipeline;
  PatchParams patch;
  nlohmann::json toJson () const;
  /** \throws std::runtime_error on a malformed settings object */
  static DetectorSettings fromJson (const nlohmann::json &doc);
};

/** Depth patches of interest points (in order) on the pipeline's filtered frame. */
void computePatches (const PipelineResult &prepared, const pcl::PointCloud<agex::InterestPoint> &points,
                     const PatchParams &params, std::vector<agex::DepthPatch> &patches);

/** \brief Classifies every interest point of a prepared frame: per point its most
  * confident class, sorted by confidence (highest first), after non-maximum
  * suppression per class within params.suppression_radius. */
std::vector<Detection> detectBodyParts (const PipelineResult &prepared, const agex::PatchClassifier &classifier,
                                        const PatchParams &params, double *patch_ms = nullptr,
                                        double *classify_ms = nullptr);

nlohmann::json detectionJson (const Detection &d);

/** Training examples from one labelled frame: every interest point (positive for class
  * c when within radius of a visible tip of class c, the nearest such tip's class; else
  * background, label -1) and random_negatives random mesh points with random in-plane
  * orientations, farther than 1.5 radius from every tip (label -1). */
void collectTrainingSamples (const PipelineResult &prepared, const std::vector<PartLabel> &labels, float radius,
                             int random_negatives, const PatchParams &patch, std::mt19937_64 &rng,
                             std::vector<agex::DepthPatch> &patches, std::vector<int> &classes);

/** \brief The paper's detection evaluation: a detection is correct when it names the class
  * of a labelled tip within radius that no more confident detection took. */
class DetectionEvaluation
{
public:
  explicit DetectionEvaluation (float radius) : radius_ (radius) {}
  void addFrame (const std::vector<Detection> &detections, const std::vector<PartLabel> &labels);
  /** Average precision of a class (area under the interpolated precision-recall curve). */
  double averagePrecision (BodyPart part) const;
  /** (recall, precision) points as the threshold falls. */
  std::vector<std::pair<double, double>> precisionRecall (BodyPart part) const;
  /** Rows: truth (head, hand, foot, background); columns: predicted (head, hand, foot,
    * none), counting detections at or above the threshold and tips nothing found. */
  std::array<std::array<int, 4>, 4> confusion (float threshold) const;
  double orientationMedianDeg (BodyPart part) const;
  int frames () const { return frames_; }
  nlohmann::json report (float confusion_threshold) const;

private:
  struct Scored
  {
    float confidence;
    bool correct;
  };
  float radius_;
  int frames_ = 0;
  std::array<std::vector<Scored>, kBodyPartCount> scored_;
  std::array<int, kBodyPartCount> positives_{};
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
}  // namespace apps
}  // namespace agex
