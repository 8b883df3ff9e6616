#include <agex/apps/landmarks.h>

#include <agex/landmarks/contour_annotation.h>
#include <agex/io/frame_io.h>
#include <agex/io/input_file.h>

#include <boost/program_options/value_semantic.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <agex/apps/command_line.h>
#include <agex/apps/output.h>
#include <agex/io/atomic_file.h>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <regex>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
const char *const kShoulderPartNames[2] = {"left_shoulder", "right_shoulder"};

namespace
{
struct ImageHeader
{
  std::uint64_t width = 0, height = 0;  ///< 0: not found in the header
  bool truncated = false;
};

// Size from a PNG's IHDR or a JPEG's SOF segment, and whether a JPEG reaches its
// end-of-image marker. Segments are walked and entropy-coded data skipped, so data a camera
// appends after the marker does no harm. Anything it cannot parse is left to the decoder.
ImageHeader
probeImage (const std::string &b)
{
  ImageHeader header;
  const auto byte = [&] (std::size_t i) { return static_cast<unsigned char> (b[i]); };
  const std::size_t n = b.size ();
  if (pngHeaderSize (reinterpret_cast<const unsigned char *> (b.data ()), n, header.width, header.height))
    return header;
  if (n < 2 || byte (0) != 0xFF || byte (1) != 0xD8)
    return header;
  std::size_t i = 2;
  while (i < n)
  {
    if (byte (i) != 0xFF)
      return header;  // not a marker where one belongs: let the decoder judge
    while (i < n && byte (i) == 0xFF)
      ++i;  // fill bytes
    if (i >= n)
      break;
    const unsigned char marker = byte (i++);
    if (marker == 0xD9)
      return header;  // end of image
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8))
      continue;  // markers without a segment
    if (i + 2 > n)
      break;
    const std::size_t length = static_cast<std::size_t> (byte (i)) << 8 | byte (i + 1);
    if (length < 2)
      return header;
    const bool frame_header = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame_header && i + 7 <= n)
    {
      header.height = static_cast<std::uint64_t> (byte (i + 3)) << 8 | byte (i + 4);
      header.width = static_cast<std::uint64_t> (byte (i + 5)) << 8 | byte (i + 6);
    }
    i += length;
    if (marker == 0xDA)
    {
      // Entropy-coded data runs to the next marker: 0xFF not followed by a stuffed zero
      // or a restart marker.
      while (i + 1 < n && !(byte (i) == 0xFF && byte (i + 1) != 0 && (byte (i + 1) < 0xD0 || byte (i + 1) > 0xD7)))
        ++i;
      if (i + 1 >= n)
        break;
    }
  }
  header.truncated = true;
  return header;
}
}  // namespace

cv::Mat
readImage (const std::string &path, int flags, const std::string &role)
{
  const std::string what = role.empty () ? "" : " (" + role + ")";
  // Before opening: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw std::runtime_error (path + ": " + problem + "; images are read from regular files only" + what);
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw std::runtime_error (path + ": cannot open the image" + what);
  const std::string bytes ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  if (bytes.empty ())
    throw std::runtime_error (path + ": empty file, not an image" + what);
  const ImageHeader header = probeImage (bytes);
  const auto too_large = [&] (std::uint64_t width, std::uint64_t height) {
    if (width * height > kMaxFramePixels)
      throw std::runtime_error (path + ": a " + std::to_string (width) + "x" + std::to_string (height) +
                                " image, more than the " + std::to_string (kMaxFramePixels) + " pixels agex reads" + what);
  };
  too_large (header.width, header.height);
  if (header.truncated)
    throw std::runtime_error (path + ": truncated JPEG (the data ends before its end-of-image marker)" + what);
  const cv::Mat image = cv::imdecode (cv::Mat (1, static_cast<int> (bytes.size ()), CV_8UC1,
                                               const_cast<char *> (bytes.data ())), flags);
  if (image.empty ())
    throw std::runtime_error (path + ": not an image OpenCV can decode" + what);
  too_large (static_cast<std::uint64_t> (image.cols), static_cast<std::uint64_t> (image.rows));
  return image;
}

