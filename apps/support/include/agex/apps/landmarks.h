#pragma once
// Code the 2D landmark apps share: annotated datasets in memory, trainer flags,
// evaluation and overlays. Kept out of agex_app_support so that the depth apps need no dlib.

#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/landmarks/people_detector.h>

#include <boost/program_options/options_description.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** A person of an annotated image: square box, 180 contour landmarks, shoulders if known. */
struct AnnotatedPerson
{
  cv::Rect box;
  std::vector<cv::Point2f> landmarks;
  bool has_shoulders = false;
  cv::Point2f shoulders[2];
};

struct AnnotatedImage
{
  std::string path;
  cv::Mat grey;
  std::vector<AnnotatedPerson> people;
  std::vector<cv::Rect> ignored;  ///< boxes marked ignore or without all landmarks
};

/** \brief Reads an image for the 2D apps (cv::imread flags). Refuses, naming the file and
  * what it was needed for (role, e.g. "an image of dataset.xml"): unreadable or undecodable
  * files, images over agex::kMaxFramePixels (checked in a PNG or JPEG header before any
  * decoding), and truncated JPEGs, which OpenCV would decode with a warning and grey rows.
  * \throws std::runtime_error */
cv::Mat readImage (const std::string &path, int flags, const std::string &role = "");

/** \brief Loads a contour shape predictor and checks that it places the
  * kContourLandmarkCount landmarks the apps draw and score. \throws std::runtime_error */
ContourShapePredictor loadContourModel (const std::string &path);

/** Part names for the shoulders in our imglab files (from COCO keypoints). */
extern const char *const kShoulderPartNames[2];

/** Loads an imglab dataset of contour landmarks and its images (grey).
  * \throws std::runtime_error naming the file and the problem */
std::vector<AnnotatedImage> loadLandmarkDataset (const std::string &xml_path);
/** Several datasets, their images in the order given. */
std::vector<AnnotatedImage> loadLandmarkDatasets (const std::vector<std::string> &xml_paths);

/** Flags of dlib's shape predictor trainer (defaults from params). */
boost::program_options::options_description shapeTrainerOptions (ShapePredictorTrainingParams &params);
/** Flags of the people detector trainer (defaults from params). */
boost::program_options::options_description detectorTrainerOptions (PeopleDetectorTrainingParams &params);

/** Trains the shape predictor on the listed images (mirrored copies added). */
ContourShapePredictor trainShapePredictor (const std::vector<AnnotatedImage> &images,
                                           const std::vector<std::size_t> &which,
                                           ShapePredictorTrainingParams params);
/** Trains the people detector on the listed images. */
PeopleDetector trainPeopleDetector (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                                    const PeopleDetectorTrainingParams &params, std::size_t *ignored = nullptr);

/** Landmark and detection errors accumulated over images (agex_landmarks_eval). */
class LandmarkEvaluation
{
public:
  /** Landmarks predicted in the true boxes; detection recall at IoU > 0.5. */
  void add (const AnnotatedImage &image, const ContourShapePredictor &predictor, const PeopleDetector *detector);
  nlohmann::json json () const;
  double meanErrorPx () const { return people_ ? sum_error_px_ / people_ : 0.0; }

private:
  std::size_t images_ = 0, people_ = 0, shoulder_people_ = 0, detect_images_ = 0, found_ = 0, truths_ = 0;
  double sum_error_px_ = 0, sum_error_box_ = 0, sum_error_shoulder_ = 0, sum_contour_ = 0;
  double detect_ms_ = 0, landmark_ms_ = 0;
};

/** A person found in an image: box, detection score and landmarks. */
struct LandmarkedPerson
{
  cv::Rect box;
  double score = 0.0;
  std::vector<cv::Point2f> landmarks;
};

/** Draws boxes and landmarks (coloured by index, the head top larger) on a BGR copy. */
cv::Mat renderLandmarkOverlay (const cv::Mat &image, const std::vector<LandmarkedPerson> &people);

/** JSON of one person: box, score, landmarks as [[x, y], ...]. */
nlohmann::json landmarkedPersonJson (const LandmarkedPerson &person);
}  // namespace apps
}  // namespace agex
