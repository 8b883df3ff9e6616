#include <agex/apps/landmarks.h>

#include <agex/apps/command_line.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/io/image_header.h>
#include <agex/io/input_file.h>
#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/image_files.h>

#include <boost/program_options/value_semantic.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
std::vector<AnnotatedImage>
loadLandmarkDatasets (const std::vector<std::string> &xml_paths)
{
  std::vector<AnnotatedImage> images;
  for (const std::string &xml_path : xml_paths)
  {
    std::size_t boxes_without_landmarks = 0;
    std::vector<AnnotatedImage> more = loadLandmarkDataset (xml_path, &boxes_without_landmarks);
    // Such boxes are legal imglab (detector-only annotations), but silently leaving them out of
    // training and scoring would hide a half-annotated dataset.
    if (boxes_without_landmarks > 0)
      std::cerr << "warning: " << xml_path << ": " << boxes_without_landmarks
                << " box(es) without contour landmarks are treated as ignore regions, not as people "
                   "(annotate them with agex_annotate, or mark them ignore='1')\n";
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
detectorTrainerOptions (PeopleDetectorTraining &training)
{
  PeopleDetectorTrainingParams &p = training.params;
  PastedPeopleParams &q = training.pasted;
  po::options_description options ("People detector training (dlib::structural_object_detection_trainer, fhog)");
  options.add_options ()
    ("detector-c", po::value (&p.c)->default_value (p.c), "SVM C")
    ("detector-epsilon", po::value (&p.epsilon)->default_value (p.epsilon), "SVM stopping tolerance")
    ("detector-loss-missed", po::value (&p.loss_per_missed_target)->default_value (p.loss_per_missed_target),
     "loss of a missed person relative to a false detection's, (0, 1000]: raise it when people-free images or many "
     "negatives make the SVM score every window below 0")
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

po::options_description
detectorCropOptions (PeopleCropChoice &choice, PeopleDetectorTraining &training)
{
  PastedCropsParams &q = training.crop_params;
  po::options_description options ("People detector training on person crops and people-free backgrounds");
  options.add_options ()
    ("detector-crops", po::value (&choice.folder), "a folder of person crops (e.g. INRIA's 96x160 positives) pasted into the "
     "training photos, whose own people are then ignored")
    ("detector-crops-box", po::value (&choice.box)->default_value (choice.box), "the person's box in every crop: x,y,width,height")
    ("detector-crops-folds", po::value (&choice.folds)->default_value (choice.folds), "crops of the i-th source photo (names alike but a final letter: crop001001a, ...c) are in fold i mod this")
    ("detector-crops-held-out", po::value (&choice.fold)->default_value (choice.fold),
     "leave this fold of the crops out of training (-1: train on all)")
    ("detector-crops-per-image", po::value (&q.people_per_image)->default_value (q.people_per_image), "crops pasted into each photo")
    ("detector-crops-min-height", po::value (&q.min_height)->default_value (q.min_height),
     "pasted crops' people are at least this many pixels tall...")
    ("detector-crops-max-height", po::value (&q.max_height)->default_value (q.max_height), "...and at most this")
    ("detector-backgrounds", po::value (&training.backgrounds)->default_value (training.backgrounds),
     "also train on the photos' people-free bands (each person's outline grown by --detector-background-dilation of its "
     "height, cut away)")
    ("detector-background-dilation", po::value (&training.background_params.dilation)->default_value (training.background_params.dilation),
     "how far round each person (fraction of its height) the people-free bands stay clear");
  return options;
}

std::shared_ptr<const PeopleCrops>
loadPeopleCrops (const PeopleCropChoice &choice, bool test, std::vector<std::size_t> &which)
{
  which.clear ();
  if (choice.folder.empty ())
    return nullptr;
  int x = 0, y = 0, w = 0, h = 0;
  char c1 = 0, c2 = 0, c3 = 0;
  std::istringstream in (choice.box);
  if (!(in >> x >> c1 >> y >> c2 >> w >> c3 >> h) || c1 != ',' || c2 != ',' || c3 != ',' || !(in >> std::ws).eof ())
    throw std::runtime_error ("the crops' person box '" + choice.box + "' is not x,y,width,height");
  if (choice.folds < 2 || choice.folds > 100 || choice.fold < -1 || choice.fold >= choice.folds)
    throw std::runtime_error ("crop folds: 2 to 100 folds and a fold from -1 (none) to folds - 1");
  auto crops = std::make_shared<PeopleCrops> (readPeopleCrops (choice.folder, cv::Rect (x, y, w, h)));
  // Folds by source photo: crops of one photo share a background (and often people).
  const std::vector<std::size_t> photos = cropSourcePhotos (crops->names);
  which = test && choice.fold < 0 ? foldIndices (photos, choice.folds, -1, false)
                                  : foldIndices (photos, choice.folds, choice.fold, test);
  if (which.empty ())
    throw std::runtime_error (choice.folder + ": no crop left in the chosen folds");
  return crops;
}

std::string
bundledPeopleDetectorFile ()
{
  return bundledDataFile ("models/agex_people_detector.svm");
}

po::options_description
detectorChoiceOptions (PeopleDetectorChoice &choice)
{
  po::options_description options ("People detector");
  options.add_options () ("detector", po::value (&choice.path),
                          "people detector file (default: the bundled one), or 'opencv-hog': OpenCV's pretrained HOG "
                          "people detector")
    ("detector-also", po::value (&choice.also)->composing (),
     "FILE or FILE@OFFSET (repeatable): another people detector run with the first as one; its detections at the "
     "threshold + OFFSET (in [-5, 5]) count, their scores less OFFSET")
    ("opencv-detector", po::bool_switch (&choice.opencv), "use OpenCV's pretrained HOG people detector instead (as "
     "--detector opencv-hog)")
    ("opencv-scale", po::value (&choice.opencv_scale)->default_value (choice.opencv_scale),
     "with --opencv-detector: resize images by this first (smaller: faster, misses people shorter than about "
     "96/scale pixels)");
  return options;
}

PeopleDetector
loadPeopleDetector (const PeopleDetectorChoice &choice)
{
  if (!(choice.opencv_scale > 0.05 && choice.opencv_scale <= 4.0))
    throw std::runtime_error ("--opencv-scale must lie in (0.05, 4]");
  const bool opencv_hog = choice.path == kOpenCvHogName;
  if (!choice.opencv && !opencv_hog && choice.opencv_scale != 0.5)
    throw std::runtime_error ("--opencv-scale applies to OpenCV's detector only (--detector opencv-hog)");
  if (choice.opencv && !choice.path.empty ())
    throw std::runtime_error ("--detector and --opencv-detector name two detectors; give one");
  PeopleDetector first = choice.opencv || opencv_hog
                          ? PeopleDetector::openCvDefault (choice.opencv_scale)
                          : PeopleDetector::load (choice.path.empty () ? bundledPeopleDetectorFile () : choice.path);
  if (choice.also.empty ())
    return first;
  std::vector<PeopleDetector> members;
  members.push_back (std::move (first));
  return combineDetectorFiles (std::move (members), {0.0}, choice.also, "--detector-also");
}

std::pair<std::string, double>
detectorFileAndOffset (const std::string &item, const std::string &flag)
{
  // A file whose name holds an '@' is that file, at offset 0.
  std::error_code error;
  const std::size_t at = item.rfind ('@');
  if (at == std::string::npos || std::filesystem::is_regular_file (item, error))
    return {item, 0.0};
  double offset = 0.0;
  std::istringstream in (item.substr (at + 1));
  if (!(in >> offset) || !(in >> std::ws).eof () || !(offset >= -5.0 && offset <= 5.0))
    throw std::runtime_error (flag + " " + item + ": the offset after '@' must be a number in [-5, 5]");
  return {item.substr (0, at), offset};
}

PeopleDetector
combineDetectorFiles (std::vector<PeopleDetector> members, std::vector<double> offsets,
                      const std::vector<std::string> &items, const std::string &flag)
{
  if (members.size () + items.size () > 8)
    throw std::runtime_error (flag + ": at most 8 detectors run as one, not " +
                              std::to_string (members.size () + items.size ()));
  for (const std::string &item : items)
  {
    const auto [file, offset] = detectorFileAndOffset (item, flag);
    members.push_back (PeopleDetector::load (file));
    offsets.push_back (offset);
  }
  try
  {
    return PeopleDetector::combine (std::move (members), offsets);
  }
  catch (const std::invalid_argument &e)
  {
    // Members that are ensembles count with all their members and offsets.
    throw std::runtime_error (flag + ": " + e.what ());
  }
}

LandmarkInputs
loadLandmarkInputs (const std::vector<std::string> &tested, const std::vector<std::string> &train_also,
                    const std::vector<std::string> &other_inputs, const std::vector<std::string> &outputs)
{
  LandmarkInputs inputs;
  inputs.read = InputFiles (tested);
  for (const auto &path : train_also)
    inputs.read.add (path);
  for (const auto &path : other_inputs)
    if (!path.empty ())
      inputs.read.add (path);
  const auto check_outputs = [&] {
    for (const auto &output : outputs)
      if (!output.empty ())
        inputs.read.checkOutput (output);
  };
  check_outputs ();
  inputs.images = loadLandmarkDatasets (tested);
  inputs.tested = inputs.images.size ();
  for (auto &image : loadLandmarkDatasets (train_also))
    inputs.images.push_back (std::move (image));
  // Nor on an image the datasets name.
  for (const auto &image : inputs.images)
    inputs.read.add (image.path);
  check_outputs ();
  return inputs;
}

po::options_description
landmarkEvaluationOptions (LandmarkEvaluationFlags &f)
{
  po::options_description general ("agex_landmarks_eval --dataset XML (--model MODEL | --folds K) [options]\n"
                                   "Mean landmark error (px, per box height, per shoulder width), mean distance to the true\n"
                                   "contour (px, per box height), people detection (AP at IoU 0.5, recall, false detections\n"
                                   "per image) and time per image. Landmarks are predicted in the true boxes so that the\n"
                                   "two errors stay apart.");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&f.datasets)->multitoken ()->required (), "imglab XML files with contour landmarks")
    ("model", po::value (&f.model), "shape predictor to evaluate")
    ("no-detector", po::bool_switch (&f.detector.none), "skip detection")
    ("threshold", po::value (&f.settings.threshold)->default_value (f.settings.threshold),
     "detection threshold for the recall and false detections")
    ("min-detection-height", po::value (&f.settings.min_detection_height)->default_value (f.settings.min_detection_height),
     "people shorter than this (pixels) are ignore regions for the detection scores")
    ("folds", po::value (&f.folds)->default_value (0), "cross-validate by image: image i is in fold i mod K")
    ("train-also", po::value (&f.train_also)->multitoken (),
     "with --folds: imglab XML files added to every fold's training set, never tested")
    ("train-detector", po::bool_switch (&f.train_detector), "with --folds: train a detector per fold too")
    ("json", po::value (&f.json), "write the results here")
    ("overlay-dir", po::value (&f.overlay_dir), "write a PNG per image with the predicted landmarks here")
    ("pasted", po::bool_switch (&f.settings.pasted),
     "also score detection on the tested people pasted into each other's photos (several per image, many sizes)")
    ("crops", po::value (&f.crops.folder), "also score detection on these person crops (e.g. INRIA's) pasted into the tested "
     "photos, whose own people are ignored (\"crops\" in the report)")
    ("crops-box", po::value (&f.crops.box)->default_value (f.crops.box), "the person's box in every crop: x,y,width,height")
    ("crops-folds", po::value (&f.crops.folds)->default_value (f.crops.folds), "crops of the i-th source photo (names alike but a final letter: crop001001a, ...c) are in fold i mod this")
    ("crops-fold", po::value (&f.crops.fold)->default_value (f.crops.fold), "score only this fold of the crops (-1: all)")
    ("crops-per-image", po::value (&f.settings.crop_params.people_per_image)->default_value (f.settings.crop_params.people_per_image),
     "crops pasted into each tested photo")
    ("crops-min-height", po::value (&f.settings.crop_params.min_height)->default_value (f.settings.crop_params.min_height),
     "pasted crops' people are at least this many pixels tall...")
    ("crops-max-height", po::value (&f.settings.crop_params.max_height)->default_value (f.settings.crop_params.max_height),
     "...and at most this")
    ("crops-background-height", po::value (&f.settings.crop_params.max_background_height)->default_value (f.settings.crop_params.max_background_height),
     "the tested photos are shrunk to this height (pixels) before the crops are pasted in");
  po::options_description all;
  all.add (general).add (detectorChoiceOptions (f.detector));
  all.add (shapeTrainerOptions (f.shape_params)).add (detectorTrainerOptions (f.detector_training));
  return all;
}

void
checkLandmarkEvaluationFlags (const LandmarkEvaluationFlags &f)
{
  if ((f.folds == 0) == f.model.empty ())
    throw std::runtime_error ("give --model MODEL, or --folds K to cross-validate (a model is trained per fold)");
  if (f.folds == 1 || f.folds < 0)
    throw std::runtime_error ("--folds needs at least 2 folds");
  if ((f.folds == 0 && (!f.train_also.empty () || f.train_detector)) || f.settings.min_detection_height < 0)
    throw std::runtime_error ("--train-also and --train-detector need --folds; --min-detection-height must be 0 or more");
}

void
checkLandmarkModelOutputs (const std::string &shape_model, const std::string &detector, const InputFiles &inputs)
{
  // Only the loader knows a dlib model; what it refuses is not an earlier model.
  const auto loads_as = [] (auto load, const std::string &what) -> OutputRecogniser {
    return [load, what] (const std::string &path) {
      try
      {
        load (path);
        return std::string ();
      }
      catch (const std::exception &)
      {
        return "exists and is not " + what;
      }
    };
  };
  checkOutputPath (shape_model, "--out",
                   loads_as ([] (const std::string &p) { ContourShapePredictor::load (p); }, "a shape predictor"), inputs);
  if (!detector.empty ())
    checkOutputPath (detector, "--detector-out",
                     loads_as ([] (const std::string &p) { PeopleDetector::load (p); }, "a people detector"), inputs);
}

ScoredImageCallback
landmarkOverlayWriter (const std::string &overlay_dir, const LandmarkInputs &inputs)
{
  if (overlay_dir.empty ())
    return {};
  const auto overlay_of = [overlay_dir] (const AnnotatedImage &image) {
    return overlay_dir + "/" + std::filesystem::path (image.path).stem ().string () + ".png";
  };
  std::vector<std::string> overlays;
  for (std::size_t i = 0; i < inputs.tested; ++i)
    overlays.push_back (overlay_of (inputs.images[i]));
  checkPngsInFolder (overlays, inputs.read);
  return [overlay_dir, overlay_of, &inputs] (const AnnotatedImage &image, const ContourShapePredictor &predictor) {
    std::vector<LandmarkedPerson> people;
    for (const auto &person : image.people)
      people.push_back ({person.box, 1.0, predictor.predict (image.grey, person.box)});
    const std::string overlay = overlay_of (image);
    inputs.read.checkOutput (overlay);
    std::filesystem::create_directories (overlay_dir);
    writePng (overlay, renderLandmarkOverlay (readImage (image.path, cv::IMREAD_COLOR), people));
  };
}

CrossValidationCallbacks
crossValidationProgress (const ScoredImageCallback &image_scored)
{
  CrossValidationCallbacks callbacks;
  callbacks.fold_started = [] (int fold, int folds, std::size_t training, std::size_t tested) {
    std::cerr << "fold " << fold + 1 << "/" << folds << ": training on " << training << " images, testing on " << tested
              << "\n";
  };
  callbacks.fold_scored = [] (int fold, int folds, const nlohmann::json &scores) {
    std::cerr << "fold " << fold + 1 << "/" << folds << ": " << scores.dump () << "\n";
  };
  callbacks.image_scored = image_scored;
  return callbacks;
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
landmarkPeopleFastest (const cv::Mat &image, const PeopleDetector &detector, const ContourShapePredictor &predictor,
                       double threshold, int runs)
{
  LandmarkedFrame best = landmarkPeople (image, detector, predictor, threshold);
  for (int r = 1; r < runs; ++r)
  {
    const LandmarkedFrame again = landmarkPeople (image, detector, predictor, threshold);
    best.detect_ms = std::min (best.detect_ms, again.detect_ms);
    best.landmarks_ms = std::min (best.landmarks_ms, again.landmarks_ms);
  }
  return best;
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
  const OutputSetClaim claim ({json_path, lines_path, overlay_path});  // written as one set
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

namespace
{
// Refuses an overlay that would replace a frame of the image-sequence video.
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
}  // namespace

void
checkLandmarkOutputs (const std::string &json, const std::string &lines, const std::string &overlay,
                      const std::vector<std::string> &images, const std::string &model, const std::string &video)
{
  if (!overlay.empty ())
    checkNotInImageSequence (overlay, video);
  InputFiles read (images);
  read.add (model);
  if (!video.empty ())
    read.add (video);
  const std::vector<std::string> outputs{json, lines, overlay};
  for (std::size_t i = 0; i < outputs.size (); ++i)
    for (std::size_t j = i + 1; j < outputs.size (); ++j)
      if (!outputs[i].empty () && outputs[i] == outputs[j])
        throw std::runtime_error (outputs[i] + ": --json, --json-lines and --overlay name the same file");
  if (!json.empty ())
    checkOutputPath (json, "agex_landmarks JSON", jsonReportWith ({"frames", "model", "detector"}), read);
  if (!lines.empty ())
    checkOutputPath (lines, "agex_landmarks JSON lines", jsonLinesWith ({"source", "people"}), read);
  if (!overlay.empty ())
    checkOutputPath (overlay, OutputKind::Png, read);
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

/** An image sequence: the file names around its frame number, the number's width (0: as
  * many digits as it has) and the first number. */
struct ImageSequence
{
  std::string before, after;
  std::size_t width = 0;
  long first = 0;
  bool numbered = true;  ///< false: one image, no number

  std::string
  frame (long n) const
  {
    if (!numbered)
      return before;
    std::string number = std::to_string (n);
    if (number.size () < width)
      number.insert (0, width - number.size (), '0');
    return before + number + after;
  }
};

/** The pattern of "vs/t%03d.jpg": one %d or %0Nd (N < 10), and no other %; its first frame is
  * the first number 0-999 that exists, as OpenCV's image-sequence reader finds it. False if
  * video holds no such conversion (a name with a % of another kind goes to OpenCV as it is).
  * \throws std::runtime_error for a second % beside the conversion (it would reach a printf),
  *         or no frame */
bool
sequencePattern (const std::string &video, ImageSequence &sequence)
{
  static const std::regex conversion ("%(0[1-9])?d");
  std::smatch match;
  if (!std::regex_search (video, match, conversion))
    return false;
  sequence.before = match.prefix ().str ();
  sequence.after = match.suffix ().str ();
  if (sequence.before.find ('%') != std::string::npos || sequence.after.find ('%') != std::string::npos)
    throw std::runtime_error ("--video " + video + ": an image sequence takes one %d or %0Nd (N < 10) and no other %");
  sequence.width = match[1].matched ? static_cast<std::size_t> (match[1].str ()[1] - '0') : 0;
  std::error_code ec;
  for (sequence.first = 0; sequence.first < 1000; ++sequence.first)
    if (std::filesystem::exists (sequence.frame (sequence.first), ec))
      return true;
  throw std::runtime_error (video + ": no frame of the image sequence exists (numbers 0 to 999 looked for)");
}

/** A still image given as the video (its content says so, whatever its name): OpenCV's
  * image-sequence reader would decode it, and the numbered files after it (f0001.png, then
  * f0002.png, ...), without agex's size checks; read here the same way through readImage.
  * False if path is no image. */
bool
stillImageSequence (const std::string &path, ImageSequence &sequence)
{
  std::ifstream in (path, std::ios::binary);
  std::vector<unsigned char> head (1 << 16);
  in.read (reinterpret_cast<char *> (head.data ()), static_cast<std::streamsize> (head.size ()));
  ImageHeader header;
  parseImageHeader (head.data (), static_cast<std::size_t> (in.gcount ()), header);
  if (header.format.empty ())
    return false;
  // The last run of digits in the file name numbers the frames.
  const std::string name = std::filesystem::path (path).filename ().string ();
  const std::size_t last = name.find_last_of ("0123456789");
  sequence.numbered = last != std::string::npos && last - name.find_last_not_of ("0123456789", last) <= 9;
  if (!sequence.numbered)
  {
    sequence.before = path;
    return true;
  }
  const std::size_t digits_start = name.find_last_not_of ("0123456789", last) + 1;  // npos + 1 == 0
  const std::size_t dir_length = path.size () - name.size ();
  sequence.before = path.substr (0, dir_length + digits_start);
  sequence.after = name.substr (last + 1);
  sequence.width = last + 1 - digits_start;
  sequence.first = std::stol (name.substr (digits_start, sequence.width));
  return true;
}

/** An image sequence read file by file through readImage (its size checks from the header,
  * regular files only), so that frames may change size. */
int
readImageSequence (const std::string &video, const ImageSequence &sequence, int max_frames,
                   const std::function<void (const std::string &, const cv::Mat &)> &on_frame)
{
  int n = 0;
  std::error_code ec;
  for (long i = sequence.first; !interrupted && (max_frames == 0 || n < max_frames); ++i, ++n)
  {
    const std::string path = sequence.frame (i);
    if ((n > 0 && !sequence.numbered) || !std::filesystem::exists (path, ec))
      break;
    on_frame (video + "#" + std::to_string (n), readImage (path, cv::IMREAD_COLOR, "a frame of " + video));
  }
  return n;
}
}  // namespace

int
readVideo (const std::string &video, int max_frames, const std::function<void (const std::string &, const cv::Mat &)> &on_frame)
{
  const bool camera = !video.empty () && std::all_of (video.begin (), video.end (), ::isdigit);
  if (camera && video.size () > 4)
    throw std::runtime_error ("--video " + video + ": no such camera number");
  interrupted = 0;
  ImageSequence sequence;
  const auto read_sequence = [&] {
    std::signal (SIGINT, stopReading);
    const int n = readImageSequence (video, sequence, max_frames, on_frame);
    std::signal (SIGINT, SIG_DFL);
    return n;
  };
  if (!camera && sequencePattern (video, sequence))
    return read_sequence ();
  // Before anything opens it: a FIFO or a device would block the open until someone writes.
  const std::string not_regular = camera ? "" : notARegularFile (video);
  if (!not_regular.empty ())
    throw std::runtime_error (video + ": " + not_regular + "; --video takes a video file, an image sequence or a camera number");
  if (!camera && stillImageSequence (video, sequence))
    return read_sequence ();
  cv::VideoCapture capture;
  // OpenCV logs each backend that fails to open the input; the one error below says it.
  const auto log_level = cv::utils::logging::setLogLevel (cv::utils::logging::LOG_LEVEL_SILENT);
  const bool opened = camera ? capture.open (std::stoi (video)) : capture.open (video);
  cv::utils::logging::setLogLevel (log_level);
  if (!opened)
    throw std::runtime_error (video + ": cannot open the video or camera");
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