ContourShapePredictor
loadContourModel (const std::string &path)
{
  ContourShapePredictor predictor = ContourShapePredictor::load (path);
  if (predictor.landmarkCount () != kContourLandmarkCount)
    throw std::runtime_error (path + ": the model places " + std::to_string (predictor.landmarkCount ()) +
                              " landmarks, not the " + std::to_string (kContourLandmarkCount) +
                              " contour landmarks agex draws and scores (train one with agex_landmarks_train)");
  return predictor;
}

std::vector<AnnotatedImage>
loadLandmarkDataset (const std::string &xml_path)
{
  const ImglabDataset dataset = readImglabDataset (xml_path);
  std::vector<AnnotatedImage> images;
  std::size_t boxes_without_landmarks = 0;
  for (const ImglabImage &entry : dataset.images)
  {
    AnnotatedImage image;
    image.path = resolveImglabImagePath (xml_path, entry.file);
    image.grey = readImage (image.path, cv::IMREAD_GRAYSCALE, "an image of " + xml_path);
    for (const ImglabBox &box : entry.boxes)
    {
      AnnotatedPerson person;
      person.box = box.rect;
      person.landmarks.resize (kContourLandmarkCount);
      int found = 0;
      for (const auto &[name, p] : box.parts)
      {
        const int index = contourLandmarkIndex (name);
        if (index >= 0)
        {
          person.landmarks[index] = p;
          ++found;
        }
      }
      if (box.ignore || found != kContourLandmarkCount)
      {
        if (found != 0 && found != kContourLandmarkCount && !box.ignore)
          throw std::runtime_error (xml_path + ": line " + std::to_string (box.line) + ": a box in " + entry.file +
                                    " has " + std::to_string (found) + " of the " +
                                    std::to_string (kContourLandmarkCount) + " contour landmarks (parts 000-179)");
        boxes_without_landmarks += !box.ignore;
        image.ignored.push_back (box.rect);
        continue;
      }
      person.tight_box = cv::boundingRect (person.landmarks);
      const auto a = box.parts.find (kShoulderPartNames[0]), b = box.parts.find (kShoulderPartNames[1]);
      if (a != box.parts.end () && b != box.parts.end ())
      {
        person.has_shoulders = true;
        person.shoulders[0] = a->second;
        person.shoulders[1] = b->second;
      }
      image.people.push_back (std::move (person));
    }
    images.push_back (std::move (image));
  }
  // Such boxes are legal imglab (detector-only annotations), but silently leaving them out of
  // training and scoring would hide a half-annotated dataset.
  if (boxes_without_landmarks > 0)
    std::cerr << "warning: " << xml_path << ": " << boxes_without_landmarks
              << " box(es) without contour landmarks are treated as ignore regions, not as people "
                 "(annotate them with agex_annotate, or mark them ignore='1')\n";
  return images;
}

std::vector<AnnotatedImage>
loadLandmarkDatasets (const std::vector<std::string> &xml_paths)
{
  std::vector<AnnotatedImage> images;
  for (const std::string &path : xml_paths)
  {
    std::vector<AnnotatedImage> more = loadLandmarkDataset (path);
    std::move (more.begin (), more.end (), std::back_inserter (images));
  }
  return images;
}

