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
  /** Sliding windows: the window's extent over the trained one (AGEX points: 1). */
  float scale = 1.f;
};

/** The detector a model was trained for (its patches are cut differently). */
enum class DetectorKind
{
  Agex,          ///< AGEX points, patches oriented along the point's orientation
  SlidingWindow  ///< every window position, upright patches (agex::SlidingWindowDetector)
};
const char *detectorKindName (DetectorKind kind);

/** Window layout of a sliding-window model (agex::SlidingWindowDetector). */
struct SlidingWindowParams
{
  int stride = 3;                      ///< pixels between window centres
  std::vector<float> scales{1.f};      ///< window extents over the trained extent
};

/** Everything a model needs to be applied as it was trained. */
struct DetectorSettings
{
  PipelineParams pipeline;
  PatchParams patch;
  DetectorKind detector = DetectorKind::Agex;  ///< models without the field are AGEX models
  SlidingWindowParams sliding_window;          ///< used by sliding-window models only
  nlohmann::json toJson () const;
  /** \throws std::runtime_error on a malformed settings object */
  static DetectorSettings fromJson (const nlohmann::json &doc);
  /** \throws std::runtime_error naming model_path when detector is not expected */
  void requireDetector (DetectorKind expected, const std::string &model_path) const;
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

/** \brief Sliding-window training examples from one labelled frame, all upright:
  * per visible tip, the mesh pixel nearest to it in 3D (within radius) and up to jitter more
  * random mesh pixels within jitter_radius of the tip (positives of the tip's class; a
  * window stride apart from the tip must still fire), and random_negatives random mesh
  * pixels farther than 1.5 radius from every tip (background, label -1). */
void collectWindowTrainingSamples (const PipelineResult &prepared, const std::vector<PartLabel> &labels,
                                   float radius, int jitter, float jitter_radius, int random_negatives,
                                   const PatchParams &patch, std::mt19937_64 &rng,
                                   std::vector<agex::DepthPatch> &patches, std::vector<int> &classes);
/** A box in pixels: [u0, u1) x [v0, v1). */
struct PixelBox
{
  float u0 = 0.f, v0 = 0.f, u1 = 0.f, v1 = 0.f;
};

/** The physical side (metres) of a body part's box for the overlap criterion: head 0.25,
  * hand 0.15, foot 0.20 (doc/results.md). */
float partBoxSide (BodyPart part);

/** The square of partBoxSide (part) * scale metres at depth z, projected with focal length
  * focal (pixels), centred on pixel (u, v) (the pixel's centre is u + 0.5, v + 0.5). */
PixelBox partBox (BodyPart part, float u, float v, float z, float scale, float focal);

/** Intersection over union of two boxes (0 if either is empty). */
float intersectionOverUnion (const PixelBox &a, const PixelBox &b);

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
  /** How well d fits l under the criterion (larger is better); negative: no match. */
  float matchQuality (const Detection &d, const PartLabel &l) const;
  /** The label (any class) that d fits best, or -1. */
  int bestLabel (const Detection &d, const std::vector<PartLabel> &labels) const;

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
