#pragma once
// Code the 2D landmark apps share: annotated datasets in memory, trainer flags,
// evaluation and overlays. Kept out of agex_app_support so that the depth apps need no dlib.

#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/landmarks/pasted_people.h>
#include <agex/landmarks/people_detector.h>
#include <agex/io/atomic_file.h>

#include <boost/program_options/options_description.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <functional>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** A person of an annotated image: square box, 180 contour landmarks, shoulders if known. */
struct AnnotatedPerson
{
  cv::Rect box;        ///< the square box of the XML (the shape predictor's)
  cv::Rect tight_box;  ///< the landmarks' bounding box: the outline's (detection truth)
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
/** How the people detector is trained: the SVM's settings, and the images it sees. */
struct DetectorTraining
{
  PeopleDetectorTrainingParams params;
  /** Train on the people pasted into each other's photos (agex::pastePeople): people that fill
    * their photos alone teach the detector that a person fills the frame. */
  bool paste_people = true;
  /** Train on the photos as they are (too). */
  bool originals = true;
  PastedPeopleParams pasted;
};
/** Flags of the people detector trainer (defaults from training). */
boost::program_options::options_description detectorTrainerOptions (DetectorTraining &training);

/** Trains the shape predictor on the listed images (mirrored copies added). */
ContourShapePredictor trainShapePredictor (const std::vector<AnnotatedImage> &images,
                                           const std::vector<std::size_t> &which,
                                           ShapePredictorTrainingParams params);
/** Trains the people detector on the listed images (their outlines' boxes; ignore boxes are
  * ignore regions). */
PeopleDetector trainPeopleDetector (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                                    const DetectorTraining &training, std::size_t *ignored = nullptr);

/** The listed images with people pasted into each other's photos (agex::pastePeople): the
  * pasted people are the people, the photos' own people and ignore boxes ignore regions. */
PeopleImages pastedPeopleImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                                 const PastedPeopleParams &params);

/** bundledDataFile ("models/agex_people_detector.svm"), the 2D apps' default people detector. */
std::string bundledPeopleDetectorFile ();

/** Which people detector an app uses: the bundled one, a file, or OpenCV's (only when asked). */
struct DetectorChoice
{
  std::string path;     ///< empty: the bundled detector
  bool opencv = false;  ///< OpenCV's pretrained HOG people detector
  double opencv_scale = 0.5;
  bool none = false;    ///< no detection (agex_landmarks_eval --no-detector)
};
/** --detector, --opencv-detector, --opencv-scale. */
boost::program_options::options_description detectorChoiceOptions (DetectorChoice &choice);
/** \throws std::runtime_error for contradicting flags or a file that is no detector */
PeopleDetector loadDetector (const DetectorChoice &choice);

/** Scores landmarks and people detection over images (agex_landmarks_eval). */
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
  nlohmann::json json () const;
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
  DetectionScores detection_, pasted_;
};

/** How agex_landmarks_eval scores. */
struct EvaluationSettings
{
  double threshold = 0.0;        ///< detection threshold for recall and false detections
  int min_detection_height = 0;  ///< shorter people are ignore regions for detection
  std::string overlay_dir;       ///< a PNG per tested image with the predicted landmarks (empty: none)
  /** Also score detection on the tested images' people pasted into each other's photos
    * (several people per image, many sizes, real backgrounds), under "pasted". */
  bool pasted = false;
  PastedPeopleParams pasted_params;
};

/** The images an evaluation reads, and every file it reads (no output may land on one). */
struct EvaluationInputs
{
  std::vector<AnnotatedImage> images;  ///< the tested datasets' images, then the --train-also ones
  std::size_t tested = 0;              ///< how many of images are tested
  InputFiles read;
};

/** \brief Loads the datasets (tested, then training-only) and checks that json_path (when given)
  * is none of the files read: the datasets, their images and other_inputs (models).
  * \throws std::runtime_error */
EvaluationInputs loadEvaluationInputs (const std::vector<std::string> &tested, const std::vector<std::string> &train_also,
                                       const std::vector<std::string> &other_inputs, const std::string &json_path);