po::options_description
shapeTrainerOptions (ShapePredictorTrainingParams &p)
{
  po::options_description options ("Shape predictor training (dlib::shape_predictor_trainer)");
  options.add_options ()
    ("oversampling", po::value (&p.oversampling_amount)->default_value (p.oversampling_amount), "random initial shapes per training person")
    ("translation-jitter", po::value (&p.oversampling_translation_jitter)->default_value (p.oversampling_translation_jitter), "random box shift of the oversampled copies (fraction of the box)")
    ("nu", po::value (&p.nu)->default_value (p.nu), "shrinkage (learning rate) of each tree")
    ("tree-depth", po::value (&p.tree_depth)->default_value (p.tree_depth), "depth of each regression tree")
    ("cascade-depth", po::value (&p.cascade_depth)->default_value (p.cascade_depth), "cascade levels")
    ("trees-per-level", po::value (&p.num_trees_per_cascade_level)->default_value (p.num_trees_per_cascade_level), "trees per cascade level")
    ("feature-pool-size", po::value (&p.feature_pool_size)->default_value (p.feature_pool_size), "pixels sampled per cascade level")
    ("feature-pool-padding", po::value (&p.feature_pool_region_padding)->default_value (p.feature_pool_region_padding), "how far outside the shape pixels may be sampled (fraction of the box)")
    ("lambda", po::value (&p.lambda)->default_value (p.lambda), "prior favouring close pixel pairs")
    ("test-splits", po::value (&p.num_test_splits)->default_value (p.num_test_splits), "random splits tried per tree node")
    ("seed", po::value (&p.random_seed)->default_value (p.random_seed), "random seed (string)")
    ("threads", po::value (&p.num_threads)->default_value (p.num_threads), "training threads (0: one per core)");
  return options;
}

po::options_description
detectorTrainerOptions (DetectorTraining &training)
{
  PeopleDetectorTrainingParams &p = training.params;
  PastedPeopleParams &q = training.pasted;
  po::options_description options ("People detector training (dlib::structural_object_detection_trainer, fhog)");
  options.add_options ()
    ("detector-c", po::value (&p.c)->default_value (p.c), "SVM C")
    ("detector-epsilon", po::value (&p.epsilon)->default_value (p.epsilon), "SVM stopping tolerance")
    ("detector-window-width", po::value (&p.window_width)->default_value (p.window_width), "detection window width (pixels)")
    ("detector-window-height", po::value (&p.window_height)->default_value (p.window_height), "detection window height (pixels)")
    ("detector-upsample", po::value (&p.upsample)->default_value (p.upsample), "times to double the images (finds smaller people, slower)")
    ("detector-train-min-person", po::value (&p.train_min_person_windows)->default_value (p.train_min_person_windows),
     "shrink training images so that their tallest person is this many window heights tall at least...")
    ("detector-train-max-person", po::value (&p.train_max_person_windows)->default_value (p.train_max_person_windows),
     "...and at most (spread over the images; 0, 0: images as they are)")
    ("detector-scale", po::value (&p.scale)->default_value (p.scale), "resize images by this before detection (below 1: faster, misses small people)")
    ("detector-flips", po::value (&p.add_flips)->default_value (p.add_flips), "add left-right mirrored training images")
    ("detector-paste-people", po::value (&training.paste_people)->default_value (training.paste_people),
     "train on the people cut out along their outlines and pasted into each other's photos")
    ("detector-originals", po::value (&training.originals)->default_value (training.originals),
     "train on the photos as they are")
    ("detector-paste-per-image", po::value (&q.people_per_image)->default_value (q.people_per_image), "people pasted into each photo")
    ("detector-paste-min-height", po::value (&q.min_height)->default_value (q.min_height),
     "pasted people are at least this fraction of the photo's height...")
    ("detector-paste-max-height", po::value (&q.max_height)->default_value (q.max_height), "...and at most this");
  return options;
}

ContourShapePredictor
trainShapePredictor (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                     ShapePredictorTrainingParams params)
{
  std::vector<LandmarkTrainingImage> training;
  for (const std::size_t i : which)
  {
    LandmarkTrainingImage t;
    t.grey = images.at (i).grey;
    for (const AnnotatedPerson &person : images[i].people)
    {
      t.boxes.push_back (person.box);
      t.shapes.push_back (person.landmarks);
    }
    training.push_back (std::move (t));
  }
  params.mirror_map.resize (kContourLandmarkCount);
  for (int i = 0; i < kContourLandmarkCount; ++i)
    params.mirror_map[i] = mirroredContourLandmark (i);
  return ContourShapePredictor::train (training, params);
}

