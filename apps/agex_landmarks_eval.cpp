// agex_landmarks_eval: landmark and detection errors of a contour model on an imglab
// dataset, or cross-validated by image (--folds K: train on K-1 folds, test on the rest).

#include <agex/apps/command_line.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/io/atomic_file.h>

#include <boost/program_options.hpp>

#include <iostream>
#include <memory>
#include <numeric>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  std::vector<std::string> dataset_paths, extra_paths;
  std::string model_path, json_path;
  int folds = 0;
  bool train_detector = false;
  agex::apps::DetectorChoice detector_choice;
  agex::apps::EvaluationSettings settings;
  agex::ShapePredictorTrainingParams shape_params;
  agex::apps::DetectorTraining detector_training;
  po::options_description general ("agex_landmarks_eval --dataset XML (--model MODEL | --folds K) [options]\n"
                                   "Mean landmark error (px, per box height, per shoulder width), mean distance to the true\n"
                                   "contour (px, per box height), people detection (AP at IoU 0.5, recall, false detections\n"
                                   "per image) and time per image. Landmarks are predicted in the true boxes so that the\n"
                                   "two errors stay apart.");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&dataset_paths)->multitoken ()->required (), "imglab XML files with contour landmarks")
    ("model", po::value (&model_path), "shape predictor to evaluate")
    ("no-detector", po::bool_switch (&detector_choice.none), "skip detection")
    ("threshold", po::value (&settings.threshold)->default_value (settings.threshold),
     "detection threshold for the recall and false detections")
    ("min-detection-height", po::value (&settings.min_detection_height)->default_value (settings.min_detection_height),
     "people shorter than this (pixels) are ignore regions for the detection scores")
    ("folds", po::value (&folds)->default_value (0), "cross-validate by image: image i is in fold i mod K")
    ("train-also", po::value (&extra_paths)->multitoken (),
     "with --folds: imglab XML files added to every fold's training set, never tested")
    ("train-detector", po::bool_switch (&train_detector), "with --folds: train a detector per fold too")
    ("json", po::value (&json_path), "write the results here")
    ("overlay-dir", po::value (&settings.overlay_dir), "write a PNG per image with the predicted landmarks here")
    ("pasted", po::bool_switch (&settings.pasted),
     "also score detection on the tested people pasted into each other's photos (several per image, many sizes)");
  po::options_description all;
  all.add (general).add (agex::apps::detectorChoiceOptions (detector_choice));
  all.add (agex::apps::shapeTrainerOptions (shape_params)).add (agex::apps::detectorTrainerOptions (detector_training));
  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, {}))
      return 0;
    if ((folds == 0) == model_path.empty ())
      throw std::runtime_error ("give --model MODEL, or --folds K to cross-validate (a model is trained per fold)");
    if (folds == 1 || folds < 0)
      throw std::runtime_error ("--folds needs at least 2 folds");
    if ((folds == 0 && (!extra_paths.empty () || train_detector)) || settings.min_detection_height < 0)
      throw std::runtime_error ("--train-also and --train-detector need --folds; --min-detection-height must be 0 or more");
    const agex::apps::EvaluationInputs inputs =
      agex::apps::loadEvaluationInputs (dataset_paths, extra_paths, {model_path, detector_choice.path}, json_path);
    const auto &images = inputs.images;
    std::unique_ptr<agex::PeopleDetector> detector;
    if (!detector_choice.none && !train_detector)
      detector = std::make_unique<agex::PeopleDetector> (agex::apps::loadDetector (detector_choice));

    nlohmann::json doc;
    if (folds == 0)
    {
      agex::apps::LandmarkEvaluation pooled;
      std::vector<std::size_t> test (inputs.tested);
      std::iota (test.begin (), test.end (), 0);
      agex::apps::evaluateImages (images, test, agex::apps::loadContourModel (model_path), detector.get (), settings,
                                  inputs.read, pooled);
      doc = pooled.json ();
      doc["model"] = model_path;
    }
    else
      doc = agex::apps::crossValidate (images, inputs.tested, folds, shape_params,
                                       train_detector && !detector_choice.none ? &detector_training : nullptr,
                                       detector.get (), settings, inputs.read);
    doc["dataset"] = dataset_paths;
    doc["detector"] = detector ? detector->description () : train_detector && !detector_choice.none ? "fhog trained per fold" : "none";
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