/** \brief Scores predictor (and detector, when given) on images[test] into pooled; returns this
  * part's scores (LandmarkEvaluation::json). Overlays are checked against inputs. */
nlohmann::json evaluateImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &test,
                               const ContourShapePredictor &predictor, const PeopleDetector *detector,
                               const EvaluationSettings &settings, const InputFiles &inputs, LandmarkEvaluation &pooled);

/** \brief Cross-validation by image: of the first tested_images images, image i is in fold
  * i mod folds; each fold is scored by a shape predictor (and, with detector_params, a people
  * detector) trained on all other images, the images after tested_images included (--train-also);
  * without detector_training, detector (may be null) scores every fold. Returns the pooled scores
  * with "folds" and "per_fold". \throws std::runtime_error for fewer images than folds */
nlohmann::json crossValidate (const std::vector<AnnotatedImage> &images, std::size_t tested_images, int folds,
                              const ShapePredictorTrainingParams &shape_params,
                              const DetectorTraining *detector_training, const PeopleDetector *detector,
                              const EvaluationSettings &settings, const InputFiles &inputs);

/** Average precision (all-point interpolated, as PASCAL VOC since 2010) of scored detections
  * (score, true positive) against truths people. */
double averagePrecision (std::vector<std::pair<double, bool>> scored, std::size_t truths);

/** A person found in an image: box, detection score and landmarks. */
struct LandmarkedPerson
{
  cv::Rect box;
  double score = 0.0;
  std::vector<cv::Point2f> landmarks;
};

/** Draws boxes and landmarks (coloured by index, the head top larger, the five anchors 0, 36,
  * 72, 108, 144 numbered) on a BGR copy. */
cv::Mat renderLandmarkOverlay (const cv::Mat &image, const std::vector<LandmarkedPerson> &people);

/** JSON of one person: box, score, landmarks as [[x, y], ...]. */
nlohmann::json landmarkedPersonJson (const LandmarkedPerson &person);

/** The people of one image or frame and the time each stage took. */
struct LandmarkedFrame
{
  std::vector<LandmarkedPerson> people;
  double detect_ms = 0, landmarks_ms = 0;
};

/** Detects the people and places each one's landmarks in the square of its box. */
LandmarkedFrame landmarkFrame (const cv::Mat &image, const PeopleDetector &detector,
                               const ContourShapePredictor &predictor, double threshold);
/** {"source", "people", "ms": {"detect", "landmarks"}}. */
nlohmann::json landmarkedFrameJson (const std::string &source, const LandmarkedFrame &frame);

/** What agex_landmarks writes: the frames as one JSON document, as JSON lines (or streamed
  * to standard output as they come), and an overlay of the last frame. */
class LandmarkOutputs
{
public:
  /** stream_lines: print each frame's JSON line on standard output as it is added (the
    * one-line summaries go to standard error then). */
  explicit LandmarkOutputs (bool stream_lines) : stream_lines_ (stream_lines) {}
  void add (const std::string &source, const cv::Mat &image, LandmarkedFrame frame);
  /** Writes the outputs that have a path, atomically; header is the JSON document's other keys. */
  void write (nlohmann::json header, const std::string &json_path, const std::string &lines_path,
              const std::string &overlay_path) const;

private:
  bool stream_lines_;
  nlohmann::json frames_ = nlohmann::json::array ();
  cv::Mat last_image_;
  LandmarkedFrame last_;
};

/** \throws std::runtime_error when overlay would replace a frame of the image-sequence video
  * (frames/f%03d.png reads every file its pattern matches). */
void checkNotInImageSequence (const std::string &overlay, const std::string &video);

/** \brief Reads a video file, image sequence or camera number frame by frame until its end,
  * max_frames (0: all) or Ctrl-C, calling on_frame (source "VIDEO#n", frame) for each.
  * \return the frames read. \throws std::runtime_error naming the video when it cannot be
  * opened or yields no frame */
int readVideo (const std::string &video, int max_frames,
               const std::function<void (const std::string &, const cv::Mat &)> &on_frame);
}  // namespace apps
}  // namespace agex
