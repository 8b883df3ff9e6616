#include <agex/landmarks/landmark_evaluation.h>

#include <agex/common/statistics.h>
#include <agex/landmarks/contour_annotation.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <limits>
#include <cmath>
#include <stdexcept>

namespace agex
{
namespace
{
nlohmann::json
meanOf (double sum, std::size_t n)
{
  if (n == 0)
    return nullptr;
  return sum / n;
}
}  // namespace

void
LandmarkEvaluation::add (const AnnotatedImage &image, const ContourShapePredictor &predictor,
                         const PeopleDetector *detector, double threshold)
{
  addLandmarks (image, predictor);
  if (!detector)
    return;
  std::vector<cv::Rect> people;
  for (const AnnotatedPerson &person : image.people)
    people.push_back (person.tight_box);
  addDetection (image.grey, people, image.ignored, *detector, threshold);
}

void
LandmarkEvaluation::addLandmarks (const AnnotatedImage &image, const ContourShapePredictor &predictor)
{
  ++images_;
  const auto start = std::chrono::steady_clock::now ();
  for (const AnnotatedPerson &person : image.people)
  {
    const std::vector<cv::Point2f> predicted = predictor.predict (image.grey, person.box);
    if (predicted.size () != person.landmarks.size ())
      throw std::runtime_error ("the model predicts " + std::to_string (predicted.size ()) + " landmarks, the dataset has " +
                                std::to_string (person.landmarks.size ()));
    double error = 0;
    for (std::size_t i = 0; i < predicted.size (); ++i)
      error += cv::norm (predicted[i] - person.landmarks[i]);
    error /= predicted.size ();
    const double box_height = std::max (1, person.box.height);
    ++people_;
    sum_error_px_ += error;
    sum_error_box_ += error / box_height;
    if (person.has_shoulders)
    {
      const double shoulder_width = cv::norm (person.shoulders[0] - person.shoulders[1]);
      if (shoulder_width > 1.0)
      {
        ++shoulder_people_;
        sum_error_shoulder_ += error / shoulder_width;
      }
    }
    const double contour = meanDistanceToClosedPolyline (predicted, person.landmarks);
    sum_contour_ += contour;
    sum_contour_box_ += contour / box_height;
  }
  landmark_ms_ += msSince (start);
}

void
LandmarkEvaluation::addDetection (const cv::Mat &grey, const std::vector<cv::Rect> &people,
                                  const std::vector<cv::Rect> &ignored, const PeopleDetector &detector, double threshold)
{
  detect (detection_, grey, people, ignored, detector, threshold);
}

void
LandmarkEvaluation::addPastedDetection (const cv::Mat &grey, const std::vector<cv::Rect> &people,
                                        const std::vector<cv::Rect> &ignored, const PeopleDetector &detector,
                                        double threshold)
{
  detect (pasted_, grey, people, ignored, detector, threshold);
}

void
LandmarkEvaluation::addCropDetection (const cv::Mat &grey, const std::vector<cv::Rect> &people,
                                      const std::vector<cv::Rect> &ignored, const PeopleDetector &detector, double threshold)
{
  detect (crops_, grey, people, ignored, detector, threshold);
}

void
LandmarkEvaluation::detect (DetectionScores &scores, const cv::Mat &grey, const std::vector<cv::Rect> &people,
                            const std::vector<cv::Rect> &ignored, const PeopleDetector &detector, double threshold) const
{
  ++scores.images;
  const auto start = std::chrono::steady_clock::now ();
  const std::vector<PersonDetection> detections = detector.detect (grey, threshold - kApScoreMargin);
  scores.ms += msSince (start);
  addDetections (scores, people, ignored, detections, threshold);
}

void
LandmarkEvaluation::addDetections (DetectionScores &scores, const std::vector<cv::Rect> &people,
                                   const std::vector<cv::Rect> &ignore_regions,
                                   const std::vector<PersonDetection> &detections, double threshold) const
{
  std::vector<cv::Rect> truths, ignored;
  for (const cv::Rect &person : people)
    (person.height >= min_detection_height_ ? truths : ignored).push_back (uprightBox (person, kMatchAspect));
  for (const cv::Rect &region : ignore_regions)
    ignored.push_back (region);
  scores.truths += truths.size ();
  // Greedy one-to-one matching, best scores first (detections come sorted by score).
  std::vector<bool> used (truths.size (), false);
  for (const PersonDetection &d : detections)
  {
    const cv::Rect box = uprightBox (d.box, kMatchAspect);
    int best = -1;
    double best_iou = 0.5;
    for (std::size_t t = 0; t < truths.size (); ++t)
    {
      const double iou = boxIoU (box, truths[t]);
      if (!used[t] && iou >= best_iou)
      {
        best_iou = iou;
        best = static_cast<int> (t);
      }
    }
    const bool above = d.score >= threshold;
    if (best >= 0)
    {
      used[best] = true;
      scores.scored.emplace_back (d.score, true);
      scores.found += above;
      continue;
    }
    // On an ignore region (an ignore box, a person too short to count, a box without
    // landmarks), or shorter than the people that count: neither hit nor false detection.
    const bool on_ignored = std::any_of (ignored.begin (), ignored.end (), [&] (const cv::Rect &r) {
      return boxIoU (box, uprightBox (r, kMatchAspect)) >= 0.5 || (box & r).area () >= 0.5 * box.area ();
    });
    if (on_ignored || d.box.height < min_detection_height_)
      continue;
    scores.scored.emplace_back (d.score, false);
    scores.false_detections += above;
  }
}

double
recallAtFalseDetections (std::vector<std::pair<double, bool>> scored, std::size_t positives, std::size_t images,
                         double max_per_image, double *score)
{
  if (score)
    *score = std::numeric_limits<double>::infinity ();
  if (positives == 0 || images == 0)
    return 0.0;
  std::sort (scored.begin (), scored.end (), [] (const std::pair<double, bool> &a, const std::pair<double, bool> &b) {
    return a.first > b.first;
  });
  std::size_t hits = 0, misses = 0, best_hits = 0;
  for (std::size_t i = 0; i < scored.size ();)
  {
    // Detections of equal score are kept or dropped together: one threshold cannot split them.
    std::size_t j = i;
    for (; j < scored.size () && scored[j].first == scored[i].first; ++j)
      (scored[j].second ? hits : misses) += 1;
    if (static_cast<double> (misses) > max_per_image * static_cast<double> (images))
      break;
    best_hits = hits;
    if (score)
      *score = scored[i].first;
    i = j;
  }
  return static_cast<double> (best_hits) / static_cast<double> (positives);
}

nlohmann::json
LandmarkEvaluation::DetectionScores::json (int min_height) const
{
  nlohmann::json doc;
  doc["detection_people"] = truths;
  doc["detection_min_height"] = min_height;
  doc["detection_recall"] = meanOf (static_cast<double> (found), truths);
  doc["detection_ap"] = truths ? nlohmann::json (averagePrecision (scored, truths)) : nlohmann::json (nullptr);
  doc["false_detections_per_image"] = meanOf (static_cast<double> (false_detections), images);
  double at = 0.0;
  const double recall = recallAtFalseDetections (scored, truths, images, 0.1, &at);
  doc["recall_at_0.1_fppi"] = truths && images ? nlohmann::json (recall) : nlohmann::json (nullptr);
  doc["score_at_0.1_fppi"] = truths && images && std::isfinite (at) ? nlohmann::json (at) : nlohmann::json (nullptr);
  doc["detection_images"] = images;
  doc["ms_per_image_detect"] = meanOf (ms, images);
  return doc;
}

nlohmann::json
LandmarkEvaluation::json () const
{
  nlohmann::json doc = detection_.json (min_detection_height_);
  doc["images"] = images_;
  doc["people"] = people_;
  doc["mean_error_px"] = meanOf (sum_error_px_, people_);
  doc["mean_error_box_height"] = meanOf (sum_error_box_, people_);
  doc["mean_error_shoulder_width"] = meanOf (sum_error_shoulder_, shoulder_people_);
  doc["people_with_shoulders"] = shoulder_people_;
  doc["mean_contour_distance_px"] = meanOf (sum_contour_, people_);
  doc["mean_contour_distance_box_height"] = meanOf (sum_contour_box_, people_);
  doc["ms_per_image"] = {{"detect", meanOf (detection_.ms, detection_.images)}, {"landmarks", meanOf (landmark_ms_, images_)}};
  doc["ms_per_person_landmarks"] = meanOf (landmark_ms_, people_);
  doc.erase ("ms_per_image_detect");
  if (pasted_.images > 0)
    doc["pasted"] = pasted_.json (min_detection_height_);
  if (crops_.images > 0)
    doc["crops"] = crops_.json (min_detection_height_);
  return doc;
}

nlohmann::json
evaluateLandmarks (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &test,
                   const ContourShapePredictor &predictor, const PeopleDetector *detector,
                   const LandmarkEvaluationSettings &settings, LandmarkEvaluation &pooled,
                   const ScoredImageCallback &on_image)
{
  LandmarkEvaluation part;
  part.setMinDetectionHeight (settings.min_detection_height);
  pooled.setMinDetectionHeight (settings.min_detection_height);
  for (const std::size_t i : test)
  {
    part.add (images[i], predictor, detector, settings.threshold);
    pooled.add (images[i], predictor, detector, settings.threshold);
    if (on_image)
      on_image (images[i], predictor);
  }
  nlohmann::json doc = part.json ();
  if (settings.pasted && detector)
  {
    LandmarkEvaluation pasted;
    pasted.setMinDetectionHeight (settings.min_detection_height);
    const PeopleImages composites = pastedPeopleImages (images, test, settings.pasted_params);
    for (std::size_t c = 0; c < composites.images.size (); ++c)
    {
      pasted.addDetection (composites.images[c], composites.boxes[c], composites.ignore[c], *detector, settings.threshold);
      pooled.addPastedDetection (composites.images[c], composites.boxes[c], composites.ignore[c], *detector,
                                 settings.threshold);
    }
    doc["pasted"] = pasted.detectionJson ();
  }
  if (settings.crops && !settings.crop_which.empty () && detector)
  {
    LandmarkEvaluation crops;
    crops.setMinDetectionHeight (settings.min_detection_height);
    const PeopleImages composites = pasteCrops (images, test, *settings.crops, settings.crop_which, settings.crop_params);
    for (std::size_t c = 0; c < composites.images.size (); ++c)
    {
      crops.addDetection (composites.images[c], composites.boxes[c], composites.ignore[c], *detector, settings.threshold);
      pooled.addCropDetection (composites.images[c], composites.boxes[c], composites.ignore[c], *detector,
                               settings.threshold);
    }
    doc["crops"] = crops.detectionJson ();
  }
  return doc;
}

nlohmann::json
crossValidateLandmarks (const std::vector<AnnotatedImage> &images, std::size_t tested_images, int folds,
                        const ShapePredictorTrainingParams &shape_params,
                        const PeopleDetectorTraining *detector_training, const PeopleDetector *detector,
                        const LandmarkEvaluationSettings &settings, const CrossValidationCallbacks &callbacks)
{
  if (folds < 2 || static_cast<std::size_t> (folds) > tested_images)
    throw std::runtime_error ("the dataset has " + std::to_string (tested_images) + " images, fewer than " +
                              std::to_string (folds) + " folds");
  LandmarkEvaluation pooled;
  nlohmann::json per_fold = nlohmann::json::array ();
  for (int f = 0; f < folds; ++f)
  {
    std::vector<std::size_t> train, test;
    for (std::size_t i = 0; i < images.size (); ++i)
      (i < tested_images && static_cast<int> (i % folds) == f ? test : train).push_back (i);
    if (callbacks.fold_started)
      callbacks.fold_started (f, folds, train.size (), test.size ());
    const ContourShapePredictor predictor = trainContourShapePredictor (images, train, shape_params);
    std::unique_ptr<PeopleDetector> fold_detector;
    if (detector_training)
      fold_detector = std::make_unique<PeopleDetector> (trainPeopleDetector (images, train, *detector_training));
    per_fold.push_back (evaluateLandmarks (images, test, predictor, fold_detector ? fold_detector.get () : detector,
                                           settings, pooled, callbacks.image_scored));
    if (callbacks.fold_scored)
      callbacks.fold_scored (f, folds, per_fold.back ());
  }
  nlohmann::json doc = pooled.json ();
  doc["folds"] = folds;
  doc["per_fold"] = per_fold;
  return doc;
}
}  // namespace agex