PeopleImages
pastedPeopleImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                    const PastedPeopleParams &params)
{
  std::vector<cv::Mat> greys;
  std::vector<std::vector<std::vector<cv::Point2f>>> outlines;
  std::vector<std::vector<cv::Rect>> ignore_regions;
  for (const std::size_t i : which)
  {
    greys.push_back (images.at (i).grey);
    outlines.emplace_back ();
    for (const AnnotatedPerson &person : images[i].people)
      outlines.back ().push_back (person.landmarks);
    ignore_regions.push_back (images[i].ignored);
  }
  return pastePeople (greys, outlines, ignore_regions, params);
}

PeopleDetector
trainPeopleDetector (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                     const DetectorTraining &training, std::size_t *ignored)
{
  if (!training.paste_people && !training.originals)
    throw std::runtime_error ("the people detector needs training images: the photos, the pasted people or both");
  PeopleImages set;
  if (training.paste_people)
    set = pastedPeopleImages (images, which, training.pasted);
  if (training.originals)
    for (const std::size_t i : which)
    {
      set.images.push_back (images.at (i).grey);
      set.boxes.emplace_back ();
      for (const AnnotatedPerson &person : images[i].people)
        set.boxes.back ().push_back (person.tight_box);
      set.ignore.push_back (images[i].ignored);
    }
  return PeopleDetector::train (set.images, set.boxes, set.ignore, training.params, ignored);
}

std::string
bundledPeopleDetectorFile ()
{
  return bundledDataFile ("models/agex_people_detector.svm");
}

po::options_description
detectorChoiceOptions (DetectorChoice &choice)
{
  po::options_description options ("People detector");
  options.add_options () ("detector", po::value (&choice.path),
                          "people detector file (default: the bundled one, trained on CCP)")
    ("opencv-detector", po::bool_switch (&choice.opencv), "use OpenCV's pretrained HOG people detector instead")
    ("opencv-scale", po::value (&choice.opencv_scale)->default_value (choice.opencv_scale),
     "with --opencv-detector: resize images by this first (smaller: faster, misses people shorter than about "
     "96/scale pixels)");
  return options;
}

PeopleDetector
loadDetector (const DetectorChoice &choice)
{
  if (!(choice.opencv_scale > 0.05 && choice.opencv_scale <= 4.0))
    throw std::runtime_error ("--opencv-scale must lie in (0.05, 4]");
  if (!choice.opencv && choice.opencv_scale != 0.5)
    throw std::runtime_error ("--opencv-scale applies to --opencv-detector only");
  if (choice.opencv && !choice.path.empty ())
    throw std::runtime_error ("--detector and --opencv-detector name two detectors; give one");
  if (choice.opencv)
    return PeopleDetector::openCvDefault (choice.opencv_scale);
  return PeopleDetector::load (choice.path.empty () ? bundledPeopleDetectorFile () : choice.path);
}

