// agex_landmarks_eval: landmark and detection errors of a contour model on an imglab
// dataset, or cross-validated by image (--folds K: train on K-1 folds, test on the rest).

#include <agex/apps/command_line.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/io/atomic_file.h>

#include <boost/program_options.hpp>

#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <numeric>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  std::vector<std::string> dataset_paths;
  std::vector<std::string> extra_paths;
  std::string model_path, detector_path, json_path, overlay_dir;
  int folds = 0;
  bool train_detector = false, no_detector = false;
  double opencv_scale = 0.5;
  agex::ShapePredictorTrainingParams shape_params;
  agex::PeopleDetectorTrainingParams detector_params;
  po::options_description general ("agex_landmarks_eval --dataset XML (--model MODEL | --folds K) [options]\n"
                                   "Mean landmark error (px, per box height, per shoulder width), mean distance to\n"
                                   "the true contour, detection recall (IoU > 0.5) and time per image. Landmarks\n"
                                   "are predicted in the true boxes so that the two errors stay apart.");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&dataset_paths)->multitoken ()->required (), "imglab XML files with contour landmarks")
    ("model", po::value (&model_path), "shape predictor to evaluate")
    ("detector", po::value (&detector_path), "people detector (default: OpenCV's HOG people detector)")
    ("opencv-scale", po::value (&opencv_scale)->default_value (opencv_scale),
     "without --detector: resize images by this before OpenCV's people detector (smaller: faster, misses "
     "people shorter than about 96/scale pixels)")
    ("no-detector", po::bool_switch (&no_detector), "skip detection")
    ("folds", po::value (&folds)->default_value (0), "cross-validate by image: image i is in fold i mod K")
    ("train-also", po::value (&extra_paths)->multitoken (),
     "with --folds: imglab XML files added to every fold's training set, never tested")
    ("train-detector", po::bool_switch (&train_detector), "with --folds: train a detector per fold too")
    ("json", po::value (&json_path), "write the results here")
    ("overlay-dir", po::value (&overlay_dir), "write a PNG per image with the predicted landmarks here");
  po::options_description all;
  all.add (general).add (agex::apps::shapeTrainerOptions (shape_params)).add (agex::apps::detectorTrainerOptions (detector_params));
  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, {}))
      return 0;
    if (folds == 0 && model_path.empty ())
      throw std::runtime_error ("give --model MODEL, or --folds K to cross-validate");
    if (folds == 1 || folds < 0)
      throw std::runtime_error ("--folds needs at least 2 folds");
    if (!(opencv_scale > 0.05 && opencv_scale <= 4.0))
      throw std::runtime_error ("--opencv-scale must lie in (0.05, 4]");
    if (!detector_path.empty () && opencv_scale != 0.5)
      throw std::runtime_error ("--opencv-scale applies to OpenCV's detector only, not to --detector");
    if (folds == 0 && (!extra_paths.empty () || train_detector))
      throw std::runtime_error ("--train-also and --train-detector need --folds");
    if (folds > 0 && !model_path.empty ())
      throw std::runtime_error ("--folds trains a model per fold; --model is not used with it");
    agex::InputFiles read (dataset_paths);
    for (const auto &path : extra_paths)
      read.add (path);
    for (const auto &path : {model_path, detector_path})
      if (!path.empty ())
        read.add (path);
    if (!json_path.empty ())
      read.checkOutput (json_path);
    auto images = agex::apps::loadLandmarkDatasets (dataset_paths);
    const std::size_t tested_images = images.size ();
    {
      std::vector<agex::apps::AnnotatedImage> extra = agex::apps::loadLandmarkDatasets (extra_paths);
      std::move (extra.begin (), extra.end (), std::back_inserter (images));
    }
    // No output may land on an image the datasets name either.
    for (const auto &image : images)
      read.add (image.path);
    if (!json_path.empty ())
      read.checkOutput (json_path);
    if (folds > static_cast<int> (tested_images))
      throw std::runtime_error ("the dataset has " + std::to_string (tested_images) + " images, fewer than " +
                                std::to_string (folds) + " folds");

    // Each fold: the models to test and the images to test them on.
    agex::apps::LandmarkEvaluation pooled;
    nlohmann::json fold_results = nlohmann::json::array ();
    auto evaluate = [&] (const agex::ContourShapePredictor &predictor, const agex::PeopleDetector *detector,
                         const std::vector<std::size_t> &test) {
      agex::apps::LandmarkEvaluation fold;
      for (const std::size_t i : test)
      {
        fold.add (images[i], predictor, detector);
        pooled.add (images[i], predictor, detector);
        if (!overlay_dir.empty ())
        {
          std::vector<agex::apps::LandmarkedPerson> people;
          for (const auto &person : images[i].people)
            people.push_back ({person.box, 1.0, predictor.predict (images[i].grey, person.box)});
          const std::string overlay = overlay_dir + "/" + std::filesystem::path (images[i].path).stem ().string () + ".png";
          read.checkOutput (overlay);
          std::filesystem::create_directories (overlay_dir);
          agex::apps::writePng (overlay, agex::apps::renderLandmarkOverlay (
                                           agex::apps::readImage (images[i].path, cv::IMREAD_COLOR), people));
        }
      }
      return fold.json ();
    };
    std::unique_ptr<agex::PeopleDetector> given_detector;
    if (!no_detector)
      given_detector = std::make_unique<agex::PeopleDetector> (
        detector_path.empty () ? agex::PeopleDetector::openCvDefault (opencv_scale)
                                : agex::PeopleDetector::load (detector_path));

    if (folds == 0)
    {
      const agex::ContourShapePredictor predictor = agex::apps::loadContourModel (model_path);
      std::vector<std::size_t> test (tested_images);
      std::iota (test.begin (), test.end (), 0);
      evaluate (predictor, given_detector.get (), test);
    }
    else
      for (int f = 0; f < folds; ++f)
      {
        std::vector<std::size_t> train, test;
        for (std::size_t i = 0; i < images.size (); ++i)
          (i < tested_images && static_cast<int> (i % folds) == f ? test : train).push_back (i);
        std::cerr << "fold " << f + 1 << "/" << folds << ": training on " << train.size () << " images\n";
        const agex::ContourShapePredictor predictor = agex::apps::trainShapePredictor (images, train, shape_params);
        std::unique_ptr<agex::PeopleDetector> fold_detector;
        if (train_detector && !no_detector)
          fold_detector = std::make_unique<agex::PeopleDetector> (
            agex::apps::trainPeopleDetector (images, train, detector_params));
        fold_results.push_back (evaluate (predictor, fold_detector ? fold_detector.get () : given_detector.get (), test));
      }

    nlohmann::json doc = pooled.json ();
    doc["dataset"] = dataset_paths;
    if (folds > 0)
    {
      doc["folds"] = folds;
      doc["train_also"] = extra_paths;
      doc["per_fold"] = fold_results;
      doc["detector"] = no_detector ? "none" : train_detector ? "fhog trained per fold" : given_detector->description ();
    }
    else
    {
      doc["model"] = model_path;
      doc["detector"] = no_detector ? "none" : given_detector->description ();
    }
    if (!json_path.empty ())
      agex::apps::writeJson (json_path, doc);
    std::cout << doc.dump (2) << "\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_landmarks_eval: error: " << e.what () << "\n";
    return 1;
  }
}
