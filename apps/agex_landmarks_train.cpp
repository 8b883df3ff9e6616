// agex_landmarks_train: trains the contour shape predictor (and, when asked, the people
// detector) on an imglab dataset of 180-landmark contours (agex_annotate writes them).

#include <agex/apps/command_line.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output_guard.h>
#include <agex/landmarks/landmark_evaluation.h>
#include <agex/landmarks/landmark_training.h>

#include <boost/program_options.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numeric>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  std::vector<std::string> dataset_paths, combined;
  std::string model_path, detector_path;
  agex::ShapePredictorTrainingParams shape_params;
  agex::PeopleDetectorTraining detector_training;
  agex::apps::PeopleCropChoice crop_choice;
  po::options_description general ("agex_landmarks_train --dataset XML --out MODEL [--detector-out FILE] [options]\n"
                                   "agex_landmarks_train --combine FILE[@OFFSET] --combine ... --detector-out FILE\n"
                                   "Trains the 180-landmark contour shape predictor (and the people detector), or writes\n"
                                   "trained people detectors as one");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&dataset_paths)->multitoken (), "imglab XML files with contour landmarks (agex_annotate)")
    ("out", po::value (&model_path), "shape predictor model to write")
    ("detector-out", po::value (&detector_path), "also train the people detector and write it here")
    ("combine", po::value (&combined)->composing (),
     "FILE or FILE@OFFSET (repeatable, 1 to 8): instead of training, write these trained people detectors to "
     "--detector-out as one (each member's detections at the threshold + OFFSET, in [-5, 5], count; their scores "
     "less OFFSET): an ensemble, or one detector with its operating threshold");
  po::options_description all;
  all.add (general).add (agex::apps::shapeTrainerOptions (shape_params)).add (agex::apps::detectorTrainerOptions (detector_training));
  all.add (agex::apps::detectorCropOptions (crop_choice, detector_training));
  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, {}))
      return 0;
    if (!combined.empty ())
    {
      if (!dataset_paths.empty () || !model_path.empty () || !crop_choice.folder.empty ())
        throw std::runtime_error ("--combine trains nothing: give no --dataset, --out or --detector-crops with it");
      if (detector_path.empty ())
        throw std::runtime_error ("--combine writes the detectors as one to --detector-out: give it");
      agex::InputFiles read;
      for (const std::string &item : combined)
        read.add (agex::apps::detectorFileAndOffset (item, "--combine").first);
      agex::apps::checkOutputPath (detector_path, "--detector-out", [] (const std::string &path) {
        try
        {
          agex::PeopleDetector::load (path);
          return std::string ();
        }
        catch (const std::exception &)
        {
          return std::string ("exists and is not a people detector");
        }
      }, read);
      const agex::PeopleDetector detector = agex::apps::combineDetectorFiles ({}, {}, combined, "--combine");
      detector.save (detector_path);
      std::cout << detector_path << ": " << detector.description () << "\n";
      return 0;
    }
    if (dataset_paths.empty () || model_path.empty ())
      throw std::runtime_error ("give --dataset and --out (or --combine)");
    if (!detector_path.empty () &&
        std::filesystem::weakly_canonical (detector_path) == std::filesystem::weakly_canonical (model_path))
      throw std::runtime_error (detector_path + ": --detector-out and --out name the same file");
    const agex::apps::LandmarkInputs inputs = agex::apps::loadLandmarkInputs (dataset_paths, {}, {}, {model_path, detector_path});
    agex::apps::checkLandmarkModelOutputs (model_path, detector_path, inputs.read);
    if (!crop_choice.folder.empty () && detector_path.empty ())
      throw std::runtime_error ("--detector-crops trains the people detector: give --detector-out too");
    const std::shared_ptr<const agex::PeopleCrops> crops =
      agex::apps::loadPeopleCrops (crop_choice, false, detector_training.crop_which);
    detector_training.crops = crops.get ();
    if (crops)
      std::cout << crop_choice.folder << ": " << detector_training.crop_which.size () << " of " << crops->images.size ()
                << " person crops for the detector\n";
    const auto &images = inputs.images;
    std::vector<std::size_t> all_images (images.size ());
    std::iota (all_images.begin (), all_images.end (), 0);
    std::size_t people = 0;
    for (const auto &image : images)
      people += image.people.size ();
    std::cout << "dataset: " << images.size () << " images, " << people << " people\n";

    shape_params.verbose = true;  // dlib reports the cascade levels as it goes
    auto start = std::chrono::steady_clock::now ();
    const agex::ContourShapePredictor predictor = agex::trainContourShapePredictor (images, all_images, shape_params);
    predictor.save (model_path);
    const double train_s = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
    agex::LandmarkEvaluation training_fit;
    for (const auto &image : images)
      training_fit.add (image, predictor, nullptr);
    const auto fit = training_fit.json ();
    std::cout << model_path << ": trained in " << train_s << " s; mean training error " << fit["mean_error_px"]
              << " px (" << fit["mean_error_box_height"] << " of the box height)\n";

    if (!detector_path.empty ())
    {
      detector_training.params.verbose = true;
      std::size_t ignored = 0;
      const agex::PeopleDetector detector = agex::trainPeopleDetector (images, all_images, detector_training, &ignored);
      detector.save (detector_path);
      agex::LandmarkEvaluation detection;
      for (const auto &image : images)
        detection.add (image, predictor, &detector);
      std::cout << detector_path << ": " << ignored << " boxes the window cannot match were ignored; training recall "
                << detection.json ()["detection_recall"] << "\n";
    }
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_landmarks_train: error: " << e.what () << "\n";
    return 1;
  }
}