namespace
{
double
msSince (std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
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
averagePrecision (std::vector<std::pair<double, bool>> scored, std::size_t truths)
{
  if (truths == 0)
    return 0.0;
  std::stable_sort (scored.begin (), scored.end (), [] (const auto &a, const auto &b) { return a.first > b.first; });
  std::vector<double> precision, recall;
  std::size_t tp = 0;
  for (std::size_t i = 0; i < scored.size (); ++i)
  {
    tp += scored[i].second;
    precision.push_back (static_cast<double> (tp) / (i + 1));
    recall.push_back (static_cast<double> (tp) / truths);
  }
  // Precision made monotone from the right, then summed over the recall steps.
  for (std::size_t i = precision.size (); i-- > 1;)
    precision[i - 1] = std::max (precision[i - 1], precision[i]);
  double ap = 0, previous_recall = 0;
  for (std::size_t i = 0; i < recall.size (); ++i)
  {
    ap += (recall[i] - previous_recall) * precision[i];
    previous_recall = recall[i];
  }
  return ap;
}

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

nlohmann::json
LandmarkEvaluation::DetectionScores::json (int min_height) const
{
  nlohmann::json doc;
  doc["detection_people"] = truths;
  doc["detection_min_height"] = min_height;
  doc["detection_recall"] = meanOf (static_cast<double> (found), truths);
  doc["detection_ap"] = truths ? nlohmann::json (averagePrecision (scored, truths)) : nlohmann::json (nullptr);
  doc["false_detections_per_image"] = meanOf (static_cast<double> (false_detections), images);
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
  return doc;
}

EvaluationInputs
loadEvaluationInputs (const std::vector<std::string> &tested, const std::vector<std::string> &train_also,
                      const std::vector<std::string> &other_inputs, const std::string &json_path)
{
  EvaluationInputs inputs;
  inputs.read = InputFiles (tested);
  for (const auto &path : train_also)
    inputs.read.add (path);
  for (const auto &path : other_inputs)
    if (!path.empty ())
      inputs.read.add (path);
  if (!json_path.empty ())
    inputs.read.checkOutput (json_path);
  inputs.images = loadLandmarkDatasets (tested);
  inputs.tested = inputs.images.size ();
  for (auto &image : loadLandmarkDatasets (train_also))
    inputs.images.push_back (std::move (image));
  for (const auto &image : inputs.images)
    inputs.read.add (image.path);
  if (!json_path.empty ())
    inputs.read.checkOutput (json_path);
  return inputs;
}

nlohmann::json
evaluateImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &test,
                const ContourShapePredictor &predictor, const PeopleDetector *detector, const EvaluationSettings &settings,
                const InputFiles &inputs, LandmarkEvaluation &pooled)
{
  LandmarkEvaluation part;
  part.setMinDetectionHeight (settings.min_detection_height);
  pooled.setMinDetectionHeight (settings.min_detection_height);
  for (const std::size_t i : test)
  {
    part.add (images[i], predictor, detector, settings.threshold);
    pooled.add (images[i], predictor, detector, settings.threshold);
    if (settings.overlay_dir.empty ())
      continue;
    std::vector<LandmarkedPerson> people;
    for (const auto &person : images[i].people)
      people.push_back ({person.box, 1.0, predictor.predict (images[i].grey, person.box)});
    const std::string overlay =
      settings.overlay_dir + "/" + std::filesystem::path (images[i].path).stem ().string () + ".png";
    inputs.checkOutput (overlay);
    std::filesystem::create_directories (settings.overlay_dir);
    writePng (overlay, renderLandmarkOverlay (readImage (images[i].path, cv::IMREAD_COLOR), people));
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
  return doc;
}

nlohmann::json
crossValidate (const std::vector<AnnotatedImage> &images, std::size_t tested_images, int folds,
               const ShapePredictorTrainingParams &shape_params, const DetectorTraining *detector_training,
               const PeopleDetector *detector, const EvaluationSettings &settings, const InputFiles &inputs)
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
    std::cerr << "fold " << f + 1 << "/" << folds << ": training on " << train.size () << " images, testing on "
              << test.size () << "\n";
    const ContourShapePredictor predictor = trainShapePredictor (images, train, shape_params);
    std::unique_ptr<PeopleDetector> fold_detector;
    if (detector_training)
      fold_detector = std::make_unique<PeopleDetector> (trainPeopleDetector (images, train, *detector_training));
    per_fold.push_back (
      evaluateImages (images, test, predictor, fold_detector ? fold_detector.get () : detector, settings, inputs, pooled));
    std::cerr << "fold " << f + 1 << "/" << folds << ": " << per_fold.back ().dump () << "\n";
  }
  nlohmann::json doc = pooled.json ();
  doc["folds"] = folds;
  doc["per_fold"] = per_fold;
  return doc;
}

