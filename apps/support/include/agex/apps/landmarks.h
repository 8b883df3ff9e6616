#pragma once
// What the 2D landmark apps share around the library (agex::landmarks): their flags, the
// inputs they check outputs against, progress lines, overlays and writers. Kept out of
// agex_app_support so that the depth apps need no dlib.

#include <agex/io/atomic_file.h>
#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/landmark_dataset.h>
#include <agex/landmarks/landmark_evaluation.h>
#include <agex/landmarks/landmark_training.h>
#include <agex/landmarks/people_detector.h>
#include <agex/landmarks/people_landmarks.h>

#include <boost/program_options/options_description.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
namespace apps
{
/** Loads the imglab datasets (agex::loadLandmarkDataset), their images in the order given, and
  * warns on standard error about each one's boxes without contour landmarks (ignore regions). */
std::vector<AnnotatedImage> loadLandmarkDatasets (const std::vector<std::string> &xml_paths);

/** Flags of dlib's shape predictor trainer (defaults from params). */
boost::program_options::options_description shapeTrainerOptions (ShapePredictorTrainingParams &params);
/** Flags of the people detector trainer (defaults from training). */
boost::program_options::options_description detectorTrainerOptions (PeopleDetectorTraining &training);

/** Person crops (agex::PeopleCrops) an app reads: a folder, the person's box in each crop, and
  * which fold of them it uses. */
struct PeopleCropChoice
{
  std::string folder;  ///< empty: no crops
  std::string box = "24,32,48,96";  ///< x,y,width,height: INRIA's 96x160 crops hold a 64x128 window at 16,16 whose middle 0.75 is the person
  int folds = 5;
  int fold = -1;  ///< training: this fold is left out; scoring: only this fold is used (-1: all)
};
/** --detector-crops, --detector-crops-box, --detector-crops-folds, --detector-crops-held-out
  * (training), and the crop placement settings of training. */
boost::program_options::options_description detectorCropOptions (PeopleCropChoice &choice, PeopleDetectorTraining &training);
/** \brief Reads the crops (nullptr for no folder) and the indices the app uses: for training
  * (test = false) all but choice.fold, for scoring (test = true) choice.fold or, for -1, all.
  * \throws std::runtime_error naming the folder or the bad setting */
std::shared_ptr<const PeopleCrops> loadPeopleCrops (const PeopleCropChoice &choice, bool test,
                                                    std::vector<std::size_t> &which);

/** bundledDataFile ("models/agex_people_detector.svm"), the 2D apps' default people detector. */
std::string bundledPeopleDetectorFile ();

/** Which people detector an app uses: the bundled one, a file, or OpenCV's (only when asked). */
struct PeopleDetectorChoice
{
  std::string path;     ///< empty: the bundled detector; kOpenCvHogName: OpenCV's
  bool opencv = false;  ///< OpenCV's pretrained HOG people detector
  double opencv_scale = 0.5;
  bool none = false;    ///< no detection (agex_landmarks_eval --no-detector)
  /** More detector files, each FILE or FILE@OFFSET, run with the first as one (PeopleDetector::combine). */
  std::vector<std::string> also;
};
/** The --detector value that selects OpenCV's pretrained HOG people detector. */
constexpr const char *kOpenCvHogName = "opencv-hog";
/** --detector, --opencv-detector, --opencv-scale. */
boost::program_options::options_description detectorChoiceOptions (PeopleDetectorChoice &choice);
/** \throws std::runtime_error for contradicting flags or a file that is no detector */
PeopleDetector loadPeopleDetector (const PeopleDetectorChoice &choice);
/** \brief The file and offset an item of --detector-also or --combine names: FILE@OFFSET (the
  * offset in [-5, 5]), or FILE at 0 (also when the whole item, '@' and all, is a file).
  * \throws std::runtime_error naming flag and the item for a bad offset */
std::pair<std::string, double> detectorFileAndOffset (const std::string &item, const std::string &flag);
/** \brief members and offsets, then the detectors items name (detectorFileAndOffset), as one
  * (PeopleDetector::combine). \throws std::runtime_error naming flag (and the item) for a bad
  * offset, a file that is no detector, or more than 8 members in all */
PeopleDetector combineDetectorFiles (std::vector<PeopleDetector> members, std::vector<double> offsets,
                                     const std::vector<std::string> &items, const std::string &flag);

/** The images a landmark app reads, and every file it reads (no output may land on one). */
struct LandmarkInputs
{
  std::vector<AnnotatedImage> images;  ///< the tested datasets' images, then the --train-also ones
  std::size_t tested = 0;              ///< how many of images are tested
  InputFiles read;
};

/** \brief Loads the datasets (tested, then training-only) and checks that no output (empty
  * ones skipped) is one of the files read: the datasets, their images and other_inputs
  * (models). \throws std::runtime_error */
LandmarkInputs loadLandmarkInputs (const std::vector<std::string> &tested, const std::vector<std::string> &train_also,
                                   const std::vector<std::string> &other_inputs, const std::vector<std::string> &outputs);

/** agex_landmarks_eval's flags. */
struct LandmarkEvaluationFlags
{
  std::vector<std::string> datasets, train_also;
  std::string model, json, overlay_dir;
  int folds = 0;
  bool train_detector = false;
  PeopleDetectorChoice detector;
  LandmarkEvaluationSettings settings;
  ShapePredictorTrainingParams shape_params;
  PeopleDetectorTraining detector_training;
  PeopleCropChoice crops;  ///< --crops: crops pasted into the tested images, scored under "crops"
};
/** Every flag of agex_landmarks_eval, bound to flags. */
boost::program_options::options_description landmarkEvaluationOptions (LandmarkEvaluationFlags &flags);
/** \throws std::runtime_error for flags that contradict each other or are out of range */
void checkLandmarkEvaluationFlags (const LandmarkEvaluationFlags &flags);

/** \brief Refuses --out (a shape predictor) and --detector-out (a people detector, if given)
  * unless each path is free, empty, or holds an earlier model of its kind (it loads as one).
  * \throws std::runtime_error naming the path */
void checkLandmarkModelOutputs (const std::string &shape_model, const std::string &detector, const InputFiles &inputs);

/** \brief Writes overlay_dir/<image stem>.png, the image with the landmarks the predictor
  * places in its true boxes, for each image scored; empty overlay_dir: nothing. Every tested
  * image's PNG is checked before anything is written: none may land on an input or replace a
  * file there that is not an earlier agex PNG. \throws std::runtime_error naming the path */
ScoredImageCallback landmarkOverlayWriter (const std::string &overlay_dir, const LandmarkInputs &inputs);
/** A line per fold on standard error as it starts and when it is scored; image_scored as given. */
CrossValidationCallbacks crossValidationProgress (const ScoredImageCallback &image_scored);

/** Draws boxes and landmarks (coloured by index, the head top larger, the five anchors 0, 36,
  * 72, 108, 144 numbered) on a BGR copy. */
cv::Mat renderLandmarkOverlay (const cv::Mat &image, const std::vector<LandmarkedPerson> &people);

/** JSON of one person: box, score, landmarks as [[x, y], ...]. */
nlohmann::json landmarkedPersonJson (const LandmarkedPerson &person);

/** {"source", "people", "ms": {"detect", "landmarks"}}. */
nlohmann::json landmarkedFrameJson (const std::string &source, const LandmarkedFrame &frame);

/** agex::landmarkPeople run `runs` times on one image: the people of the first run, the
  * fastest time of each stage (timing on a busy machine). */
LandmarkedFrame landmarkPeopleFastest (const cv::Mat &image, const PeopleDetector &detector,
                                       const ContourShapePredictor &predictor, double threshold, int runs);

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

/** \brief Refuses agex_landmarks' outputs (json, lines, overlay; empty ones skipped) where one
  * would replace an input: the images, the model, the video, or, for the overlay, a frame of
  * the image-sequence video (frames/f%03d.png reads every file its pattern matches).
  * \throws std::runtime_error */
void checkLandmarkOutputs (const std::string &json, const std::string &lines, const std::string &overlay,
                           const std::vector<std::string> &images, const std::string &model, const std::string &video);

/** \brief Reads a video file, image sequence or camera number frame by frame until its end,
  * max_frames (0: all) or Ctrl-C, calling on_frame (source "VIDEO#n", frame) for each.
  * \return the frames read. \throws std::runtime_error naming the video when it cannot be
  * opened or yields no frame */
int readVideo (const std::string &video, int max_frames,
               const std::function<void (const std::string &, const cv::Mat &)> &on_frame);
}  // namespace apps
}  // namespace agex
