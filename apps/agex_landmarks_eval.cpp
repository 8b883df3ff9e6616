// agex_landmarks_eval: landmark and detection errors of a contour model on an imglab
// dataset, or cross-validated by image (--folds K: train on K-1 folds, test on the rest).

#include <agex/apps/command_line.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/landmarks/landmark_evaluation.h>
#include <agex/landmarks/people_landmarks.h>

#include <boost/program_options.hpp>

#include <iostream>
#include <memory>
#include <numeric>

int
main (int argc, char **argv)
{
  agex::apps::LandmarkEvaluationFlags flags;
  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, agex::apps::landmarkEvaluationOptions (flags), {}))
      return 0;
    agex::apps::checkLandmarkEvaluationFlags (flags);
    const agex::apps::LandmarkInputs inputs =
      agex::apps::loadLandmarkInputs (flags.datasets, flags.train_also, {flags.model, flags.detector.path}, {flags.json});
    if (!flags.json.empty ())
      agex::apps::checkOutputPath (flags.json, "agex_landmarks_eval report",
                                   agex::apps::jsonReportWith ({"dataset", "detector"}), inputs.read);
    flags.settings.crop_params.min_background_height = flags.settings.crop_params.max_background_height;
    const std::shared_ptr<const agex::PeopleCrops> crops =
      agex::apps::loadPeopleCrops (flags.crops, true, flags.settings.crop_which);
    flags.settings.crops = crops.get ();
    const bool train_detector = flags.train_detector && !flags.detector.none;
    std::unique_ptr<agex::PeopleDetector> detector;
    if (!flags.detector.none && !flags.train_detector)
      detector = std::make_unique<agex::PeopleDetector> (agex::apps::loadPeopleDetector (flags.detector));
    const agex::ScoredImageCallback overlays = agex::apps::landmarkOverlayWriter (flags.overlay_dir, inputs);

    nlohmann::json doc;
    if (flags.folds == 0)
    {
      agex::LandmarkEvaluation pooled;
      std::vector<std::size_t> test (inputs.tested);
      std::iota (test.begin (), test.end (), 0);
      agex::evaluateLandmarks (inputs.images, test, agex::loadContourModel (flags.model), detector.get (), flags.settings,
                               pooled, overlays);
      doc = pooled.json ();
      doc["model"] = flags.model;
    }
    else
      doc = agex::crossValidateLandmarks (inputs.images, inputs.tested, flags.folds, flags.shape_params,
                                          train_detector ? &flags.detector_training : nullptr, detector.get (),
                                          flags.settings, agex::apps::crossValidationProgress (overlays));
    doc["dataset"] = flags.datasets;
    doc["detector"] = detector ? detector->description () : train_detector ? "fhog trained per fold" : "none";
    if (!flags.json.empty ())
      agex::apps::writeJson (flags.json, doc);
    std::cout << doc.dump (2) << "\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_landmarks_eval: error: " << e.what () << "\n";
    return 1;
  }
}