cv::Mat
renderLandmarkOverlay (const cv::Mat &image, const std::vector<LandmarkedPerson> &people)
{
  cv::Mat canvas;
  if (image.channels () == 1)
    cv::cvtColor (image, canvas, cv::COLOR_GRAY2BGR);
  else if (image.channels () == 4)
    cv::cvtColor (image, canvas, cv::COLOR_BGRA2BGR);
  else
    canvas = image.clone ();
  const int radius = std::max (1, std::min (canvas.cols, canvas.rows) / 250);
  for (const LandmarkedPerson &person : people)
  {
    cv::rectangle (canvas, person.box, cv::Scalar (255, 255, 255), 1);
    const int n = static_cast<int> (person.landmarks.size ());
    for (int i = 0; i < n; ++i)
    {
      // Hue runs round the body with the landmark index (red at the head top).
      cv::Mat hsv (1, 1, CV_8UC3, cv::Scalar (static_cast<double> (170 * i / std::max (1, n)), 255, 255)), bgr;
      cv::cvtColor (hsv, bgr, cv::COLOR_HSV2BGR);
      const cv::Vec3b c = bgr.at<cv::Vec3b> (0, 0);
      cv::line (canvas, person.landmarks[i], person.landmarks[(i + 1) % n], cv::Scalar (c[0], c[1], c[2]), 1, cv::LINE_AA);
      cv::circle (canvas, person.landmarks[i], i == 0 ? 3 * radius : radius, cv::Scalar (c[0], c[1], c[2]), cv::FILLED,
                  cv::LINE_AA);
    }
    // The anchors (head top, hands, feet: every 36th landmark) numbered, so that one can see
    // landmark i land on the same body place in every person.
    if (n == kContourLandmarkCount)
      for (int i = 0; i < n; i += kLandmarksPerSegment)
      {
        const double scale = std::max (0.35, person.box.height / 900.0);
        const cv::Point at = cv::Point (person.landmarks[i]) + cv::Point (2 * radius + 1, -2 * radius - 1);
        cv::circle (canvas, person.landmarks[i], 2 * radius + 1, cv::Scalar (255, 255, 255), 1, cv::LINE_AA);
        cv::putText (canvas, std::to_string (i), at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar (0, 0, 0), 3, cv::LINE_AA);
        cv::putText (canvas, std::to_string (i), at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar (255, 255, 255), 1,
                     cv::LINE_AA);
      }
  }
  return canvas;
}

LandmarkedFrame
landmarkFrame (const cv::Mat &image, const PeopleDetector &detector, const ContourShapePredictor &predictor,
               double threshold)
{
  LandmarkedFrame result;
  const cv::Mat grey = toGrey (image);
  auto start = std::chrono::steady_clock::now ();
  const std::vector<PersonDetection> detections = detector.detect (grey, threshold);
  result.detect_ms = msSince (start);
  start = std::chrono::steady_clock::now ();
  for (const PersonDetection &d : detections)
    result.people.push_back ({d.box, d.score, predictor.predict (grey, squareBox (d.box))});
  result.landmarks_ms = msSince (start);
  return result;
}

nlohmann::json
landmarkedFrameJson (const std::string &source, const LandmarkedFrame &frame)
{
  nlohmann::json people = nlohmann::json::array ();
  for (const auto &person : frame.people)
    people.push_back (landmarkedPersonJson (person));
  return {{"source", source}, {"people", people}, {"ms", {{"detect", frame.detect_ms}, {"landmarks", frame.landmarks_ms}}}};
}

void
LandmarkOutputs::add (const std::string &source, const cv::Mat &image, LandmarkedFrame frame)
{
  (stream_lines_ ? std::cerr : std::cout) << source << ": " << frame.people.size () << " people, detect "
                                          << frame.detect_ms << " ms, landmarks " << frame.landmarks_ms << " ms\n";
  frames_.push_back (landmarkedFrameJson (source, frame));
  if (stream_lines_)
    std::cout << frames_.back ().dump () << std::endl;  // flushed: a reader sees each frame as it is done
  last_image_ = image;
  last_ = std::move (frame);
}

