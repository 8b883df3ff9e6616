#pragma once
// Scores of a contour shape predictor and a people detector on annotated images: landmark
// error (pixels, per box height, per shoulder width), the mean distance to the true contour
// (which does not punish a landmark slid along the outline, as the landmark error does),
// detection recall, false detections per image and average precision; and cross-validation by
// image. Landmarks are predicted in the true boxes, so that their error and the detector's
// stay apart. agex_landmarks_eval reports these; doc/landmarks.md has the figures.

#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/landmark_dataset.h>
#include <agex/landmarks/landmark_training.h>
#include <agex/landmarks/pasted_people.h>
#include <agex/landmarks/people_crops.h>
#include <agex/landmarks/people_detector.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

namespace agex
{
/** Scores landmarks and people detection over images; json () reports them. */
class LandmarkEvaluation
{
public:
  /** Detection truths shorter than this (pixels) are ignore regions, like imglab's ignore
    * boxes: a detection on one is neither a hit nor a false detection ("people at least 150 px
    * tall"). Unmatched detections shorter than it are not counted either. */
  void setMinDetectionHeight (int pixels) { min_detection_height_ = pixels; }
  /** Landmarks predicted in the true boxes. With a detector: detections at and above threshold
    * (recall, false detections per image), and down to threshold - kApScoreMargin for the
    * average precision, each matched one-to-one to the truths at IoU >= 0.5. */
  void add (const AnnotatedImage &image, const ContourShapePredictor &predictor, const PeopleDetector *detector,
            double threshold = 0.0);
  /** Only the landmarks of add (). */
  void addLandmarks (const AnnotatedImage &image, const ContourShapePredictor &predictor);
  /** Only the detection of add (), on any image: people are their outlines' boxes, ignored
    * the ignore regions. */
  void addDetection (const cv::Mat &grey, const std::vector<cv::Rect> &people, const std::vector<cv::Rect> &ignored,
                     const PeopleDetector &detector, double threshold);
  /** As addDetection, into a second set of scores ("pasted" in json ()): people pasted into
    * other photos. */
  void addPastedDetection (const cv::Mat &grey, const std::vector<cv::Rect> &people, const std::vector<cv::Rect> &ignored,
                           const PeopleDetector &detector, double threshold);
  /** images, people, mean_error_px, mean_error_box_height, mean_error_shoulder_width,
    * mean_contour_distance_px / _box_height, detection_* (null where nothing was scored),
    * ms_per_image, and "pasted" / "crops" when pasted people / crops were scored. */
  nlohmann::json json () const;
  /** As addDetection, into a third set of scores ("crops" in json ()): person crops pasted
    * into the tested photos (pasteCrops). */
  void addCropDetection (const cv::Mat &grey, const std::vector<cv::Rect> &people, const std::vector<cv::Rect> &ignored,
                         const PeopleDetector &detector, double threshold);
  /** The detection fields of json () alone. */
  nlohmann::json detectionJson () const { return detection_.json (min_detection_height_); }
  double meanErrorPx () const { return people_ ? sum_error_px_ / people_ : 0.0; }

  static constexpr double kApScoreMargin = 0.5;
  /** Boxes are compared as pedestrian benchmarks do (Caltech): made this wide per height around
    * their centre, so that the IoU scores position and height, not how far the arms reach. */
  static constexpr double kMatchAspect = 0.41;

private:
  struct DetectionScores
  {
    std::size_t images = 0, truths = 0, found = 0, false_detections = 0;
    double ms = 0;
    std::vector<std::pair<double, bool>> scored;  ///< (score, true positive) of every counted detection
    nlohmann::json json (int min_height) const;
  };
  void addDetections (DetectionScores &scores, const std::vector<cv::Rect> &people, const std::vector<cv::Rect> &ignored,
                      const std::vector<PersonDetection> &detections, double threshold) const;
  void detect (DetectionScores &scores, const cv::Mat &grey, const std::vector<cv::Rect> &people,
               const std::vector<cv::Rect> &ignored, const PeopleDetector &detector, double threshold) const;

  std::size_t images_ = 0, people_ = 0, shoulder_people_ = 0;
  int min_detection_height_ = 0;
  double sum_error_px_ = 0, sum_error_box_ = 0, sum_error_shoulder_ = 0, sum_contour_ = 0, sum_contour_box_ = 0;
  double landmark_ms_ = 0;
  DetectionScores detection_, pasted_, crops_;
};

/** Recall at the lowest score threshold that keeps the false detections per image at or below
  * max_per_image (the operating point pedestrian benchmarks and issue 35's targets quote), from
  * (score, true positive) pairs; *score (if not null) receives that threshold (+infinity when
  * none qualifies: recall 0). Only the pairs given count: scored down to a threshold t, a recall
  * reached at t is a lower bound. */
double recallAtFalseDetections (std::vector<std::pair<double, bool>> scored, std::size_t positives, std::size_t images,
                                double max_per_image, double *score = nullptr);

/** How images are scored. */
struct LandmarkEvaluationSettings
{
  double threshold = 0.0;        ///< detection threshold for recall and false detections
  int min_detection_height = 0;  ///< shorter people are ignore regions for detection
  /** Also score detection on the tested images' people pasted into each other's photos
    * (several people per image, many sizes, real backgrounds), under "pasted": photos that each
    * show one person filling the frame say little about a detector on its own. */
  bool pasted = false;
  PastedPeopleParams pasted_params;
  /** When not null: also score detection on crops[crop_which] pasted into the tested images
    * (pasteCrops), under "crops". Not owned. */
  const PeopleCrops *crops = nullptr;
  std::vector<std::size_t> crop_which;
  PastedCropsParams crop_params;
};

/** Called after each tested image is scored, with the shape predictor that scored it (in
  * cross-validation the fold's own), e.g. to draw the predicted landmarks. */
using ScoredImageCallback = std::function<void (const AnnotatedImage &image, const ContourShapePredictor &predictor)>;

/** \brief Scores predictor (and detector, when not null) on images[test], into pooled as well;
  * returns this part's scores (LandmarkEvaluation::json, with "pasted" when settings ask). */
nlohmann::json evaluateLandmarks (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &test,
                                  const ContourShapePredictor &predictor, const PeopleDetector *detector,
                                  const LandmarkEvaluationSettings &settings, LandmarkEvaluation &pooled,
                                  const ScoredImageCallback &on_image = {});

/** What crossValidateLandmarks reports as it goes, for progress lines and overlays (any may
  * be empty). Folds count from 0. */
struct CrossValidationCallbacks
{
  std::function<void (int fold, int folds, std::size_t training_images, std::size_t tested_images)> fold_started;
  std::function<void (int fold, int folds, const nlohmann::json &scores)> fold_scored;
  ScoredImageCallback image_scored;
};

/** \brief Cross-validation by image: of the first tested_images images, image i is in fold
  * i mod folds; each fold is scored by a shape predictor (and, with detector_training, a people
  * detector) trained on all other images, those after tested_images included (training-only
  * images); without detector_training, detector (may be null) scores every fold. Returns the
  * pooled scores with "folds" and "per_fold".
  * \throws std::runtime_error for fewer than 2 folds or fewer tested images than folds */
nlohmann::json crossValidateLandmarks (const std::vector<AnnotatedImage> &images, std::size_t tested_images, int folds,
                                       const ShapePredictorTrainingParams &shape_params,
                                       const PeopleDetectorTraining *detector_training, const PeopleDetector *detector,
                                       const LandmarkEvaluationSettings &settings,
                                       const CrossValidationCallbacks &callbacks = {});
}  // namespace agex