void
LandmarkOutputs::write (nlohmann::json header, const std::string &json_path, const std::string &lines_path,
                        const std::string &overlay_path) const
{
  if (!json_path.empty ())
  {
    header["frames"] = frames_;
    writeJson (json_path, header);
  }
  if (!lines_path.empty ())
  {
    std::string lines;
    for (const auto &frame : frames_)
      lines += frame.dump () + "\n";
    writeFileAtomic (lines_path, lines);
  }
  if (!overlay_path.empty () && !last_image_.empty ())
    writePng (overlay_path, renderLandmarkOverlay (last_image_, last_.people));
}

void
checkNotInImageSequence (const std::string &overlay, const std::string &video)
{
  namespace fs = std::filesystem;
  if (video.find ('%') == std::string::npos)
    return;
  std::string pattern;
  const std::string name = fs::path (video).filename ().string ();
  for (std::size_t i = 0; i < name.size (); ++i)
  {
    std::size_t j = i + 1;
    while (name[i] == '%' && j < name.size () && std::isdigit (static_cast<unsigned char> (name[j])))
      ++j;
    if (name[i] == '%' && j < name.size () && name[j] == 'd')
    {
      pattern += "[0-9]+";
      i = j;
    }
    else
      pattern += std::isalnum (static_cast<unsigned char> (name[i])) ? std::string (1, name[i]) : "\\" + std::string (1, name[i]);
  }
  std::error_code ec;
  const fs::path out = fs::weakly_canonical (overlay, ec);
  const fs::path dir = fs::weakly_canonical (fs::path (video).parent_path ().empty () ? "." : fs::path (video).parent_path (), ec);
  if (out.parent_path () == dir && std::regex_match (out.filename ().string (), std::regex (pattern)))
    throw std::runtime_error (overlay + ": output would overwrite a frame of the image sequence " + video +
                              "; choose another path");
}

namespace
{
// Set by Ctrl-C: a camera runs until then, and what was seen is still written. (A signal
// handler can only reach a flag like this.)
volatile std::sig_atomic_t interrupted = 0;

void
stopReading (int)
{
  interrupted = 1;
  std::signal (SIGINT, SIG_DFL);  // a second Ctrl-C ends a read that blocks
}
}  // namespace

int
readVideo (const std::string &video, int max_frames, const std::function<void (const std::string &, const cv::Mat &)> &on_frame)
{
  const bool camera = !video.empty () && std::all_of (video.begin (), video.end (), ::isdigit);
  if (camera && video.size () > 4)
    throw std::runtime_error ("--video " + video + ": no such camera number");
  cv::VideoCapture capture;
  // OpenCV logs each backend that fails to open the input; the one error below says it.
  const auto log_level = cv::utils::logging::setLogLevel (cv::utils::logging::LOG_LEVEL_SILENT);
  const bool opened = camera ? capture.open (std::stoi (video)) : capture.open (video);
  cv::utils::logging::setLogLevel (log_level);
  if (!opened)
    throw std::runtime_error (video + ": cannot open the video or camera");
  interrupted = 0;
  std::signal (SIGINT, stopReading);
  cv::Mat frame;
  int n = 0;
  for (; !interrupted && (max_frames == 0 || n < max_frames) && capture.read (frame) && !frame.empty (); ++n)
    on_frame (video + "#" + std::to_string (n), frame);
  std::signal (SIGINT, SIG_DFL);
  if (n == 0 && !interrupted)
    throw std::runtime_error (video + ": opened, but not a single frame could be read from it");
  return n;
}

nlohmann::json
landmarkedPersonJson (const LandmarkedPerson &person)
{
  nlohmann::json points = nlohmann::json::array ();
  for (const cv::Point2f &p : person.landmarks)
    points.push_back ({p.x, p.y});
  return {{"box", {{"x", person.box.x}, {"y", person.box.y}, {"width", person.box.width}, {"height", person.box.height}}},
          {"score", person.score},
          {"landmarks", points}};
}
}  // namespace apps
}  // namespace agex
